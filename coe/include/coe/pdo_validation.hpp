#pragma once
// PDO mapping and assignment (0x1C10 + n for SM n) checks, for the objects the object model declares as such
// (od::Object::direction: a PDO's direction is what its product says, wherever its index lies),
// installed as validators on the dictionary so SDO downloads, complete-access downloads and any other
// master-side write meet them. Entries are UINT32 index<<16 | subindex<<8 | bit length (index 0: a gap).
// Pre-Op-only writing comes from the entries' od access flags, not from here.
#include <cstddef>
#include <cstdint>

#include <span>

#include "od/device.hpp"
#include "od/dictionary.hpp"

namespace coe {

struct PdoLimits {
    // Largest process-data image one SyncManager may carry (SM2 outputs, SM3 inputs), in bytes. The default
    // is the room maxpos::place_sync_managers() leaves: 4 PDOs x 10 entries x 32 bits (MAXPOS firmware
    // specification §7.2.6-16).
    std::size_t max_sm_bytes = 160;
};

// Mapping entry check: Ok for 0, for a gap (index 0, or a dummy data-type object 0x0001-0x0007, subindex 0),
// or for an existing object mappable in that direction whose bit
// length matches; NotMappable otherwise.
od::Status check_mapping_entry(const od::Dictionary& dict, bool rx, uint32_t value);
// Bits a mapping object maps with its current count (subindex 0); 0 if the object does not exist.
std::size_t mapped_bits(const od::Dictionary& dict, uint16_t pdo);

// Installs the validators on every mapping object and every assignment object present (0x1C12/0x1C13, and
// the other process-data SMs' 0x1C10 + n). An assignment holds only mapping objects of its direction. The
// validators keep a pointer to dict: install after the dictionary has reached its final place.
void install_pdo_validators(od::Dictionary& dict, PdoLimits limits = {});
// The same, and the assignments also keep the ESI's PDO rules (od::DeviceDescription::pdo_rules): a count
// written to an assignment (or an entry within the count) that would assign two PDOs one of which Excludes
// the other, or leave out a Mandatory PDO of that SyncManager, is refused with
// Incompatible (0x06040043, "general parameter incompatibility"; docs/decisions/coe.md). The rules are
// copied.
void install_pdo_validators(od::Dictionary& dict, PdoLimits limits, std::span<const od::PdoRule> rules);
// The rule check alone: Ok, or Incompatible for the PDOs `assigned` to SyncManager assignment `assign`. The
// rules that apply are those of the PDOs of the assignment's direction (with several SMs of one direction:
// those its default holds), as `dict` declares them.
od::Status check_pdo_rules(const od::Dictionary& dict, uint16_t assign, std::span<const uint16_t> assigned,
                           std::span<const od::PdoRule> rules);

}  // namespace coe
