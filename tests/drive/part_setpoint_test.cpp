// SetpointGenerator alone: the profile position set-point, CSP interpolation, CSV and CST references
// (no Axis).
#include <gtest/gtest.h>

#include <cmath>

#include "drive/setpoint.hpp"

using namespace drive;

namespace {

constexpr double kH = 0.0004;

struct SpRig {
    SetpointGenerator sp;
    Command c;
    Parameters p;
    PositionFrame f;
    SetpointGenerator::Inputs in{0, 0, 2000};

    explicit SpRig(int8_t m) { sp.switch_mode(m, true, 0); }
    void command(uint16_t cw, uint16_t prev, bool enabled = true, int64_t now = 0) {
        c.controlword = cw;
        sp.command(c, prev, enabled, f, true, now, 1'000'000);
    }
    LoopReference tick(int64_t t = 0) { return sp.tick(c, p, in, f, t, kH); }
};

}  // namespace

TEST(SetpointPart, AccelerationsAreLimitedAndConverted) {
    EXPECT_EQ(limited_acceleration(600, 100000, 2000), 600 * 2000 / 60.0);
    EXPECT_EQ(limited_acceleration(600, 300, 2000), 300 * 2000 / 60.0);  // 0x60C5
    EXPECT_EQ(limited_acceleration(0, 300, 2000), 2000 / 60.0);          // at least 1 rpm/s
}

TEST(SetpointPart, NewSetpointEdges) {
    EXPECT_TRUE(new_setpoint_edge(0x1F, 0x0F).rise);
    EXPECT_FALSE(new_setpoint_edge(0x1F, 0x1F).rise);
    EXPECT_TRUE(new_setpoint_edge(0x0F, 0x1F).fall);
}

TEST(SetpointPart, ProfilePositionMovesToTheTargetAndAcknowledges) {
    SpRig r(mode::ProfilePosition);
    r.c.target_position = 1000;
    r.command(0x1F, 0x0F);
    EXPECT_TRUE(r.sp.setpoint_acknowledged());
    EXPECT_FALSE(r.sp.target_reached());
    for (int i = 0; i < 10000 && !r.sp.target_reached(); ++i)
        r.tick();
    EXPECT_TRUE(r.sp.target_reached());
    EXPECT_EQ(r.sp.demand_position(), 1000);
    EXPECT_EQ(r.sp.control(), Control::Position);
    r.command(0x0F, 0x1F);
    EXPECT_FALSE(r.sp.setpoint_acknowledged());
}

TEST(SetpointPart, ProfilePositionTargetIsClampedToTheSoftwareLimits) {
    SpRig r(mode::ProfilePosition);
    r.f.sw_max = 500;
    r.c.target_position = 1000;
    r.command(0x1F, 0x0F);
    EXPECT_TRUE(r.sp.target_limited());
    for (int i = 0; i < 10000 && !r.sp.target_reached(); ++i)
        r.tick();
    EXPECT_EQ(r.sp.demand_position(), 500);
}

TEST(SetpointPart, ProfilePositionIgnoresSetpointsWhenNotEnabled) {
    SpRig r(mode::ProfilePosition);
    r.c.target_position = 1000;
    r.command(0x1F, 0x0F, false);
    EXPECT_FALSE(r.sp.setpoint_acknowledged());
    r.tick();
    EXPECT_EQ(r.sp.demand_position(), 0);
}

TEST(SetpointPart, CyclicSyncPositionInterpolatesOverTheCycle) {
    SpRig r(mode::CyclicSyncPosition);
    r.c.target_position = 100;
    r.command(0x0F, 0x0F, true, 0);
    r.tick(400'000);
    EXPECT_NEAR(r.sp.demand_position(), 40, 1e-9);
    EXPECT_NEAR(r.sp.demand_velocity(), 40 / kH, 1e-6);
    r.tick(1'000'000);
    EXPECT_NEAR(r.sp.demand_position(), 100, 1e-9);
    EXPECT_FALSE(r.sp.target_outside_limits());
    r.f.sw_max = 50;
    r.command(0x0F, 0x0F, true, 1'000'000);
    EXPECT_TRUE(r.sp.target_outside_limits());
}

TEST(SetpointPart, CyclicSyncPositionOffsetsAreFeedForwards) {
    SpRig r(mode::CyclicSyncPosition);
    r.c.velocity_offset = 60;  // rpm
    r.c.torque_offset = 500;   // per mille
    r.p.nominal_current = 2000;
    const LoopReference ref = r.tick();
    EXPECT_NEAR(ref.vel_ff, 6.283185307179586, 1e-12);
    EXPECT_NEAR(ref.torque_ff_a, 1.0, 1e-12);
}

TEST(SetpointPart, CyclicSyncVelocityAndTorqueFeedTheirLoops) {
    SpRig v(mode::CyclicSyncVelocity);
    v.c.target_velocity = 600;
    v.in.actual = 77;
    const LoopReference rv = v.tick();
    EXPECT_EQ(v.sp.control(), Control::Velocity);
    EXPECT_NEAR(rv.vel_ref, 6.283185307179586 * 10, 1e-9);
    EXPECT_NEAR(v.sp.demand_velocity(), 600 * 2000 / 60.0, 1e-9);
    EXPECT_EQ(v.sp.demand_position(), 77);
    v.c.target_velocity = 1'000'000;  // clamped to 0x6080
    EXPECT_NEAR(v.tick().vel_ref, 6.283185307179586 * v.p.max_motor_speed / 60.0, 1e-6);

    SpRig t(mode::CyclicSyncTorque);
    t.c.target_torque = 500;
    t.p.nominal_current = 2000;
    EXPECT_NEAR(t.tick().cur_ref, 1.0, 1e-12);
    EXPECT_EQ(t.sp.control(), Control::Torque);
}

TEST(SetpointPart, ModeSwitchWithoutPowerHoldsAtTheActualPosition) {
    SetpointGenerator sp;
    sp.switch_mode(mode::ProfileVelocity, false, 123);
    EXPECT_EQ(sp.mode(), mode::ProfileVelocity);
    EXPECT_EQ(sp.profile().position(), 123);
    sp.follow(200);
    EXPECT_EQ(sp.demand_position(), 200);
    EXPECT_EQ(sp.demand_velocity(), 0);
}

TEST(SetpointPart, StopRampReachesZeroSpeed) {
    SetpointGenerator sp;
    sp.ramp_from(0, 1000);
    int ticks = 0;
    while (!sp.ramp(1e5, kH) && ticks < 1000)
        ++ticks;
    EXPECT_EQ(sp.profile().velocity(), 0);
    EXPECT_GT(ticks, 0);
}
