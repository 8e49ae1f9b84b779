#include "drive/state_machine.hpp"

namespace drive {

DeviceCommand decode(uint16_t c, uint16_t prev) {
    if (c & cw::FaultReset) {
        // Fault reset is the rising edge; while bit 7 is held high no other command is decoded
        // (every command pattern of Table 3-7 has bit 7 = 0).
        return (prev & cw::FaultReset) ? DeviceCommand::None : DeviceCommand::FaultReset;
    }
    if (!(c & cw::EnableVoltage)) return DeviceCommand::DisableVoltage;  // 0xxx xx0x
    if (!(c & cw::QuickStop)) return DeviceCommand::QuickStop;           // 0xxx x01x
    if (!(c & cw::SwitchOn)) return DeviceCommand::Shutdown;             // 0xxx x110
    if (!(c & cw::EnableOperation)) return DeviceCommand::SwitchOn;      // 0xxx 0111
    return DeviceCommand::EnableOperation;                               // 0xxx 1111
}

Transition next(State s, DeviceCommand c) {
    using S = State;
    using C = DeviceCommand;
    switch (s) {
        case S::SwitchOnDisabled:
            if (c == C::Shutdown) return {S::ReadyToSwitchOn, 2};
            break;
        case S::ReadyToSwitchOn:
            if (c == C::SwitchOn) return {S::SwitchedOn, 3};
            // "Switch on + enable operation" from Ready: transition 3 now, 4 follows on the next evaluation.
            if (c == C::EnableOperation) return {S::SwitchedOn, 3};
            if (c == C::DisableVoltage || c == C::QuickStop) return {S::SwitchOnDisabled, 7};
            break;
        case S::SwitchedOn:
            if (c == C::EnableOperation) return {S::OperationEnabled, 4};
            if (c == C::Shutdown) return {S::ReadyToSwitchOn, 6};
            if (c == C::DisableVoltage || c == C::QuickStop) return {S::SwitchOnDisabled, 10};
            break;
        case S::OperationEnabled:
            if (c == C::SwitchOn) return {S::SwitchedOn, 5};
            if (c == C::Shutdown) return {S::ReadyToSwitchOn, 8};
            if (c == C::DisableVoltage) return {S::SwitchOnDisabled, 9};
            if (c == C::QuickStop) return {S::QuickStopActive, 11};
            break;
        case S::QuickStopActive:
            if (c == C::DisableVoltage) return {S::SwitchOnDisabled, 12};
            if (c == C::EnableOperation) return {S::OperationEnabled, 16};
            break;
        case S::Fault:
            if (c == C::FaultReset) return {S::SwitchOnDisabled, 15};
            break;
        case S::NotReadyToSwitchOn:
        case S::FaultReactionActive:
            break;
    }
    return {s, -1};
}

uint16_t state_bits(State s, bool power_on) {
    switch (s) {
        case State::NotReadyToSwitchOn:
            return 0x00;  // x000 0000
        case State::SwitchOnDisabled:
            return 0x40;  // x100 0000
        case State::ReadyToSwitchOn:
            return 0x21;  // x010 0001
        case State::SwitchedOn:
            return 0x23;  // x010 0011
        case State::OperationEnabled:
            return 0x37;  // x011 0111
        case State::QuickStopActive:
            return 0x17;  // x001 0111
        case State::FaultReactionActive:
            return power_on ? 0x1F : 0x0F;  // x001 1111 / x000 1111
        case State::Fault:
            return 0x08;  // x000 1000
    }
    return 0;
}

const char* to_string(State s) {
    switch (s) {
        case State::NotReadyToSwitchOn:
            return "Not Ready to Switch On";
        case State::SwitchOnDisabled:
            return "Switch On Disabled";
        case State::ReadyToSwitchOn:
            return "Ready to Switch On";
        case State::SwitchedOn:
            return "Switched On";
        case State::OperationEnabled:
            return "Operation Enabled";
        case State::QuickStopActive:
            return "Quick Stop Active";
        case State::FaultReactionActive:
            return "Fault Reaction Active";
        case State::Fault:
            return "Fault";
    }
    return "?";
}

}  // namespace drive
