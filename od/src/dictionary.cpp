#include "od/dictionary.hpp"
#include "util/strfmt.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

namespace od {

static_assert(std::endian::native == std::endian::little, "the value image is little-endian, as the wire");

// ---- Entry / Object ---------------------------------------------------------------------------------

bool Entry::readable(AlState s) const {
    switch (s) {
        case AlState::PreOp:
            return access & access::ReadPreOp;
        case AlState::SafeOp:
            return access & access::ReadSafeOp;
        case AlState::Op:
            return access & access::ReadOp;
        default:
            return false;  // Init and Bootstrap: no CoE access
    }
}

bool Entry::writable(AlState s) const {
    switch (s) {
        case AlState::PreOp:
            return access & access::WritePreOp;
        case AlState::SafeOp:
            return access & access::WriteSafeOp;
        case AlState::Op:
            return access & access::WriteOp;
        default:
            return false;
    }
}

const Entry* Object::entry(uint8_t sub) const {
    auto it = std::lower_bound(entries.begin(), entries.end(), sub,
                               [](const Entry& e, uint8_t s) { return e.subindex < s; });
    if (it == entries.end() || it->subindex != sub) return nullptr;
    return &*it;
}

// ---- value helpers ----------------------------------------------------------------------------------
namespace {

constexpr std::size_t kStringPrefix = 2;  // a string's current length (UINT16) precedes its bytes

int64_t load_signed(std::span<const uint8_t> b) {
    uint64_t u = 0;
    for (std::size_t i = 0; i < b.size(); ++i)
        u |= static_cast<uint64_t>(b[i]) << (8 * i);
    const unsigned bits = static_cast<unsigned>(8 * b.size());
    if (bits < 64 && (u >> (bits - 1)) & 1u) u |= ~uint64_t{0} << bits;  // sign-extend
    return static_cast<int64_t>(u);
}

uint64_t load_unsigned(std::span<const uint8_t> b) {
    uint64_t u = 0;
    for (std::size_t i = 0; i < b.size(); ++i)
        u |= static_cast<uint64_t>(b[i]) << (8 * i);
    return u;
}

double load_real(std::span<const uint8_t> b) {
    if (b.size() == 4) {
        float f;
        std::memcpy(&f, b.data(), 4);
        return f;
    }
    double d;
    std::memcpy(&d, b.data(), 8);
    return d;
}

// -1: v below the bound, 0: not below, for a lower bound. Bounds may be given in any Number alternative.
bool below(int64_t v, const Number& m) {
    if (auto p = std::get_if<int64_t>(&m)) return v < *p;
    if (auto p = std::get_if<uint64_t>(&m)) return v < 0 || static_cast<uint64_t>(v) < *p;
    if (auto p = std::get_if<double>(&m)) return static_cast<double>(v) < *p;
    return false;
}
bool above(int64_t v, const Number& m) {
    if (auto p = std::get_if<int64_t>(&m)) return v > *p;
    if (auto p = std::get_if<uint64_t>(&m)) return v >= 0 && static_cast<uint64_t>(v) > *p;
    if (auto p = std::get_if<double>(&m)) return static_cast<double>(v) > *p;
    return false;
}
bool below(uint64_t v, const Number& m) {
    if (auto p = std::get_if<int64_t>(&m)) return *p > 0 && v < static_cast<uint64_t>(*p);
    if (auto p = std::get_if<uint64_t>(&m)) return v < *p;
    if (auto p = std::get_if<double>(&m)) return static_cast<double>(v) < *p;
    return false;
}
bool above(uint64_t v, const Number& m) {
    if (auto p = std::get_if<int64_t>(&m)) return *p < 0 || v > static_cast<uint64_t>(*p);
    if (auto p = std::get_if<uint64_t>(&m)) return v > *p;
    if (auto p = std::get_if<double>(&m)) return static_cast<double>(v) > *p;
    return false;
}
double as_double(const Number& m) {
    if (auto p = std::get_if<int64_t>(&m)) return static_cast<double>(*p);
    if (auto p = std::get_if<uint64_t>(&m)) return static_cast<double>(*p);
    if (auto p = std::get_if<double>(&m)) return *p;
    return 0.0;
}

// Checks type, length and declared limits of a value for an entry.
Status check_value(const Entry& e, std::span<const uint8_t> v) {
    if (is_string(e.type)) return v.size() > e.byte_size() ? Status::LengthTooHigh : Status::Ok;
    const std::size_t n = e.byte_size();
    if (v.size() > n) return Status::LengthTooHigh;
    if (v.size() < n) return Status::LengthTooLow;
    if (e.type == DataType::Boolean) return v[0] > 1 ? Status::ValueTooHigh : Status::Ok;
    if (is_signed(e.type)) {
        const int64_t x = load_signed(v);
        if (below(x, e.minimum)) return Status::ValueTooLow;
        if (above(x, e.maximum)) return Status::ValueTooHigh;
    } else if (is_real(e.type)) {
        const double x = load_real(v);
        if (std::isnan(x)) return Status::InvalidValue;
        if (!std::holds_alternative<std::monostate>(e.minimum) && x < as_double(e.minimum))
            return Status::ValueTooLow;
        if (!std::holds_alternative<std::monostate>(e.maximum) && x > as_double(e.maximum))
            return Status::ValueTooHigh;
    } else {
        const uint64_t x = load_unsigned(v);
        if (below(x, e.minimum)) return Status::ValueTooLow;
        if (above(x, e.maximum)) return Status::ValueTooHigh;
    }
    return Status::Ok;
}

[[noreturn]] void declaration_error(const Entry& e, const std::string& what) {
    throw std::logic_error(
        util::strprintf("od: entry 0x%04X:%02X (%s): ", e.index, e.subindex, e.name.c_str()) + what);
}

// Encodes a declared default into n little-endian bytes of the entry's type.
void encode_default(const Entry& e, uint8_t* out) {
    const std::size_t n = e.byte_size();
    if (is_string(e.type)) {
        if (e.default_string.size() > n) declaration_error(e, "default string longer than its capacity");
        const auto len = static_cast<uint16_t>(e.default_string.size());
        std::memcpy(out - kStringPrefix, &len, kStringPrefix);
        std::memcpy(out, e.default_string.data(), len);
        return;
    }
    const Number& d = e.default_value;
    if (is_real(e.type)) {
        const double x = as_double(d);
        if (n == 4) {
            const float f = static_cast<float>(x);
            std::memcpy(out, &f, 4);
        } else {
            std::memcpy(out, &x, 8);
        }
        return;
    }
    uint64_t bits = 0;
    if (is_signed(e.type)) {
        int64_t x = 0;
        if (auto p = std::get_if<int64_t>(&d)) x = *p;
        if (auto p = std::get_if<uint64_t>(&d)) {
            if (*p > static_cast<uint64_t>(std::numeric_limits<int64_t>::max()))
                declaration_error(e, "default out of the type's range");
            x = static_cast<int64_t>(*p);
        }
        if (auto p = std::get_if<double>(&d)) x = std::llround(*p);
        if (n < 8) {
            const int64_t lim = int64_t{1} << (8 * n - 1);
            if (x < -lim || x >= lim) declaration_error(e, "default out of the type's range");
        }
        bits = static_cast<uint64_t>(x);
    } else {
        if (auto p = std::get_if<int64_t>(&d)) {
            if (*p < 0) declaration_error(e, "negative default for an unsigned type");
            bits = static_cast<uint64_t>(*p);
        }
        if (auto p = std::get_if<uint64_t>(&d)) bits = *p;
        if (auto p = std::get_if<double>(&d)) bits = static_cast<uint64_t>(std::llround(*p));
        if (n < 8 && (bits >> (8 * n)) != 0) declaration_error(e, "default out of the type's range");
    }
    for (std::size_t i = 0; i < n; ++i)
        out[i] = static_cast<uint8_t>(bits >> (8 * i));
}

}  // namespace

// ---- Dictionary -------------------------------------------------------------------------------------

struct Dictionary::Impl {
    // Each hook remembers who installed it, so that an owner that goes away first can take its hooks
    // with it (remove_hooks) instead of leaving a dangling callback behind.
    template <typename F>
    struct Owned {
        const void* owner;
        F fn;
    };
    struct Hooks {
        std::vector<Owned<Validator>> validators;
        std::vector<Owned<Listener>> listeners;
        std::vector<Owned<ReadHook>> read_hooks;
    };
    std::vector<Object> objects;  // sorted by index
    std::vector<Hooks> hooks;     // parallel to objects
    std::vector<uint8_t> image;
    std::vector<uint8_t> defaults;

