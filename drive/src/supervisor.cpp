// Supervision and error handling: errors, their reactions, fault reset, following error, limits, standstill.
#include "drive/axis.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "axis_internal.hpp"
#include "drive/errors.hpp"

namespace drive {

using namespace detail;

void Axis::raise_error(uint16_t code) {
    fault(code, now_ns_);
}

void Axis::connection_lost() {
    // Only a drive that has power on its motor reacts: without power there is nothing to stop, and a master
    // that merely walks the ESM down after disabling the drive must not find a fault on its next start.
    if (!dc_.power) return;
    fault(error_code::EthercatStateMachine, now_ns_);
    update_feedback();
}

void Axis::fault(uint16_t code, int64_t now_ns) {
    const ErrorInfo* info = find_error(code);
    const uint8_t reg = info ? info->error_register : 0x01;
    const Reaction rx = info ? info->reaction : Reaction::Disable;
    const std::string_view name = info ? info->name : std::string_view("Unknown error");
    // Reaction "fault signal only": a warning (statusword bit 7), no state change.
    const int16_t option = rx == Reaction::FaultReactionCode     ? params.fault_reaction
                           : rx == Reaction::AbortConnectionCode ? params.abort_connection
                                                                 : 0;
    const bool signal_only = (rx == Reaction::FaultReactionCode && option == -1) ||
                             (rx == Reaction::AbortConnectionCode && option == 1);
    if (signal_only) {
        if (std::find(sup_.warnings.begin(), sup_.warnings.end(), code) == sup_.warnings.end()) {
            auto slot = std::find(sup_.warnings.begin(), sup_.warnings.end(), uint16_t{0});
            if (slot != sup_.warnings.end()) *slot = code;
            sink_->diag(Severity::Warning, code, name);
        }
        return;
    }
    if (error_active(code)) return;  // already active: no second emergency
    auto slot = std::find(sup_.active.begin(), sup_.active.end(), uint16_t{0});
    if (slot != sup_.active.end()) *slot = code;
    sup_.last_error = code;
    sup_.error_register |= reg;
    const std::array<uint8_t, 5> mfr{static_cast<uint8_t>(dc_.state), static_cast<uint8_t>(sp_.mode), 0, 0,
                                     0};
    sink_->raise(code, sup_.error_register, mfr);

    if (home_.status == HomingStatus::InProgress) home_.status = HomingStatus::Error;
    if (dc_.state == State::Fault) return;
    if (dc_.state == State::FaultReactionActive) {
        if (rx == Reaction::Disable) begin_stop(StopKind::Disable, 0, now_ns);
        return;
    }
    const bool was_powered = dc_.power;
    dc_.pending = {false, State::Fault, 14, now_ns};
    dc_.fra = true;
    if (!was_powered || rx == Reaction::Disable || option == 0 ||
        (rx == Reaction::AbortConnectionCode && option == 2)) {
        begin_stop(StopKind::Disable, 0, now_ns);
    } else if (rx == Reaction::FaultReactionCode && option == 1) {
        begin_stop(StopKind::Ramp, params.profile_deceleration, now_ns);
    } else {
        begin_stop(StopKind::Ramp, params.quick_stop_deceleration, now_ns);
    }
    enter(State::FaultReactionActive, 13);
    // Powerless and at rest already: the reaction is complete at once (transition 14).
    if (!was_powered && std::abs(ctl_.vel_avg_rpm) <= static_cast<double>(params.standstill_window)) {
        dc_.fra = false;
        dc_.stop = StopKind::None;
        enter(State::Fault, 14);
    }
}

bool Axis::cause_present(uint16_t code) const {
    switch (code) {
        case error_code::Sto:
            return (pins_ & 0x30) != 0x30;
        case error_code::TorqueFault:
            return ctl_.km <= 0;
        case error_code::MaxSpeed:
            return std::abs(ctl_.obs_vel) * 60.0 / kTwoPi > static_cast<double>(params.max_motor_speed);
        default:
            return false;
    }
}

void Axis::fault_reset() {
    for (uint16_t c : sup_.active) {
        if (c && cause_present(c)) {
            sink_->diag(Severity::Warning, c, "Fault reset refused: cause still present");
            return;
        }
    }
    for (auto& c : sup_.active) {
        if (!c) continue;
        const uint16_t code = c;
        c = 0;
        uint8_t reg = 0;
        for (uint16_t o : sup_.active)
            if (o) reg |= find_error(o) ? find_error(o)->error_register : 0x01;
        sup_.error_register = reg;
        sink_->clear(code, sup_.error_register);
    }
    for (auto& w : sup_.warnings) {
        if (w) sink_->clear(w, sup_.error_register);
        w = 0;
    }
    sup_.error_register = 0;
    sup_.last_error = 0;
    enter(State::SwitchOnDisabled, 15);
}

void Supervisor::standstill(double vel_avg_rpm, uint32_t window, uint16_t time_ms, int64_t dt_ns) {
    const bool in = window == kNoWindow || std::abs(vel_avg_rpm) <= static_cast<double>(window);
    if (in) {
        still_ms += static_cast<double>(dt_ns) * 1e-6;
        still = still_ms >= time_ms;
    } else {
        still_ms = 0;
        still = false;
    }
}

void Axis::supervise(int64_t now_ns, int64_t dt_ns) {
    sup_.standstill(ctl_.vel_avg_rpm, params.standstill_window, params.standstill_time, dt_ns);
    const bool enabled = dc_.state == State::OperationEnabled && dc_.power && !dc_.pending.active;
    const bool homing = sp_.mode == mode::Homing && home_.status == HomingStatus::InProgress;
    if (enabled) {
        // Following error (MAXPOS firmware specification §4.6): position-controlled modes.
        const bool pos_mode = sp_.mode == mode::CyclicSyncPosition || sp_.mode == mode::ProfilePosition ||
                              sp_.mode == mode::Homing;
        const double ferr = std::abs(sp_.demand_pos - static_cast<double>(count_));
        if (pos_mode && params.following_error_window != kNoWindow &&
            ferr > static_cast<double>(params.following_error_window)) {
            sup_.ferr_time_ms += static_cast<double>(dt_ns) * 1e-6;
            if (sup_.ferr_time_ms >= params.following_error_timeout)
                fault(error_code::FollowingError, now_ns);
        } else {
            sup_.ferr_time_ms = 0;
        }
    } else {
        sup_.ferr_time_ms = 0;
    }
    if (enabled && !homing) {
        const double v = sp_.control == Control::Torque ? ctl_.obs_vel * res_ / kTwoPi : sp_.demand_vel;
        // Limit switches: error when reaching one, or when driving further into it after a fault reset.
        const bool neg = func_ & 0x1, pos = func_ & 0x2;
        if (neg && v < -1e-6) fault(error_code::NegativeLimitSwitch, now_ns);
        if (pos && v > 1e-6) fault(error_code::PositiveLimitSwitch, now_ns);
        // Software position limits on the actual position (and the CSP target).
        const int64_t actual = count_ + shift_;
        const bool below =
            params.sw_limit_min != std::numeric_limits<int32_t>::min() && actual < params.sw_limit_min;
        const bool above =
            params.sw_limit_max != std::numeric_limits<int32_t>::max() && actual > params.sw_limit_max;
        // In PPM the limits clamp the demand instead (the target), so the actual position is not checked.
        const bool check_actual = sp_.mode != mode::ProfilePosition;
        if ((check_actual && ((below && v < 0) || (above && v > 0))) || sp_.csp_limit_violation)
            fault(error_code::SoftwarePositionLimit, now_ns);
    }
    if (dc_.power && std::abs(ctl_.obs_vel) * 60.0 / kTwoPi > static_cast<double>(params.max_motor_speed))
        fault(error_code::MaxSpeed, now_ns);
    if (dc_.power && (pins_ & 0x30) != 0x30) fault(error_code::Sto, now_ns);
    check_pending(now_ns);
}

}  // namespace drive
