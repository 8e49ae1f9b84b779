#pragma once
// The drive's object dictionary as the MAXPOS firmware specification (maxon), chapter 7, declares it,
// and the device description (identity, mailboxes, SyncManagers, DC modes) that goes with it.
// 0x1018, 0x1008, 0x1009, 0x100A and 0x2100 take their values from DeviceDescription::identity, so the SII,
// the ESI and CoE always agree.
#include "od/device.hpp"
#include "od/dictionary.hpp"

namespace od {

// The MAXPOS 50/5 with firmware 0120h, as the MAXPOS firmware specification gives or implies it (see
// docs/decisions/od.md).
DeviceDescription default_drive_description();

// Places SM0/SM1 on the standard mailbox and SM2/SM3 after it (3 buffers of the largest PDO set each),
// with the control bytes of od::default_sm_control and the default process-data sizes. Throws
// std::out_of_range if the process-data areas would not fit below 0x10000.
void place_sync_managers(DeviceDescription& description);

// Every object and subindex of the drive, defaults as the specification gives them, identity from
// `description`. Validators wired here: the value lists the specification gives (sync modes of 0x1C32/0x1C33,
// 0x3000:02/03, modes of operation 0x6060, homing methods 0x6098, motor type 0x6402) answer InvalidValue
// otherwise. The dictionary is returned by value; Ref<T> handles taken afterwards stay valid across moves.
Dictionary make_drive_dictionary(const DeviceDescription& description);

// Signatures of the store (0x1010 / 0x2110) and restore (0x1011 / 0x2111) objects.
constexpr uint32_t kSignatureSave = 0x65766173;  // "save", little-endian
constexpr uint32_t kSignatureLoad = 0x64616F6C;  // "load", little-endian

// Capacity (bytes) of one 0x10F3 diagnosis message (OCTET_STRING, ETG.1020 layout: code, flags, text id,
// time stamp, parameters) and the number of messages the history holds (subindices 6...15).
constexpr uint16_t kDiagMessageBytes = 32;
constexpr uint8_t kDiagMaxMessages = 10;

}  // namespace od
