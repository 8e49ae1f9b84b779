#pragma once
// The simulated motor and load: winding (R, L, back-EMF), rotor + load inertia with viscous and Coulomb
// friction, and optional hard mechanical stops. State x = [i (A), omega (rad/s), theta (rad)], input =
// winding voltage. The linear part is discretized exactly (matrix exponential, Eigen) for the integration
// step; Coulomb friction, stiction and the stops are applied per step. Nothing here allocates after
// configure().
#include <Eigen/Dense>
#include <cmath>
#include <limits>

namespace drive {

// Physical data of the simulated motor and load. Values the object dictionary carries (torque constant,
// current limits, pole pairs, thermal time constant) come from there; these are the ones it does not have.
// Defaults: maxon EC-4pole 30 with load, the EPOS4 tuning example 2 (EPOS4 Application Notes §2.4).
struct MotorModel {
    double resistance = 0.836;           // ohm, terminal resistance
    double inductance = 0.118e-3;        // H
    double torque_constant = 25.5e-3;    // Nm/A, used when 0x3001:05 is 0
    double rotor_inertia = 33.3e-7;      // kg m^2
    double load_inertia = 155.0e-7;      // kg m^2 (rotor + load = 188.3 g cm^2 as in the example)
    double viscous_friction = 445.7e-6;  // Nm/(rad/s)
    double coulomb_friction = 6.88e-3;   // Nm
    double supply_voltage = 48.0;        // V, the power stage's limit
    double index_angle = 0.25;           // rad, where the encoder index pulse sits within a turn
};

class Plant {
  public:
    // Recomputes the discrete model for step h (s). Cheap enough to call when a parameter changes.
    void configure(const MotorModel& m, double torque_constant, double h);
    // One integration step with winding voltage u (V) and external load torque (Nm, positive = positive
    // direction). With power off the winding is open: the current decays to zero and no torque is made.
    inline void step(double u, bool power_on, double load_torque = 0.0);
    // The same step on a copy of the state the caller holds (in registers: the drive runs 100 steps per 1 ms
    // cycle, docs/decisions/drive.md "Cost of a cycle"); returns whether the step ended at a stop. Hand the
    // state back with set_state().
    struct State {
        double current, velocity, angle;
    };
    State state() const { return {x_(0), x_(1), x_(2)}; }
    void set_state(const State& s, bool at_stop) {
        x_ << s.current, s.velocity, s.angle;
        at_stop_ = at_stop;
    }
    inline bool advance(State& s, double u, bool power_on, double load_torque = 0.0) const;
    // kHeldSteps steps with power on, voltage u held and no load torque, all computed from s at once (no
    // chain from step to step): x_k = Phi^k x0 + G_k u + T_k tau with the Coulomb term tau = -sign(w0)
    // coulomb constant. That is what advance() gives (up to rounding in the last bits) as long as the
    // velocity keeps its sign and no stop is reached, so the result is taken only when every step's velocity
    // is nonzero with the sign of s.velocity and every step's angle lies strictly between the stops: then s
    // becomes the last step's state, angles[] gets each step's angle, and the steps ended away from a stop.
    // Otherwise (at rest, a zero crossing, a stop, NaN) it returns false with s untouched and the caller runs
    // advance() kHeldSteps times. docs/decisions/drive.md "Cost of a cycle".
    static constexpr int kHeldSteps = 4;
    inline bool advance_held(State& s, double u, double (&angles)[kHeldSteps]) const;

    double current() const { return x_(0); }
    double velocity() const { return x_(1); }
    double angle() const { return x_(2); }
    double torque_constant() const { return km_; }
    double inertia() const { return j_; }
    double step_size() const { return h_; }
    // Teleport (tests): put the rotor at an angle, at rest.
    void set_angle(double theta) { x_ << 0.0, 0.0, theta; }
    // Hard stops in rad (defaults: none).
    void set_stops(double lo, double hi) {
        lo_ = lo;
        hi_ = hi;
    }
    bool at_stop() const { return at_stop_; }

