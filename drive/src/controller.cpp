// The control loops, the observer and the I2t model (Controller), and the one piece of Axis that runs them in
// the current-loop sample with the machine's steps (Axis::current_tick): here, so the controller's current
// loop and observer compile into the flattened sample (docs/decisions/drive.md "Cost of a cycle").
#include "drive/controller.hpp"

#include "drive/axis.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "axis_internal.hpp"
#include "machine_step.hpp"

namespace drive {

using namespace detail;

void Controller::position(double demand_pos, double demand_vel, double demand_acc, double actual,
                          bool internal_ff, double km_plant, double rad_per_inc) {
    const double e = (demand_pos - actual) * rad_per_inc;
    const double w_ff = internal_ff ? demand_vel * rad_per_inc : vel_ff;
    vel_ref = kpp * e + w_ff;
    if (internal_ff) {
        // Feed-forward of inertia and viscous friction (0x30A1:04/05) in the profile modes.
        const double k = km > 0 ? km : km_plant;
        torque_ff_a = (j * (demand_acc * rad_per_inc) + r * (demand_vel * rad_per_inc)) / k;
    }
}

void Controller::velocity(bool power, bool torque_control, uint16_t nominal_ma, uint16_t output_limit_ma) {
    if (!power) {
        vel_int = 0;
        cur_ref = 0;
        return;
    }
    if (torque_control) {
        vel_int = 0;
    } else {
        const double e = vel_ref - obs_vel;
        vel_int += kiv * e * kVelH;
        cur_ref = kv * e + vel_int + torque_ff_a;
    }
    const double limit = current_limit(nominal_ma, output_limit_ma);
    if (cur_ref > limit || cur_ref < -limit) {
        const double c = std::clamp(cur_ref, -limit, limit);
        // Anti-windup: the integrator takes back what the limit cut off.
        if (!torque_control) vel_int = std::clamp(vel_int - (cur_ref - c), -limit, limit);
        cur_ref = c;
    }
}

// Flattened: the four machine steps and the observer compile into the sample (docs/decisions/drive.md "Cost
// of a cycle").
[[gnu::flatten]] void Axis::current_tick(int64_t t_ns) {
    // The current loop (PI) with back-EMF decoupling, written out here rather than as a Controller method:
    // as a call (inlined or not) it made the sample 8 % slower (drive-sim --bench 1001 -> 1081 ns, the
    // registers of the four plant steps below spill), written out it costs nothing (docs/decisions/drive.md
    // "Cost of a cycle"). It changes only the controller's current-loop state.
    double u = 0;
    const double km = plant_.torque_constant();
    const bool power = dc_.power();
    if (power) {
        const double limit = ctl_.current_limit(params.nominal_current, params.output_current_limit);
        if (sp_.control() == Control::Torque) ctl_.cur_ref = std::clamp(ctl_.cur_ref, -limit, limit);
        const double e = ctl_.cur_ref - i_meas();
        ctl_.cur_int += ctl_.kii * e * kTick;
        const double unclamped = ctl_.kpi * e + ctl_.cur_int + km * ctl_.obs_vel + ctl_.kff_i * ctl_.cur_ref;
        const double vs = motor_.supply_voltage;
        u = std::clamp(unclamped, -vs, vs);
        if (u != unclamped) ctl_.cur_int -= (unclamped - u);
    } else {
        ctl_.cur_int = 0;
    }
    ctl_.voltage = u;
    // The machine in 10 us steps, its state in registers meanwhile (nothing called from machine_step reads
    // the plant or the count); the encoder count is taken at the end, from the last step's position.
    Plant::State x = plant_.state();
    bool at_stop = plant_.at_stop();
    const double u_motor = pol_ * u;  // polarity: the motor turns the other way
    // With power on the four steps come from the state at once while the friction sign holds and no stop
    // is near (Plant::advance_held); otherwise, one after the other.
    static_assert(kPlantStepsPerTick == Plant::kHeldSteps);
    double angles[Plant::kHeldSteps];
    if (power && plant_.advance_held(x, u_motor, angles)) {
        at_stop = false;
        for (int k = 0; k < kPlantStepsPerTick; ++k)
            machine_step(angles[k] * inc_per_rad_,
                         t_ns + static_cast<int64_t>((k + 1) * kCurrentTickNs / kPlantStepsPerTick));
    } else {
        for (int k = 0; k < kPlantStepsPerTick; ++k) {
            at_stop = plant_.advance(x, u_motor, power);
            machine_step(x.angle * inc_per_rad_,
                         t_ns + static_cast<int64_t>((k + 1) * kCurrentTickNs / kPlantStepsPerTick));
        }
    }
    plant_.set_state(x, at_stop);
    count_ = floor_to_int(pol_ * prev_raw_pos_);

    ctl_.observe(inc_to_rad(static_cast<double>(count_) + 0.5), i_meas(), km);
}

void Controller::observe(double meas_rad, double i_meas, double km_plant) {
    // Velocity observer on the encoder count (EPOS4 style, EPOS4 Application Notes §2.3.2): model-based
    // prediction with the controller's inertia and torque constant, corrected by the position error.
    // A load-torque state removes the bias friction would otherwise leave in the speed estimate; the three
    // observer poles sit at -kObserverHz.
    const double wo = kTwoPi * kObserverHz;
    const double err = meas_rad - obs_pos;
    const double kmc = km > 0 ? km : km_plant;
    obs_pos += kTick * (obs_vel + 3.0 * wo * err);
    obs_vel += kTick * ((kmc * i_meas - obs_load - r * obs_vel) * inv_j + 3.0 * wo * wo * err);
    obs_load -= obs_load_gain * err;

    // I2t: normalized winding temperature rise, 1.0 = the level continuous nominal current reaches.
    const double ratio = i_meas / i2t_nominal;
    thermal += i2t_rate * (ratio * ratio - thermal);
    if (thermal >= 1.0)
        i2t_active = true;
    else if (thermal < 0.98)
        i2t_active = false;

    // One multiplication: a division here held back every sample (docs/decisions/drive.md "Cost of a cycle").
    const double rpm = obs_vel * (60.0 / kTwoPi);
    vel_avg_rpm += kAvgAlpha * (rpm - vel_avg_rpm);
    cur_avg_a += kAvgAlpha * (i_meas - cur_avg_a);
}

void Controller::tune(const Parameters& p, double km_plant) {
    const TuneInputs in{p.torque_constant, p.inertia,   p.friction,  p.bandwidth,  p.damping,
                        p.reset_time,      p.current_p, p.current_i, p.current_ff, p.thermal_time_constant,
                        p.nominal_current, km_plant,    true};
    if (in == tuned) return;
    tuned = in;
    // 0x30A1: bandwidth, damping, reset time, inertia, friction -> cascade gains by pole placement
    // (docs/decisions/drive.md "Control loops").
    set_torque_constant(p.torque_constant);
    const double k = km > 0 ? km : km_plant;
    j = std::max<double>(p.inertia, 1.0) * 1e-10;
    r = p.friction * 1e-9 * 60.0 / kTwoPi;
    const double wb = kTwoPi * std::max<double>(p.bandwidth, 1.0) * 1e-3;
    const double zeta = std::max<double>(p.damping, 1.0) * 1e-3;
    const double ti = std::max<double>(p.reset_time, 100.0) * 1e-6;
    kv = 2.0 * zeta * wb * j / k;
    kiv = kv / ti;
    kpp = wb / (2.0 * zeta);
    // 0x30A0: 2^-16 V/A; the I gain integrates once per current-loop sample.
    kpi = p.current_p / 65536.0;
    kii = p.current_i / 65536.0 / kTick;
    kff_i = p.current_ff / 65536.0;
    // observe(): the same products in the same order, once per cycle instead of 25 times.
    const double wo = kTwoPi * kObserverHz;
    obs_load_gain = kTick * j * wo * wo * wo;
    inv_j = 1.0 / j;
    const double tau = std::max<double>(p.thermal_time_constant, 1.0) * 0.1;
    i2t_rate = kTick / tau;
    i2t_nominal = std::max<double>(p.nominal_current, 1.0) * 1e-3;
}

bool Controller::diverged() const {
    return !std::isfinite(obs_vel) || !std::isfinite(obs_pos) || !std::isfinite(obs_load) ||
           !std::isfinite(vel_int) || !std::isfinite(cur_int) || !std::isfinite(cur_ref);
}

void Controller::reset_estimates(double pos_rad) {
    obs_pos = pos_rad;
    obs_vel = obs_load = vel_int = cur_int = cur_ref = vel_ref = 0;
}

}  // namespace drive
