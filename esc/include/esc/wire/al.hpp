#pragma once
// The AL (application layer) vocabulary of ETG.1000.6 §5.3: the AL states written to AL control (0x0120) and
// read from AL status (0x0130), and the AL status codes (0x0134, ETG.1000.6 Table 11) with their names.
// The ESC defines these registers, so the vocabulary lives with it: the ESC, the object model, the slave
// stack, the master and the tools all take it from here.
#include <cstdint>
#include <string_view>

namespace esc {

// EtherCAT AL states (AL control/status bits 3:0).
enum class AlState : uint8_t { Init = 0x01, PreOp = 0x02, Boot = 0x03, SafeOp = 0x04, Op = 0x08 };

// "INIT", "PREOP", "BOOT", "SAFEOP", "OP" for bits 3:0 of a state/status byte, "UNKNOWN" otherwise.
constexpr std::string_view al_state_name(uint8_t state) {
    switch (state & 0x0F) {
        case 0x01:
            return "INIT";
        case 0x02:
            return "PREOP";
        case 0x03:
            return "BOOT";
        case 0x04:
            return "SAFEOP";
        case 0x08:
            return "OP";
        default:
            return "UNKNOWN";
    }
}
constexpr std::string_view al_state_name(AlState s) {
    return al_state_name(static_cast<uint8_t>(s));
}

}  // namespace esc

// AL status codes (0x0134).
namespace esc::al {

constexpr uint16_t NoError = 0x0000;
constexpr uint16_t Unspecified = 0x0001;
constexpr uint16_t NoMemory = 0x0002;
constexpr uint16_t InvalidDeviceSetup = 0x0003;
constexpr uint16_t InvalidRevision = 0x0004;
constexpr uint16_t SiiMismatch = 0x0006;
constexpr uint16_t FirmwareUpdateFailed = 0x0007;
constexpr uint16_t LicenseError = 0x000E;
constexpr uint16_t InvalidStateChange = 0x0011;
constexpr uint16_t UnknownState = 0x0012;
constexpr uint16_t BootstrapNotSupported = 0x0013;
constexpr uint16_t NoValidFirmware = 0x0014;
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
constexpr uint16_t ExternalHardwareNotReady = 0x0052;
constexpr uint16_t RestartedLocally = 0x0060;
constexpr uint16_t DeviceIdUpdated = 0x0061;
constexpr uint16_t ModuleIdentMismatch = 0x0070;
constexpr uint16_t SupplyVoltageTooLow = 0x0080;
constexpr uint16_t SupplyVoltageTooHigh = 0x0081;
constexpr uint16_t TemperatureTooLow = 0x0082;
constexpr uint16_t TemperatureTooHigh = 0x0083;
constexpr uint16_t ApplicationControllerAvailable = 0x00F0;

// The name of an AL status code ("" for a code not in ETG.1000.6 Table 11; 0x8000..0xFFFF are vendor
// specific).
constexpr std::string_view status_text(uint16_t code) {
    switch (code) {
        case NoError:
            return "No error";
        case Unspecified:
            return "Unspecified error";
        case NoMemory:
            return "No memory";
        case InvalidDeviceSetup:
            return "Invalid device setup";
        case InvalidRevision:
            return "Invalid revision";
        case SiiMismatch:
            return "SII/EEPROM information does not match firmware";
        case FirmwareUpdateFailed:
            return "Firmware update not successful";
        case LicenseError:
            return "License error";
        case InvalidStateChange:
            return "Invalid requested state change";
        case UnknownState:
            return "Unknown requested state";
        case BootstrapNotSupported:
            return "Bootstrap not supported";
        case NoValidFirmware:
            return "No valid firmware";
        case InvalidMailboxConfigBoot:
            return "Invalid mailbox configuration (Bootstrap)";
        case InvalidMailboxConfigPreOp:
            return "Invalid mailbox configuration (PreOp)";
        case InvalidSmConfig:
            return "Invalid sync manager configuration";
        case NoValidInputs:
            return "No valid inputs available";
        case NoValidOutputs:
            return "No valid outputs";
        case SyncError:
            return "Synchronization error";
        case SmWatchdog:
            return "Sync manager watchdog";
        case InvalidSmTypes:
            return "Invalid sync manager types";
        case InvalidOutputConfig:
            return "Invalid output configuration";
        case InvalidInputConfig:
            return "Invalid input configuration";
        case InvalidWatchdogConfig:
            return "Invalid watchdog configuration";
        case NeedsColdStart:
            return "Slave needs cold start";
        case NeedsInit:
            return "Slave needs INIT";
        case NeedsPreOp:
            return "Slave needs PREOP";
        case NeedsSafeOp:
            return "Slave needs SAFEOP";
        case InvalidInputMapping:
            return "Invalid input mapping";
        case InvalidOutputMapping:
            return "Invalid output mapping";
        case InconsistentSettings:
            return "Inconsistent settings";
        case FreeRunNotSupported:
            return "FreeRun not supported";
        case SyncModeNotSupported:
            return "SyncMode not supported";
        case FreeRunNeeds3Buffer:
            return "FreeRun needs 3-buffer mode";
        case BackgroundWatchdog:
            return "Background watchdog";
        case NoValidInputsOutputs:
            return "No valid inputs and outputs";
        case FatalSyncError:
            return "Fatal sync error";
        case NoSyncError:
            return "No sync error";
        case CycleTimeTooSmall:
            return "Cycle time too small";
        case InvalidDcSyncConfig:
            return "Invalid DC SYNC configuration";
        case InvalidDcLatchConfig:
            return "Invalid DC latch configuration";
        case PllError:
            return "PLL error";
        case DcSyncIoError:
            return "DC sync I/O error";
        case DcSyncTimeout:
            return "DC sync timeout error";
        case DcInvalidSyncCycleTime:
            return "DC invalid sync cycle time";
        case DcSync0CycleTime:
            return "DC SYNC0 cycle time";
        case DcSync1CycleTime:
            return "DC SYNC1 cycle time";
        case MailboxAoe:
            return "Mailbox error AoE";
        case MailboxEoe:
            return "Mailbox error EoE";
        case MailboxCoe:
            return "Mailbox error CoE";
        case MailboxFoe:
            return "Mailbox error FoE";
        case MailboxSoe:
            return "Mailbox error SoE";
        case MailboxVoe:
            return "Mailbox error VoE";
        case EepromNoAccess:
            return "EEPROM no access";
        case EepromError:
            return "EEPROM error";
        case ExternalHardwareNotReady:
            return "External hardware not ready";
        case RestartedLocally:
            return "Slave restarted locally";
        case DeviceIdUpdated:
            return "Device identification value updated";
        case ModuleIdentMismatch:
            return "Detected module ident list does not match";
        case SupplyVoltageTooLow:
            return "Supply voltage too low";
        case SupplyVoltageTooHigh:
            return "Supply voltage too high";
        case TemperatureTooLow:
            return "Temperature too low";
        case TemperatureTooHigh:
            return "Temperature too high";
        case ApplicationControllerAvailable:
            return "Application controller available";
        default:
            return "";
    }
}

}  // namespace esc::al
