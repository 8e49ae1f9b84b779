#pragma once
// The configuration of a modular device (ETG.2000 Slots, Modules): the module in each slot (its default, or
// as chosen), with its PDO and object indices moved by the slot's increments. No object model: the ESI ->
// od::Product direction (esi/device) and ecat-conform both take the expansion from here.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "esi/esi_reader.hpp"

namespace esi {

// A PDO of a slot's module: index with the slot's PDO increment, entries with its index increment.
struct SlotPdo {
    const EsiPdo* esi = nullptr;  // the module's PDO
    uint16_t index = 0;
    std::vector<EsiPdoEntry> entries;
};

// An object of a slot's module at its index with the slot's index increment.
struct SlotObject {
    const EsiObject* esi = nullptr;
    uint16_t index = 0;
};

struct SlotModule {
    std::size_t slot = 0;  // 0-based position in EsiDevice::slots
    const EsiSlot* esi_slot = nullptr;
    uint32_t ident = 0;                 // the module's ident (ModuleIdent)
    const EsiModule* module = nullptr;  // nullptr: the module is not in Descriptions/Modules
    std::vector<SlotPdo> pdos;          // the module's RxPDOs, then its TxPDOs
    std::vector<SlotObject> objects;    // in the module's index order
};

// Each slot of d that takes a module, in order: modules[n] is slot n's module ident (nullopt, or n past the
// end: the slot is empty). The pointers point into f and d.
std::vector<SlotModule> slot_modules(const EsiFile& f, const EsiDevice& d,
                                     const std::vector<std::optional<uint32_t>>& modules);
// Whether slot s of a device of f takes module m: m's ident is one the slot lists, or m's Type ModuleClass is
// a class the slot lists (and the class's VendorId, when given, is f's vendor).
bool slot_takes(const EsiFile& f, const EsiSlot& s, const EsiModule& m);
// The default configuration: each slot's default module (none in a slot that names classes).
std::vector<std::optional<uint32_t>> default_modules(const EsiDevice& d);
std::vector<SlotModule> default_slot_modules(const EsiFile& f, const EsiDevice& d);
// The modules a list names, one item per slot in order, comma-separated: a module's Type name (any case) or
// ModuleIdent (0x, #x or decimal) of a module the slot takes (slot_takes), "-" or nothing for an empty slot;
// slots past the list are empty
// ("EXM-DI8,-,EXM-AI2"; ecat-slave --device SPEC@LIST, ecat-conform --modules LIST). Throws InputError naming
// the file for a module the file lacks or the slot does not take, more items than slots, or a device
// without slots.
std::vector<std::optional<uint32_t>> parse_module_list(const EsiFile& f, const EsiDevice& d,
                                                       const std::string& list);

}  // namespace esi
