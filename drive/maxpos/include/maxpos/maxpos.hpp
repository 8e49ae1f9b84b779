#pragma once
// The MAXPOS drive (maxon), the built-in product of softecat: its device description (identity, mailboxes,
// SyncManagers, DC modes, PDO rules and sets) and its object dictionary as the MAXPOS firmware
// specification, chapter 7, declares it, with the CiA 402 drive core (drive/) behind it. One device
// description among others: od/ is the generic object model, an ESI file gives other products.
//
// The dictionary is one table (src/maxpos.cpp), one row per object header or entry; a row that holds one of
// the drive's vendor parameters names it (drive::Param), and drive_objects() is made from those rows: a
// MAXPOS parameter is declared in one place.
// 0x1018, 0x1008, 0x1009, 0x100A and 0x2100 take their values from DeviceDescription::identity, so the SII,
// the ESI and CoE always agree.
#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include "drive/objects.hpp"
#include "od/device.hpp"
#include "od/dictionary.hpp"
#include "od/product.hpp"

namespace maxpos {

// The MAXPOS 50/5 with firmware 0120h, as the MAXPOS firmware specification gives or implies it (see
// docs/decisions/od.md).
od::DeviceDescription description();

// Places SM0/SM1 on the standard mailbox and SM2/SM3 after it (3 buffers of the largest PDO set each),
// with the control bytes of od::default_sm_control and the default process-data sizes. Throws
// std::out_of_range if the process-data areas would not fit below 0x10000.
void place_sync_managers(od::DeviceDescription& description);

// Every object and subindex of the drive, defaults as the specification gives them, identity from
// `description`. Validators wired here: the value lists the specification gives (sync modes of 0x1C32/0x1C33,
// 0x3000:02/03, modes of operation 0x6060, homing methods 0x6098, motor type 0x6402) answer InvalidValue
// otherwise. The dictionary is returned by value; Ref<T> handles taken afterwards stay valid across moves.
od::Dictionary dictionary(const od::DeviceDescription& description);

// The configuration file of `ecat-slave --config` (od/device_config.hpp) on top of description(); the
// SyncManagers placed again for the mailbox it sets. Throws od::ConfigError.
od::DeviceDescription load_config(const std::filesystem::path& path);
od::DeviceDescription parse_config(std::string_view text, const std::string& source = "<config>");

// The MAXPOS as a product: description() or, with a file, load_config(config_file); its dictionary; the CiA
// 402 drive. Throws od::ConfigError for a bad file.
od::Product product(const std::filesystem::path& config_file = {});

// Where the MAXPOS keeps the drive's vendor parameters (motor data 0x3001, encoder 0x3010, gains 0x30A0/
// 0x30A1, ...) and the objects it lets a master write only in "Power Disable" (§7.2.22-7.2.29,
// §7.2.78-7.2.80, §7.2.100): pass to drive::Drive and drive::commission for a MAXPOS dictionary.
const drive::VendorObjects& drive_objects();

// The modes of operation the MAXPOS accepts in 0x6060 (MAXPOS firmware specification §7.2.53, Table 7-123;
// 0x6502 = 0x000003A5): those of the drive core without profile torque and interpolated position.
inline constexpr std::array<int8_t, 6> kModesOfOperation{
    drive::modes::ProfilePosition,    drive::modes::ProfileVelocity,    drive::modes::Homing,
    drive::modes::CyclicSyncPosition, drive::modes::CyclicSyncVelocity, drive::modes::CyclicSyncTorque};

// 0x1C00:01..04: the communication type of SM0..SM3, in the order the device places them.
inline constexpr std::array<od::SmKind, 4> kSmCommunicationTypes{od::SmKind::MBoxOut, od::SmKind::MBoxIn,
                                                                 od::SmKind::Outputs, od::SmKind::Inputs};

// Capacity (bytes) of one 0x10F3 diagnosis message (OCTET_STRING, ETG.1020 layout: code, flags, text id,
// time stamp, parameters) and the number of messages the history holds (subindices 6...15).
constexpr uint16_t kDiagMessageBytes = 32;
constexpr uint8_t kDiagMaxMessages = 10;

// Objects named by index (whole objects).
namespace obj {
inline constexpr uint16_t SyncManagerCommunicationType = 0x1C00;
inline constexpr uint16_t SupportedHomingMethods = 0x60E3;
}  // namespace obj

}  // namespace maxpos
