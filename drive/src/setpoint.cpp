// Set-point generation: mode switching, the profile modes and the cyclic synchronous modes
// (SetpointGenerator).
#include "drive/axis.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "axis_internal.hpp"
#include "drive/errors.hpp"

namespace drive {

using namespace detail;

bool mode::supported(int8_t m) {
    return od::contains(od::kModesOfOperation, m);
}

void Axis::switch_mode(int8_t m) {
    // On-the-fly switching: the new mode takes over from the current demand without a jump.
    if (sp_.mode == mode::Homing && home_.status == HomingStatus::InProgress)
        home_.status = HomingStatus::Interrupted;
    sp_.mode = m;
    const double from = dc_.power ? sp_.demand_pos : static_cast<double>(count_);
    sp_.profile.reset(from, dc_.power ? sp_.demand_vel : 0.0);
    sp_.hold(from);
    sp_.ppm_ack = false;
    ctl_.vel_ref = dc_.power ? ctl_.vel_ref : 0.0;
    if (m == mode::Homing && home_.status != HomingStatus::Done) home_.status = HomingStatus::Idle;
}

void Axis::mode_commands(int64_t now_ns, int64_t dt_ns) {
    const uint16_t c = command.controlword;
    const bool rise4 = (c & cw::NewSetpoint) && !(dc_.cw_prev & cw::NewSetpoint);
    const bool fall4 = !(c & cw::NewSetpoint) && (dc_.cw_prev & cw::NewSetpoint);
    const bool enabled =
        dc_.state == State::OperationEnabled && !dc_.pending.active && dc_.stop == StopKind::None;
    sp_.halted = (c & cw::Halt) != 0 && (sp_.mode == mode::ProfilePosition ||
                                         sp_.mode == mode::ProfileVelocity || sp_.mode == mode::Homing);
    switch (sp_.mode) {
        case mode::ProfilePosition: {
            if (rise4 && enabled) {
                const bool rel = c & cw::Relative;
                const bool immediate = c & cw::ChangeImmediately;
                if (immediate || !sp_.ppm_moving) {
                    double t = rel          ? sp_.demand_pos + command.target_position
                               : range_on() ? unwrap(command.target_position, sp_.demand_pos)
                                            : static_cast<double>(command.target_position) -
                                                  static_cast<double>(shift_);
                    // Software position limits act on the demand: clamp the target (internal limit bit).
                    const double lo = params.sw_limit_min == std::numeric_limits<int32_t>::min()
                                          ? -INFINITY
                                          : static_cast<double>(params.sw_limit_min) - shift_;
                    const double hi = params.sw_limit_max == std::numeric_limits<int32_t>::max()
                                          ? INFINITY
                                          : static_cast<double>(params.sw_limit_max) - shift_;
                    sp_.ppm_limited = t < lo || t > hi;
                    sp_.ppm_target = std::clamp(t, lo, hi);
                    sp_.ppm_moving = true;
                    sp_.ppm_buffered = false;
                    if (!immediate) sp_.profile.reset(sp_.demand_pos, sp_.demand_vel);
                } else {
                    sp_.ppm_buffered = true;
                    sp_.ppm_next_rel = rel;
                    sp_.ppm_next_raw = command.target_position;
                }
                sp_.ppm_ack = true;
            }
            if (!(c & cw::NewSetpoint) && !sp_.ppm_buffered) sp_.ppm_ack = false;
            break;
        }
        case mode::Homing:
            if (rise4 && enabled) {
                homing_start();
            } else if (rise4 && !dc_.power && params.homing_method == 37 && dc_.state != State::Fault &&
                       dc_.state != State::FaultReactionActive) {
                // Method 37 while disabled: no offset move, the actual position becomes the home position
                // (MAXPOS firmware specification §4.5.3.11).
                home_.method = 37;
                home_.ref = static_cast<double>(count_);
                shift_ = static_cast<int64_t>(params.home_position) - count_;
                home_.status = HomingStatus::Done;
                home_.phase = HomingPhase::Finished;
                home_.referenced = true;
                sink_->diag(Severity::Info, 0, "Homing attained");
            }
            if (fall4) home_.interrupt(HomingPhase::Stopping);
            break;
        case mode::CyclicSyncPosition: {
            // New target each cycle, interpolated linearly over the interpolation period (= this cycle when
            // 0x60C2 is set, as MAXPOS sets it to the SYNC0 cycle; 0 = no interpolation).
            const int64_t tgt = static_cast<int64_t>(command.target_position) + command.position_offset;
            const double t_raw =
                range_on() ? unwrap(static_cast<int32_t>(tgt), sp_.ip_to) : static_cast<double>(tgt - shift_);
            const double now_val =
                sp_.ip_period > 0
                    ? sp_.ip_from + (sp_.ip_to - sp_.ip_from) *
                                        std::min(1.0, static_cast<double>(now_ns - sp_.ip_t0) / sp_.ip_period)
                    : sp_.ip_to;
            sp_.ip_from = now_val;
            sp_.ip_to = t_raw;
            sp_.ip_t0 = now_ns;
            sp_.ip_period = params.interpolation_value != 0 ? dt_ns : 0;
            const bool lim_lo =
                params.sw_limit_min != std::numeric_limits<int32_t>::min() && tgt < params.sw_limit_min;
            const bool lim_hi =
                params.sw_limit_max != std::numeric_limits<int32_t>::max() && tgt > params.sw_limit_max;
            sp_.csp_limit_violation = enabled && (lim_lo || lim_hi);
            break;
        }
        default:
            break;
    }
}

void Axis::trajectory_tick(int64_t t_ns) {
    const double h = kPosH;
    ctl_.vel_ff = 0;
    ctl_.torque_ff_a = 0;
    const double rated_a = params.nominal_current * 1e-3;  // rated torque / km
    if (!dc_.power) {
        sp_.control = Control::Position;
        sp_.demand_pos = static_cast<double>(count_);
        sp_.demand_vel = sp_.demand_acc = 0;
        sp_.profile.reset(sp_.demand_pos, 0);
        return;
    }
    auto from_profile = [&] {
        sp_.demand_pos = sp_.profile.position();
        sp_.demand_vel = sp_.profile.velocity();
        sp_.demand_acc = sp_.profile.acceleration();
        sp_.control = Control::Position;
    };
    if (dc_.stop == StopKind::Ramp) {
        dc_.ramp_done = sp_.profile.step_velocity(0.0, dc_.stop_decel, dc_.stop_decel, h) || dc_.ramp_done;
        from_profile();
        return;
    }
    const double acc = decel_limit(params.profile_acceleration);
    const double dec = decel_limit(params.profile_deceleration);
    const double qs = decel_limit(params.quick_stop_deceleration);
    const double vmax = rpm_to_inc_s(std::min(params.profile_velocity, params.max_profile_velocity));
    switch (sp_.mode) {
        case mode::CyclicSyncPosition: {
            const double f = sp_.ip_period > 0
                                 ? std::min(1.0, static_cast<double>(t_ns - sp_.ip_t0) / sp_.ip_period)
                                 : 1.0;
            const double p = sp_.ip_from + (sp_.ip_to - sp_.ip_from) * f;
            sp_.demand_vel = (p - sp_.demand_pos) / h;
            sp_.demand_acc = 0;
            sp_.demand_pos = p;
            ctl_.vel_ff = kTwoPi * command.velocity_offset / 60.0;
            ctl_.torque_ff_a = command.torque_offset * 1e-3 * rated_a;
            sp_.control = Control::Position;
            sp_.profile.reset(sp_.demand_pos, sp_.demand_vel);
            return;
        }
        case mode::CyclicSyncVelocity: {
            const double vmot = static_cast<double>(params.max_motor_speed);
            const double v = std::clamp(
                static_cast<double>(command.target_velocity) + command.velocity_offset, -vmot, vmot);
            sp_.control = Control::Velocity;
            ctl_.vel_ref = kTwoPi * v / 60.0;
            sp_.demand_vel = rpm_to_inc_s(v);
            sp_.demand_pos = static_cast<double>(count_);
            ctl_.torque_ff_a = command.torque_offset * 1e-3 * rated_a;
            sp_.profile.reset(sp_.demand_pos, sp_.demand_vel);
            return;
        }
        case mode::CyclicSyncTorque: {
            sp_.control = Control::Torque;
            const double permille = static_cast<double>(command.target_torque) + command.torque_offset;
            ctl_.cur_ref = permille * 1e-3 * rated_a;
            sp_.demand_pos = static_cast<double>(count_);
            sp_.demand_vel = ctl_.obs_vel * res_ / kTwoPi;
            sp_.profile.reset(sp_.demand_pos, sp_.demand_vel);
            return;
        }
        case mode::ProfilePosition:
            if (sp_.halted) {
                sp_.profile.step_velocity(0.0, qs, qs, h);
            } else if (sp_.ppm_moving) {
                if (sp_.profile.step_position(sp_.ppm_target, vmax, acc, dec, h)) {
                    sp_.ppm_moving = false;
                    if (sp_.ppm_buffered) {
                        sp_.ppm_buffered = false;
                        const double t = sp_.ppm_next_rel ? sp_.profile.position() + sp_.ppm_next_raw
                                         : range_on()     ? unwrap(sp_.ppm_next_raw, sp_.profile.position())
                                                          : static_cast<double>(sp_.ppm_next_raw) - shift_;
                        const double lo = params.sw_limit_min == std::numeric_limits<int32_t>::min()
                                              ? -INFINITY
                                              : static_cast<double>(params.sw_limit_min) - shift_;
                        const double hi = params.sw_limit_max == std::numeric_limits<int32_t>::max()
                                              ? INFINITY
                                              : static_cast<double>(params.sw_limit_max) - shift_;
                        sp_.ppm_limited = t < lo || t > hi;
                        sp_.ppm_target = std::clamp(t, lo, hi);
                        sp_.ppm_moving = true;
                    }
                }
            } else {
                sp_.profile.step_velocity(0.0, dec, dec, h);
            }
            from_profile();
            return;
        case mode::ProfileVelocity: {
            const double vlim =
                static_cast<double>(std::min(params.max_profile_velocity, params.max_motor_speed));
            const double v = std::clamp(static_cast<double>(command.target_velocity), -vlim, vlim);
            if (sp_.halted)
                sp_.profile.step_velocity(0.0, qs, qs, h);
            else
                sp_.profile.step_velocity(rpm_to_inc_s(v), acc, dec, h);
            from_profile();
            return;
        }
        case mode::Homing:
            homing_tick(h);
            from_profile();
            return;
        default:
            sp_.profile.step_velocity(0.0, dec, dec, h);
            from_profile();
            return;
    }
}

}  // namespace drive