    std::size_t position(uint16_t index) const {
        auto it = std::lower_bound(objects.begin(), objects.end(), index,
                                   [](const Object& o, uint16_t i) { return o.index < i; });
        if (it == objects.end() || it->index != index) return objects.size();
        return static_cast<std::size_t>(it - objects.begin());
    }

    // Finds an entry; status NoObject / NoSubindex when missing.
    Status locate(uint16_t index, uint8_t sub, std::size_t& pos, const Entry*& e) const {
        pos = position(index);
        if (pos == objects.size()) return Status::NoObject;
        e = objects[pos].entry(sub);
        return e ? Status::Ok : Status::NoSubindex;
    }

    std::span<const uint8_t> value_of(const Entry& e, const std::vector<uint8_t>& img) const {
        if (is_string(e.type)) {
            uint16_t len;
            std::memcpy(&len, img.data() + e.offset - kStringPrefix, kStringPrefix);
            return {img.data() + e.offset, len};
        }
        return {img.data() + e.offset, e.byte_size()};
    }

    void commit(const Entry& e, std::span<const uint8_t> v) {
        uint8_t* p = image.data() + e.offset;
        if (is_string(e.type)) {
            const auto len = static_cast<uint16_t>(v.size());
            std::memcpy(p - kStringPrefix, &len, kStringPrefix);
            std::memset(p, 0, e.byte_size());
        }
        if (!v.empty()) std::memmove(p, v.data(), v.size());
    }

