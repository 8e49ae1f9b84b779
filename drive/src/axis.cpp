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
    const double a = std::min<double>(std::max(rpm_s, 1.0), static_cast<double>(params.max_acceleration));
    return rpm_to_inc_s(a);
}

bool Axis::range_on() const {
    return params.range_min != std::numeric_limits<int32_t>::min() && params.range_max > params.range_min;
}

int32_t Axis::report(int64_t v) const {
    if (!range_on()) return wrap32(v);
    const int64_t span = static_cast<int64_t>(params.range_max) - params.range_min + 1;
    int64_t m = (v - params.range_min) % span;
    if (m < 0) m += span;
    return static_cast<int32_t>(params.range_min + m);
}

double Axis::unwrap(int32_t target, double near_raw) const {
    // The target inside the range, taken the short way from where the axis is (raw increments).
    const double span = static_cast<double>(params.range_max) - params.range_min + 1.0;
    const double here = std::round(near_raw + static_cast<double>(shift_));
    const double here_wrapped = static_cast<double>(report(static_cast<int64_t>(here)));
    double d = static_cast<double>(target) - here_wrapped;
    d -= span * std::round(d / span);
    return here + d - static_cast<double>(shift_);
}

void Axis::derive() {
    const int32_t res =
        static_cast<int32_t>(std::clamp<uint64_t>(4ull * params.encoder_pulses, 4ull, 1ull << 30));
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
        shift_ = 0;
        home_.referenced = false;
        ctl_.obs_pos = inc_to_rad(static_cast<double>(count_) + 0.5);
        ctl_.obs_vel = ctl_.obs_load = 0;
        sp_.demand_pos = static_cast<double>(count_);
        sp_.profile.reset(sp_.demand_pos, 0);
        plant_dirty_ = true;  // the stops are given in increments
    }
    ctl_.km = params.torque_constant * 1e-6;
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
    // Touch-probe source (MAXPOS firmware specification §7.2.84): b3..2 = 00 TP1 input (function 26), 10 =
    // 0x60D0:01.
    const uint16_t src = (command.touch_probe_function >> 2) & 0x3;
    int tp_bit = -1;
    if (src == 0) tp_bit = 26;
    if (src == 2) {
        const int16_t s = params.touch_probe_source;
        if (s >= 1 && s <= 4) tp_bit = 32 + s - 1;
        if (s == -2) tp_bit = 32 + 4;
        if (s == -3) tp_bit = 32 + 5;
    }
    if (bit == tp_bit) tp_latch(rising, raw_pos);
    if (home_.status == HomingStatus::InProgress && bit == home_.bit && rising == home_.rise) {
        const double v = sp_.profile.velocity();
        // Only count the edge when moving the way the phase expects (an overshoot during a reversal
        // must not be taken for the awaited edge).
        if ((home_.dir > 0 && v > 0) || (home_.dir < 0 && v < 0)) {
            home_.edge = true;
            home_.event_pos = raw_pos;
        }
    }
}

void Axis::on_index(double raw_pos) {
    index_count_ = static_cast<int64_t>(std::floor(raw_pos));
    const uint16_t src = (command.touch_probe_function >> 2) & 0x3;
    if (src == 1 || (src == 2 && params.touch_probe_source == 5)) {
        // The index is a pulse: it has both edges at the same place.
        tp_latch(true, raw_pos);
        tp_latch(false, raw_pos);
    }
    if (home_.status == HomingStatus::InProgress && home_.phase == HomingPhase::ToIndex) {
        const double v = sp_.profile.velocity();
        if ((home_.dir > 0 && v > 0) || (home_.dir < 0 && v < 0)) {
            home_.index = true;
            home_.event_pos = raw_pos;
        }
    }
}

void Axis::cycle(int64_t now_ns, int64_t dt_ns) {
    now_ns_ = now_ns;
    derive();
    if (dc_.state == State::NotReadyToSwitchOn) {
        pins_ = env_.pins(phys_position_inc(), now_ns);
        func_ = functions(pins_);
        prev_raw_pos_ = phys_position_inc();
        count_ = static_cast<int64_t>(std::floor(raw_position_inc()));
        ctl_.obs_pos = inc_to_rad(static_cast<double>(count_) + 0.5);
        enter(State::SwitchOnDisabled, 1);
    }
    tp_.configure(command.touch_probe_function);
    if (command.mode != sp_.mode && mode::supported(command.mode)) switch_mode(command.mode);
    device_control(now_ns);
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
                position_tick();
            }
            if (tick_ % kVelocityDivider == 0) velocity_tick();
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
    dc_.cw_prev = command.controlword;
}

