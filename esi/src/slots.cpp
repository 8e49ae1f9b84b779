// The configuration of a modular device's slots (esi/slots.hpp).
#include "esi/slots.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <string>

namespace esi {
namespace {

std::string hex8(uint32_t v) {
    char b[16];
    std::snprintf(b, sizeof b, "0x%08X", static_cast<unsigned>(v));
    return b;
}

bool same_text(const std::string& a, const std::string& b) {
    return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
               return std::toupper(static_cast<unsigned char>(x)) ==
                      std::toupper(static_cast<unsigned char>(y));
           });
}

}  // namespace

std::vector<std::optional<uint32_t>> parse_module_list(const EsiFile& file, const EsiDevice& d,
                                                       const std::string& list) {
    std::vector<std::string> items;
    std::size_t from = 0;
    for (;;) {
        const std::size_t comma = list.find(',', from);
        std::string item = list.substr(from, comma == std::string::npos ? std::string::npos : comma - from);
        while (!item.empty() && std::isspace(static_cast<unsigned char>(item.back())))
            item.pop_back();
        while (!item.empty() && std::isspace(static_cast<unsigned char>(item.front())))
            item.erase(0, 1);
        items.push_back(std::move(item));
        if (comma == std::string::npos) break;
        from = comma + 1;
    }
    const std::string device = d.type_name + " " + hex8(d.product_code) + ":" + hex8(d.revision);
    if (d.slots.empty())
        throw InputError(file.source, d.line, device + " has no slots: no modules to choose");
    if (items.size() > d.slots.size())
        throw InputError(file.source, d.line,
                         std::to_string(items.size()) + " modules for the " + std::to_string(d.slots.size()) +
                             " slots of " + device);
    std::vector<std::optional<uint32_t>> out(d.slots.size());
    for (std::size_t n = 0; n < items.size(); ++n) {
        const std::string& item = items[n];
        if (item.empty() || item == "-") continue;  // an empty slot
        const EsiModule* m = nullptr;
        if (const auto ident = parse_esi_number(item)) m = file.module(static_cast<uint32_t>(*ident));
        for (std::size_t k = 0; m == nullptr && k < file.modules.size(); ++k)
            if (same_text(file.modules[k].type_name, item)) m = &file.modules[k];
        const EsiSlot& slot = d.slots[n];
        std::string offered;
        for (uint32_t ident : slot.module_idents) {
            const EsiModule* o = file.module(ident);
            offered += " " + (o != nullptr ? o->type_name + " (" + hex8(ident) + ")" : hex8(ident));
        }
        for (const EsiModuleClass& c : slot.module_classes)
            offered += " class " + c.class_name + (c.vendor_id ? " of vendor " + hex8(*c.vendor_id) : "");
        if (m == nullptr)
            throw InputError(file.source, slot.line,
                             "slot " + std::to_string(n + 1) + ": no module '" + item +
                                 "' in the file; the slot takes:" + offered);
        if (!slot_takes(file, slot, *m))
            throw InputError(file.source, slot.line,
                             "slot " + std::to_string(n + 1) + " does not take module " + m->type_name +
                                 "; it takes:" + offered);
        out[n] = m->ident;
    }
    return out;
}

bool slot_takes(const EsiFile& f, const EsiSlot& s, const EsiModule& m) {
    if (std::find(s.module_idents.begin(), s.module_idents.end(), m.ident) != s.module_idents.end())
        return true;
    if (m.module_class.empty()) return false;
    return std::any_of(s.module_classes.begin(), s.module_classes.end(), [&](const EsiModuleClass& c) {
        return c.class_name == m.module_class && (!c.vendor_id || *c.vendor_id == f.vendor_id);
    });
}

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
