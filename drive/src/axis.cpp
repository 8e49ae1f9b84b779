#include "drive/axis.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "axis_internal.hpp"
#include "drive/errors.hpp"
#include "machine_step.hpp"

namespace drive {

using namespace detail;

Axis::Axis(EventSink* sink) : sink_(sink ? sink : &null_sink_) {}

double Axis::raw_position_inc() const {
    return pol_ * phys_position_inc();
}

double Axis::phys_position_inc() const {
    return plant_.angle() * inc_per_rad_;
}

bool Axis::error_active(uint16_t code) const {
    return sup_.error_active(code);
}

int32_t Axis::clamp_i32(double v) const {
    return static_cast<int32_t>(std::clamp(v, -2147483648.0, 2147483647.0));
}

double Axis::decel_limit(double rpm_s) const {
    return limited_acceleration(rpm_s, params.max_acceleration, res_);
}

PositionFrame Axis::frame() const {
    // Software position limits that define no range (min >= max: 0/0 as many vendors' ESIs ship 0x607D) are
    // off, as a position range limit 0x607B without a range is.
    constexpr int32_t kOffMin = std::numeric_limits<int32_t>::min(),
                      kOffMax = std::numeric_limits<int32_t>::max();
    const bool sw_on = params.sw_limit_max > params.sw_limit_min;
    return {home_.shift(), params.range_min, params.range_max, sw_on ? params.sw_limit_min : kOffMin,
            sw_on ? params.sw_limit_max : kOffMax};
}

DeviceControl::Options Axis::dc_options() const {
    return {params.shutdown, params.disable_operation, params.profile_deceleration,
            params.quick_stop_deceleration, params.quick_stop};
}

// What device control's transitions ask of the other parts.
class Axis::Parts final : public DeviceControl::Parts {
  public:
    Parts(Axis& a, int64_t now_ns) : a_(a), now_ns_(now_ns) {}
    uint16_t enable_refused() override {
        if (a_.ctl_.km <= 0) return error_code::TorqueFault;
        if ((a_.pins_ & 0x30) != 0x30) return error_code::Sto;
        return 0;
    }
    void powered() override {
        a_.ctl_.power_on();
        a_.sp_.power_on(static_cast<double>(a_.count_));
    }
    double stopping(StopKind kind, double decel_rpm_s) override {
        // A stop (quick stop, shutdown, fault) ends a running homing: interrupted, to be started again.
        a_.home_.interrupt(HomingPhase::Finished);
        if (kind != StopKind::Ramp && kind != StopKind::Limit) return 0;
        // A ramp starts where the motor really is (position and speed), whatever the set-points did.
        a_.sp_.ramp_from(static_cast<double>(a_.count_), a_.ctl_.obs_vel * a_.res_ / kTwoPi);
        return kind == StopKind::Ramp ? a_.decel_limit(decel_rpm_s) : 0.0;
    }
    void resumed() override { a_.sp_.resume(); }
    bool fault_reset() override {
        const Supervisor::Causes causes{(a_.pins_ & 0x30) != 0x30, a_.ctl_.km <= 0,
                                        Supervisor::overspeed(a_.ctl_.obs_vel, a_.params.max_motor_speed)};
        return a_.sup_.reset(causes, *a_.sink_);
    }
    void acknowledge_warnings() override { a_.sup_.acknowledge_warnings(*a_.sink_); }
    void fault(uint16_t code) override { a_.fault(code, now_ns_); }

