#pragma once
// The simulated motor and load: winding (R, L, back-EMF), rotor + load inertia with viscous and Coulomb
// friction, and optional hard mechanical stops. State x = [i (A), omega (rad/s), theta (rad)], input =
// winding voltage. The linear part is discretized exactly (matrix exponential, Eigen) for the integration
// step; Coulomb friction, stiction and the stops are applied per step. Nothing here allocates after
// configure().
#include <Eigen/Dense>
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
    void step(double u, bool power_on, double load_torque = 0.0);

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
    double km_ = 0.0, j_ = 1.0, coulomb_ = 0.0, h_ = 1e-5, l_ = 1e-3, r_ = 1.0;
    double lo_ = -std::numeric_limits<double>::infinity();
    double hi_ = std::numeric_limits<double>::infinity();
    bool at_stop_ = false;
};

// exp(M) for a small dense matrix (scaling and squaring with a Taylor series); used to discretize the plant.
Eigen::MatrixXd expm(const Eigen::MatrixXd& m);

}  // namespace drive