    void notify(std::size_t pos, const Entry& e) {
        for (auto& l : hooks[pos].listeners)
            l.fn(e);
    }
};

Dictionary::Dictionary() : impl_(std::make_unique<Impl>()) {}
Dictionary::~Dictionary() = default;
Dictionary::Dictionary(Dictionary&&) noexcept = default;
Dictionary& Dictionary::operator=(Dictionary&&) noexcept = default;

void Dictionary::add(Object object) {
    auto& im = *impl_;
    const std::size_t pos = im.position(object.index);
    if (pos != im.objects.size()) {
        throw std::logic_error(util::strprintf("od: duplicate object 0x%04X", object.index));
    }
    if (object.direction == PdoDirection::None) object.direction = standard_pdo_direction(object.index);
    std::sort(object.entries.begin(), object.entries.end(),
              [](const Entry& a, const Entry& b) { return a.subindex < b.subindex; });
    for (std::size_t i = 1; i < object.entries.size(); ++i)
        if (object.entries[i].subindex == object.entries[i - 1].subindex)
            declaration_error(object.entries[i], "duplicate subindex");
    if (object.code == ObjectCode::Var) {
        if (object.entries.size() != 1 || object.entries[0].subindex != 0)
            throw std::logic_error("od: VAR object " + object.name + " needs exactly subindex 0");
    } else {
        if (object.entries.empty() || object.entries[0].subindex != 0) {
            // Sub-index 0 of an ARRAY/RECORD: "highest sub-index supported", UNSIGNED8, read-only.
            Entry s0;
            s0.name = "Highest Subindex supported";
            s0.type = DataType::Unsigned8;
            s0.access = access::RO;
            s0.default_value = uint64_t{object.entries.empty() ? 0u : object.entries.back().subindex};
            object.entries.insert(object.entries.begin(), std::move(s0));
        }
        if (object.entries[0].type != DataType::Unsigned8)
            declaration_error(object.entries[0], "sub-index 0 of an ARRAY/RECORD must be UNSIGNED8");
        if (object.code == ObjectCode::Array)
            for (std::size_t i = 1; i < object.entries.size(); ++i)
                if (object.entries[i].type != object.type)
                    declaration_error(object.entries[i], "ARRAY element of another type than the array's");
    }
    // Storage: each entry aligned to its natural size (max 8); strings get a 2-byte length prefix.
    for (auto& e : object.entries) {
        e.index = object.index;
        if (e.bit_length == 0) {
            e.bit_length =
                is_string(e.type) ? static_cast<uint16_t>(8 * e.default_string.size()) : bit_size(e.type);
            if (e.bit_length == 0) declaration_error(e, "no bit length (structured type or empty string)");
        }
        if (!is_string(e.type) && e.bit_length != bit_size(e.type))
            declaration_error(e, "bit length != type size");
        std::size_t off = im.image.size();
        if (is_string(e.type)) {
            off = (off + 1) & ~std::size_t{1};
            off += kStringPrefix;
        } else {
            const std::size_t align = std::min<std::size_t>(e.byte_size(), 8);
            off = (off + align - 1) / align * align;
        }
        e.offset = off;
        im.image.resize(off + e.byte_size(), 0);
        im.defaults.resize(im.image.size(), 0);
        encode_default(e, im.defaults.data() + off);
        if (!is_string(e.type)) {
            const Status st = check_value(e, {im.defaults.data() + off, e.byte_size()});
            if (st != Status::Ok) declaration_error(e, "default outside [minimum, maximum]");
        }
        std::memcpy(im.image.data() + off - (is_string(e.type) ? kStringPrefix : 0),
                    im.defaults.data() + off - (is_string(e.type) ? kStringPrefix : 0),
                    e.byte_size() + (is_string(e.type) ? kStringPrefix : 0));
    }
    const auto at = std::lower_bound(im.objects.begin(), im.objects.end(), object.index,
                                     [](const Object& o, uint16_t i) { return o.index < i; });
    const auto hp = im.hooks.begin() + (at - im.objects.begin());
    im.objects.insert(at, std::move(object));
    im.hooks.insert(hp, Impl::Hooks{});
}

const Object* Dictionary::find(uint16_t index) const {
    const std::size_t pos = impl_->position(index);
    return pos == impl_->objects.size() ? nullptr : &impl_->objects[pos];
}

const Entry* Dictionary::find(uint16_t index, uint8_t sub) const {
    const Object* o = find(index);
    return o ? o->entry(sub) : nullptr;
}

std::span<const Object> Dictionary::objects() const {
    return impl_->objects;
}

Status Dictionary::read(uint16_t index, uint8_t sub, AlState state, std::span<uint8_t> out,
                        std::size_t& length) {
    auto& im = *impl_;
    std::size_t pos;
    const Entry* e = nullptr;
    length = 0;
    if (Status st = im.locate(index, sub, pos, e); st != Status::Ok) return st;
    if ((e->access & access::ReadMask) == 0) return Status::WriteOnly;
    if (!e->readable(state)) return Status::WrongState;
    for (auto& h : im.hooks[pos].read_hooks)
        h.fn(*e);
    const auto v = im.value_of(*e, im.image);
    length = v.size();
    if (out.size() < v.size()) return Status::LengthTooHigh;
    if (!v.empty()) std::memcpy(out.data(), v.data(), v.size());
    return Status::Ok;
}

Status Dictionary::write(uint16_t index, uint8_t sub, AlState state, std::span<const uint8_t> value) {
    auto& im = *impl_;
    std::size_t pos;
    const Entry* e = nullptr;
    if (Status st = im.locate(index, sub, pos, e); st != Status::Ok) return st;
    if ((e->access & access::WriteMask) == 0) return Status::ReadOnly;
    if (!e->writable(state)) return Status::WrongState;
    if (Status st = check_value(*e, value); st != Status::Ok) return st;
    for (auto& v : im.hooks[pos].validators)
        if (Status st = v.fn(*e, value); st != Status::Ok) return st;
    im.commit(*e, value);
    im.notify(pos, *e);
    return Status::Ok;
}

Status Dictionary::set_raw(uint16_t index, uint8_t sub, std::span<const uint8_t> value) {
    auto& im = *impl_;
    std::size_t pos;
    const Entry* e = nullptr;
    if (Status st = im.locate(index, sub, pos, e); st != Status::Ok) return st;
    if (Status st = check_value(*e, value); st != Status::Ok) return st;
    im.commit(*e, value);
    im.notify(pos, *e);
    return Status::Ok;
}

std::span<const uint8_t> Dictionary::raw(uint16_t index, uint8_t sub) const {
    const Entry* e = find(index, sub);
    return e ? impl_->value_of(*e, impl_->image) : std::span<const uint8_t>{};
}

Status Dictionary::check(uint16_t index, uint8_t sub, std::span<const uint8_t> value) const {
    std::size_t pos;
    const Entry* e = nullptr;
    if (Status st = impl_->locate(index, sub, pos, e); st != Status::Ok) return st;
    return check_value(*e, value);
}

std::span<const uint8_t> Dictionary::default_raw(uint16_t index, uint8_t sub) const {
    const Entry* e = find(index, sub);
    return e ? impl_->value_of(*e, impl_->defaults) : std::span<const uint8_t>{};
}

std::span<uint8_t> Dictionary::mutable_raw(uint16_t index, uint8_t sub) {
    const Entry* e = find(index, sub);
    if (!e || is_string(e->type)) return {};
    return {impl_->image.data() + e->offset, e->byte_size()};
}

void Dictionary::add_validator(uint16_t index, Validator v, const void* owner) {
    const std::size_t pos = impl_->position(index);
    if (pos == impl_->objects.size())
        throw std::out_of_range("od::Dictionary::add_validator: no such object");
    impl_->hooks[pos].validators.push_back({owner, std::move(v)});
}

void Dictionary::add_listener(uint16_t index, Listener l, const void* owner) {
    const std::size_t pos = impl_->position(index);
    if (pos == impl_->objects.size()) throw std::out_of_range("od::Dictionary::add_listener: no such object");
    impl_->hooks[pos].listeners.push_back({owner, std::move(l)});
}

void Dictionary::add_read_hook(uint16_t index, ReadHook h, const void* owner) {
    const std::size_t pos = impl_->position(index);
    if (pos == impl_->objects.size())
        throw std::out_of_range("od::Dictionary::add_read_hook: no such object");
    impl_->hooks[pos].read_hooks.push_back({owner, std::move(h)});
}

void Dictionary::remove_hooks(const void* owner) {
    if (owner == nullptr) return;
    auto drop = [owner](auto& list) {
        std::erase_if(list, [owner](const auto& h) { return h.owner == owner; });
    };
    for (auto& h : impl_->hooks) {
        drop(h.validators);
        drop(h.listeners);
        drop(h.read_hooks);
    }
}

void Dictionary::reset_to_defaults() {
    impl_->image = impl_->defaults;
}

uint8_t* Dictionary::storage(uint16_t index, uint8_t sub, std::size_t size) {
    const Entry* e = find(index, sub);
    if (!e) throw std::out_of_range("od::Dictionary::ref: no such entry");
    if (is_string(e->type) || e->byte_size() != size)
        throw std::out_of_range("od::Dictionary::ref: size does not match the entry's type");
    return impl_->image.data() + e->offset;
}

}  // namespace od
