// Controller alone: the gains, the position and velocity loops, the references and the observer (no Axis).
#include <gtest/gtest.h>

#include <cmath>

#include "drive/controller.hpp"
#include "drive/parameters.hpp"

using namespace drive;

namespace {
constexpr double kTwoPi = 6.283185307179586;
}

TEST(ControllerPart, TuneByPolePlacementAndOnlyWhenInputsChange) {
    Controller c;
    Parameters p;
    c.tune(p, 0.03);
    const double wb = kTwoPi * p.bandwidth * 1e-3;
    const double zeta = p.damping * 1e-3;
    EXPECT_NEAR(c.kpp, wb / (2 * zeta), 1e-9);
    EXPECT_TRUE(c.tuned.valid);
    c.kpp = 0;
    c.tune(p, 0.03);  // same inputs: nothing recomputed
    EXPECT_EQ(c.kpp, 0);
    p.bandwidth += 1000;
    c.tune(p, 0.03);
    EXPECT_GT(c.kpp, 0);
}

TEST(ControllerPart, PositionLoopGivesTheSpeedReference) {
    Controller c;
    c.kpp = 100;
    c.vel_ff = 5;
    const double rpi = kTwoPi / 2000;
    c.position(100, 0, 0, 0, false, 0.03, rpi);  // CSP: the velocity offset is the feed-forward
    EXPECT_NEAR(c.vel_ref, 100 * 100 * rpi + 5, 1e-12);
    c.position(100, 2000, 0, 0, true, 0.03, rpi);  // profile modes: the demand's speed
    EXPECT_NEAR(c.vel_ref, 100 * 100 * rpi + 2000 * rpi, 1e-12);
}

TEST(ControllerPart, VelocityLoopLimitsTheCurrentWithAntiWindup) {
    Controller c;
    c.kv = 1;
    c.kiv = 10;
    c.vel_ref = 1000;
    c.velocity(true, false, 1000, 3000);
    EXPECT_EQ(c.cur_ref, 3.0);  // 0x3001:02 = 3000 mA
    EXPECT_LE(std::abs(c.vel_int), 3.0);
    c.i2t_active = true;
    c.velocity(true, false, 1000, 3000);
    EXPECT_EQ(c.cur_ref, 1.0);  // I2t: the nominal current
    c.velocity(false, false, 1000, 3000);
    EXPECT_EQ(c.cur_ref, 0);
    EXPECT_EQ(c.vel_int, 0);
}

TEST(ControllerPart, FollowTakesTheReferenceOfTheChosenLoop) {
    Controller c;
    c.vel_ref = 1;
    c.cur_ref = 2;
    c.follow({3, 4, 5, 6}, Control::Position);
    EXPECT_EQ(c.vel_ff, 3);
    EXPECT_EQ(c.torque_ff_a, 4);
    EXPECT_EQ(c.vel_ref, 1);
    EXPECT_EQ(c.cur_ref, 2);
    c.follow({0, 0, 5, 6}, Control::Velocity);
    EXPECT_EQ(c.vel_ref, 5);
    EXPECT_EQ(c.cur_ref, 2);
    c.follow({0, 0, 5, 6}, Control::Torque);
    EXPECT_EQ(c.cur_ref, 6);
}

TEST(ControllerPart, ObserverFollowsAConstantSpeed) {
    Controller c;
    Parameters p;
    c.tune(p, 0.03);
    const double w = 10;  // rad/s
    const double tick = static_cast<double>(kCurrentTickNs) * 1e-9;
    for (int k = 1; k <= 5000; ++k)
        c.observe(w * k * tick, 0, 0.03);
    EXPECT_NEAR(c.obs_vel, w, 0.01 * w);
    EXPECT_NEAR(c.vel_avg_rpm, w * 60 / kTwoPi, 0.02 * w * 60 / kTwoPi);
    EXPECT_FALSE(c.diverged());
    c.obs_vel = NAN;
    EXPECT_TRUE(c.diverged());
    c.reset_estimates(1.5);
    EXPECT_FALSE(c.diverged());
    EXPECT_EQ(c.obs_pos, 1.5);
}

TEST(ControllerPart, ThermalModelLimitsAboveTheNominalCurrent) {
    Controller c;
    Parameters p;
    p.thermal_time_constant = 1;  // 0.1 s
    c.tune(p, 0.03);
    const double over = 2.0 * p.nominal_current * 1e-3;
    for (int k = 0; k < 25000 && !c.i2t_active; ++k)
        c.observe(0, over, 0.03);
    EXPECT_TRUE(c.i2t_active);
    for (int k = 0; k < 100000 && c.i2t_active; ++k)
        c.observe(0, 0, 0.03);
    EXPECT_FALSE(c.i2t_active);
}

TEST(ControllerPart, ModeSwitchAndFrameChange) {
    Controller c;
    c.vel_ref = 3;
    c.mode_switched(true);
    EXPECT_EQ(c.vel_ref, 3);
    c.mode_switched(false);
    EXPECT_EQ(c.vel_ref, 0);
    c.obs_vel = 7;
    c.obs_load = 0.1;
    c.vel_int = 0.5;
    c.rebase(2.0);
    EXPECT_EQ(c.obs_pos, 2.0);
    EXPECT_EQ(c.obs_vel, 0);
    EXPECT_EQ(c.obs_load, 0);
    EXPECT_EQ(c.vel_int, 0.5);  // the loops keep their state
    c.set_torque_constant(25500);
    EXPECT_NEAR(c.km, 0.0255, 1e-12);
}
