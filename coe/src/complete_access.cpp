#include "complete_access.hpp"

#include <algorithm>
#include <cstring>

namespace coe::ca {
namespace {

bool byte_aligned(const od::Entry& e) {
    return e.bit_length % 8 == 0 || od::is_string(e.type);
}

uint32_t entry_bits(const od::Entry& e) {
    return e.subindex == 0 ? 16u : e.bit_length;
}

// Bit position of e in an image whose running end is `end` (in bits); advances end past e.
uint32_t place(const od::Entry& e, uint32_t& end) {
    if (e.subindex != 0 && byte_aligned(e)) end = (end + 7u) & ~7u;
    uint32_t at = end;
    end += entry_bits(e);
    return at;
}

void put_bits(std::span<uint8_t> out, uint32_t at, const uint8_t* src, uint32_t bits) {
    if (at % 8 == 0 && bits % 8 == 0) {
        std::memcpy(out.data() + at / 8, src, bits / 8);
        return;
    }
    for (uint32_t i = 0; i < bits; ++i) {
        uint32_t bit = (src[i / 8] >> (i % 8)) & 1u;
        uint32_t pos = at + i;
        if (bit)
            out[pos / 8] = static_cast<uint8_t>(out[pos / 8] | (1u << (pos % 8)));
        else
            out[pos / 8] = static_cast<uint8_t>(out[pos / 8] & ~(1u << (pos % 8)));
    }
}

void get_bits(std::span<const uint8_t> in, uint32_t at, uint8_t* dst, uint32_t bits) {
    std::memset(dst, 0, (bits + 7) / 8);
    if (at % 8 == 0 && bits % 8 == 0) {
        std::memcpy(dst, in.data() + at / 8, bits / 8);
        return;
    }
    for (uint32_t i = 0; i < bits; ++i) {
        uint32_t pos = at + i;
        if ((in[pos / 8] >> (pos % 8)) & 1u) dst[i / 8] = static_cast<uint8_t>(dst[i / 8] | (1u << (i % 8)));
    }
}

bool in_range(const od::Entry& e, uint8_t first, uint8_t last) {
    return e.subindex >= first && e.subindex <= last;
}

bool writable_at_all(const od::Entry& e) {
    return (e.access & od::access::WriteMask) != 0;
}

// The value bytes an entry gets from its slot in an image: strings lose their NUL padding.
std::size_t value_length(const od::Entry& e, const uint8_t* v) {
    std::size_t n = e.subindex == 0 ? 1 : e.byte_size();
    if (e.type == od::DataType::VisibleString) {
        std::size_t len = 0;
        while (len < n && v[len] != 0)
            ++len;
        return len;
    }
    return n;
}

void save(std::vector<uint8_t>& rb, const od::Dictionary& dict, const od::Entry& e) {
    auto cur = dict.raw(e.index, e.subindex);
    rb.push_back(e.subindex);
    rb.push_back(static_cast<uint8_t>(cur.size()));
    rb.push_back(static_cast<uint8_t>(cur.size() >> 8));
    rb.insert(rb.end(), cur.begin(), cur.end());
}

void restore(od::Dictionary& dict, uint16_t index, const std::vector<uint8_t>& rb) {
    // Subindex 0 is restored first to 0 (if saved) so count-checking validators see no active entries, then
    // every entry, then subindex 0's old value. set_raw bypasses validators and access rights.
    const uint8_t zero = 0;
    bool have_sub0 = !rb.empty() && rb[0] == 0;
    if (have_sub0) dict.set_raw(index, 0, std::span<const uint8_t>(&zero, 1));
    std::size_t pos = 0;
    while (pos + 3 <= rb.size()) {
        uint8_t sub = rb[pos];
        std::size_t len = rb[pos + 1] | (static_cast<std::size_t>(rb[pos + 2]) << 8);
        if (sub != 0) dict.set_raw(index, sub, std::span<const uint8_t>(rb.data() + pos + 3, len));
        pos += 3 + len;
    }
    if (have_sub0) {
        std::size_t len = rb[1] | (static_cast<std::size_t>(rb[2]) << 8);
        dict.set_raw(index, 0, std::span<const uint8_t>(rb.data() + 3, len));
    }
}

}  // namespace

uint8_t upload_last_subindex(const od::Dictionary& dict, const od::Object& obj) {
    uint8_t max = obj.max_subindex();
    if (obj.code != od::ObjectCode::Array) return max;
    auto sub0 = dict.raw(obj.index, 0);
    if (sub0.empty()) return max;
    return std::min(sub0[0], max);
}

std::size_t image_size(const od::Object& obj, uint8_t first, uint8_t last) {
    uint32_t end = 0;
    for (const auto& e : obj.entries)
        if (in_range(e, first, last)) place(e, end);
    return (end + 7u) / 8u;
}

std::size_t max_image_size(const od::Object& obj) {
    return image_size(obj, 0, obj.max_subindex());
}

od::Status upload(od::Dictionary& dict, const od::Object& obj, uint8_t first, od::AlState state,
                  std::span<uint8_t> out, std::size_t& size, std::span<uint8_t> scratch) {
    uint8_t last = upload_last_subindex(dict, obj);
    size = image_size(obj, first, last);
    if (out.size() < size) return od::Status::OutOfMemory;
    std::memset(out.data(), 0, size);
    uint32_t end = 0;
    for (const auto& e : obj.entries) {
        if (!in_range(e, first, last)) continue;
        uint32_t at = place(e, end);
        std::size_t len = 0;
        od::Status st = dict.read(obj.index, e.subindex, state, scratch, len);
        if (st == od::Status::WriteOnly) continue;  // not readable: its slot stays zero
        if (st != od::Status::Ok) return st;
        uint32_t bits = e.subindex == 0 ? 8u : e.bit_length;
        if (od::is_string(e.type)) {
            std::memcpy(out.data() + at / 8, scratch.data(), std::min<std::size_t>(len, bits / 8));
        } else {
            put_bits(out, at, scratch.data(), std::min<uint32_t>(bits, static_cast<uint32_t>(len * 8)));
        }
    }
    return od::Status::Ok;
}

od::Status download(od::Dictionary& dict, const od::Object& obj, uint8_t first, od::AlState state,
                    std::span<const uint8_t> data, std::vector<uint8_t>& rollback,
                    std::span<uint8_t> scratch) {
    const uint32_t have_bits = static_cast<uint32_t>(data.size() * 8);
    const od::Entry* sub0 = obj.entry(0);
    uint8_t new_count = 0;
    bool with_sub0 = first == 0 && sub0 != nullptr;
    if (with_sub0) {
        if (data.size() < 2) return od::Status::LengthTooLow;
        new_count = data[0];
    }

    // Which entries the image carries: every declared entry whose slot lies completely inside the data.
    uint32_t end = 0;
    uint8_t provided_last = 0;
    bool all_placed = true;
    uint32_t used_bits = with_sub0 ? 16u : 0u;
    bool any_writable = with_sub0 && writable_at_all(*sub0);
    for (const auto& e : obj.entries) {
        if (e.subindex == 0 || e.subindex < first) {
            if (e.subindex == 0 && first == 0) place(e, end);
            continue;
        }
        place(e, end);
        if (end > have_bits) {
            all_placed = false;
            break;
        }
        provided_last = e.subindex;
        used_bits = end;
        any_writable = any_writable || writable_at_all(e);
    }
    std::size_t used_bytes = (used_bits + 7u) / 8u;
    // Data left over: beyond the last declared entry (too long), or a partial entry (too short).
    if (data.size() > used_bytes) return all_placed ? od::Status::LengthTooHigh : od::Status::LengthTooLow;
    if (!any_writable) return od::Status::ReadOnly;

    // Read-only entries (subindex 0 included) are skipped, as SOES does: masters download whole images.
    bool sub0_writable = with_sub0 && writable_at_all(*sub0);
    if (sub0_writable) {
        if (new_count > obj.max_subindex()) return od::Status::ValueTooHigh;
        // Every counted entry must be in the image (entries may be absent from a RECORD's declaration).
        for (const auto& e : obj.entries)
            if (e.subindex > provided_last && e.subindex <= new_count) return od::Status::LengthTooLow;
    }

    rollback.clear();
    if (sub0_writable) save(rollback, dict, *sub0);
    for (const auto& e : obj.entries)
        if (e.subindex != 0 && e.subindex >= first && e.subindex <= provided_last) save(rollback, dict, e);

    auto fail = [&](od::Status st) {
        restore(dict, obj.index, rollback);
        return st;
    };

    if (sub0_writable) {
        const uint8_t zero = 0;
        // A device whose subindex 0 cannot be 0 still takes the entries; the final write reports real errors.
        (void)dict.write(obj.index, 0, state, std::span<const uint8_t>(&zero, 1));
    }
    end = 0;
    for (const auto& e : obj.entries) {
        if (e.subindex == 0 || e.subindex < first) {
            if (e.subindex == 0 && first == 0) place(e, end);
            continue;
        }
        uint32_t at = place(e, end);
        if (e.subindex > provided_last) break;
        uint32_t bits = e.bit_length;
        if (od::is_string(e.type)) {
            std::memcpy(scratch.data(), data.data() + at / 8, bits / 8);
        } else {
            get_bits(data, at, scratch.data(), bits);
        }
        std::size_t len = value_length(e, scratch.data());
        std::span<const uint8_t> value(scratch.data(), len);
        if (!writable_at_all(e)) continue;
        od::Status st = dict.write(obj.index, e.subindex, state, value);
        // Entries past the new count are "don't care" (a master may send the whole array with zeros there):
        // one the dictionary refuses keeps its old value instead of failing the download.
        if (st != od::Status::Ok && !(sub0_writable && e.subindex > new_count)) return fail(st);
    }
    if (sub0_writable) {
        od::Status st = dict.write(obj.index, 0, state, std::span<const uint8_t>(&new_count, 1));
        if (st != od::Status::Ok) return fail(st);
    }
    return od::Status::Ok;
}

}  // namespace coe::ca
