#include "drive/axis.hpp"

#include <algorithm>
#include <cmath>

#include "drive/errors.hpp"

namespace drive {

namespace {
constexpr double kTwoPi = 6.283185307179586;
constexpr double kTick = static_cast<double>(kCurrentTickNs) * 1e-9;
constexpr double kPlantStep = kTick / kPlantStepsPerTick;
constexpr double kVelH = kTick * kVelocityDivider;
constexpr double kPosH = kTick * kPositionDivider;
constexpr double kObserverHz = 250.0;
// First-order low-pass coefficient for the averaged values (50 Hz, as 0x30D1), per current tick.
const double kAvgAlpha = 1.0 - std::exp(-kTwoPi * 50.0 * kTick);
constexpr uint32_t kNoWindow = 0xFFFFFFFFu;

int32_t wrap32(int64_t v) {
    return static_cast<int32_t>(static_cast<uint32_t>(static_cast<uint64_t>(v)));
}
int16_t sat16(double v) {
    return static_cast<int16_t>(std::clamp(std::lround(v), -32768L, 32767L));
}
}  // namespace

bool mode::supported(int8_t m) {
    return m == ProfilePosition || m == ProfileVelocity || m == Homing || m == CyclicSyncPosition ||
           m == CyclicSyncVelocity || m == CyclicSyncTorque;
}

Axis::Axis(EventSink* sink) : sink_(sink ? sink : &null_sink_) {}

double Axis::raw_position_inc() const {
    return pol_ * phys_position_inc();
}

double Axis::phys_position_inc() const {
    return plant_.angle() * res_ / kTwoPi;
}

bool Axis::error_active(uint16_t code) const {
    return std::find(active_.begin(), active_.end(), code) != active_.end() && code != 0;
}

int32_t Axis::clamp_i32(double v) const {
    return static_cast<int32_t>(std::clamp(v, -2147483648.0, 2147483647.0));
}

double Axis::decel_limit(double rpm_s) const {
    const double a = std::min<double>(std::max(rpm_s, 1.0), static_cast<double>(params.max_acceleration));
    return rpm_to_inc_s(a);
}

// ---- position range limit 0x607B (modulo axis) ----------------------------------------------------------

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

// ---- configuration ------------------------------------------------------------------------------------

void Axis::derive() {
    const int32_t res =
        static_cast<int32_t>(std::clamp<uint64_t>(4ull * params.encoder_pulses, 4ull, 1ull << 30));
    const double pol = (params.axis_misc & 0x1) ? -1.0 : 1.0;
    if (res != res_ || pol != pol_) {
        // A new resolution or polarity invalidates the position and the reference [001 §7.2.22].
        const double phys_angle = plant_.angle();
        res_ = res;
        pol_ = pol;
        count_ = static_cast<int64_t>(std::floor(pol_ * phys_angle * res_ / kTwoPi));
        prev_raw_pos_ = phys_angle * res_ / kTwoPi;
        shift_ = 0;
        referenced_ = false;
        obs_pos_ = inc_to_rad(static_cast<double>(count_) + 0.5);
        obs_vel_ = obs_load_ = 0;
        demand_pos_ = static_cast<double>(count_);
        profile_.reset(demand_pos_, 0);
        plant_dirty_ = true;  // the stops are given in increments
    }
    km_ctrl_ = params.torque_constant * 1e-6;
    const double km_plant = km_ctrl_ > 0 ? km_ctrl_ : motor_.torque_constant;
    if (plant_dirty_ || km_plant != km_plant_ || env_.take_stops_changed()) {
        // configure() keeps the state (current, speed, angle): changing the model does not jump.
        plant_.configure(motor_, km_plant, kPlantStep);
        const double lo = std::isnan(env_.stop_lo()) ? -INFINITY : env_.stop_lo() * kTwoPi / res_;
        const double hi = std::isnan(env_.stop_hi()) ? INFINITY : env_.stop_hi() * kTwoPi / res_;
        plant_.set_stops(lo, hi);
        km_plant_ = km_plant;
        plant_dirty_ = false;
    }
    // 0x30A1: bandwidth, damping, reset time, inertia, friction -> cascade gains by pole placement
    // (docs/decisions/drive.md "Control loops").
    const double km = km_ctrl_ > 0 ? km_ctrl_ : km_plant;
    j_ctrl_ = std::max<double>(params.inertia, 1.0) * 1e-10;
    r_ctrl_ = params.friction * 1e-9 * 60.0 / kTwoPi;
    const double wb = kTwoPi * std::max<double>(params.bandwidth, 1.0) * 1e-3;
    const double zeta = std::max<double>(params.damping, 1.0) * 1e-3;
    const double ti = std::max<double>(params.reset_time, 100.0) * 1e-6;
    kv_ = 2.0 * zeta * wb * j_ctrl_ / km;
    kiv_ = kv_ / ti;
    kpp_ = wb / (2.0 * zeta);
    // 0x30A0: 2^-16 V/A; the I gain integrates once per current-loop sample.
    kpi_ = params.current_p / 65536.0;
    kii_ = params.current_i / 65536.0 / kTick;
    kff_i_ = params.current_ff / 65536.0;
}

// ---- device control -----------------------------------------------------------------------------------

void Axis::enter(State s, int number) {
    if (s == state_) return;
    state_ = s;
    (void)number;
    sink_->diag(Severity::Info, 0, to_string(s));
}

void Axis::begin_stop(StopKind kind, double decel_rpm_s, int64_t) {
    stop_ = kind;
    ramp_done_ = false;
    // A stop (quick stop, shutdown, fault) ends a running homing: interrupted, to be started again.
    if (hstat_ == HomingStatus::InProgress) {
        hstat_ = HomingStatus::Interrupted;
        hphase_ = HomingPhase::Finished;
    }
    if (kind == StopKind::Ramp) {
        stop_decel_ = decel_limit(decel_rpm_s);
        // The ramp starts where the motor really is (position and speed), whatever the set-points did.
        profile_.reset(static_cast<double>(count_), obs_vel_ * res_ / kTwoPi);
        control_ = Control::Position;
    } else if (kind == StopKind::Disable) {
        power_ = false;
        ramp_done_ = true;
    }
}

void Axis::device_control(int64_t now_ns) {
    const uint16_t c = command.controlword;
    DeviceCommand dc = decode(c, cw_prev_);
    if ((dc == DeviceCommand::QuickStop && state_ == State::OperationEnabled && faults.quick_stop_ignored) ||
        (dc == DeviceCommand::FaultReset && faults.fault_reset_ignored))
        dc = DeviceCommand::None;
    if (pending_.active || state_ == State::FaultReactionActive) return;  // one command completes first
    if (dc == DeviceCommand::FaultReset && state_ != State::Fault) {
        // A fault reset outside Fault acknowledges warnings ("fault signal only" reactions).
        for (auto& w : warnings_) {
            if (w) sink_->clear(w, error_register_);
            w = 0;
        }
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
                enter(t.to, t.number);
                break;
            case 4: {
                if (km_ctrl_ <= 0) {
                    fault(error_code::TorqueFault, now_ns);
                    return;
                }
                if ((pins_ & 0x30) != 0x30) {
                    fault(error_code::Sto, now_ns);
                    return;
                }
                power_ = true;
                stop_ = StopKind::None;
                vel_int_ = cur_int_ = 0;
                demand_pos_ = static_cast<double>(count_);
                demand_vel_ = demand_acc_ = 0;
                profile_.reset(demand_pos_, 0);
                ip_from_ = ip_to_ = demand_pos_;
                ip_period_ = 0;
                ppm_moving_ = ppm_buffered_ = false;
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
                pending_ = {true, t.to, t.number, now_ns};
                break;
            }
            case 9:
            case 12:
                begin_stop(StopKind::Disable, 0, now_ns);
                pending_ = {true, t.to, t.number, now_ns};
                break;
            case 11:
                // 0x605A = 6 (the only value seed 001 allows): quick-stop ramp, stay in Quick Stop Active.
                begin_stop(StopKind::Ramp, params.quick_stop_deceleration, now_ns);
                enter(State::QuickStopActive, 11);
                break;
            case 15:
                fault_reset();
                break;
            case 16:
                stop_ = StopKind::None;
                demand_pos_ = profile_.position();
                demand_vel_ = 0;
                ip_from_ = ip_to_ = demand_pos_;
                ip_period_ = 0;
                ppm_moving_ = ppm_buffered_ = false;
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
    if (!pending_.active && !fra_) return;
    if (stop_ == StopKind::Ramp && !ramp_done_) return;
    power_ = false;  // the ramp (if any) is over: power stage off
    const bool detection_off = params.standstill_window == kNoWindow;
    const int64_t since = pending_.active ? pending_.since_ns : pending_.since_ns;
    const bool timeout = params.standstill_timeout != 0xFFFF &&
                         now_ns - since >= static_cast<int64_t>(params.standstill_timeout) * 1000000;
    if (!(still_ || detection_off || timeout)) return;
    stop_ = StopKind::None;
    if (fra_) {
        fra_ = false;
        pending_.active = false;
        enter(State::Fault, 14);
    } else {
        pending_.active = false;
        enter(pending_.to, pending_.number);
    }
}

// ---- errors -------------------------------------------------------------------------------------------

void Axis::raise_error(uint16_t code) {
    fault(code, now_ns_);
}

void Axis::connection_lost() {
    // Only a drive that has power on its motor reacts: without power there is nothing to stop, and a master
    // that merely walks the ESM down after disabling the drive must not find a fault on its next start.
    if (!power_) return;
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
        if (std::find(warnings_.begin(), warnings_.end(), code) == warnings_.end()) {
            auto slot = std::find(warnings_.begin(), warnings_.end(), uint16_t{0});
            if (slot != warnings_.end()) *slot = code;
            sink_->diag(Severity::Warning, code, name);
        }
        return;
    }
    if (error_active(code)) return;  // already active: no second emergency
    auto slot = std::find(active_.begin(), active_.end(), uint16_t{0});
    if (slot != active_.end()) *slot = code;
    last_error_ = code;
    error_register_ |= reg;
    const std::array<uint8_t, 5> mfr{static_cast<uint8_t>(state_), static_cast<uint8_t>(mode_), 0, 0, 0};
    sink_->raise(code, error_register_, mfr);

    if (hstat_ == HomingStatus::InProgress) hstat_ = HomingStatus::Error;
    if (state_ == State::Fault) return;
    if (state_ == State::FaultReactionActive) {
        if (rx == Reaction::Disable) begin_stop(StopKind::Disable, 0, now_ns);
        return;
    }
    const bool was_powered = power_;
    pending_ = {false, State::Fault, 14, now_ns};
    fra_ = true;
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
    if (!was_powered && std::abs(vel_avg_rpm_) <= static_cast<double>(params.standstill_window)) {
        fra_ = false;
        stop_ = StopKind::None;
        enter(State::Fault, 14);
    }
}

bool Axis::cause_present(uint16_t code) const {
    switch (code) {
        case error_code::Sto:
            return (pins_ & 0x30) != 0x30;
        case error_code::TorqueFault:
            return km_ctrl_ <= 0;
        case error_code::MaxSpeed:
            return std::abs(obs_vel_) * 60.0 / kTwoPi > static_cast<double>(params.max_motor_speed);
        default:
            return false;
    }
}

void Axis::fault_reset() {
    for (uint16_t c : active_) {
        if (c && cause_present(c)) {
            sink_->diag(Severity::Warning, c, "Fault reset refused: cause still present");
            return;
        }
    }
    for (auto& c : active_) {
        if (!c) continue;
        const uint16_t code = c;
        c = 0;
        uint8_t reg = 0;
        for (uint16_t o : active_)
            if (o) reg |= find_error(o) ? find_error(o)->error_register : 0x01;
        error_register_ = reg;
        sink_->clear(code, error_register_);
    }
    for (auto& w : warnings_) {
        if (w) sink_->clear(w, error_register_);
        w = 0;
    }
    error_register_ = 0;
    last_error_ = 0;
    enter(State::SwitchOnDisabled, 15);
}

// ---- modes --------------------------------------------------------------------------------------------

void Axis::switch_mode(int8_t m) {
    // On-the-fly switching: the new mode takes over from the current demand without a jump.
    if (mode_ == mode::Homing && hstat_ == HomingStatus::InProgress) hstat_ = HomingStatus::Interrupted;
    mode_ = m;
    const double from = power_ ? demand_pos_ : static_cast<double>(count_);
    profile_.reset(from, power_ ? demand_vel_ : 0.0);
    ip_from_ = ip_to_ = from;
    ip_period_ = 0;
    ppm_moving_ = ppm_buffered_ = ppm_ack_ = false;
    vel_ref_ = power_ ? vel_ref_ : 0.0;
    if (m == mode::Homing && hstat_ != HomingStatus::Done) hstat_ = HomingStatus::Idle;
}

void Axis::mode_commands(int64_t now_ns, int64_t dt_ns) {
    const uint16_t c = command.controlword;
    const bool rise4 = (c & cw::NewSetpoint) && !(cw_prev_ & cw::NewSetpoint);
    const bool fall4 = !(c & cw::NewSetpoint) && (cw_prev_ & cw::NewSetpoint);
    const bool enabled = state_ == State::OperationEnabled && !pending_.active && stop_ == StopKind::None;
    halted_ = (c & cw::Halt) != 0 &&
              (mode_ == mode::ProfilePosition || mode_ == mode::ProfileVelocity || mode_ == mode::Homing);
    switch (mode_) {
        case mode::ProfilePosition: {
            if (rise4 && enabled) {
                const bool rel = c & cw::Relative;
                const bool immediate = c & cw::ChangeImmediately;
                if (immediate || !ppm_moving_) {
                    double t = rel          ? demand_pos_ + command.target_position
                               : range_on() ? unwrap(command.target_position, demand_pos_)
                                            : static_cast<double>(command.target_position) -
                                                  static_cast<double>(shift_);
                    // Software position limits act on the demand: clamp the target (internal limit bit).
                    const double lo = params.sw_limit_min == std::numeric_limits<int32_t>::min()
                                          ? -INFINITY
                                          : static_cast<double>(params.sw_limit_min) - shift_;
                    const double hi = params.sw_limit_max == std::numeric_limits<int32_t>::max()
                                          ? INFINITY
                                          : static_cast<double>(params.sw_limit_max) - shift_;
                    ppm_limited_ = t < lo || t > hi;
                    ppm_target_ = std::clamp(t, lo, hi);
                    ppm_moving_ = true;
                    ppm_buffered_ = false;
                    if (!immediate) profile_.reset(demand_pos_, demand_vel_);
                } else {
                    ppm_buffered_ = true;
                    ppm_next_rel_ = rel;
                    ppm_next_raw_ = command.target_position;
                }
                ppm_ack_ = true;
            }
            if (!(c & cw::NewSetpoint) && !ppm_buffered_) ppm_ack_ = false;
            break;
        }
        case mode::Homing:
            if (rise4 && enabled) {
                homing_start();
            } else if (rise4 && !power_ && params.homing_method == 37 && state_ != State::Fault &&
                       state_ != State::FaultReactionActive) {
                // Method 37 while disabled: no offset move, the actual position becomes the home position
                // [001 §4.5.3.11].
                hmethod_ = 37;
                href_ = static_cast<double>(count_);
                shift_ = static_cast<int64_t>(params.home_position) - count_;
                hstat_ = HomingStatus::Done;
                hphase_ = HomingPhase::Finished;
                referenced_ = true;
                sink_->diag(Severity::Info, 0, "Homing attained");
            }
            if (fall4 && hstat_ == HomingStatus::InProgress) {
                hstat_ = HomingStatus::Interrupted;
                hphase_ = HomingPhase::Stopping;
            }
            break;
        case mode::CyclicSyncPosition: {
            // New target each cycle, interpolated linearly over the interpolation period (= this cycle when
            // 0x60C2 is set, as MAXPOS sets it to the SYNC0 cycle; 0 = no interpolation).
            const int64_t tgt = static_cast<int64_t>(command.target_position) + command.position_offset;
            const double t_raw =
                range_on() ? unwrap(static_cast<int32_t>(tgt), ip_to_) : static_cast<double>(tgt - shift_);
            const double now_val =
                ip_period_ > 0
                    ? ip_from_ + (ip_to_ - ip_from_) *
                                     std::min(1.0, static_cast<double>(now_ns - ip_t0_) / ip_period_)
                    : ip_to_;
            ip_from_ = now_val;
            ip_to_ = t_raw;
            ip_t0_ = now_ns;
            ip_period_ = params.interpolation_value != 0 ? dt_ns : 0;
            const bool lim_lo =
                params.sw_limit_min != std::numeric_limits<int32_t>::min() && tgt < params.sw_limit_min;
            const bool lim_hi =
                params.sw_limit_max != std::numeric_limits<int32_t>::max() && tgt > params.sw_limit_max;
            csp_limit_violation_ = enabled && (lim_lo || lim_hi);
            break;
        }
        default:
            break;
    }
}

void Axis::trajectory_tick(int64_t t_ns) {
    const double h = kPosH;
    vel_ff_ = 0;
    torque_ff_a_ = 0;
    const double rated_a = params.nominal_current * 1e-3;  // rated torque / km
    if (!power_) {
        control_ = Control::Position;
        demand_pos_ = static_cast<double>(count_);
        demand_vel_ = demand_acc_ = 0;
        profile_.reset(demand_pos_, 0);
        return;
    }
    auto from_profile = [&] {
        demand_pos_ = profile_.position();
        demand_vel_ = profile_.velocity();
        demand_acc_ = profile_.acceleration();
        control_ = Control::Position;
    };
    if (stop_ == StopKind::Ramp) {
        ramp_done_ = profile_.step_velocity(0.0, stop_decel_, stop_decel_, h) || ramp_done_;
        from_profile();
        return;
    }
    const double acc = decel_limit(params.profile_acceleration);
    const double dec = decel_limit(params.profile_deceleration);
    const double qs = decel_limit(params.quick_stop_deceleration);
    const double vmax = rpm_to_inc_s(std::min(params.profile_velocity, params.max_profile_velocity));
    switch (mode_) {
        case mode::CyclicSyncPosition: {
            const double f =
                ip_period_ > 0 ? std::min(1.0, static_cast<double>(t_ns - ip_t0_) / ip_period_) : 1.0;
            const double p = ip_from_ + (ip_to_ - ip_from_) * f;
            demand_vel_ = (p - demand_pos_) / h;
            demand_acc_ = 0;
            demand_pos_ = p;
            vel_ff_ = kTwoPi * command.velocity_offset / 60.0;
            torque_ff_a_ = command.torque_offset * 1e-3 * rated_a;
            control_ = Control::Position;
            profile_.reset(demand_pos_, demand_vel_);
            return;
        }
        case mode::CyclicSyncVelocity: {
            const double vmot = static_cast<double>(params.max_motor_speed);
            const double v = std::clamp(
                static_cast<double>(command.target_velocity) + command.velocity_offset, -vmot, vmot);
            control_ = Control::Velocity;
            vel_ref_ = kTwoPi * v / 60.0;
            demand_vel_ = rpm_to_inc_s(v);
            demand_pos_ = static_cast<double>(count_);
            torque_ff_a_ = command.torque_offset * 1e-3 * rated_a;
            profile_.reset(demand_pos_, demand_vel_);
            return;
        }
        case mode::CyclicSyncTorque: {
            control_ = Control::Torque;
            const double permille = static_cast<double>(command.target_torque) + command.torque_offset;
            cur_ref_ = permille * 1e-3 * rated_a;
            demand_pos_ = static_cast<double>(count_);
            demand_vel_ = obs_vel_ * res_ / kTwoPi;
            profile_.reset(demand_pos_, demand_vel_);
            return;
        }
        case mode::ProfilePosition:
            if (halted_) {
                profile_.step_velocity(0.0, qs, qs, h);
            } else if (ppm_moving_) {
                if (profile_.step_position(ppm_target_, vmax, acc, dec, h)) {
                    ppm_moving_ = false;
                    if (ppm_buffered_) {
                        ppm_buffered_ = false;
                        const double t = ppm_next_rel_ ? profile_.position() + ppm_next_raw_
                                         : range_on()  ? unwrap(ppm_next_raw_, profile_.position())
                                                       : static_cast<double>(ppm_next_raw_) - shift_;
                        const double lo = params.sw_limit_min == std::numeric_limits<int32_t>::min()
                                              ? -INFINITY
                                              : static_cast<double>(params.sw_limit_min) - shift_;
                        const double hi = params.sw_limit_max == std::numeric_limits<int32_t>::max()
                                              ? INFINITY
                                              : static_cast<double>(params.sw_limit_max) - shift_;
                        ppm_limited_ = t < lo || t > hi;
                        ppm_target_ = std::clamp(t, lo, hi);
                        ppm_moving_ = true;
                    }
                }
            } else {
                profile_.step_velocity(0.0, dec, dec, h);
            }
            from_profile();
            return;
        case mode::ProfileVelocity: {
            const double vlim =
                static_cast<double>(std::min(params.max_profile_velocity, params.max_motor_speed));
            const double v = std::clamp(static_cast<double>(command.target_velocity), -vlim, vlim);
            if (halted_)
                profile_.step_velocity(0.0, qs, qs, h);
            else
                profile_.step_velocity(rpm_to_inc_s(v), acc, dec, h);
            from_profile();
            return;
        }
        case mode::Homing:
            homing_tick(h);
            from_profile();
            return;
        default:
            profile_.step_velocity(0.0, dec, dec, h);
            from_profile();
            return;
    }
}

// ---- control loops ------------------------------------------------------------------------------------

void Axis::position_tick() {
    if (!power_ || control_ != Control::Position) return;
    const double e = inc_to_rad(demand_pos_ - static_cast<double>(count_));
    const bool internal_ff = mode_ != mode::CyclicSyncPosition || stop_ != StopKind::None;
    const double w_ff = internal_ff ? inc_to_rad(demand_vel_) : vel_ff_;
    vel_ref_ = kpp_ * e + w_ff;
    if (internal_ff) {
        // Feed-forward of inertia and viscous friction (0x30A1:04/05) in the profile modes.
        const double km = km_ctrl_ > 0 ? km_ctrl_ : plant_.torque_constant();
        torque_ff_a_ = (j_ctrl_ * inc_to_rad(demand_acc_) + r_ctrl_ * inc_to_rad(demand_vel_)) / km;
    }
}

void Axis::velocity_tick() {
    if (!power_) {
        vel_int_ = 0;
        cur_ref_ = 0;
        return;
    }
    if (control_ == Control::Torque) {
        vel_int_ = 0;
    } else {
        const double e = vel_ref_ - obs_vel_;
        vel_int_ += kiv_ * e * kVelH;
        cur_ref_ = kv_ * e + vel_int_ + torque_ff_a_;
    }
    const double limit = (i2t_active_ ? params.nominal_current : params.output_current_limit) * 1e-3;
    if (cur_ref_ > limit || cur_ref_ < -limit) {
        const double c = std::clamp(cur_ref_, -limit, limit);
        // Anti-windup: the integrator takes back what the limit cut off.
        if (control_ != Control::Torque) vel_int_ = std::clamp(vel_int_ - (cur_ref_ - c), -limit, limit);
        cur_ref_ = c;
    }
}

void Axis::current_tick(int64_t t_ns) {
    double u = 0;
    const double km = plant_.torque_constant();
    if (power_) {
        const double limit = (i2t_active_ ? params.nominal_current : params.output_current_limit) * 1e-3;
        if (control_ == Control::Torque) cur_ref_ = std::clamp(cur_ref_, -limit, limit);
        const double e = cur_ref_ - i_meas();
        cur_int_ += kii_ * e * kTick;
        // Back-EMF decoupling with the estimated speed, plus the 0x30A0:03 feed-forward.
        const double unclamped = kpi_ * e + cur_int_ + km * obs_vel_ + kff_i_ * cur_ref_;
        const double vs = motor_.supply_voltage;
        u = std::clamp(unclamped, -vs, vs);
        if (u != unclamped) cur_int_ -= (unclamped - u);
    } else {
        cur_int_ = 0;
    }
    voltage_ = u;
    for (int k = 0; k < kPlantStepsPerTick; ++k)
        plant_step(t_ns + static_cast<int64_t>((k + 1) * kCurrentTickNs / kPlantStepsPerTick), u);

    // Velocity observer on the encoder count (EPOS4 style, [004 §2.3.2]): model-based prediction with
    // the controller's inertia and torque constant, corrected by the position error.
    // A load-torque state removes the bias friction would otherwise leave in the speed estimate; the three
    // observer poles sit at -kObserverHz.
    const double wo = kTwoPi * kObserverHz;
    const double meas = inc_to_rad(static_cast<double>(count_) + 0.5);
    const double err = meas - obs_pos_;
    const double kmc = km_ctrl_ > 0 ? km_ctrl_ : km;
    obs_pos_ += kTick * (obs_vel_ + 3.0 * wo * err);
    obs_vel_ += kTick * ((kmc * i_meas() - obs_load_ - r_ctrl_ * obs_vel_) / j_ctrl_ + 3.0 * wo * wo * err);
    obs_load_ -= kTick * j_ctrl_ * wo * wo * wo * err;

    // I2t: normalized winding temperature rise, 1.0 = the level continuous nominal current reaches.
    const double tau = std::max<double>(params.thermal_time_constant, 1.0) * 0.1;
    const double in = std::max<double>(params.nominal_current, 1.0) * 1e-3;
    const double ratio = i_meas() / in;
    thermal_ += kTick / tau * (ratio * ratio - thermal_);
    if (thermal_ >= 1.0)
        i2t_active_ = true;
    else if (thermal_ < 0.98)
        i2t_active_ = false;

    const double rpm = obs_vel_ * 60.0 / kTwoPi;
    vel_avg_rpm_ += kAvgAlpha * (rpm - vel_avg_rpm_);
    cur_avg_a_ += kAvgAlpha * (i_meas() - cur_avg_a_);
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

void Axis::plant_step(int64_t t_ns, double u) {
    const double prev = prev_raw_pos_;
    plant_.step(pol_ * u, power_);           // polarity: the motor turns the other way
    const double raw = phys_position_inc();  // the machine sees physical positions
    const uint16_t p = env_.pins(raw, t_ns);
    const uint64_t f = functions(p);
    const uint64_t changed = f ^ func_;
    if (changed) {
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
                if (static_cast<bool>(functions(env_.pins(pos, t)) & m) == before)
                    lo = mid;
                else
                    hi = mid;
            }
            on_edge(bit, !before, pol_ * (prev + (raw - prev) * hi));
        }
    }
    func_ = f;
    pins_ = p;
    // Encoder index: once per revolution at the configured angle (only with a 3-channel encoder).
    if (params.encoder_type & 0x0001) {
        const double p0 = motor_.index_angle / kTwoPi * res_;
        const double k0 = std::floor((prev - p0) / res_), k1 = std::floor((raw - p0) / res_);
        if (k0 != k1) on_index(pol_ * (p0 + std::max(k0, k1) * res_));
    }
    count_ = static_cast<int64_t>(std::floor(pol_ * raw));
    prev_raw_pos_ = raw;
}

