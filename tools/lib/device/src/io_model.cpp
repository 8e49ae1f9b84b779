// device::IoModel: the inputs of a device without an application (see device/io_model.hpp).
#include "device/io_model.hpp"

#include <algorithm>
#include <cctype>
#include <string>

#include "ecat/process_data.hpp"

namespace device {
namespace {

// The entries of a copy plan, in mapping order (padding is not in the plan).
void mapped(std::span<const ecat::PdoCopy> plan, std::vector<IoEntry>& out) {
    out.clear();
    for (const ecat::PdoCopy& c : plan)
        if (c.entry != nullptr && c.storage != nullptr) out.push_back({c.entry, c.storage});
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

void IoModel::build(const ecat::ProcessData& pd, const std::set<uint32_t>& held) {
    clear();
    mapped(pd.rx_plan(), outputs_);
    mapped(pd.tx_plan(), inputs_);
    std::vector<bool> taken(outputs_.size(), false);
    for (const IoEntry& in : inputs_) {
        const uint32_t key = io_key(in.entry->index, in.entry->subindex);
        if (held.count(key) != 0) continue;
        // An entry an output PDO maps too (a watchdog counter the master writes and reads back) holds what
        // the master writes: its input shows that, neither counted nor mirrored from another output.
        if (std::any_of(outputs_.begin(), outputs_.end(),
                        [&in](const IoEntry& out) { return out.storage == in.storage; }))
            continue;
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

void IoModel::safe_outputs() {
    static constexpr uint8_t kZero[8] = {};
    for (const IoEntry& out : outputs_)
        for (std::size_t bit = 0; bit < out.entry->bit_length; bit += 64)
            ecat::ProcessData::copy_bits(kZero, 0, out.storage, bit,
                                         std::min<std::size_t>(64, out.entry->bit_length - bit));
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
