#include "ecat/process_data.hpp"

#include <cstring>

#include "esc/wire/al.hpp"

namespace ecat {

ProcessData::ProcessData(od::Dictionary& dictionary) : dict_(dictionary) {
    rx_.reserve(kMaxEntries);
    tx_.reserve(kMaxEntries);
    rx_sms_.reserve(kMaxSms);
    tx_sms_.reserve(kMaxSms);
}

void ProcessData::clear() {
    rx_.clear();
    tx_.clear();
    rx_sms_.clear();
    tx_sms_.clear();
    rx_bits_ = 0;
    tx_bits_ = 0;
}

namespace {

// Reads an unsigned value of up to 8 bytes from the dictionary; false if the entry does not exist.
bool read_unsigned(const od::Dictionary& d, uint16_t index, uint8_t sub, uint64_t& value) {
    const auto raw = d.raw(index, sub);
    if (raw.empty() || raw.size() > 8) return false;
    value = 0;
    for (std::size_t i = 0; i < raw.size(); ++i)
        value |= static_cast<uint64_t>(raw[i]) << (8 * i);
    return true;
}

bool is_padding(uint16_t index, uint8_t sub) {
    // Index 0 or the standard data type "dummy" objects 0x0001..0x0007 (BOOLEAN .. UNSIGNED32), sub 0.
    return index == 0 || (index <= 0x0007 && sub == 0);
}

}  // namespace

uint16_t ProcessData::build_sm(unsigned sm, bool rx, std::vector<PdoCopy>& plan, std::size_t& bits) {
    const uint16_t code = rx ? esc::al::InvalidOutputMapping : esc::al::InvalidInputMapping;
    const od::PdoDirection dir = rx ? od::PdoDirection::Rx : od::PdoDirection::Tx;
    const uint16_t assign_index = ProcessData::assign_index(sm);
    if (dict_.find(assign_index) == nullptr) return 0;  // no assignment: no process data in that SM
    uint64_t pdo_count = 0;
    if (!read_unsigned(dict_, assign_index, 0, pdo_count)) return code;
    for (uint8_t i = 1; i <= pdo_count; ++i) {
        uint64_t pdo = 0;
        if (!read_unsigned(dict_, assign_index, i, pdo)) return code;
        // A mapping object of this direction, wherever its index lies (the object model carries it).
        const od::Object* mapping = pdo <= 0xFFFF ? dict_.find(static_cast<uint16_t>(pdo)) : nullptr;
        if (mapping == nullptr || !mapping->is_pdo_mapping() || mapping->direction != dir) return code;
        uint64_t entry_count = 0;
        if (!read_unsigned(dict_, static_cast<uint16_t>(pdo), 0, entry_count)) return code;
        for (uint8_t k = 1; k <= entry_count; ++k) {
            uint64_t m = 0;
            if (!read_unsigned(dict_, static_cast<uint16_t>(pdo), k, m)) return code;
            const auto index = static_cast<uint16_t>(m >> 16);
            const auto sub = static_cast<uint8_t>(m >> 8);
            const auto length = static_cast<uint16_t>(m & 0xFF);
            if (length == 0) return code;
            if (!is_padding(index, sub)) {
                const od::Entry* e = dict_.find(index, sub);
                if (e == nullptr || !e->mappable_with(length)) return code;
                if (rx ? !e->rx_mappable() : !e->tx_mappable()) return code;
                if (plan.size() == kMaxEntries) return code;
                const auto raw = dict_.raw(index, sub);
                if (raw.size() * 8 < length) return code;
                // The value image is owned by the dictionary and never moves after declaration; the plan
                // writes outputs straight into it, as od::Ref<T> does.
                plan.push_back({const_cast<uint8_t*>(raw.data()), static_cast<uint32_t>(bits), length, e});
            }
            bits += length;
        }
    }
    return 0;
}

uint16_t ProcessData::build(std::span<const unsigned> outputs_sms, std::span<const unsigned> inputs_sms) {
    clear();
    uint16_t code = 0;
    auto side = [this, &code](std::span<const unsigned> sms, bool rx) {
        std::vector<PdoCopy>& plan = rx ? rx_ : tx_;
        std::vector<SmImage>& images = rx ? rx_sms_ : tx_sms_;
        std::size_t& bits = rx ? rx_bits_ : tx_bits_;
        for (const unsigned sm : sms) {
            if (code != 0 || sm >= 32 || images.size() == kMaxSms) continue;
            bits = (bits + 7) / 8 * 8;  // each SM's part starts on a byte of its own
            const std::size_t first = bits;
            code = build_sm(sm, rx, plan, bits);
            images.push_back({sm, first / 8, (bits - first + 7) / 8});
        }
    };
    side(outputs_sms, true);
    side(inputs_sms, false);
    if (code != 0) clear();
    return code;
}

uint16_t ProcessData::build(unsigned outputs_sm, unsigned inputs_sm) {
    const unsigned out[1] = {outputs_sm};
    const unsigned in[1] = {inputs_sm};
    return build(std::span<const unsigned>(out, outputs_sm < 32 ? 1 : 0),
                 std::span<const unsigned>(in, inputs_sm < 32 ? 1 : 0));
}

void ProcessData::copy_bits(const uint8_t* src, std::size_t src_bit, uint8_t* dst, std::size_t dst_bit,
                            std::size_t n) {
    if (src_bit % 8 == 0 && dst_bit % 8 == 0) {
        const std::size_t whole = n / 8;
        std::memcpy(dst + dst_bit / 8, src + src_bit / 8, whole);
        src_bit += whole * 8;
        dst_bit += whole * 8;
        n -= whole * 8;
    }
    for (std::size_t i = 0; i < n; ++i) {
        const std::size_t s = src_bit + i;
        const std::size_t d = dst_bit + i;
        const bool bit = (src[s / 8] >> (s % 8)) & 1u;
        const auto mask = static_cast<uint8_t>(1u << (d % 8));
        dst[d / 8] = bit ? static_cast<uint8_t>(dst[d / 8] | mask) : static_cast<uint8_t>(dst[d / 8] & ~mask);
    }
}

void ProcessData::outputs_to_dictionary(std::span<const uint8_t> sm2) const {
    for (const PdoCopy& c : rx_) {
        if (c.bit_offset + c.bits > sm2.size() * 8) continue;
        copy_bits(sm2.data(), c.bit_offset, c.storage, 0, c.bits);
    }
}

void ProcessData::dictionary_to_inputs(std::span<uint8_t> sm3) const {
    for (const PdoCopy& c : tx_) {
        if (c.bit_offset + c.bits > sm3.size() * 8) continue;
        copy_bits(c.storage, 0, sm3.data(), c.bit_offset, c.bits);
    }
}

void ProcessData::inputs_to_dictionary(std::span<const uint8_t> sm3, const SmImage& part) const {
    const std::size_t first = part.offset * 8, end = (part.offset + part.bytes) * 8;
    for (const PdoCopy& c : tx_) {
        if (c.bit_offset < first || c.bit_offset + c.bits > end || c.bit_offset + c.bits > sm3.size() * 8)
            continue;
        copy_bits(sm3.data(), c.bit_offset, c.storage, 0, c.bits);
    }
}

}  // namespace ecat
