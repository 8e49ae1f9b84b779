#pragma once
// AL status codes written to 0x0134 (ethercat-protocol.md §6.3).
#include <cstdint>
#include <string_view>

namespace ecat::al {

constexpr uint16_t NoError = 0x0000;
constexpr uint16_t Unspecified = 0x0001;
constexpr uint16_t NoMemory = 0x0002;
constexpr uint16_t InvalidDeviceSetup = 0x0003;
constexpr uint16_t NoValidFirmware = 0x0014;
constexpr uint16_t InvalidStateChange = 0x0011;
constexpr uint16_t UnknownState = 0x0012;
constexpr uint16_t BootstrapNotSupported = 0x0013;
constexpr uint16_t InvalidMailboxConfigBoot = 0x0015;
constexpr uint16_t InvalidMailboxConfigPreOp = 0x0016;
constexpr uint16_t InvalidSmConfig = 0x0017;
constexpr uint16_t NoValidInputs = 0x0018;
constexpr uint16_t NoValidOutputs = 0x0019;
constexpr uint16_t SyncError = 0x001A;
constexpr uint16_t SmWatchdog = 0x001B;
constexpr uint16_t InvalidSmTypes = 0x001C;
constexpr uint16_t InvalidOutputConfig = 0x001D;
constexpr uint16_t InvalidInputConfig = 0x001E;
constexpr uint16_t InvalidWatchdogConfig = 0x001F;
constexpr uint16_t NeedsColdStart = 0x0020;
constexpr uint16_t NeedsInit = 0x0021;
constexpr uint16_t NeedsPreOp = 0x0022;
constexpr uint16_t NeedsSafeOp = 0x0023;
constexpr uint16_t InvalidInputMapping = 0x0024;
constexpr uint16_t InvalidOutputMapping = 0x0025;
constexpr uint16_t InconsistentSettings = 0x0026;
constexpr uint16_t FreeRunNotSupported = 0x0027;
constexpr uint16_t SyncModeNotSupported = 0x0028;
constexpr uint16_t FreeRunNeeds3Buffer = 0x0029;
constexpr uint16_t BackgroundWatchdog = 0x002A;
constexpr uint16_t NoValidInputsOutputs = 0x002B;
constexpr uint16_t FatalSyncError = 0x002C;
constexpr uint16_t NoSyncError = 0x002D;
constexpr uint16_t CycleTimeTooSmall = 0x002E;
constexpr uint16_t InvalidDcSyncConfig = 0x0030;
constexpr uint16_t InvalidDcLatchConfig = 0x0031;
constexpr uint16_t PllError = 0x0032;
constexpr uint16_t DcSyncIoError = 0x0033;
constexpr uint16_t DcSyncTimeout = 0x0034;
constexpr uint16_t DcInvalidSyncCycleTime = 0x0035;
constexpr uint16_t DcSync0CycleTime = 0x0036;
constexpr uint16_t DcSync1CycleTime = 0x0037;
constexpr uint16_t MailboxAoe = 0x0041;
constexpr uint16_t MailboxEoe = 0x0042;
constexpr uint16_t MailboxCoe = 0x0043;
constexpr uint16_t MailboxFoe = 0x0044;
constexpr uint16_t MailboxSoe = 0x0045;
constexpr uint16_t MailboxVoe = 0x004F;
constexpr uint16_t EepromNoAccess = 0x0050;
constexpr uint16_t EepromError = 0x0051;
constexpr uint16_t RestartedLocally = 0x0060;
constexpr uint16_t DeviceIdUpdated = 0x0061;

// Human-readable name ("" for codes this stack does not know).
std::string_view name(uint16_t code);

}  // namespace ecat::al