void Axis::update_feedback() {
    Feedback& f = fb_;
    uint16_t s = state_bits(dc_.state, dc_.power);
    if (dc_.state != State::NotReadyToSwitchOn) s |= sw::Reserved8;
    s |= sw::Remote;
    if (sup_.warning()) s |= sw::Warning;
    if (ctl_.i2t_active || (sp_.mode == mode::ProfilePosition && sp_.ppm_limited)) s |= sw::InternalLimit;
    if (home_.referenced) s |= sw::Referenced;
    const bool oe = dc_.state == State::OperationEnabled && !dc_.pending.active;
    const bool ferr =
        params.following_error_window != kNoWindow && std::abs(sp_.demand_pos - static_cast<double>(count_)) >
                                                          static_cast<double>(params.following_error_window);
    switch (sp_.mode) {
        case mode::ProfilePosition:
            if (sp_.halted ? sp_.profile.velocity() == 0.0 : !sp_.ppm_moving) s |= sw::TargetReached;
            if (sp_.ppm_ack) s |= sw::Bit12;
            if (ferr && dc_.power) s |= sw::Bit13;
            break;
        case mode::ProfileVelocity: {
            const double vlim =
                static_cast<double>(std::min(params.max_profile_velocity, params.max_motor_speed));
            const double target =
                sp_.halted
                    ? 0.0
                    : rpm_to_inc_s(std::clamp(static_cast<double>(command.target_velocity), -vlim, vlim));
            if (sp_.profile.velocity() == target) s |= sw::TargetReached;
            if (std::abs(ctl_.vel_avg_rpm) <= static_cast<double>(params.standstill_window)) s |= sw::Bit12;
            break;
        }
        case mode::Homing:
            switch (home_.status) {
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
                        sup_.still)
                        s |= sw::TargetReached;
                    break;
            }
            break;
        case mode::CyclicSyncPosition:
            if (oe && dc_.stop == StopKind::None) s |= sw::Bit12;
            if (ferr && dc_.power) s |= sw::Bit13;
            break;
        case mode::CyclicSyncVelocity:
        case mode::CyclicSyncTorque:
            if (oe && dc_.stop == StopKind::None) s |= sw::Bit12;
            break;
        default:
            break;
    }
    if (dc_.state == State::QuickStopActive && dc_.ramp_done) s |= sw::TargetReached;
    f.statusword = s;
    if (!faults.mode_display_stuck || f.mode_display == mode::None) f.mode_display = sp_.mode;
    f.position_actual = report(count_ + shift_);
    f.position_demand = report(static_cast<int64_t>(std::llround(sp_.demand_pos)) + shift_);
    f.following_error = clamp_i32(std::round(sp_.demand_pos - static_cast<double>(count_)));
    const double vd =
        sp_.control == Control::Velocity ? ctl_.vel_ref * 60.0 / kTwoPi : sp_.demand_vel * 60.0 / res_;
    f.velocity_demand = clamp_i32(std::round(vd));
    f.velocity_actual = clamp_i32(std::round(ctl_.obs_vel * 60.0 / kTwoPi));
    f.velocity_averaged = clamp_i32(std::round(ctl_.vel_avg_rpm));
    const double in = std::max<double>(params.nominal_current, 1.0) * 1e-3;
    f.torque_actual = sat16(i_meas() / in * 1000.0);
    f.current_actual = sat16(i_meas() * 1000.0);
    f.current_demand = sat16(dc_.power ? ctl_.cur_ref * 1000.0 : 0.0);
    f.current_averaged = sat16(ctl_.cur_avg_a * 1000.0);
    f.motor_rated_torque =
        static_cast<uint32_t>(static_cast<uint64_t>(params.nominal_current) * params.torque_constant / 1000u);
    f.digital_inputs = static_cast<uint32_t>(func_ & 0x033F0007ull);
    f.input_logic_state = pins_;
    f.index_position = report(index_count_ + shift_);
    f.touch_probe_status = tp_.status;
    f.touch_probe_pos = tp_.pos;
    f.touch_probe_neg = tp_.neg;
    f.touch_probe_pos_count = tp_.pos_cnt;
    f.touch_probe_neg_count = tp_.neg_cnt;
    f.error_code = sup_.last_error;
    f.error_register = sup_.error_register;
}

}  // namespace drive
