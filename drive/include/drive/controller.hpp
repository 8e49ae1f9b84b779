#pragma once
// The cascaded loops of one axis (position P 2.5 kHz, velocity PI 5 kHz, current PI 25 kHz), the velocity
// observer and the I2t model, with the gains derived from 0x30A0/0x30A1 (docs/decisions/drive.md "Control
// loops"). Angles and speeds in rad and rad/s of the raw frame, currents in A. Axis runs the loops at their
// rates (position(), velocity(), observe(); the current loop is written out in Axis's flattened sample) and
// tells them what they need: the set-point generator's demand and reference, the measured current and
// position, the power stage.
#include <cstdint>

#include "drive/setpoint.hpp"

namespace drive {

struct Parameters;

// The loop state stays readable (the feedback and the tests show it); the loops own its changes.
struct Controller {
    // gains derived from the parameters
    double km = 0, j = 1e-5, r = 0;      // torque constant (0 = not configured), inertia, viscous friction
    double kv = 0, kiv = 0, kpp = 0;     // velocity PI (A s/rad, A/rad), position P (1/s)
    double kpi = 0, kii = 0, kff_i = 0;  // current PI
    // constants of observe() that only change with the parameters (set by tune())
    double obs_load_gain = 0;   // kTick j wo^3
    double inv_j = 1e5;         // 1 / j
    double i2t_rate = 0;        // kTick / thermal time constant
    double i2t_nominal = 1e-3;  // A
    // loop state
    double vel_ref = 0;      // rad/s, output of the position loop / CSV input
    double vel_ff = 0;       // rad/s
    double torque_ff_a = 0;  // A (current feed-forward)
    double cur_ref = 0;      // A
    double vel_int = 0, cur_int = 0;
    double voltage = 0;
    // observer
    double obs_pos = 0, obs_vel = 0;  // rad, rad/s (raw frame)
    double obs_load = 0;              // Nm, estimated load + friction torque
    double vel_avg_rpm = 0, cur_avg_a = 0;
    // I2t
    double thermal = 0;
    bool i2t_active = false;

    // Gains by pole placement from 0x30A1 and 0x30A0; `km_plant` stands in when 0x3001:05 is 0. Called every
    // cycle; recomputes only when one of its inputs changed.
    void tune(const Parameters& p, double km_plant);
    // The inputs tune() last computed from (0x3001:01/:04/:05, 0x30A0:01-03, 0x30A1:01-05, km_plant).
    struct TuneInputs {
        uint32_t torque_constant = 0, inertia = 0, friction = 0, bandwidth = 0, damping = 0, reset_time = 0,
                 current_p = 0, current_i = 0, current_ff = 0;
        uint16_t thermal_time_constant = 0, nominal_current = 0;
        double km_plant = 0;
        bool valid = false;
        bool operator==(const TuneInputs&) const = default;
    } tuned;
    // A trajectory tick's feed-forwards, and the reference of the loop the set-point enters (`control`).
    void follow(const LoopReference& ref, Control control) {
        vel_ff = ref.vel_ff;
        torque_ff_a = ref.torque_ff_a;
        if (control == Control::Velocity) vel_ref = ref.vel_ref;
        if (control == Control::Torque) cur_ref = ref.cur_ref;
    }
    // Transition 4: the integrators start empty.
    void power_on() { vel_int = cur_int = 0; }
    // A new mode of operation: without power the speed reference drops to zero.
    void mode_switched(bool power) { vel_ref = power ? vel_ref : 0.0; }
    // The observer starts at `pos_rad` (start-up).
    void start_at(double pos_rad) { obs_pos = pos_rad; }
    // The encoder frame changed (resolution, polarity): the observer restarts at rest at `pos_rad`.
    void rebase(double pos_rad) {
        obs_pos = pos_rad;
        obs_vel = obs_load = 0;
    }
    // 0x3001:05 in uNm/A (0 = not configured); tune() derives the gains from it.
    void set_torque_constant(uint32_t unm_per_a) { km = unm_per_a * 1e-6; }
    // Position loop (P, 2.5 kHz) on the demand (raw inc, inc/s, inc/s^2) against the encoder count `actual`:
    // the speed reference; with `internal_ff` (profile modes, stops) the demand's own speed and the inertia
    // and friction feed-forward, otherwise the CSP velocity offset. `rad_per_inc`: 2 pi / resolution.
    void position(double demand_pos, double demand_vel, double demand_acc, double actual, bool internal_ff,
                  double km_plant, double rad_per_inc);
    // Velocity loop (PI, 5 kHz): the current reference, limited to 0x3001:02 (0x3001:01 while I2t limits),
    // in mA; `torque_control`: CST sets the current reference itself.
    void velocity(bool power, bool torque_control, uint16_t nominal_ma, uint16_t output_limit_ma);
    // The current limit, A: 0x3001:02, or 0x3001:01 while I2t limits (both mA).
    double current_limit(uint16_t nominal_ma, uint16_t output_limit_ma) const {
        return (i2t_active ? nominal_ma : output_limit_ma) * 1e-3;
    }
    // One current-loop sample of the observer (measured angle, measured current), the I2t model and the
    // averaged values; `km_plant` stands in for an unconfigured torque constant.
    void observe(double meas_rad, double i_meas, double km_plant);
    // The estimates diverged (absurd gains): true if any is not finite.
    bool diverged() const;
    void reset_estimates(double pos_rad);
};

}  // namespace drive
