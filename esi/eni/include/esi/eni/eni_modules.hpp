#pragma once
// The module configuration an ENI slave was configured with, for a modular device served from its ESI
// (ETG.2000 Slots/Modules). An ENI carries no module list of its own: a configuration tool writes the modules
// it configured into the ENI as the slave's PDOs (each module's PDOs at its slot's indices), and, for a
// device that asks for it (ETG.5001.1 Slots DownloadModuleIdentList), as the CoE init command that writes
// the configured module ident list 0xF030. A device served with its default modules while the master was
// configured with others gets SyncManager lengths and PDO contents it does not have, and never reaches Op.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "esi/eni/eni_reader.hpp"
#include "esi/esi_reader.hpp"

namespace esi::eni {

struct EniModules {
    std::vector<std::optional<uint32_t>> modules;  // one per slot of the device, nullopt: empty
    std::string how;                               // "0xF030 init command" or "its PDOs"
};

// The modules of slave's device d (of f) as the ENI slave configures them:
//  1. the data of a CoE init command that downloads 0xF030 (complete access, or subindex by subindex): slot
//     n holds the module ident of subindex n+1 (0: empty), when every ident is a module of f the slot takes;
//  2. else, slot by slot in order, the module whose PDOs at the slot's indices are PDOs of the ENI slave with
//     the same entries (index, subindex, bit length), the slot's default module first; a slot none of whose
//     modules has such PDOs stays empty (a module without PDOs is the default one, or is left out); the
//     result must account for every PDO of the ENI slave that the device itself does not declare.
// nullopt for a device without slots, or with *why (when given) set to what did not match: the caller
// serves the default modules and says so.
std::optional<EniModules> modules_from_eni(const EsiFile& f, const EsiDevice& d, const Slave& slave,
                                           std::string* why = nullptr);

// What the master configured that device d of f with these modules (one per slot; none for a device without
// slots) does not have, one line per PDO of the ENI slave: a PDO the device does not declare, or a Fixed PDO
// of the device whose entries differ from the ENI's (a PDO the master may map, it maps by its CoE init
// commands), with the ENI's line of that PDO. Empty: the device is what the master was configured for.
struct PdoMismatch {
    int line = 0;
    std::string what;
};
std::vector<PdoMismatch> pdo_mismatches(const EsiFile& f, const EsiDevice& d,
                                        const std::vector<std::optional<uint32_t>>& modules,
                                        const Slave& slave);

}  // namespace esi::eni
