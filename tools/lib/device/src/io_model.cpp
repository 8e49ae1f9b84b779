// device::IoModel: the inputs of a device without an application (see device/io_model.hpp).
#include "device/io_model.hpp"

#include <algorithm>
#include <cctype>
#include <string>

#include "ecat/process_data.hpp"

namespace device {
namespace {

bool read_unsigned(const od::Dictionary& d, uint16_t index, uint8_t sub, uint64_t& value) {
    const auto raw = d.raw(index, sub);
    if (raw.empty() || raw.size() > 8) return false;
    value = 0;
    for (std::size_t i = 0; i < raw.size(); ++i)
        value |= static_cast<uint64_t>(raw[i]) << (8 * i);
    return true;
}

// The entries mapped by the PDOs assigned to SM n, in mapping order (padding left out).
void mapped(od::Dictionary& d, unsigned sm, std::vector<IoEntry>& out) {
    out.clear();
    if (sm >= 32) return;
    const uint16_t assign = ecat::ProcessData::assign_index(sm);
    uint64_t pdos = 0;
    if (d.find(assign) == nullptr || !read_unsigned(d, assign, 0, pdos)) return;
    for (uint8_t i = 1; i <= pdos && i != 0; ++i) {
        uint64_t pdo = 0, count = 0;
        if (!read_unsigned(d, assign, i, pdo) || !read_unsigned(d, static_cast<uint16_t>(pdo), 0, count))
            continue;
        for (uint8_t k = 1; k <= count && k != 0; ++k) {
            uint64_t m = 0;
            if (!read_unsigned(d, static_cast<uint16_t>(pdo), k, m)) continue;
            const auto index = static_cast<uint16_t>(m >> 16);
            const auto sub = static_cast<uint8_t>(m >> 8);
            const od::Entry* e = d.find(index, sub);
            if (e == nullptr || index < 0x1000 || e->bit_length == 0) continue;  // padding or missing
            const auto raw = d.mutable_raw(index, sub);
            if (raw.empty()) continue;
            out.push_back({e, raw.data()});
        }
    }
}

std::string lower(std::string_view s) {
    std::string r(s);
    for (char& c : r)
        c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return r;
}

}  // namespace

IoModel::IoModel() {
    outputs_.reserve(ecat::ProcessData::kMaxEntries);
    inputs_.reserve(ecat::ProcessData::kMaxEntries);
}

bool IoModel::is_counter_name(std::string_view name) {
    return lower(name).find("counter") != std::string::npos;
}

void IoModel::build(od::Dictionary& dict, unsigned outputs_sm, unsigned inputs_sm,
                    const std::set<uint32_t>& held) {
    clear();
    mapped(dict, outputs_sm, outputs_);
    mapped(dict, inputs_sm, inputs_);
    std::vector<bool> taken(outputs_.size(), false);
    for (const IoEntry& in : inputs_) {
        const uint32_t key = io_key(in.entry->index, in.entry->subindex);
        if (held.count(key) != 0) continue;
        if (is_counter_name(in.entry->name)) {
            if (in.entry->bit_length <= 64) counters_.push_back({in.storage, in.entry->bit_length, key});
            continue;
        }
        const std::string name = lower(in.entry->name);
        for (std::size_t o = 0; o < outputs_.size(); ++o) {
            const od::Entry& out = *outputs_[o].entry;
            if (taken[o] || out.type != in.entry->type || out.bit_length != in.entry->bit_length ||
                lower(out.name) != name)
                continue;
            taken[o] = true;
            mirrors_.push_back({outputs_[o].storage, in.storage, in.entry->bit_length, key});
            break;
        }
    }
}

void IoModel::clear() {
    outputs_.clear();
    inputs_.clear();
    mirrors_.clear();
    counters_.clear();
}

void IoModel::hold(uint16_t index, uint8_t sub) {
    const uint32_t key = io_key(index, sub);
    std::erase_if(mirrors_, [key](const Mirror& m) { return m.key == key; });
    std::erase_if(counters_, [key](const Counter& c) { return c.key == key; });
}

void IoModel::cycle() {
    for (const Mirror& m : mirrors_)
        ecat::ProcessData::copy_bits(m.src, 0, m.dst, 0, m.bits);
    for (const Counter& c : counters_) {
        const std::size_t bytes = (c.bits + 7u) / 8u;
        uint64_t v = 0;
        for (std::size_t i = 0; i < bytes; ++i)
            v |= static_cast<uint64_t>(c.value[i]) << (8 * i);
        ++v;
        if (c.bits < 64) v &= (uint64_t{1} << c.bits) - 1;
        for (std::size_t i = 0; i < bytes; ++i) {
            if (i == bytes - 1 && c.bits % 8 != 0) {
                const auto keep = static_cast<uint8_t>(0xFFu << (c.bits % 8));
                c.value[i] =
                    static_cast<uint8_t>((c.value[i] & keep) | (static_cast<uint8_t>(v >> (8 * i)) & ~keep));
            } else {
                c.value[i] = static_cast<uint8_t>(v >> (8 * i));
            }
        }
    }
}

}  // namespace device
