#include "drive/plant.hpp"

#include <cmath>

namespace drive {

Eigen::MatrixXd expm(const Eigen::MatrixXd& m) {
    const double norm = m.cwiseAbs().rowwise().sum().maxCoeff();
    int squarings = 0;
    if (norm > 0.5) squarings = static_cast<int>(std::ceil(std::log2(norm / 0.5)));
    const Eigen::MatrixXd a = m / std::ldexp(1.0, squarings);
    Eigen::MatrixXd term = Eigen::MatrixXd::Identity(m.rows(), m.cols());
    Eigen::MatrixXd sum = term;
    for (int k = 1; k <= 18; ++k) {
        term = term * a / static_cast<double>(k);
        sum += term;
    }
    for (int i = 0; i < squarings; ++i)
        sum = sum * sum;
    return sum;
}

void Plant::configure(const MotorModel& model, double torque_constant, double h) {
    // A physical motor has positive R, L and J; keep the model there whatever the caller set (NaN included).
    auto at_least = [](double v, double lo) { return std::isfinite(v) && v > lo ? v : lo; };
    MotorModel m = model;
    m.resistance = at_least(m.resistance, 1e-3);
    m.inductance = at_least(m.inductance, 1e-6);
    m.rotor_inertia = at_least(m.rotor_inertia, 1e-9);
    m.load_inertia = at_least(m.load_inertia, 0.0);
    m.viscous_friction = at_least(m.viscous_friction, 0.0);
    m.coulomb_friction = at_least(m.coulomb_friction, 0.0);
    km_ = std::isfinite(torque_constant) ? torque_constant : 0.0;
    j_ = m.rotor_inertia + m.load_inertia;
    coulomb_ = m.coulomb_friction;
    h_ = at_least(h, 1e-9);
    h = h_;
    l_ = m.inductance;
    r_ = m.resistance;
    const double b = m.viscous_friction;
    // Augmented system [x; u; T]' = [[A, B, E], [0, 0, 0]] [x; u; T] with inputs held over the step.
    Eigen::MatrixXd aug = Eigen::MatrixXd::Zero(5, 5);
    aug(0, 0) = -m.resistance / m.inductance;
    aug(0, 1) = -km_ / m.inductance;
    aug(1, 0) = km_ / j_;
    aug(1, 1) = -b / j_;
    aug(2, 1) = 1.0;
    aug(0, 3) = 1.0 / m.inductance;
    aug(1, 4) = 1.0 / j_;
    const Eigen::MatrixXd e = expm(aug * h);
    phi_ = e.block<3, 3>(0, 0);
    gamma_u_ = e.block<3, 1>(0, 3);
    gamma_t_ = e.block<3, 1>(0, 4);
    // advance_held(): the same augmented system over k steps gives [Phi^k | G_k | T_k] in one exponential.
    for (int k = 1; k <= kHeldSteps; ++k) {
        const Eigen::MatrixXd ek = k == 1 ? e : expm(aug * (h * k));
        auto pair = [&](int c) { return Pair{ek(1, c), ek(2, c)}; };  // velocity, angle
        held_[k - 1] = {pair(0), pair(1), pair(2), pair(3), pair(4)};
        if (k == kHeldSteps) held_i_ = {ek(0, 0), ek(0, 1), ek(0, 2), ek(0, 3), ek(0, 4)};
    }
    // Power off: mechanics alone, [omega, theta].
    Eigen::MatrixXd mech = Eigen::MatrixXd::Zero(3, 3);
    mech(0, 0) = -b / j_;
    mech(1, 0) = 1.0;
    mech(0, 2) = 1.0 / j_;
    const Eigen::MatrixXd em = expm(mech * h);
    phi_mech_ = em.block<2, 2>(0, 0);
    gamma_mech_ = em.block<2, 1>(0, 2);
}

}  // namespace drive
