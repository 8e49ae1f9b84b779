// The simulated machine: plant discretization, current loop, encoder resolution, I2t limitation.
#include "rig.hpp"

using namespace drive;
using namespace drive::test;

TEST(Plant, ExpmMatchesTheScalarExponential) {
    Eigen::MatrixXd m(1, 1);
    m << -3.7;
    EXPECT_NEAR(expm(m)(0, 0), std::exp(-3.7), 1e-12);
    Eigen::MatrixXd rot(2, 2);
    rot << 0, -1, 1, 0;
    const Eigen::MatrixXd e = expm(rot * 2.0);
    EXPECT_NEAR(e(0, 0), std::cos(2.0), 1e-12);
    EXPECT_NEAR(e(1, 0), std::sin(2.0), 1e-12);
}

TEST(Plant, LockedRotorCurrentIsVoltageOverResistance) {
    MotorModel m;
    Plant p;
    p.configure(m, m.torque_constant, 1e-5);
    p.set_stops(0.0, 0.0);  // blocked shaft
    for (int i = 0; i < 2000; ++i)
        p.step(2.0, true);  // 20 ms >> L/R
    EXPECT_NEAR(p.current(), 2.0 / m.resistance, 1e-3);
    EXPECT_EQ(p.velocity(), 0.0);
}

TEST(Plant, NoLoadSpeedFromBackEmf) {
    MotorModel m;
    m.coulomb_friction = 0;
    m.viscous_friction = 0;
    Plant p;
    p.configure(m, m.torque_constant, 1e-5);
    for (int i = 0; i < 200000; ++i)
        p.step(10.0, true);  // 2 s
    EXPECT_NEAR(p.velocity(), 10.0 / m.torque_constant, 0.5);
}

TEST(Plant, CoulombFrictionHoldsBelowBreakaway) {
    MotorModel m;
    Plant p;
    p.configure(m, m.torque_constant, 1e-5);
    // 0.2 A x 25.5 mNm/A = 5.1 mNm < 6.88 mNm: the shaft does not move. Drive the current with a voltage.
    for (int i = 0; i < 5000; ++i)
        p.step(0.2 * m.resistance, true);
    EXPECT_EQ(p.velocity(), 0.0);
    for (int i = 0; i < 5000; ++i)
        p.step(0.4 * m.resistance, true);
    EXPECT_GT(p.velocity(), 0.0);
}

TEST(Machine, CurrentLoopStepWithSeedGainsAndWithResistanceFeedForward) {
    // Seed gains 0x30A0 = 32768 / 4096 / 0: the integrator does most of the work (about 1 ms).
    for (uint32_t ff : {0u, 54788u}) {  // 54788 x 2^-16 V/A = 0.836 ohm: the winding resistance
        Rig r;
        r.ax.params.current_ff = ff;
        r.ax.environment().set_mechanical_stops(-10, 10);
        r.ax.command.mode = mode::CyclicSyncTorque;
        r.enable();
        r.ax.command.target_torque = 400;  // 2 A
        r.run(1);
        if (ff) {
            EXPECT_NEAR(r.fb().current_actual, 2000, 100);
        } else {
            EXPECT_GT(r.fb().current_actual, 1300);
            EXPECT_LT(r.fb().current_actual, 1900);
        }
        r.run(4);
        EXPECT_NEAR(r.fb().current_actual, 2000, 40);
        EXPECT_EQ(r.fb().current_demand, 2000);
    }
}

TEST(Machine, EncoderResolutionFromPulsesPerTurn) {
    Rig r;
    r.ax.params.encoder_pulses = 1024;  // 4096 inc/rev
    r.ax.command.mode = mode::CyclicSyncVelocity;
    r.enable();
    r.ax.command.target_velocity = 600;
    r.run_ms(400);
    const int32_t p0 = r.fb().position_actual;
    const double a0 = r.ax.plant().angle();
    r.run_ms(100);
    const double turns = (r.ax.plant().angle() - a0) / 6.283185307179586;
    EXPECT_EQ(r.ax.increments_per_rev(), 4096);
    EXPECT_NEAR(r.fb().position_actual - p0, turns * 4096, 2);
    EXPECT_NEAR(turns, 1.0, 0.03);
}

