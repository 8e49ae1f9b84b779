#include "ecat/al_status.hpp"

namespace ecat::al {

std::string_view name(uint16_t code) {
    switch (code) {
        case NoError:
            return "No error";
        case Unspecified:
            return "Unspecified error";
        case NoMemory:
            return "No memory";
        case InvalidDeviceSetup:
            return "Invalid device setup";
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
            return "Invalid SyncManager configuration";
        case NoValidInputs:
            return "No valid inputs available";
        case NoValidOutputs:
            return "No valid outputs";
        case SyncError:
            return "Synchronization error";
        case SmWatchdog:
            return "SyncManager watchdog";
        case InvalidSmTypes:
            return "Invalid SyncManager types";
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
            return "Mailbox AoE";
        case MailboxEoe:
            return "Mailbox EoE";
        case MailboxCoe:
            return "Mailbox CoE";
        case MailboxFoe:
            return "Mailbox FoE";
        case MailboxSoe:
            return "Mailbox SoE";
        case MailboxVoe:
            return "Mailbox VoE";
        case EepromNoAccess:
            return "EEPROM no access";
        case EepromError:
            return "EEPROM error";
        case RestartedLocally:
            return "Slave restarted locally";
        case DeviceIdUpdated:
            return "Device identification value updated";
        default:
            return "";
    }
}

}  // namespace ecat::al