  private:
    Eigen::Matrix3d phi_ = Eigen::Matrix3d::Identity();
    Eigen::Vector3d gamma_u_ = Eigen::Vector3d::Zero();       // input: voltage
    Eigen::Vector3d gamma_t_ = Eigen::Vector3d::Zero();       // input: torque on the shaft
    Eigen::Matrix2d phi_mech_ = Eigen::Matrix2d::Identity();  // power off: [omega, theta] only
    Eigen::Vector2d gamma_mech_ = Eigen::Vector2d::Zero();
    Eigen::Vector3d x_ = Eigen::Vector3d::Zero();
    // advance_held(): the rows of [Phi^k | G_k | T_k] for k = 1..kHeldSteps, velocity and angle side by side
    // (the two are computed as one pair: GCC/Clang vector extension, SSE2 on x86-64), and the current's row
    // for the last step.
    typedef double Pair __attribute__((vector_size(16)));
    template <typename T>
    struct HeldRow {
        T p0{}, p1{}, p2{}, gu{}, gt{};
        T apply(double x0, double x1, double x2, double u, double tau) const {
            // Grouped as advance() groups one step (the input terms apart from the state).
            return (p0 * x0 + p1 * x1) + (p2 * x2 + (gu * u + gt * tau));
        }
    };
    HeldRow<Pair> held_[kHeldSteps];
    HeldRow<double> held_i_;
    double km_ = 0.0, j_ = 1.0, coulomb_ = 0.0, h_ = 1e-5, l_ = 1e-3, r_ = 1.0;
    double lo_ = -std::numeric_limits<double>::infinity();
    double hi_ = std::numeric_limits<double>::infinity();
    bool at_stop_ = false;
};

inline void Plant::step(double u, bool power_on, double load_torque) {
    State s{x_(0), x_(1), x_(2)};
    at_stop_ = advance(s, u, power_on, load_torque);
    x_ << s.current, s.velocity, s.angle;
}

inline bool Plant::advance(State& s, double u, bool power_on, double load_torque) const {
    const double w0 = s.velocity;
    const double motor_torque = power_on ? km_ * s.current : 0.0;
    // Coulomb friction: opposes motion; at rest it holds as long as the driving torque is below it.
    double friction;
    if (w0 != 0.0) {
        friction = w0 > 0 ? -coulomb_ : coulomb_;
    } else {
        const double drive = motor_torque + load_torque;
        friction = std::abs(drive) <= coulomb_ ? -drive : (drive > 0 ? -coulomb_ : coulomb_);
    }
    const double torque = load_torque + friction;
    const double x0 = s.current, x1 = s.velocity, x2 = s.angle;
    if (power_on) {
        // x = phi x + gamma_u u + gamma_t torque, summed as a tree (the input terms do not wait for x)
        const double f0 = gamma_u_(0) * u + gamma_t_(0) * torque;
        const double f1 = gamma_u_(1) * u + gamma_t_(1) * torque;
        const double f2 = gamma_u_(2) * u + gamma_t_(2) * torque;
        s.current = (phi_(0, 0) * x0 + phi_(0, 1) * x1) + (phi_(0, 2) * x2 + f0);
        s.velocity = (phi_(1, 0) * x0 + phi_(1, 1) * x1) + (phi_(1, 2) * x2 + f1);
        s.angle = (phi_(2, 0) * x0 + phi_(2, 1) * x1) + (phi_(2, 2) * x2 + f2);
    } else {
        // Open winding: no current path (the power stage is off), current ends at once.
        s.current = 0.0;
        s.velocity = phi_mech_(0, 0) * x1 + phi_mech_(0, 1) * x2 + gamma_mech_(0) * torque;
        s.angle = phi_mech_(1, 0) * x1 + phi_mech_(1, 1) * x2 + gamma_mech_(1) * torque;
    }
    // Friction cannot reverse the motion within one step: stop at the zero crossing instead.
    if (w0 != 0.0 && (s.velocity > 0) != (w0 > 0)) {
        const double drive = (power_on ? km_ * s.current : 0.0) + load_torque;
        if (std::abs(drive) <= coulomb_) s.velocity = 0.0;
    }
    if (s.angle >= hi_) {
        s.angle = hi_;
        if (s.velocity > 0) s.velocity = 0.0;
        return true;
    }
    if (s.angle <= lo_) {
        s.angle = lo_;
        if (s.velocity < 0) s.velocity = 0.0;
        return true;
    }
    return false;
}

inline bool Plant::advance_held(State& s, double u, double (&angles)[kHeldSteps]) const {
    const double w0 = s.velocity;
    const double sg = w0 > 0 ? 1.0 : -1.0;
    if (!(sg * w0 > 0)) return false;  // at rest (stiction decides) or NaN
    const double tau = -sg * coulomb_;
    const double x0 = s.current, x1 = w0, x2 = s.angle;
    // Strictly inside: the velocity on w0's side of zero (and finite), the angle between the stops. Tested on
    // the smallest and largest of the steps (packed min/max) and their sum, which is NaN when any step is.
    Pair wa = held_[0].apply(x0, x1, x2, u, tau);
    angles[0] = wa[1];
    Pair mn = wa, mx = wa, sum = wa;
#pragma GCC unroll 4
    for (int k = 1; k < kHeldSteps; ++k) {
        wa = held_[k].apply(x0, x1, x2, u, tau);
        angles[k] = wa[1];
        mn = wa < mn ? wa : mn;
        mx = wa > mx ? wa : mx;
        sum += wa;
    }
    const bool inside = (sg > 0 ? mn[0] > 0 && mx[0] < INFINITY : mx[0] < 0 && mn[0] > -INFINITY) &&
                        mn[1] > lo_ && mx[1] < hi_ && sum[0] == sum[0] && sum[1] == sum[1];
    if (!inside) return false;
    s.current = held_i_.apply(x0, x1, x2, u, tau);
    s.velocity = wa[0];
    s.angle = wa[1];
    return true;
}

// exp(M) for a small dense matrix (scaling and squaring with a Taylor series); used to discretize the plant.
Eigen::MatrixXd expm(const Eigen::MatrixXd& m);

}  // namespace drive
