#include "coe/diagnosis.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>

#include "wire.hpp"

namespace coe {

namespace {
constexpr uint8_t kSubMax = 1;
constexpr uint8_t kSubNewest = 2;
constexpr uint8_t kSubAcked = 3;
constexpr uint8_t kSubNewAvailable = 4;
constexpr uint8_t kSubFlags = 5;
constexpr std::size_t kHead = 16;  // code 4 + flags 2 + text id 2 + time stamp 8
constexpr uint16_t kWritableFlags = 0x001F;
}  // namespace

od::Object DiagnosisHistory::make_object(uint8_t max_messages, uint16_t message_bytes) {
    using namespace od::access;
    max_messages = static_cast<uint8_t>(std::clamp<unsigned>(max_messages, 1, kMaxMessages));
    od::Object o;
    o.index = kIndex;
    o.code = od::ObjectCode::Record;
    o.name = "Diagnosis History";
    o.type = od::DataType::Unsigned8;
    auto add = [&](uint8_t sub, std::string name, od::DataType t, uint16_t bits, uint16_t acc,
                   od::Number def) {
        od::Entry e;
        e.index = kIndex;
        e.subindex = sub;
        e.name = std::move(name);
        e.type = t;
        e.bit_length = bits;
        e.access = acc;
        e.default_value = def;
        o.entries.push_back(std::move(e));
    };
    add(0, "Number of entries", od::DataType::Unsigned8, 8, RO, uint64_t{5u + max_messages});
    add(kSubMax, "Maximum Messages", od::DataType::Unsigned8, 8, RO, uint64_t{max_messages});
    add(kSubNewest, "Newest Message", od::DataType::Unsigned8, 8, RO, uint64_t{0});
    add(kSubAcked, "Newest Acknowledged Message", od::DataType::Unsigned8, 8, RW, uint64_t{0});
    add(kSubNewAvailable, "New Messages Available", od::DataType::Boolean, 1, RO | TxPdo, uint64_t{0});
    add(kSubFlags, "Flags", od::DataType::Unsigned16, 16, RW, uint64_t{0});
    for (unsigned i = 0; i < max_messages; ++i) {
        add(static_cast<uint8_t>(kFirstMessage + i), "Diagnosis Message " + std::to_string(i + 1),
            od::DataType::OctetString, static_cast<uint16_t>(message_bytes * 8), RO, {});
    }
    return o;
}

std::size_t DiagnosisHistory::encode(const DiagMessage& m, std::span<uint8_t> out) {
    if (out.size() < kHead) return 0;
    uint8_t* p = out.data();
    std::size_t at = kHead;
    unsigned n = 0;
    for (const auto& prm : m.params) {
        if (n == 255 || at + 2 > out.size()) break;
        std::size_t len = prm.data.size();
        uint16_t pflags = prm.flags;
        if (at + 2 + len > out.size()) {
            // Byte arrays and strings are cut to the room left (Unicode to whole characters); values are
            // left out whole.
            const unsigned kind = pflags >> 12;
            if (kind < 1 || kind > 3) break;
            len = out.size() - at - 2;
            if (kind == 3) len &= ~std::size_t{1};
            if (len == 0) break;
            pflags = static_cast<uint16_t>((pflags & 0xF000) | len);
        }
        wire::put16(p + at, pflags);
        std::memcpy(p + at + 2, prm.data.data(), len);
        at += 2 + len;
        ++n;
    }
    wire::put32(p, m.code);
    uint16_t flags =
        static_cast<uint16_t>((static_cast<uint16_t>(m.type) & 0x0F) | (m.local_time ? 0x10 : 0) | (n << 8));
    wire::put16(p + 4, flags);
    wire::put16(p + 6, m.text_id);
    wire::put64(p + 8, m.timestamp_ns);
    return at;
}

std::string DiagnosisHistory::unusable(const od::Dictionary& dict) {
    const od::Object* obj = dict.find(kIndex);
    if (obj == nullptr) return {};
    for (uint8_t sub = 1; sub <= kSubFlags; ++sub)
        if (obj->entry(sub) == nullptr) return "0x10F3 lacks :01..:05";
    std::size_t slots = 0, capacity = 0;
    for (const auto& e : obj->entries) {
        if (e.subindex < kFirstMessage) continue;
        if (e.subindex != kFirstMessage + slots) return "0x10F3 messages are not contiguous from :06";
        capacity = capacity == 0 ? e.byte_size() : std::min(capacity, e.byte_size());
        ++slots;
    }
    if (slots == 0) return "0x10F3 has no message subindex (:06 and after)";
    if (slots > kMaxMessages) return "0x10F3 has more than 250 messages";
    if (capacity < kHead) return "0x10F3 has a message shorter than 16 bytes";
    return {};
}

DiagnosisHistory::DiagnosisHistory(od::Dictionary& dict, Emergency* emergency)
    : dict_(dict), emergency_(emergency) {
    const od::Object* obj = dict_.find(kIndex);
    if (obj == nullptr) throw std::logic_error("coe::DiagnosisHistory: the dictionary has no 0x10F3");
    if (const std::string why = unusable(dict_); !why.empty())
        throw std::logic_error("coe::DiagnosisHistory: " + why +
                               " (it needs :01..:05 and 1..250 contiguous messages of at least 16 bytes)");
    for (const auto& e : obj->entries) {
        if (e.subindex < kFirstMessage) continue;
        capacity_ = capacity_ == 0 ? e.byte_size() : std::min(capacity_, e.byte_size());
        ++slots_;
    }
    buf_.resize(capacity_);
    updating_ = true;
    set_u8(kSubMax, static_cast<uint8_t>(slots_));
    updating_ = false;
    dict_.add_validator(
        kIndex, [this](const od::Entry& e, std::span<const uint8_t> v) { return validate(e, v); }, this);
    dict_.add_listener(
        kIndex, [this](const od::Entry& e) { on_written(e); }, this);
    dict_.add_read_hook(
        kIndex, [this](const od::Entry& e) { on_read(e); }, this);
}

DiagnosisHistory::~DiagnosisHistory() {
    dict_.remove_hooks(this);
}

uint16_t DiagnosisHistory::flags() const {
    auto r = dict_.raw(kIndex, kSubFlags);
    return r.size() >= 2 ? wire::get16(r, 0) : 0;
}

uint8_t DiagnosisHistory::newest() const {
    auto r = dict_.raw(kIndex, kSubNewest);
    return r.empty() ? 0 : r[0];
}

std::size_t DiagnosisHistory::unacknowledged() const {
    std::size_t n = 0;
    for (std::size_t i = 0; i < slots_; ++i)
        if (seq_[i] != 0 && seq_[i] > acked_seq_) ++n;
    return n;
}

void DiagnosisHistory::set_u8(uint8_t sub, uint8_t v) {
    dict_.set_raw(kIndex, sub, std::span<const uint8_t>(&v, 1));
}

void DiagnosisHistory::set_flags(uint16_t v) {
    uint8_t b[2];
    wire::put16(b, v);
    dict_.set_raw(kIndex, kSubFlags, b);
}

void DiagnosisHistory::store(uint8_t sub, std::span<const uint8_t> bytes) {
    if (dict_.set_raw(kIndex, sub, bytes) == od::Status::Ok) return;
    // A dictionary that keeps octet strings at their full length: pad with zeros.
    std::fill(buf_.begin() + static_cast<std::ptrdiff_t>(bytes.size()), buf_.end(), 0);
    if (bytes.data() != buf_.data()) std::copy(bytes.begin(), bytes.end(), buf_.begin());
    dict_.set_raw(kIndex, sub, std::span<const uint8_t>(buf_.data(), capacity_));
}

DiagnosisHistory::Result DiagnosisHistory::add(const DiagMessage& m, bool may_send_emergency) {
    const uint16_t f = flags();
    if ((m.type == DiagType::Info && (f & kFlagNoInfo)) ||
        (m.type == DiagType::Warning && (f & kFlagNoWarning)) ||
        (m.type == DiagType::Error && (f & kFlagNoError)))
        return Result::Suppressed;

    updating_ = true;
    Result result = Result::Stored;
    const bool acknowledge_mode = (f & kFlagAcknowledgeMode) != 0;
    if (acknowledge_mode && unacknowledged() >= slots_) {
        overflow_ = true;  // buffer full of unacknowledged messages: the new one is discarded
        result = Result::Discarded;
    } else {
        if (seq_[next_] != 0 && seq_[next_] > acked_seq_) {
            // Overwrite mode: an unacknowledged message is lost.
            overflow_ = true;
            acked_seq_ = 0;
            set_u8(kSubAcked, 0);
        }
        std::size_t len = encode(m, buf_);
        const uint8_t sub = static_cast<uint8_t>(kFirstMessage + next_);
        store(sub, std::span<const uint8_t>(buf_.data(), len));
        seq_[next_] = next_seq_++;
        next_ = (next_ + 1) % slots_;
        count_ = std::min(count_ + 1, slots_);
        set_u8(kSubNewest, sub);
        set_u8(kSubNewAvailable, 1);
    }
    set_flags(static_cast<uint16_t>((f & ~kFlagOverflow) | (overflow_ ? kFlagOverflow : 0)));
    updating_ = false;

    if (result == Result::Stored && may_send_emergency && (f & kFlagEmergency) && emergency_ != nullptr) {
        // Emergency-derived codes carry their error code; others go out as "device specific" (0xFF00) with
        // the diag code and the message type as manufacturer data.
        uint16_t code = (m.code & 0xFFFF) == 0xE800 ? static_cast<uint16_t>(m.code >> 16) : 0xFF00;
        uint8_t mfr[5];
        wire::put32(mfr, m.code);
        mfr[4] = static_cast<uint8_t>(m.type);
        // The error register as the dictionary holds it (the application may keep 0x1001 itself).
        auto reg = dict_.raw(0x1001, 0);
        emergency_->send(code, reg.empty() ? emergency_->error_register() : reg[0], mfr);
    }
    return result;
}

void DiagnosisHistory::clear() {
    updating_ = true;
    for (std::size_t i = 0; i < slots_; ++i) {
        seq_[i] = 0;
        store(static_cast<uint8_t>(kFirstMessage + i), {});
    }
    next_ = 0;
    count_ = 0;
    acked_seq_ = 0;
    overflow_ = false;
    set_u8(kSubNewest, 0);
    set_u8(kSubAcked, 0);
    set_u8(kSubNewAvailable, 0);
    set_flags(static_cast<uint16_t>(flags() & ~kFlagOverflow));
    updating_ = false;
}

od::Status DiagnosisHistory::validate(const od::Entry& e, std::span<const uint8_t> v) const {
    if (e.subindex == kSubAcked) {
        if (v.size() != 1) return od::Status::LengthMismatch;
        if (v[0] == 0) return od::Status::Ok;
        if (v[0] < kFirstMessage) return od::Status::ValueTooLow;
        if (v[0] >= kFirstMessage + slots_) return od::Status::ValueTooHigh;
        return od::Status::Ok;
    }
    if (e.subindex == kSubFlags) {
        if (v.size() != 2) return od::Status::LengthMismatch;
        uint16_t f = static_cast<uint16_t>(wire::get16(v, 0) & ~kFlagOverflow);  // b5 is status: ignored
        if (f & ~kWritableFlags) return od::Status::InvalidValue;
        if ((f & kFlagEmergency) && emergency_ == nullptr) return od::Status::InvalidValue;
        return od::Status::Ok;
    }
    return od::Status::Ok;
}

void DiagnosisHistory::on_written(const od::Entry& e) {
    if (updating_) return;
    if (e.subindex == kSubAcked) {
        auto r = dict_.raw(kIndex, kSubAcked);
        uint8_t v = r.empty() ? 0 : r[0];
        if (v == 0) {
            clear();
            return;
        }
        std::size_t slot = v - kFirstMessage;
        if (slot < slots_ && seq_[slot] != 0) acked_seq_ = std::max(acked_seq_, seq_[slot]);
        if (unacknowledged() < slots_ && (flags() & kFlagAcknowledgeMode)) {
            // Room again: the overflow status of acknowledge mode ends with the acknowledgement.
            overflow_ = false;
            updating_ = true;
            set_flags(static_cast<uint16_t>(flags() & ~kFlagOverflow));
            updating_ = false;
        }
    } else if (e.subindex == kSubFlags) {
        // Keep the read-only overflow bit what it really is.
        updating_ = true;
        set_flags(static_cast<uint16_t>((flags() & ~kFlagOverflow) | (overflow_ ? kFlagOverflow : 0)));
        updating_ = false;
    }
}

void DiagnosisHistory::on_read(const od::Entry& e) {
    if (updating_ || e.subindex < kFirstMessage) return;
    if (count_ > 0 && e.subindex == newest()) {
        updating_ = true;
        set_u8(kSubNewAvailable, 0);
        updating_ = false;
    }
}

}  // namespace coe
