// The module configuration an ENI slave was configured with (see eni_modules.hpp).
#include "esi/eni/eni_modules.hpp"

#include <algorithm>
#include <map>
#include <set>
#include <tuple>

#include "esi/slots.hpp"
#include "util/strfmt.hpp"

namespace esi::eni {

namespace {

// An entry as both files can state it: index, subindex (0 for a gap) and bit length.
using Entry = std::tuple<uint16_t, uint8_t, uint16_t>;

uint32_t le32(const std::vector<uint8_t>& d, std::size_t at) {
    return uint32_t(d[at]) | uint32_t(d[at + 1]) << 8 | uint32_t(d[at + 2]) << 16 | uint32_t(d[at + 3]) << 24;
}

bool takes(const EsiFile& f, const EsiDevice& d, std::size_t slot, uint32_t ident) {
    const EsiModule* m = f.module(ident);
    return m != nullptr && slot < d.slots.size() && slot_takes(f, d.slots[slot], *m);
}

// 1. The configured module ident list the master downloads (0xF030, ETG.5001.1): complete access from
// subindex 0 (8-bit count, a padding byte, then the idents) or 1 (the idents), or one subindex at a time.
std::optional<std::vector<std::optional<uint32_t>>> from_f030(const EsiFile& f, const EsiDevice& d,
                                                              const Slave& s) {
    std::map<std::size_t, uint32_t> idents;  // slot -> ident
    bool seen = false;
    for (const CoeInitCmd& c : s.mailbox.coe_init_cmds) {
        if (c.index != 0xF030 || c.ccs != 1 || c.disabled) continue;
        if (c.complete_access) {
            const std::size_t first = c.subindex == 0 ? 2 : 0;
            if (c.subindex > 1 || c.data.size() < first) return std::nullopt;
            const std::size_t count = c.subindex == 0 ? c.data[0] : (c.data.size() - first) / 4;
            if (c.data.size() < first + 4 * count) return std::nullopt;
            for (std::size_t k = 0; k < count; ++k)
                idents[k] = le32(c.data, first + 4 * k);
            seen = true;
        } else if (c.subindex >= 1 && c.data.size() == 4) {
            idents[c.subindex - 1u] = le32(c.data, 0);
            seen = true;
        }
    }
    if (!seen) return std::nullopt;
    std::vector<std::optional<uint32_t>> modules(d.slots.size());
    for (const auto& [slot, ident] : idents) {
        if (ident == 0) continue;
        if (!takes(f, d, slot, ident)) return std::nullopt;
        modules[slot] = ident;
    }
    return modules;
}

std::vector<Entry> entries_of(const Pdo& p) {
    std::vector<Entry> e;
    for (const PdoEntry& x : p.entries)
        e.emplace_back(x.index, x.index == 0 ? uint8_t{0} : x.subindex, x.bit_len);
    return e;
}

std::vector<Entry> entries_of(const std::vector<EsiPdoEntry>& entries) {
    std::vector<Entry> e;
    for (const EsiPdoEntry& x : entries)
        e.emplace_back(x.index, x.index == 0 ? uint8_t{0} : x.subindex, x.bit_len);
    return e;
}

}  // namespace

std::vector<PdoMismatch> pdo_mismatches(const EsiFile& f, const EsiDevice& d,
                                        const std::vector<std::optional<uint32_t>>& modules, const Slave& s) {
    struct Declared {
        std::vector<Entry> entries;
        bool fixed = false;
    };
    std::map<uint16_t, Declared> device;  // the device's own PDOs, then its modules' at their slots
    for (const auto* list : {&d.rxpdos, &d.txpdos})
        for (const EsiPdo& p : *list)
            device[p.index] = {entries_of(p.entries), p.fixed};
    for (const SlotModule& m : slot_modules(f, d, modules))
        for (const SlotPdo& p : m.pdos)
            device[p.index] = {entries_of(p.entries), p.esi != nullptr && p.esi->fixed};
    std::vector<PdoMismatch> out;
    for (const auto* list : {&s.process_data.rxpdos, &s.process_data.txpdos})
        for (const Pdo& p : *list) {
            auto it = device.find(p.index);
            const std::string pdo =
                std::string("the ENI's ") + (p.rx ? "RxPDO " : "TxPDO ") + util::hex(p.index);
            if (it == device.end())
                out.push_back({p.line, pdo + " is not a PDO of the device"});
            else if (it->second.fixed && it->second.entries != entries_of(p))
                out.push_back({p.line, pdo + " maps other entries than the device's fixed PDO"});
        }
    return out;
}

std::optional<EniModules> modules_from_eni(const EsiFile& f, const EsiDevice& d, const Slave& s,
                                           std::string* why) {
    if (d.slots.empty()) return std::nullopt;
    if (auto m = from_f030(f, d, s)) return EniModules{std::move(*m), "its 0xF030 init command"};

    std::map<uint16_t, std::vector<Entry>> eni;  // the ENI slave's PDOs
    std::map<uint16_t, int> eni_line;
    for (const auto* list : {&s.process_data.rxpdos, &s.process_data.txpdos})
        for (const Pdo& p : *list) {
            eni[p.index] = entries_of(p);
            eni_line[p.index] = p.line;
        }
    auto matches = [&](const SlotPdo& p) {
        auto it = eni.find(p.index);
        return it != eni.end() && it->second == entries_of(p.entries);
    };

    EniModules out;
    out.how = "its PDOs";
    out.modules.resize(d.slots.size());
    std::set<uint16_t> explained;  // ENI PDOs the device or a chosen module declares
    for (const auto* list : {&d.rxpdos, &d.txpdos})
        for (const EsiPdo& p : *list)
            explained.insert(p.index);
    for (std::size_t n = 0; n < d.slots.size(); ++n) {
        const EsiSlot& slot = d.slots[n];
        std::vector<uint32_t> candidates;  // the default first, then the slot's own list, then by class
        if (slot.default_module) candidates.push_back(*slot.default_module);
        for (uint32_t id : slot.module_idents)
            candidates.push_back(id);
        for (const EsiModule& m : f.modules)
            if (slot_takes(f, slot, m)) candidates.push_back(m.ident);
        std::optional<uint32_t> best;
        std::size_t best_pdos = 0;
        std::vector<uint16_t> best_indices;
        for (uint32_t id : candidates) {
            std::vector<std::optional<uint32_t>> probe(n + 1);
            probe[n] = id;
            const std::vector<SlotModule> placed = slot_modules(f, d, probe);
            if (placed.empty() || placed[0].module == nullptr || placed[0].pdos.empty()) continue;
            if (!std::all_of(placed[0].pdos.begin(), placed[0].pdos.end(), matches)) continue;
            if (placed[0].pdos.size() <= best_pdos) continue;  // the most PDOs; on a tie the earlier
            best = id;
            best_pdos = placed[0].pdos.size();
            best_indices.clear();
            for (const SlotPdo& p : placed[0].pdos)
                best_indices.push_back(p.index);
        }
        if (!best && slot.default_module) {
            // No module's PDOs are the ENI's: the default stays where it has no PDOs (a module the PDOs
            // cannot tell) or where the slot must hold a module.
            const std::vector<SlotModule> placed = slot_modules(f, d, [&] {
                std::vector<std::optional<uint32_t>> v(n + 1);
                v[n] = slot.default_module;
                return v;
            }());
            if (slot.min_instances > 0 || placed.empty() || placed[0].pdos.empty())
                best = slot.default_module;
        }
        out.modules[n] = best;
        explained.insert(best_indices.begin(), best_indices.end());
    }
    for (const auto& [index, entries] : eni)
        if (!explained.count(index)) {
            if (why)
                *why =
                    "line " + std::to_string(eni_line[index]) + ": PDO " + util::hex(index) +
                    " of the ENI is the PDO of no module its slots take (at that slot, with those entries)";
            return std::nullopt;
        }
    return out;
}

}  // namespace esi::eni
