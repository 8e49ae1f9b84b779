// Set-point generation (SetpointGenerator): mode switching, the profile modes and the cyclic synchronous
// modes.
#include "drive/setpoint.hpp"

#include <algorithm>
#include <cmath>

#include "axis_internal.hpp"
#include "drive/state_machine.hpp"

namespace drive {

using namespace detail;

bool mode::supported(int8_t m, uint32_t announced) {
    // 0x6502 = 0 announces no mode at all, as vendors' ESIs ship it where the device reports its own (Elmo
    // Gold): it states nothing, and the modes the drive implements are taken.
    if (announced == 0) announced = supported_drive_modes();
    return contains(kModesOfOperation, m) && (announced & mode_bit(m)) != 0;
}

void SetpointGenerator::hold(double pos) {
    ip_from_ = ip_to_ = pos;
    ip_period_ = 0;
    ppm_moving_ = ppm_buffered_ = false;
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
    halted_ = (c & cw::Halt) != 0 &&
              (mode_ == mode::ProfilePosition || mode_ == mode::ProfileVelocity || mode_ == mode::Homing);
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
            // New target each cycle, interpolated linearly over the interpolation period (= this cycle when
            // 0x60C2 is set, as MAXPOS sets it to the SYNC0 cycle; 0 = no interpolation).
            const int64_t tgt = static_cast<int64_t>(cmd.target_position) + cmd.position_offset;
            const double t_raw = f.range_on() ? f.unwrap(static_cast<int32_t>(tgt), ip_to_)
                                              : static_cast<double>(tgt - f.shift);
            const double now_val =
                ip_period_ > 0
                    ? ip_from_ + (ip_to_ - ip_from_) *
                                     std::min(1.0, static_cast<double>(now_ns - ip_t0_) / ip_period_)
                    : ip_to_;
            ip_from_ = now_val;
            ip_to_ = t_raw;
            ip_t0_ = now_ns;
            ip_period_ = interpolate ? dt_ns : 0;
            csp_limit_violation_ = enabled && f.outside_limits(tgt);
            break;
        }
        default:
            break;
    }
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
            const double fr =
                ip_period_ > 0 ? std::min(1.0, static_cast<double>(t_ns - ip_t0_) / ip_period_) : 1.0;
            const double pos = ip_from_ + (ip_to_ - ip_from_) * fr;
            demand_vel_ = (pos - demand_pos_) / h;
            demand_acc_ = 0;
            demand_pos_ = pos;
            ref.vel_ff = kTwoPi * c.velocity_offset / 60.0;
            ref.torque_ff_a = c.torque_offset * 1e-3 * rated_a;
            control_ = Control::Position;
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