TEST(Machine, I2tLimitsToNominalCurrentAfterTheThermalBudget) {
    Rig r;
    r.ax.environment().set_mechanical_stops(-100, 100);  // stalled against a stop
    r.ax.command.mode = mode::CyclicSyncTorque;
    r.ax.params.max_motor_speed = 200000;
    r.enable();
    r.ax.command.target_torque = 3000;  // 3 x nominal = 15 A = 0x3001:02
    r.run_ms(300);
    EXPECT_NEAR(r.fb().current_actual, 15000, 200);
    EXPECT_FALSE(r.sw() & sw::InternalLimit);
    // Normalized heating (i/In)^2 = 9 reaches 1 after tau x ln(9/8) = 4 s x 0.118 = 0.47 s.
    ASSERT_TRUE(r.until([&] { return (r.sw() & sw::InternalLimit) != 0; }, 400));
    EXPECT_NEAR(r.t * 1e-9, 1e-3 + 4.0 * std::log(9.0 / 8.0), 0.02);
    r.run_ms(50);
    EXPECT_NEAR(r.fb().current_actual, 5000, 200);
    EXPECT_TRUE(r.ax.i2t_limiting());
    // Demand below nominal: the winding cools, the limit releases.
    r.ax.command.target_torque = 500;
    ASSERT_TRUE(r.until([&] { return (r.sw() & sw::InternalLimit) == 0; }, 2000));
}

TEST(Machine, NothingMovesWithThePowerStageOff) {
    Rig r;
    r.ax.command.mode = mode::CyclicSyncTorque;
    r.ax.command.target_torque = 1000;
    r.cw(0x06);
    r.cw(0x07, 100);
    EXPECT_EQ(r.fb().current_actual, 0);
    EXPECT_EQ(r.ax.plant().velocity(), 0.0);
}

TEST(Profile, ReachesTargetsWithoutOvershootAndWithinTheRamps) {
    const double vmax = 100000, a = 1e6, h = 0.4e-3;
    for (double dist : {6000.0, 20000.0, 3.0, 0.3, -5000.0}) {
        for (double v0 : {0.0, 50000.0, -50000.0}) {
            Profile p;
            p.reset(0, v0);
            double amax = 0, vpeak = 0, lo = 0, hi = 0;
            bool done = false;
            for (int i = 0; i < 20000 && !done; ++i) {
                const double vb = p.velocity();
                done = p.step_position(dist, vmax, a, a, h);
                amax = std::max(amax, std::abs(p.velocity() - vb) / h);
                vpeak = std::max(vpeak, std::abs(p.velocity()));
                lo = std::min(lo, p.position());
                hi = std::max(hi, p.position());
            }
            ASSERT_TRUE(done);
            EXPECT_EQ(p.position(), dist);
            EXPECT_LE(amax, 2.0 * a + 1);
            EXPECT_LE(vpeak, std::max(vmax, std::abs(v0)) + 1);
            // No overshoot unless the start velocity made the stop impossible.
            const double stop = v0 * v0 / (2 * a);
            if (v0 == 0 || (v0 > 0 && dist > stop) || (v0 < 0 && dist < -stop)) {
                EXPECT_LE(hi, std::max(dist, 0.0) + 1e-6);
                EXPECT_GE(lo, std::min(dist, 0.0) - 1e-6);
            }
        }
    }
}

TEST(Machine, InversePolarityTurnsTheMotorTheOtherWayAndKeepsTheLoopStable) {
    Rig r;
    r.ax.params.axis_misc = 1;
    r.ax.command.mode = mode::CyclicSyncVelocity;
    r.enable();
    r.ax.command.target_velocity = 1000;
    r.run_ms(400);
    EXPECT_NEAR(r.fb().velocity_actual, 1000, 30);
    EXPECT_NEAR(r.rpm(), -1000, 30);  // physically negative
    EXPECT_GT(r.fb().current_actual, 0);
    EXPECT_LT(r.ax.phys_position_inc(), -1000);
    EXPECT_GT(r.fb().position_actual, 1000);
}

TEST(Machine, PolarityAppliesToSwitchEdgesToo) {
    Rig r;
    r.ax.params.axis_misc = 1;
    r.ax.params.input_function[3] = 26;
    r.ax.environment().set_home_switch(-5000.5, -4000.5, 4);  // physical positions
    r.ax.command.touch_probe_function = 0x0031;
    r.ax.command.mode = mode::ProfileVelocity;
    r.ax.command.target_velocity = 1500;  // axis positive = physically negative
    r.enable();
    ASSERT_TRUE(r.until([&] { return (r.fb().touch_probe_status & 0x6) == 0x6; }, 2000));
    EXPECT_NEAR(r.fb().touch_probe_pos, 4000, 1);  // reached first, at axis position +4000.5
    EXPECT_NEAR(r.fb().touch_probe_neg, 5000, 1);
}

TEST(Plant, NonsenseModelValuesAreClampedToAPhysicalMotor) {
    MotorModel m;
    m.inductance = 0;
    m.rotor_inertia = -1;
    m.load_inertia = std::numeric_limits<double>::quiet_NaN();
    m.resistance = 0;
    Plant p;
    p.configure(m, 0.0255, 1e-5);
    for (int i = 0; i < 1000; ++i)
        p.step(1.0, true);
    EXPECT_TRUE(std::isfinite(p.current()));
    EXPECT_TRUE(std::isfinite(p.velocity()));
}