  private:
    Axis& a_;
    int64_t now_ns_;
};

void Axis::raise_error(uint16_t code) {
    fault(code, now_ns_);
}

void Axis::connection_lost() {
    // Only a drive that has power on its motor reacts: without power there is nothing to stop, and a master
    // that merely walks the ESM down after disabling the drive must not find a fault on its next start.
    if (!dc_.power()) return;
    fault(error_code::EthercatStateMachine, now_ns_);
    update_feedback();
}

void Axis::fault(uint16_t code, int64_t now_ns) {
    const std::array<uint8_t, 5> mfr{static_cast<uint8_t>(dc_.state()), static_cast<uint8_t>(sp_.mode()), 0,
                                     0, 0};
    const Supervisor::Raised r =
        sup_.raise(code, params.fault_reaction, params.abort_connection, mfr, *sink_);
    if (!r.react) return;
    home_.error();
    const bool at_rest = std::abs(ctl_.vel_avg_rpm) <= static_cast<double>(params.standstill_window);
    Parts parts(*this, now_ns);
    dc_.react(r.reaction, r.option, at_rest, dc_options(), parts, *sink_, now_ns);
}

void Axis::supervise(int64_t now_ns, int64_t dt_ns) {
    sup_.standstill(ctl_.vel_avg_rpm, params.standstill_window, params.standstill_time, dt_ns);
    const bool enabled = dc_.state() == State::OperationEnabled && dc_.power() && !dc_.waiting();
    const int8_t m = sp_.mode();
    const bool homing = m == mode::Homing && home_.running();
    // Following error in the position-controlled modes.
    const bool pos_mode = m == mode::CyclicSyncPosition || m == mode::ProfilePosition || m == mode::Homing ||
                          m == mode::InterpolatedPosition;
    const double ferr = std::abs(sp_.demand_position() - static_cast<double>(count_));
    if (sup_.following_error(enabled && pos_mode, ferr, params.following_error_window,
                             params.following_error_timeout, dt_ns))
        fault(error_code::FollowingError, now_ns);
    if (enabled && !homing) {
        const double v =
            sp_.control() == Control::Torque ? ctl_.obs_vel * res_ / kTwoPi : sp_.demand_velocity();
        const Supervisor::Motion motion{v,
                                        (func_ & 0x1) != 0,
                                        (func_ & 0x2) != 0,
                                        count_ + home_.shift(),
                                        m != mode::ProfilePosition,
                                        sp_.target_outside_limits()};
        const Supervisor::Found found = Supervisor::limits(motion, frame());
        for (int i = 0; i < found.count; ++i)
            fault(found.codes[static_cast<std::size_t>(i)], now_ns);
    }
    if (dc_.power() && Supervisor::overspeed(ctl_.obs_vel, params.max_motor_speed))
        fault(error_code::MaxSpeed, now_ns);
    if (dc_.power() && (pins_ & 0x30) != 0x30) fault(error_code::Sto, now_ns);
    dc_.settle(sup_.still(), params.standstill_window, params.standstill_timeout, *sink_, now_ns);
}

void Axis::mode_commands(int64_t now_ns, int64_t dt_ns) {
    const bool enabled = dc_.operational() && dc_.stop() == StopKind::None;
    sp_.command(command, dc_.previous_controlword(), enabled, frame(), params.interpolation_value != 0,
                now_ns, dt_ns);
    if (sp_.mode() != mode::Homing) return;
    const SetpointEdge e = new_setpoint_edge(command.controlword, dc_.previous_controlword());
    const State s = dc_.state();
    if (e.rise && enabled) {
        // Homing clears touch-probe states and latched values (MAXPOS firmware specification §4.5).
        tp_.clear_for_homing();
        sp_.profile().reset(sp_.demand_position(), sp_.demand_velocity());
        home_.start(params, func_, static_cast<double>(count_), *sink_);
    } else if (e.rise && !dc_.power() && params.homing_method == 37 && s != State::Fault &&
               s != State::FaultReactionActive) {
        // Method 37 while disabled: no offset move, the actual position becomes the home position.
        home_.set_here(params.home_position, count_, *sink_);
    }
    if (e.fall) home_.interrupt(HomingPhase::Stopping);
}

void Axis::trajectory_tick(int64_t t_ns) {
    const double h = kPosH;
    ctl_.follow(LoopReference{}, Control::Position);  // no feed-forward unless the mode gives one
    if (!dc_.power()) {
        sp_.follow(static_cast<double>(count_));
        return;
    }
    if (dc_.stop() == StopKind::Limit && !dc_.ramp_done()) {
        // At the current limit: all the current the drive may give (0x3001:02, the rated current while I2t
        // limits), against the motion, until the motor stands; then the position loop holds it there.
        const double speed = ctl_.obs_vel * res_ / kTwoPi;
        if (sp_.brake(static_cast<double>(count_), speed, res_ / 60.0)) {
            dc_.ramp_reached(true);
            return;
        }
        LoopReference ref;
        ref.cur_ref = (speed > 0 ? -1.0 : 1.0) *
                      ctl_.current_limit(params.nominal_current, params.output_current_limit);
        ctl_.follow(ref, Control::Torque);
        return;
    }
    if (dc_.stop() == StopKind::Ramp || dc_.stop() == StopKind::Limit) {
        dc_.ramp_reached(sp_.ramp(dc_.stop_deceleration(), h));
        return;
    }
    if (sp_.mode() == mode::Homing) {
        const Homing::Motion motion{rpm_to_inc_s(params.homing_speed_switch),
                                    rpm_to_inc_s(params.homing_speed_zero),
                                    decel_limit(params.homing_acceleration)};
        const Homing::Inputs in{sp_.halted(), std::abs(plant_.current()), func_, static_cast<double>(count_),
                                res_};
        home_.tick(sp_.profile(), motion, in, params, *sink_, h);
        sp_.from_profile();
        return;
    }
    const SetpointGenerator::Inputs in{
        static_cast<double>(count_), ctl_.obs_vel, static_cast<double>(res_),
        i_meas() / (std::max<double>(params.nominal_current, 1.0) * 1e-3) * 1e3};
    const LoopReference ref = sp_.tick(command, params, in, frame(), t_ns, h);
    ctl_.follow(ref, sp_.control());  // the loop the tick chose
}

void Axis::tp_latch(bool rising, double raw_pos) {
    const uint16_t fn = command.touch_probe_function;
    if (!TouchProbe::armed(fn, sp_.mode() == mode::Homing)) return;
    tp_.latch(fn, rising, frame().report(static_cast<int64_t>(std::floor(raw_pos)) + home_.shift()));
}

void Axis::derive() {
    // Increments per motor revolution: 0x608F where the device has it (IEC 61800-7-201 position encoder
    // resolution), else 4 x the encoder's pulses (quadrature).
    const uint64_t per_rev = params.resolution_increments > 0 && params.resolution_revolutions > 0
                                 ? params.resolution_increments / params.resolution_revolutions
                                 : 4ull * params.encoder_pulses;
    const int32_t res = static_cast<int32_t>(std::clamp<uint64_t>(per_rev, 4ull, 1ull << 30));
    const double pol = (params.axis_misc & 0x1) ? -1.0 : 1.0;
    if (res != res_ || pol != pol_) {
        // A new resolution or polarity invalidates the position and the reference (MAXPOS firmware
        // specification §7.2.22).
        const double phys_angle = plant_.angle();
        res_ = res;
        rad_per_inc_ = kTwoPi / res_;
        inc_per_rad_ = res_ / kTwoPi;
        pol_ = pol;
        count_ = static_cast<int64_t>(std::floor(pol_ * phys_angle * res_ / kTwoPi));
        prev_raw_pos_ = phys_angle * res_ / kTwoPi;
        home_.invalidate();
        ctl_.rebase(inc_to_rad(static_cast<double>(count_) + 0.5));
        sp_.reset_to(static_cast<double>(count_));
        plant_dirty_ = true;  // the stops are given in increments
    }
    ctl_.set_torque_constant(params.torque_constant);
    const double km_plant = ctl_.km > 0 ? ctl_.km : motor_.torque_constant;
    if (plant_dirty_ || km_plant != km_plant_ || env_.take_stops_changed()) {
        // configure() keeps the state (current, speed, angle): changing the model does not jump.
        plant_.configure(motor_, km_plant, kPlantStep);
        const double lo = std::isnan(env_.stop_lo()) ? -INFINITY : env_.stop_lo() * kTwoPi / res_;
        const double hi = std::isnan(env_.stop_hi()) ? INFINITY : env_.stop_hi() * kTwoPi / res_;
        plant_.set_stops(lo, hi);
        km_plant_ = km_plant;
        plant_dirty_ = false;
    }
    ctl_.tune(params, km_plant);
}

uint64_t Axis::functions(uint16_t pins) const {
    const uint16_t logical = static_cast<uint16_t>((pins ^ params.input_polarity) & 0x3F);
    uint64_t f = static_cast<uint64_t>(logical) << 32;
    for (int i = 0; i < 6; ++i) {
        if (!(logical & (1u << i))) continue;
        const uint8_t fn = params.input_function[static_cast<std::size_t>(i)];
        if (fn <= 2 || (fn >= 16 && fn <= 21) || fn == 24 || fn == 25 || fn == 26) f |= 1ull << fn;
    }
    return f;
}

void Axis::prepare_steps(int64_t from_ns, int64_t to_ns) {
    // Everything here is constant for the cycle (parameters, environment, resolution): computed once instead
    // of in each of the 100 machine steps of a 1 ms cycle.
    fn_valid_ = false;
    pins_fixed_ = env_.constant_over(from_ns, to_ns, fixed_pins_);
    index_on_ = (params.encoder_type & 0x0001) != 0;
    if (index_on_) {
        index_p0_ = motor_.index_angle / kTwoPi * res_;
        index_k_ = std::floor((prev_raw_pos_ - index_p0_) / res_);
        index_bounds(index_k_, res_, index_lo_, index_hi_);
    }
}

void Axis::edges(double prev, double raw, int64_t t_ns, uint64_t changed) {
    const int64_t t0 = t_ns - kCurrentTickNs / kPlantStepsPerTick;
    for (int bit = 0; bit < 64; ++bit) {
        const uint64_t m = 1ull << bit;
        if (!(changed & m)) continue;
        // Where between the two samples did it switch? Bisection on the straight line between them.
        double lo = 0, hi = 1;
        const bool before = func_ & m;
        for (int it = 0; it < 20; ++it) {
            const double mid = 0.5 * (lo + hi);
            const double pos = prev + (raw - prev) * mid;
            const int64_t t = t0 + static_cast<int64_t>((t_ns - t0) * mid);
            if (static_cast<bool>(functions_now(env_.pins(pos, t)) & m) == before)
                lo = mid;
            else
                hi = mid;
        }
        on_edge(bit, !before, pol_ * (prev + (raw - prev) * hi));
    }
}

void Axis::on_edge(int bit, bool rising, double raw_pos) {
    if (bit == TouchProbe::source_bit(command.touch_probe_function, params.touch_probe_source))
        tp_latch(rising, raw_pos);
    home_.edge(bit, rising, sp_.profile().velocity(), raw_pos);
}

void Axis::on_index(double raw_pos) {
    index_count_ = static_cast<int64_t>(std::floor(raw_pos));
    if (TouchProbe::index_selected(command.touch_probe_function, params.touch_probe_source)) {
        // The index is a pulse: it has both edges at the same place.
        tp_latch(true, raw_pos);
        tp_latch(false, raw_pos);
    }
    home_.index_pulse(sp_.profile().velocity(), raw_pos);
}

void Axis::cycle(int64_t now_ns, int64_t dt_ns) {
    now_ns_ = now_ns;
    derive();
    if (dc_.state() == State::NotReadyToSwitchOn) {
        pins_ = env_.pins(phys_position_inc(), now_ns);
        func_ = functions(pins_);
        prev_raw_pos_ = phys_position_inc();
        count_ = static_cast<int64_t>(std::floor(raw_position_inc()));
        ctl_.start_at(inc_to_rad(static_cast<double>(count_) + 0.5));
        dc_.start(*sink_);
    }
    tp_.configure(command.touch_probe_function);
    if (command.mode != sp_.mode() && mode::supported(command.mode, params.supported_modes, served_modes_)) {
        // A running homing ends with the mode: interrupted, to be started again.
        if (sp_.mode() == mode::Homing) home_.interrupt();
        sp_.switch_mode(command.mode, dc_.power(), static_cast<double>(count_));
        ctl_.mode_switched(dc_.power());
        if (command.mode == mode::Homing) home_.entered();
    }
    {
        Parts parts(*this, now_ns);
        dc_.command(command.controlword, faults, dc_options(), parts, *sink_, now_ns);
    }
    mode_commands(now_ns, dt_ns);
    // At most one second of simulated time per call: a caller that skipped time (or passed a bogus dt)
    // must not stall its thread for minutes.
    dt_ns = std::min<int64_t>(dt_ns, 1'000'000'000);
    if (dt_ns > 0) {
        const int64_t total = residual_ns_ + dt_ns;
        const int64_t ticks = total / kCurrentTickNs;
        residual_ns_ = total % kCurrentTickNs;
        prepare_steps(now_ns, now_ns + ticks * kCurrentTickNs);
        for (int64_t k = 0; k < ticks; ++k) {
            const int64_t t = now_ns + k * kCurrentTickNs;
            if (tick_ % kPositionDivider == 0) {
                trajectory_tick(t);
                if (dc_.power() && sp_.control() == Control::Position) {
                    const bool internal_ff = sp_.mode() != mode::CyclicSyncPosition ||
                                             dc_.stop() != StopKind::None || params.csp_own_feed_forward;
                    ctl_.position(sp_.demand_position(), sp_.demand_velocity(), sp_.demand_acceleration(),
                                  static_cast<double>(count_), internal_ff, plant_.torque_constant(),
                                  rad_per_inc_);
                }
            }
            if (tick_ % kVelocityDivider == 0)
                ctl_.velocity(dc_.power(), sp_.control() == Control::Torque, params.nominal_current,
                              params.output_current_limit);
            current_tick(t);
            ++tick_;
        }
        // A loop that diverged numerically (absurd gains for the machine) must not poison the outputs:
        // reset the estimates and report a controller gain error.
        if (ctl_.diverged()) {
            ctl_.reset_estimates(inc_to_rad(static_cast<double>(count_) + 0.5));
            fault(error_code::ControllerGain, now_ns);
        }
        supervise(now_ns + dt_ns, dt_ns);
    }
    update_feedback();
    dc_.end_cycle(command.controlword);
}

void Axis::update_feedback() {
    Feedback& f = fb_;
    uint16_t s = state_bits(dc_.state(), dc_.power());
    if (dc_.state() != State::NotReadyToSwitchOn) s |= sw::Reserved8;
    s |= sw::Remote;
    if (sup_.warning()) s |= sw::Warning;
    if (ctl_.i2t_active || (sp_.mode() == mode::ProfilePosition && sp_.target_limited()))
        s |= sw::InternalLimit;
    if (home_.referenced()) s |= sw::Referenced;
    const bool oe = dc_.operational();
    const bool ferr = following_error_checked(params.following_error_window) &&
                      std::abs(sp_.demand_position() - static_cast<double>(count_)) >
                          static_cast<double>(params.following_error_window);
    switch (sp_.mode()) {
        case mode::ProfilePosition:
            if (sp_.target_reached()) s |= sw::TargetReached;
            if (sp_.setpoint_acknowledged()) s |= sw::Bit12;
            if (ferr && dc_.power()) s |= sw::Bit13;
            break;
        case mode::ProfileVelocity: {
            const double vlim = static_cast<double>(
                std::min(speed_limit(params.max_profile_velocity), speed_limit(params.max_motor_speed)));
            const double target =
                sp_.halted()
                    ? 0.0
                    : rpm_to_inc_s(std::clamp(static_cast<double>(command.target_velocity), -vlim, vlim));
            if (sp_.profile().velocity() == target) s |= sw::TargetReached;
            if (std::abs(ctl_.vel_avg_rpm) <= static_cast<double>(params.standstill_window)) s |= sw::Bit12;
            break;
        }
        case mode::Homing:
            switch (home_.status()) {
                case HomingStatus::InProgress:
                    break;  // 000
                case HomingStatus::Idle:
                case HomingStatus::Interrupted:
                    s |= sw::TargetReached;
                    break;  // 001
                case HomingStatus::Done:
                    s |= sw::TargetReached | sw::Bit12;
                    break;                 // 011
                case HomingStatus::Error:  // 100 / 101
                    s |= sw::Bit13;
                    if (std::abs(ctl_.vel_avg_rpm) <= static_cast<double>(params.standstill_window) &&
                        sup_.still())
                        s |= sw::TargetReached;
                    break;
            }
            break;
        case mode::CyclicSyncPosition:
            if (oe && dc_.stop() == StopKind::None) s |= sw::Bit12;
            if (ferr && dc_.power()) s |= sw::Bit13;
            break;
        case mode::CyclicSyncVelocity:
        case mode::CyclicSyncTorque:
            if (oe && dc_.stop() == StopKind::None) s |= sw::Bit12;
            break;
        case mode::InterpolatedPosition:
            // IEC 61800-7-201: bit 10 target reached (the last set-point reached and at rest; with halt or
            // without the interpolation: at rest), bit 12 ip mode active; bit 13 is not defined in this mode.
            if (oe && dc_.stop() == StopKind::None && sp_.ip_target_reached() && sup_.still())
                s |= sw::TargetReached;
            if (oe && dc_.stop() == StopKind::None && sp_.ip_active()) s |= sw::Bit12;
            break;
        case mode::ProfileTorque:
            // Bit 10: the torque demand reached the target torque (with halt: the axis stands still).
            if (oe && dc_.stop() == StopKind::None && sp_.torque_reached()) s |= sw::TargetReached;
            break;
        default:
            break;
    }
    if (dc_.state() == State::QuickStopActive && dc_.ramp_done()) s |= sw::TargetReached;
    f.statusword = s;
    if (!faults.mode_display_stuck || f.mode_display == mode::None) f.mode_display = sp_.mode();
    const PositionFrame fr = frame();
    f.position_actual = fr.report(count_ + home_.shift());
    f.position_demand = fr.report(static_cast<int64_t>(std::llround(sp_.demand_position())) + home_.shift());
    f.following_error = clamp_i32(std::round(sp_.demand_position() - static_cast<double>(count_)));
    const double vd = sp_.control() == Control::Velocity ? ctl_.vel_ref * 60.0 / kTwoPi
                                                         : sp_.demand_velocity() * 60.0 / res_;
    f.velocity_demand = clamp_i32(std::round(vd));
    f.velocity_actual = clamp_i32(std::round(ctl_.obs_vel * 60.0 / kTwoPi));
    f.velocity_averaged = clamp_i32(std::round(ctl_.vel_avg_rpm));
    const double in = std::max<double>(params.nominal_current, 1.0) * 1e-3;
    f.torque_actual = sat16(i_meas() / in * 1000.0);
    f.torque_demand = sat16(dc_.power() ? ctl_.cur_ref / in * 1000.0 : 0.0);
    f.current_actual = sat16(i_meas() * 1000.0);
    f.current_demand = sat16(dc_.power() ? ctl_.cur_ref * 1000.0 : 0.0);
    f.current_averaged = sat16(ctl_.cur_avg_a * 1000.0);
    f.motor_rated_torque =
        static_cast<uint32_t>(static_cast<uint64_t>(params.nominal_current) * params.torque_constant / 1000u);
    f.digital_inputs = static_cast<uint32_t>(func_ & 0x033F0007ull);
    f.input_logic_state = pins_;
    f.index_position = fr.report(index_count_ + home_.shift());
    f.touch_probe_status = tp_.status();
    f.touch_probe_pos = tp_.position_rising();
    f.touch_probe_neg = tp_.position_falling();
    f.touch_probe_pos_count = tp_.count_rising();
    f.touch_probe_neg_count = tp_.count_falling();
    f.error_code = sup_.last_error();
    f.error_register = sup_.error_register();
}

}  // namespace drive
