// The configuration of a modular device's slots (esi/slots.hpp).
#include "esi/slots.hpp"

namespace esi {

std::vector<std::optional<uint32_t>> default_modules(const EsiDevice& d) {
    std::vector<std::optional<uint32_t>> out;
    for (const EsiSlot& slot : d.slots)
        out.push_back(slot.default_module);
    return out;
}

std::vector<SlotModule> default_slot_modules(const EsiFile& f, const EsiDevice& d) {
    return slot_modules(f, d, default_modules(d));
}

std::vector<SlotModule> slot_modules(const EsiFile& f, const EsiDevice& d,
                                     const std::vector<std::optional<uint32_t>>& modules) {
    std::vector<SlotModule> out;
    for (std::size_t n = 0; n < d.slots.size() && n < modules.size(); ++n) {
        const EsiSlot& slot = d.slots[n];
        if (!modules[n]) continue;
        SlotModule sm;
        sm.slot = n;
        sm.esi_slot = &slot;
        sm.ident = *modules[n];
        sm.module = f.module(sm.ident);
        if (sm.module != nullptr) {
            const uint32_t pdo_inc = slot.pdo_increment.value_or(d.slot_pdo_increment);
            const uint32_t idx_inc = slot.index_increment.value_or(d.slot_index_increment);
            for (const auto* list : {&sm.module->rxpdos, &sm.module->txpdos})
                for (const EsiPdo& p : *list) {
                    SlotPdo x{&p, static_cast<uint16_t>(p.index + (p.depend_on_slot ? n * pdo_inc : 0)),
                              p.entries};
                    for (EsiPdoEntry& e : x.entries)
                        if (e.depend_on_slot && e.index != 0)
                            e.index = static_cast<uint16_t>(e.index + n * idx_inc);
                    sm.pdos.push_back(std::move(x));
                }
            for (const auto& [index, o] : sm.module->objects)
                sm.objects.push_back(
                    {&o, static_cast<uint16_t>(index + (o.depend_on_slot ? n * idx_inc : 0))});
        }
        out.push_back(std::move(sm));
    }
    return out;
}

}  // namespace esi
