// CiA 402 device control: the transitions of IEC 61800-7-201 §6.2.2 and the stop they wait for
// (DeviceControl).
#include "drive/axis.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "axis_internal.hpp"
#include "drive/errors.hpp"

namespace drive {

using namespace detail;

void Axis::enter(State s, int number) {
    if (s == dc_.state) return;
    dc_.state = s;
    (void)number;
    sink_->diag(Severity::Info, 0, to_string(s));
}

void Axis::begin_stop(StopKind kind, double decel_rpm_s, int64_t) {
    dc_.stop = kind;
    dc_.ramp_done = false;
    // A stop (quick stop, shutdown, fault) ends a running homing: interrupted, to be started again.
    home_.interrupt(HomingPhase::Finished);
    if (kind == StopKind::Ramp) {
        dc_.stop_decel = decel_limit(decel_rpm_s);
        // The ramp starts where the motor really is (position and speed), whatever the set-points did.
        sp_.profile.reset(static_cast<double>(count_), ctl_.obs_vel * res_ / kTwoPi);
        sp_.control = Control::Position;
    } else if (kind == StopKind::Disable) {
        dc_.power = false;
        dc_.ramp_done = true;
    }
}

void Axis::device_control(int64_t now_ns) {
    const uint16_t c = command.controlword;
    DeviceCommand dc = decode(c, dc_.cw_prev);
    if ((dc == DeviceCommand::QuickStop && dc_.state == State::OperationEnabled &&
         faults.quick_stop_ignored) ||
        (dc == DeviceCommand::FaultReset && faults.fault_reset_ignored))
        dc = DeviceCommand::None;
    if (dc_.pending.active || dc_.state == State::FaultReactionActive) return;  // one command completes first
    if (dc == DeviceCommand::FaultReset && dc_.state != State::Fault) {
        // A fault reset outside Fault acknowledges warnings ("fault signal only" reactions).
        for (auto& w : sup_.warnings) {
            if (w) sink_->clear(w, sup_.error_register);
            w = 0;
        }
        return;
    }
    for (int pass = 0; pass < 2; ++pass) {
        const Transition t = next(dc_.state, dc);
        if (t.number < 0) return;
        switch (t.number) {
            case 2:
            case 3:
            case 6:
            case 7:
            case 10:
                enter(t.to, t.number);
                break;
            case 4: {
                if (ctl_.km <= 0) {
                    fault(error_code::TorqueFault, now_ns);
                    return;
                }
                if ((pins_ & 0x30) != 0x30) {
                    fault(error_code::Sto, now_ns);
                    return;
                }
                dc_.power = true;
                dc_.stop = StopKind::None;
                ctl_.vel_int = ctl_.cur_int = 0;
                sp_.demand_pos = static_cast<double>(count_);
                sp_.demand_vel = sp_.demand_acc = 0;
                sp_.profile.reset(sp_.demand_pos, 0);
                sp_.hold(sp_.demand_pos);
                enter(State::OperationEnabled, 4);
                break;
            }
            case 5:
            case 8: {
                const int16_t code = t.number == 5 ? params.disable_operation : params.shutdown;
                if (code == 1)
                    begin_stop(StopKind::Ramp, params.profile_deceleration, now_ns);
                else
                    begin_stop(StopKind::Disable, 0, now_ns);
                dc_.pending = {true, t.to, t.number, now_ns};
                break;
            }
            case 9:
            case 12:
                begin_stop(StopKind::Disable, 0, now_ns);
                dc_.pending = {true, t.to, t.number, now_ns};
                break;
            case 11:
                // 0x605A = 6 (the only value the MAXPOS firmware specification allows): quick-stop ramp, stay
                // in Quick Stop Active.
                begin_stop(StopKind::Ramp, params.quick_stop_deceleration, now_ns);
                enter(State::QuickStopActive, 11);
                break;
            case 15:
                fault_reset();
                break;
            case 16:
                dc_.stop = StopKind::None;
                sp_.demand_pos = sp_.profile.position();
                sp_.demand_vel = 0;
                sp_.hold(sp_.demand_pos);
                enter(State::OperationEnabled, 16);
                break;
            default:
                break;
        }
        // "Switch on + enable operation" from Ready to Switch On: transition 3, then 4 automatically.
        if (!(t.number == 3 && dc == DeviceCommand::EnableOperation)) return;
    }
}

void Axis::check_pending(int64_t now_ns) {
    if (!dc_.pending.active && !dc_.fra) return;
    if (dc_.stop == StopKind::Ramp && !dc_.ramp_done) return;
    dc_.power = false;  // the ramp (if any) is over: power stage off
    const bool detection_off = params.standstill_window == kNoWindow;
    const int64_t since = dc_.pending.active ? dc_.pending.since_ns : dc_.pending.since_ns;
    const bool timeout = params.standstill_timeout != 0xFFFF &&
                         now_ns - since >= static_cast<int64_t>(params.standstill_timeout) * 1000000;
    if (!(sup_.still || detection_off || timeout)) return;
    dc_.stop = StopKind::None;
    if (dc_.fra) {
        dc_.fra = false;
        dc_.pending.active = false;
        enter(State::Fault, 14);
    } else {
        dc_.pending.active = false;
        enter(dc_.pending.to, dc_.pending.number);
    }
}

}  // namespace drive
