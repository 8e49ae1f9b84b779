// Set-point generation (SetpointGenerator): mode switching, the profile modes and the cyclic synchronous
// modes.
#include "drive/setpoint.hpp"

#include <algorithm>
#include <cmath>

#include "axis_internal.hpp"
#include "drive/state_machine.hpp"

namespace drive {

using namespace detail;

bool mode::supported(int8_t m, uint32_t announced, uint32_t served) {
    // 0x6502 = 0 announces no mode at all, as vendors' ESIs ship it where the device reports its own (Elmo
    // Gold): it states nothing, and the modes the drive implements are taken.
    if (announced == 0) announced = supported_drive_modes();
    return contains(kModesOfOperation, m) && (announced & served & mode_bit(m)) != 0;
}

void SetpointGenerator::hold(double pos) {
    ip_from_ = ip_to_ = pos;
    ip_period_ = 0;
    ip_active_ = false;
    ppm_moving_ = ppm_buffered_ = false;
    pt_restart_ = true;
}

void SetpointGenerator::move_to(double t, const PositionFrame& f) {
    // Software position limits act on the demand: clamp the target (internal limit bit).
    const double lo = f.raw_min();
    const double hi = f.raw_max();
    ppm_limited_ = t < lo || t > hi;
    ppm_target_ = std::clamp(t, lo, hi);
    ppm_moving_ = true;
}

void SetpointGenerator::switch_mode(int8_t m, bool power, double actual) {
    // On-the-fly switching: the new mode takes over from the current demand without a jump.
    mode_ = m;
    const double from = power ? demand_pos_ : actual;
    profile_.reset(from, power ? demand_vel_ : 0.0);
    hold(from);
    ppm_ack_ = false;
}

void SetpointGenerator::follow(double actual) {
    control_ = Control::Position;
    demand_pos_ = actual;
    demand_vel_ = demand_acc_ = 0;
    profile_.reset(demand_pos_, 0);
}

void SetpointGenerator::from_profile() {
    demand_pos_ = profile_.position();
    demand_vel_ = profile_.velocity();
    demand_acc_ = profile_.acceleration();
    control_ = Control::Position;
}

bool SetpointGenerator::ramp(double decel, double h) {
    const bool at_zero = profile_.step_velocity(0.0, decel, decel, h);
    from_profile();
    return at_zero;
}

bool SetpointGenerator::brake(double actual, double speed, double still) {
    if (std::abs(speed) <= still || speed * stop_direction_ <= 0) {
        ramp_from(actual, 0.0);
        demand_pos_ = actual;
        demand_vel_ = demand_acc_ = 0;
        return true;
    }
    control_ = Control::Torque;
    demand_pos_ = actual;
    demand_vel_ = speed;
    demand_acc_ = 0;
    profile_.reset(actual, speed);
    return false;
}

void SetpointGenerator::power_on(double actual) {
    demand_pos_ = actual;
    demand_vel_ = demand_acc_ = 0;
    profile_.reset(demand_pos_, 0);
    hold(demand_pos_);
}

void SetpointGenerator::resume() {
    demand_pos_ = profile_.position();
    demand_vel_ = 0;
    hold(demand_pos_);
}

void SetpointGenerator::ramp_from(double actual, double speed_inc_s) {
    profile_.reset(actual, speed_inc_s);
    stop_direction_ = speed_inc_s > 0 ? 1.0 : speed_inc_s < 0 ? -1.0 : 0.0;
    control_ = Control::Position;
}

void SetpointGenerator::reset_to(double actual) {
    demand_pos_ = actual;
    profile_.reset(demand_pos_, 0);
}

void SetpointGenerator::command(const Command& cmd, uint16_t cw_prev, bool enabled, const PositionFrame& f,
                                bool interpolate, int64_t now_ns, int64_t dt_ns) {
    const uint16_t c = cmd.controlword;
    const bool rise4 = new_setpoint_edge(c, cw_prev).rise;
    // Halt (bit 8) in the modes that define it (IEC 61800-7-201: profile position, profile velocity, profile
    // torque, homing, interpolated position).
    halted_ = (c & cw::Halt) != 0 &&
              (mode_ == mode::ProfilePosition || mode_ == mode::ProfileVelocity || mode_ == mode::Homing ||
               mode_ == mode::ProfileTorque || mode_ == mode::InterpolatedPosition);
    switch (mode_) {
        case mode::ProfilePosition: {
            if (rise4 && enabled) {
                const bool rel = c & cw::Relative;
                const bool immediate = c & cw::ChangeImmediately;
                if (immediate || !ppm_moving_) {
                    move_to(
                        rel ? demand_pos_ + cmd.target_position : f.to_raw(cmd.target_position, demand_pos_),
                        f);
                    ppm_buffered_ = false;
                    if (!immediate) profile_.reset(demand_pos_, demand_vel_);
                } else {
                    ppm_buffered_ = true;
                    ppm_next_rel_ = rel;
                    ppm_next_raw_ = cmd.target_position;
                }
                ppm_ack_ = true;
            }
            if (!(c & cw::NewSetpoint) && !ppm_buffered_) ppm_ack_ = false;
            break;
        }
        case mode::CyclicSyncPosition: {
            const int64_t tgt = static_cast<int64_t>(cmd.target_position) + cmd.position_offset;
            next_setpoint(tgt, f, interpolate, now_ns, dt_ns);
            csp_limit_violation_ = enabled && f.outside_limits(tgt);
            break;
        }
        case mode::InterpolatedPosition: {
            // Controlword bit 4 enables the interpolation (IEC 61800-7-201 interpolated position mode): while
            // it is set in Operation enabled and no halt, each cycle's 0x60C1:01 is a set-point, interpolated
            // linearly (sub-mode 0x60C0 = 0) over the cycle as in CSP. Taken on, the interpolation starts at
            // the demand; taken off (or halt), the demand comes to rest on the profile's ramp.
            const bool on = enabled && (c & cw::NewSetpoint) != 0 && !halted_;
            if (on && !ip_active_) {
                ip_from_ = ip_to_ = demand_pos_;
                ip_period_ = 0;
            }
            ip_active_ = on;
            if (!on) {
                csp_limit_violation_ = false;
                break;
            }
            next_setpoint(cmd.ip_position, f, interpolate, now_ns, dt_ns);
            csp_limit_violation_ = f.outside_limits(cmd.ip_position);
            break;
        }
        default:
            break;
    }
}

void SetpointGenerator::next_setpoint(int64_t tgt, const PositionFrame& f, bool interpolate, int64_t now_ns,
                                      int64_t dt_ns) {
    // New target each cycle, interpolated linearly over the interpolation period (= this cycle when 0x60C2 is
    // set, as MAXPOS sets it to the SYNC0 cycle; 0 = no interpolation). The new segment starts where the last
    // one ends: the cycle that took it simulated its whole gap, whatever the gap to this cycle is. (Cut at
    // this cycle's time instead, a short gap after a long one, a late slave's cycle or the jitter of a loaded
    // host, put the demand back by the part of the last segment the axis had already run: a following error
    // spike that a vendor's 100-increment window turned into a fault.)
    const double t_raw =
        f.range_on() ? f.unwrap(static_cast<int32_t>(tgt), ip_to_) : static_cast<double>(tgt - f.shift);
    ip_from_ = ip_to_;
    ip_to_ = t_raw;
    ip_t0_ = now_ns;
    ip_period_ = interpolate ? dt_ns : 0;
}

void SetpointGenerator::interpolate_at(int64_t t_ns, double h) {
    const double fr = ip_period_ > 0 ? std::min(1.0, static_cast<double>(t_ns - ip_t0_) / ip_period_) : 1.0;
    const double pos = ip_from_ + (ip_to_ - ip_from_) * fr;
    demand_vel_ = (pos - demand_pos_) / h;
    demand_acc_ = 0;
    demand_pos_ = pos;
    control_ = Control::Position;
    profile_.reset(demand_pos_, demand_vel_);
}

void SetpointGenerator::torque_ramp(double target, const Parameters& p, double h) {
    // 0x6087 torque slope in per mille of the rated torque per second; 0 (as vendors' ESIs ship it where the
    // device sets its own) and 0xFFFFFFFF: no ramp, the target at once. 0x6088 = 1: a sin^2 ramp over the
    // time the linear ramp takes (the same mean slope); any other value: linear (0).
    if (p.torque_slope == 0 || p.torque_slope == 0xFFFFFFFFu) {
        pt_demand_ = pt_from_ = pt_target_ = target;
        return;
    }
    const double slope = static_cast<double>(p.torque_slope);
    if (p.torque_profile_type == 1) {
        if (target != pt_target_) {  // a new target: a new ramp from where the demand is
            pt_from_ = pt_demand_;
            pt_target_ = target;
            pt_time_ = 0;
        }
        const double span = pt_target_ - pt_from_;
        const double duration = std::abs(span) / slope;
        pt_time_ += h;
        if (pt_time_ >= duration) {
            pt_demand_ = pt_target_;
            return;
        }
        const double s = std::sin(0.5 * kTwoPi * 0.5 * pt_time_ / duration);  // sin(pi/2 t/T)
        pt_demand_ = pt_from_ + span * s * s;
        return;
    }
    pt_target_ = target;
    const double step = slope * h;
    pt_demand_ =
        std::abs(target - pt_demand_) <= step ? target : pt_demand_ + (target > pt_demand_ ? step : -step);
}

LoopReference SetpointGenerator::tick(const Command& c, const Parameters& p, const Inputs& in,
                                      const PositionFrame& f, int64_t t_ns, double h) {
    LoopReference ref;
    const double rated_a = p.nominal_current * 1e-3;  // rated torque / km
    // The profile modes' limits (inc/s^2).
    auto limit = [&](uint32_t rpm_s) {
        return limited_acceleration(rpm_s, p.max_acceleration, in.resolution);
    };
    switch (mode_) {
        case mode::CyclicSyncPosition: {
            interpolate_at(t_ns, h);
            ref.vel_ff = kTwoPi * c.velocity_offset / 60.0;
            ref.torque_ff_a = c.torque_offset * 1e-3 * rated_a;
            return ref;
        }
        case mode::InterpolatedPosition: {
            if (ip_active_) {
                interpolate_at(t_ns, h);
                return ref;
            }
            // Without the interpolation (bit 4 off) the demand comes to rest on the profile deceleration;
            // with halt on the quick stop deceleration, as in the profile modes.
            const double dec = halted_ ? limit(p.quick_stop_deceleration) : limit(p.profile_deceleration);
            profile_.step_velocity(0.0, dec, dec, h);
            from_profile();
            return ref;
        }
        case mode::ProfileTorque: {
            if (halted_) {
                // Halt: the axis stops on the quick stop ramp under position control and holds; released,
                // the torque ramp starts again from the torque the motor gives then.
                const double qs = limit(p.quick_stop_deceleration);
                profile_.step_velocity(0.0, qs, qs, h);
                from_profile();
                pt_restart_ = true;
                return ref;
            }
            if (pt_restart_) {
                pt_demand_ = pt_from_ = pt_target_ = in.torque;
                pt_time_ = 0;
                pt_restart_ = false;
            }
            torque_ramp(static_cast<double>(c.target_torque), p, h);
            control_ = Control::Torque;
            ref.cur_ref = pt_demand_ * 1e-3 * rated_a;
            demand_pos_ = in.actual;
            demand_vel_ = in.speed * in.resolution / kTwoPi;
            profile_.reset(demand_pos_, demand_vel_);
            return ref;
        }
        case mode::CyclicSyncVelocity: {
            const double vmot = static_cast<double>(speed_limit(p.max_motor_speed));
            const double v =
                std::clamp(static_cast<double>(c.target_velocity) + c.velocity_offset, -vmot, vmot);
            control_ = Control::Velocity;
            ref.vel_ref = kTwoPi * v / 60.0;
            demand_vel_ = v * in.resolution / 60.0;
            demand_pos_ = in.actual;
            ref.torque_ff_a = c.torque_offset * 1e-3 * rated_a;
            profile_.reset(demand_pos_, demand_vel_);
            return ref;
        }
        case mode::CyclicSyncTorque: {
            control_ = Control::Torque;
            const double permille = static_cast<double>(c.target_torque) + c.torque_offset;
            ref.cur_ref = permille * 1e-3 * rated_a;
            demand_pos_ = in.actual;
            demand_vel_ = in.speed * in.resolution / kTwoPi;
            profile_.reset(demand_pos_, demand_vel_);
            return ref;
        }
        case mode::ProfilePosition: {
            const double acc = limit(p.profile_acceleration), dec = limit(p.profile_deceleration);
            const double qs = limit(p.quick_stop_deceleration);
            const double vmax =
                std::min(p.profile_velocity, speed_limit(p.max_profile_velocity)) * in.resolution / 60.0;
            if (halted_) {
                profile_.step_velocity(0.0, qs, qs, h);
            } else if (ppm_moving_) {
                if (profile_.step_position(ppm_target_, vmax, acc, dec, h)) {
                    ppm_moving_ = false;
                    if (ppm_buffered_) {
                        ppm_buffered_ = false;
                        move_to(ppm_next_rel_ ? profile_.position() + ppm_next_raw_
                                              : f.to_raw(ppm_next_raw_, profile_.position()),
                                f);
                    }
                }
            } else {
                profile_.step_velocity(0.0, dec, dec, h);
            }
            from_profile();
            return ref;
        }
        case mode::ProfileVelocity: {
            const double acc = limit(p.profile_acceleration), dec = limit(p.profile_deceleration);
            const double qs = limit(p.quick_stop_deceleration);
            const double vlim = static_cast<double>(
                std::min(speed_limit(p.max_profile_velocity), speed_limit(p.max_motor_speed)));
            const double v = std::clamp(static_cast<double>(c.target_velocity), -vlim, vlim);
            if (halted_)
                profile_.step_velocity(0.0, qs, qs, h);
            else
                profile_.step_velocity(v * in.resolution / 60.0, acc, dec, h);
            from_profile();
            return ref;
        }
        default: {
            const double dec = limit(p.profile_deceleration);
            profile_.step_velocity(0.0, dec, dec, h);
            from_profile();
            return ref;
        }
    }
}

}  // namespace drive
