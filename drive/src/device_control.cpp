// CiA 402 device control: the transitions of IEC 61800-7-201 §6.2.2 and the stop they wait for
// (DeviceControl).
#include "drive/device_control.hpp"

#include <cstdlib>

namespace drive {

void DeviceControl::enter(State s, EventSink& sink) {
    if (s == state_) return;
    state_ = s;
    sink.diag(Severity::Info, 0, to_string(s));
}

void DeviceControl::begin_stop(StopKind kind, double decel_rpm_s, Parts& parts) {
    // A deceleration of 0 is no ramp at all (it would never stop): vendors' ESIs ship 0x6084/0x6085 = 0 where
    // the device's own tuning sets it (Synapticon, Novanta). The drive then stops as fast as it can: at the
    // current limit.
    if (kind == StopKind::Ramp && decel_rpm_s <= 0) kind = StopKind::Limit;
    stop_ = kind;
    ramp_done_ = false;
    const double decel = parts.stopping(kind, decel_rpm_s);
    if (kind == StopKind::Ramp || kind == StopKind::Limit) {
        stop_decel_ = decel;
    } else if (kind == StopKind::Disable) {
        power_ = false;
        ramp_done_ = true;
    }
}

void DeviceControl::command(uint16_t c, const AxisFaults& faults, const Options& o, Parts& parts,
                            EventSink& sink, int64_t now_ns) {
    DeviceCommand dc = decode(c, cw_prev_);
    if ((dc == DeviceCommand::QuickStop && state_ == State::OperationEnabled && faults.quick_stop_ignored) ||
        (dc == DeviceCommand::FaultReset && faults.fault_reset_ignored))
        dc = DeviceCommand::None;
    if (pending_.active || state_ == State::FaultReactionActive) return;  // one command completes first
    if (dc == DeviceCommand::FaultReset && state_ != State::Fault) {
        // A fault reset outside Fault acknowledges warnings ("fault signal only" reactions).
        parts.acknowledge_warnings();
        return;
    }
    for (int pass = 0; pass < 2; ++pass) {
        const Transition t = next(state_, dc);
        if (t.number < 0) return;
        switch (t.number) {
            case 2:
            case 3:
            case 6:
            case 7:
            case 10:
                enter(t.to, sink);
                break;
            case 4: {
                if (const uint16_t refused = parts.enable_refused()) {
                    parts.fault(refused);
                    return;
                }
                power_ = true;
                stop_ = StopKind::None;
                parts.powered();
                enter(State::OperationEnabled, sink);
                break;
            }
            case 5:
            case 8: {
                const int16_t code = t.number == 5 ? o.disable_operation : o.shutdown;
                if (code == 1)
                    begin_stop(StopKind::Ramp, o.profile_deceleration, parts);
                else
                    begin_stop(StopKind::Disable, 0, parts);
                pending_ = {true, t.to, t.number, now_ns};
                break;
            }
            case 9:
            case 12:
                begin_stop(StopKind::Disable, 0, parts);
                pending_ = {true, t.to, t.number, now_ns};
                break;
            case 11: {
                // 0x605A (IEC 61800-7-201): 0 disable the drive function; 1/5 slow down on the slow-down ramp
                // (0x6084), 2/6 on the quick stop ramp (0x6085), 3/4/7/8 on the current or voltage limit
                // (both the current limit here, see docs/decisions/drive.md). 0...4 then go on to Switch On
                // Disabled (transition 12 once stopped), 5...8 stay in Quick Stop Active. A
                // manufacturer-specific code
                // (< 0) stops on the quick stop ramp and stays. The MAXPOS allows only 6.
                const int16_t code = o.quick_stop;
                if (code == 0)
                    begin_stop(StopKind::Disable, 0, parts);
                else if (code == 1 || code == 5)
                    begin_stop(StopKind::Ramp, o.profile_deceleration, parts);
                else if (code == 3 || code == 4 || code == 7 || code == 8)
                    begin_stop(StopKind::Limit, 0, parts);
                else
                    begin_stop(StopKind::Ramp, o.quick_stop_deceleration, parts);
                enter(State::QuickStopActive, sink);
                if (code >= 0 && code <= 4) pending_ = {true, State::SwitchOnDisabled, 12, now_ns};
                break;
            }
            case 15:
                if (parts.fault_reset()) enter(State::SwitchOnDisabled, sink);
                break;
            case 16:
                stop_ = StopKind::None;
                parts.resumed();
                enter(State::OperationEnabled, sink);
                break;
            default:
                break;
        }
        // "Switch on + enable operation" from Ready to Switch On: transition 3, then 4 automatically.
        if (!(t.number == 3 && dc == DeviceCommand::EnableOperation)) return;
    }
}

void DeviceControl::react(Reaction rx, int16_t option, bool at_rest, const Options& o, Parts& parts,
                          EventSink& sink, int64_t now_ns) {
    if (state_ == State::Fault) return;
    if (state_ == State::FaultReactionActive) {
        if (rx == Reaction::Disable) begin_stop(StopKind::Disable, 0, parts);
        return;
    }
    const bool was_powered = power_;
    pending_ = {false, State::Fault, 14, now_ns};
    fra_ = true;
    if (!was_powered || rx == Reaction::Disable || option == 0 ||
        (rx == Reaction::AbortConnectionCode && option == 2)) {
        begin_stop(StopKind::Disable, 0, parts);
    } else if (rx == Reaction::FaultReactionCode && option == 1) {
        begin_stop(StopKind::Ramp, o.profile_deceleration, parts);
    } else if (rx == Reaction::FaultReactionCode && (option == 3 || option == 4)) {
        begin_stop(StopKind::Limit, 0, parts);  // 0x605E 3/4: at the current (voltage) limit
    } else {
        begin_stop(StopKind::Ramp, o.quick_stop_deceleration, parts);
    }
    enter(State::FaultReactionActive, sink);
    // Powerless and at rest already: the reaction is complete at once (transition 14).
    if (!was_powered && at_rest) {
        fra_ = false;
        stop_ = StopKind::None;
        enter(State::Fault, sink);
    }
}

void DeviceControl::settle(bool still, uint32_t standstill_window, uint16_t standstill_timeout_ms,
                           EventSink& sink, int64_t now_ns) {
    if (!pending_.active && !fra_) return;
    if ((stop_ == StopKind::Ramp || stop_ == StopKind::Limit) && !ramp_done_) return;
    power_ = false;  // the ramp (if any) is over: power stage off
    const bool detection_off = standstill_window == 0xFFFFFFFFu;
    const bool timeout = standstill_timeout_ms != 0xFFFF &&
                         now_ns - pending_.since_ns >= static_cast<int64_t>(standstill_timeout_ms) * 1000000;
    if (!(still || detection_off || timeout)) return;
    stop_ = StopKind::None;
    pending_.active = false;
    if (fra_) {
        fra_ = false;
        enter(State::Fault, sink);
    } else {
        enter(pending_.to, sink);
    }
}

}  // namespace drive
