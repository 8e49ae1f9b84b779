#pragma once
// A device from its vendor's ESI file (ETG.2000 EtherCATInfo): the ESI -> object model direction. The ESI
// reader (esi/esi_reader.hpp, od-free) reads the file; this turns one of its devices into an od::Product:
// the description (identity, SyncManagers, FMMUs, mailbox and protocols, DC op modes, PDO rules and sets,
// EEPROM configuration), the dictionary builder (data types, objects, access, defaults, limits, enums, the
// PDO mapping and assignment objects), the device's own EEPROM image (Eeprom/Data) and the application
// (the CiA 402 drive core for a profile 402 device). Target `esi_device`. The decisions (what is an error,
// what a warning) are in docs/decisions/esi.md.
#include <optional>
#include <string>
#include <vector>

#include "esi/esi_reader.hpp"
#include "od/product.hpp"

namespace esi {

// Picks one device of a file. spec: "" (the file must hold exactly one device), "0xPRODUCT:0xREVISION",
// "0xPRODUCT" (one revision of it in the file; "#x" and decimal numbers too), or the Type text (one device
// of that Type). Throws InputError naming the file; when the spec matches none or several, the message
// lists the devices (type, product code, revision, name).
const EsiDevice& select_device(const EsiFile& file, const std::string& spec);

// One line per device of the file: "EXD1008 0x03F03052:0x00100000 EXD1008 8Ch. Dig. Input 24V, 3ms".
std::vector<std::string> list_devices(const EsiFile& file);

// The product of one device of an ESI file. Throws InputError ("FILE:LINE: message") for what cannot be
// served (an undefined data type an object or PDO needs, a PDO entry naming a subindex a VAR lacks, a
// default the type cannot hold, ...); what can be served despite a fault, or is declared but not emulated
// (EoE, SoE, AoE, VoE, module configurations other than the default), becomes a line of Product::warnings.
//
// A spec may end in "@MODULES", the module configuration of a modular device (ESI Slots/Modules): one item
// per slot in order, comma-separated, each a module's Type name (any case) or ModuleIdent (0x, #x or
// decimal),
// "-" or nothing for an empty slot; slots past the list are empty ("EXM9000@EXM-DI8,-,EXM-AI2"). A module the
// file lacks or the slot does not take, more items than slots, or modules for a device without slots are
// InputErrors naming the file. Without "@", each slot holds its default module.
od::Product load_product(const std::string& path, const std::string& spec);
od::Product load_product(const EsiFile& file, const std::string& spec);
od::Product load_product(const EsiFile& file, const EsiDevice& device);
// The product with the module of each slot given (nullopt: empty slot; slots past the vector are empty).
od::Product load_product(const EsiFile& file, const EsiDevice& device,
                         const std::vector<std::optional<uint32_t>>& modules);

}  // namespace esi