// ---- touch probe --------------------------------------------------------------------------------------

void Axis::touch_probe_config() {
    const uint16_t fn = command.touch_probe_function;
    const uint16_t prev = tp_prev_fn_;
    if (!(fn & 0x1)) {
        tp_status_ = 0;
        tp_pos_cnt_ = tp_neg_cnt_ = 0;
    } else {
        if (!(prev & 0x1)) {
            tp_status_ = 0x1;
            tp_pos_cnt_ = tp_neg_cnt_ = 0;
        }
        // Clearing an edge's enable clears its "stored" bit; setting it again re-arms first-event mode.
        if (!(fn & 0x10) || !(prev & 0x10)) tp_status_ &= static_cast<uint16_t>(~0x2u);
        if (!(fn & 0x20) || !(prev & 0x20)) tp_status_ &= static_cast<uint16_t>(~0x4u);
    }
    tp_prev_fn_ = fn;
}

void Axis::tp_latch(bool rising, double raw_pos) {
    const uint16_t fn = command.touch_probe_function;
    if (!(fn & 0x1) || mode_ == mode::Homing) return;  // TP and homing are mutually exclusive [001 §4.5]
    const bool continuous = fn & 0x2;
    const int32_t value = report(static_cast<int64_t>(std::floor(raw_pos)) + shift_);
    if (rising && (fn & 0x10)) {
        if (continuous || !(tp_status_ & 0x2)) {
            tp_pos_ = value;
            tp_status_ |= 0x2;
            tp_pos_cnt_ = continuous ? static_cast<uint16_t>(tp_pos_cnt_ + 1) : 1;
        }
    } else if (!rising && (fn & 0x20)) {
        if (continuous || !(tp_status_ & 0x4)) {
            tp_neg_ = value;
            tp_status_ |= 0x4;
            tp_neg_cnt_ = continuous ? static_cast<uint16_t>(tp_neg_cnt_ + 1) : 1;
        }
    }
}

