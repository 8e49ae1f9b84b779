#pragma once
// CiA 402 device control of one axis (IEC 61800-7-201 §6.2.2): the state of the power drive system, the
// power stage, the transition waiting for the drive to stop, the stop ramp and the fault reaction. The
// transitions themselves are decoded in state_machine.hpp; Axis (axis.hpp) runs them against its other parts.
#include <cstdint>

#include "drive/state_machine.hpp"

namespace drive {

enum class StopKind : uint8_t { None, Ramp, Disable };

struct DeviceControl {
    struct Pending {  // a transition waiting for the drive to stop
        bool active = false;
        State to = State::SwitchOnDisabled;
        int number = -1;
        int64_t since_ns = 0;
    };

    State state = State::NotReadyToSwitchOn;
    bool power = false;
    uint16_t cw_prev = 0;  // controlword of the previous cycle (mode bits)
    Pending pending;
    StopKind stop = StopKind::None;
    double stop_decel = 0;  // inc/s^2
    bool ramp_done = false;
    bool fra = false;  // fault reaction running
    bool fra_power_off = false;

    // Operation enabled and no transition waiting: the drive follows its set-points.
    bool operational() const { return state == State::OperationEnabled && !pending.active; }
};

}  // namespace drive