void Axis::on_edge(int bit, bool rising, double raw_pos) {
    // Touch-probe source [001 §7.2.84]: b3..2 = 00 TP1 input (function 26), 10 = 0x60D0:01.
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
    if (hstat_ == HomingStatus::InProgress && bit == hbit_ && rising == hrise_) {
        const double v = profile_.velocity();
        // Only count the edge when moving the way the phase expects (an overshoot during a reversal
        // must not be taken for the awaited edge).
        if ((hdir_ > 0 && v > 0) || (hdir_ < 0 && v < 0)) {
            hedge_ = true;
            hevent_pos_ = raw_pos;
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
    if (hstat_ == HomingStatus::InProgress && hphase_ == HomingPhase::ToIndex) {
        const double v = profile_.velocity();
        if ((hdir_ > 0 && v > 0) || (hdir_ < 0 && v < 0)) {
            hindex_ = true;
            hevent_pos_ = raw_pos;
        }
    }
}

// ---- supervision --------------------------------------------------------------------------------------

void Axis::standstill(int64_t dt_ns) {
    const bool in = params.standstill_window == kNoWindow ||
                    std::abs(vel_avg_rpm_) <= static_cast<double>(params.standstill_window);
    if (in) {
        still_ms_ += static_cast<double>(dt_ns) * 1e-6;
        still_ = still_ms_ >= params.standstill_time;
    } else {
        still_ms_ = 0;
        still_ = false;
    }
}

void Axis::supervise(int64_t now_ns, int64_t dt_ns) {
    standstill(dt_ns);
    const bool enabled = state_ == State::OperationEnabled && power_ && !pending_.active;
    const bool homing = mode_ == mode::Homing && hstat_ == HomingStatus::InProgress;
    if (enabled) {
        // Following error [001 §4.6]: position-controlled modes.
        const bool pos_mode =
            mode_ == mode::CyclicSyncPosition || mode_ == mode::ProfilePosition || mode_ == mode::Homing;
        const double ferr = std::abs(demand_pos_ - static_cast<double>(count_));
        if (pos_mode && params.following_error_window != kNoWindow &&
            ferr > static_cast<double>(params.following_error_window)) {
            ferr_time_ms_ += static_cast<double>(dt_ns) * 1e-6;
            if (ferr_time_ms_ >= params.following_error_timeout) fault(error_code::FollowingError, now_ns);
        } else {
            ferr_time_ms_ = 0;
        }
    } else {
        ferr_time_ms_ = 0;
    }
    if (enabled && !homing) {
        const double v = control_ == Control::Torque ? obs_vel_ * res_ / kTwoPi : demand_vel_;
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
        const bool check_actual = mode_ != mode::ProfilePosition;
        if ((check_actual && ((below && v < 0) || (above && v > 0))) || csp_limit_violation_)
            fault(error_code::SoftwarePositionLimit, now_ns);
    }
    if (power_ && std::abs(obs_vel_) * 60.0 / kTwoPi > static_cast<double>(params.max_motor_speed))
        fault(error_code::MaxSpeed, now_ns);
    if (power_ && (pins_ & 0x30) != 0x30) fault(error_code::Sto, now_ns);
    check_pending(now_ns);
}

// ---- the cycle ----------------------------------------------------------------------------------------

void Axis::cycle(int64_t now_ns, int64_t dt_ns) {
    now_ns_ = now_ns;
    derive();
    if (state_ == State::NotReadyToSwitchOn) {
        pins_ = env_.pins(phys_position_inc(), now_ns);
        func_ = functions(pins_);
        prev_raw_pos_ = phys_position_inc();
        count_ = static_cast<int64_t>(std::floor(raw_position_inc()));
        obs_pos_ = inc_to_rad(static_cast<double>(count_) + 0.5);
        enter(State::SwitchOnDisabled, 1);
    }
    touch_probe_config();
    if (command.mode != mode_ && mode::supported(command.mode)) switch_mode(command.mode);
    device_control(now_ns);
    mode_commands(now_ns, dt_ns);
    // At most one second of simulated time per call: a caller that skipped time (or passed a bogus dt)
    // must not stall its thread for minutes.
    dt_ns = std::min<int64_t>(dt_ns, 1'000'000'000);
    if (dt_ns > 0) {
        const int64_t total = residual_ns_ + dt_ns;
        const int64_t ticks = total / kCurrentTickNs;
        residual_ns_ = total % kCurrentTickNs;
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
        if (!std::isfinite(obs_vel_) || !std::isfinite(obs_pos_) || !std::isfinite(obs_load_) ||
            !std::isfinite(vel_int_) || !std::isfinite(cur_int_) || !std::isfinite(cur_ref_)) {
            obs_pos_ = inc_to_rad(static_cast<double>(count_) + 0.5);
            obs_vel_ = obs_load_ = vel_int_ = cur_int_ = cur_ref_ = vel_ref_ = 0;
            fault(error_code::ControllerGain, now_ns);
        }
        supervise(now_ns + dt_ns, dt_ns);
    }
    update_feedback();
    cw_prev_ = command.controlword;
}

void Axis::update_feedback() {
    Feedback& f = fb_;
    uint16_t s = state_bits(state_, power_);
    if (state_ != State::NotReadyToSwitchOn) s |= sw::Reserved8;
    s |= sw::Remote;
    if (std::any_of(warnings_.begin(), warnings_.end(), [](uint16_t w) { return w != 0; })) s |= sw::Warning;
    if (i2t_active_ || (mode_ == mode::ProfilePosition && ppm_limited_)) s |= sw::InternalLimit;
    if (referenced_) s |= sw::Referenced;
    const bool oe = state_ == State::OperationEnabled && !pending_.active;
    const bool ferr =
        params.following_error_window != kNoWindow && std::abs(demand_pos_ - static_cast<double>(count_)) >
                                                          static_cast<double>(params.following_error_window);
    switch (mode_) {
        case mode::ProfilePosition:
            if (halted_ ? profile_.velocity() == 0.0 : !ppm_moving_) s |= sw::TargetReached;
            if (ppm_ack_) s |= sw::Bit12;
            if (ferr && power_) s |= sw::Bit13;
            break;
        case mode::ProfileVelocity: {
            const double vlim =
                static_cast<double>(std::min(params.max_profile_velocity, params.max_motor_speed));
            const double target =
                halted_ ? 0.0
                        : rpm_to_inc_s(std::clamp(static_cast<double>(command.target_velocity), -vlim, vlim));
            if (profile_.velocity() == target) s |= sw::TargetReached;
            if (std::abs(vel_avg_rpm_) <= static_cast<double>(params.standstill_window)) s |= sw::Bit12;
            break;
        }
        case mode::Homing:
            switch (hstat_) {
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
                    if (std::abs(vel_avg_rpm_) <= static_cast<double>(params.standstill_window) && still_)
                        s |= sw::TargetReached;
                    break;
            }
            break;
        case mode::CyclicSyncPosition:
            if (oe && stop_ == StopKind::None) s |= sw::Bit12;
            if (ferr && power_) s |= sw::Bit13;
            break;
        case mode::CyclicSyncVelocity:
        case mode::CyclicSyncTorque:
            if (oe && stop_ == StopKind::None) s |= sw::Bit12;
            break;
        default:
            break;
    }
    if (state_ == State::QuickStopActive && ramp_done_) s |= sw::TargetReached;
    f.statusword = s;
    if (!faults.mode_display_stuck || f.mode_display == mode::None) f.mode_display = mode_;
    f.position_actual = report(count_ + shift_);
    f.position_demand = report(static_cast<int64_t>(std::llround(demand_pos_)) + shift_);
    f.following_error = clamp_i32(std::round(demand_pos_ - static_cast<double>(count_)));
    const double vd = control_ == Control::Velocity ? vel_ref_ * 60.0 / kTwoPi : demand_vel_ * 60.0 / res_;
    f.velocity_demand = clamp_i32(std::round(vd));
    f.velocity_actual = clamp_i32(std::round(obs_vel_ * 60.0 / kTwoPi));
    f.velocity_averaged = clamp_i32(std::round(vel_avg_rpm_));
    const double in = std::max<double>(params.nominal_current, 1.0) * 1e-3;
    f.torque_actual = sat16(i_meas() / in * 1000.0);
    f.current_actual = sat16(i_meas() * 1000.0);
    f.current_demand = sat16(power_ ? cur_ref_ * 1000.0 : 0.0);
    f.current_averaged = sat16(cur_avg_a_ * 1000.0);
    f.motor_rated_torque =
        static_cast<uint32_t>(static_cast<uint64_t>(params.nominal_current) * params.torque_constant / 1000u);
    f.digital_inputs = static_cast<uint32_t>(func_ & 0x033F0007ull);
    f.input_logic_state = pins_;
    f.index_position = report(index_count_ + shift_);
    f.touch_probe_status = tp_status_;
    f.touch_probe_pos = tp_pos_;
    f.touch_probe_neg = tp_neg_;
    f.touch_probe_pos_count = tp_pos_cnt_;
    f.touch_probe_neg_count = tp_neg_cnt_;
    f.error_code = last_error_;
    f.error_register = error_register_;
}

}  // namespace drive
