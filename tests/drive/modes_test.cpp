// Operating modes: CSP, CSV, CST, PPM, PVM, on-the-fly switching, following error, position limits.
#include "rig.hpp"

using namespace drive;
using namespace drive::test;

namespace {

// Profile position mode with the profile velocity and the same acceleration and deceleration, enabled.
void enable_profile_position(Rig& r, uint32_t velocity, uint32_t acceleration) {
    r.ax.command.mode = mode::ProfilePosition;
    r.ax.params.profile_velocity = velocity;
    r.ax.params.profile_acceleration = acceleration;
    r.ax.params.profile_deceleration = acceleration;
    r.enable();
}

// A new set-point in profile position mode: the target, then controlword bit 4 raised (with `bits`: 0x20
// change immediately, 0x40 relative) and lowered again.
void new_setpoint(Rig& r, int32_t target, uint16_t bits = 0) {
    r.ax.command.target_position = target;
    r.cw(static_cast<uint16_t>(0x1F | bits));
    r.cw(0x0F);
}

// Runs until statusword bit 10 (target reached) is set, for ms milliseconds at most.
bool target_reached_within(Rig& r, int ms) {
    return r.until([&] { return (r.sw() & sw::TargetReached) != 0; }, ms);
}

}  // namespace

TEST(Modes, DisplayFollowsSupportedModesOnly) {
    Rig r;
    EXPECT_EQ(r.fb().mode_display, mode::CyclicSyncPosition);
    r.ax.command.mode = 2;  // velocity mode: not supported (0x6502 = 0x3A5)
    r.run(1);
    EXPECT_EQ(r.fb().mode_display, mode::CyclicSyncPosition);
    r.ax.command.mode = mode::CyclicSyncTorque;
    r.run(1);
    EXPECT_EQ(r.fb().mode_display, mode::CyclicSyncTorque);
}

TEST(Modes, CspRampIsFollowedWithinTheFollowingErrorWindow) {
    Rig r;
    r.enable();
    // Master trajectory: accelerate at 20000 rpm/s to 1500 rpm, cruise, decelerate; 1 ms set-points.
    const double res = 2000, acc = 20000.0 / 60 * res, vmax = 1500.0 / 60 * res;  // inc/s^2, inc/s
    double p = r.fb().position_actual, v = 0;
    const double start = p;
    int32_t max_ferr = 0;
    bool follows = true;
    for (int k = 0; k < 1200; ++k) {
        const double vt = k < 900 ? vmax : 0.0;
        if (v < vt) v = std::min(vt, v + acc * 1e-3);
        if (v > vt) v = std::max(vt, v - acc * 1e-3);
        p += v * 1e-3;
        r.ax.command.target_position = static_cast<int32_t>(std::lround(p));
        r.run(1);
        max_ferr = std::max(max_ferr, std::abs(r.fb().following_error));
        follows = follows && (r.sw() & sw::Bit12);
    }
    r.run(200);
    EXPECT_TRUE(follows);
    EXPECT_FALSE(r.rec.has(error_code::FollowingError));
    EXPECT_LT(max_ferr, 2000);
    EXPECT_GT(p - start, 20000);
    EXPECT_NEAR(r.fb().position_actual, std::lround(p), 2);
    EXPECT_FALSE(r.sw() & sw::Bit13);
}

TEST(Modes, CspVelocityOffsetIsFeedForward) {
    auto run_with = [](bool ff) {
        Rig r;
        r.enable();
        const double v = 1000.0 / 60 * 2000;  // 1000 rpm in inc/s
        double p = r.fb().position_actual;
        int32_t worst = 0;
        for (int k = 0; k < 600; ++k) {
            p += v * 1e-3 * std::min(1.0, k / 100.0);
            r.ax.command.target_position = static_cast<int32_t>(std::lround(p));
            r.ax.command.velocity_offset = ff ? static_cast<int32_t>(1000 * std::min(1.0, k / 100.0)) : 0;
            r.run(1);
            if (k > 400) worst = std::max(worst, std::abs(r.fb().following_error));
        }
        return worst;
    };
    EXPECT_LT(run_with(true), run_with(false) / 3);
}

TEST(Modes, CsvStepReachesAndHoldsTheVelocity) {
    Rig r;
    r.ax.command.mode = mode::CyclicSyncVelocity;
    r.enable();
    r.ax.command.target_velocity = 2000;
    r.run_ms(300);
    for (int i = 0; i < 200; ++i) {
        r.run(1);
        EXPECT_NEAR(r.rpm(), 2000, 2000 * 0.02);
    }
    EXPECT_NEAR(r.fb().velocity_actual, 2000, 40);
    EXPECT_TRUE(r.sw() & sw::Bit12);
    EXPECT_EQ(r.fb().velocity_demand, 2000);
    // The velocity offset adds to the target.
    r.ax.command.velocity_offset = -500;
    r.run_ms(300);
    EXPECT_NEAR(r.rpm(), 1500, 40);
}

TEST(Modes, CstTorqueGivesTheAccelerationTheInertiaPredicts) {
    Rig r;
    r.ax.motor().coulomb_friction = 0;
    r.ax.motor().viscous_friction = 0;
    r.ax.reconfigure();
    r.ax.command.mode = mode::CyclicSyncTorque;
    r.enable();
    r.ax.command.target_torque = 100;  // 100 per mille of 5 A x 25.5 mNm/A = 12.75 mNm
    r.run_ms(20);
    const double w0 = r.ax.plant().velocity();
    r.run_ms(100);
    const double alpha = (r.ax.plant().velocity() - w0) / 0.1;
    const double j = r.ax.motor().rotor_inertia + r.ax.motor().load_inertia;
    const double expected = 0.1 * 5.0 * 0.0255 / j;
    EXPECT_NEAR(alpha, expected, expected * 0.03);
    EXPECT_NEAR(r.fb().torque_actual, 100, 5);
    EXPECT_NEAR(r.fb().current_actual, 500, 20);
    EXPECT_EQ(r.fb().motor_rated_torque, 127500u);
    // The torque offset adds.
    r.ax.command.target_torque = 0;
    r.ax.command.torque_offset = -100;
    r.run_ms(10);
    EXPECT_NEAR(r.fb().current_actual, -500, 20);
}

TEST(Modes, PpmAbsoluteMoveWithSetpointHandshake) {
    Rig r;
    enable_profile_position(r, 2000, 20000);
    const int32_t start = r.fb().position_actual;
    r.ax.command.target_position = start + 10000;
    r.cw(0x1F);
    EXPECT_TRUE(r.sw() & sw::Bit12);  // set-point acknowledged
    EXPECT_FALSE(r.sw() & sw::TargetReached);
    r.cw(0x0F);
    EXPECT_FALSE(r.sw() & sw::Bit12);  // ready for the next one
    // Peak demand velocity = 0x6081.
    int32_t vmax = 0;
    ASSERT_TRUE(r.until(
        [&] {
            vmax = std::max(vmax, r.fb().velocity_demand);
            return (r.sw() & sw::TargetReached) != 0;
        },
        2000));
    EXPECT_NEAR(vmax, 2000, 20);
    EXPECT_EQ(r.fb().position_demand, start + 10000);
    r.run_ms(200);
    EXPECT_NEAR(r.fb().position_actual, start + 10000, 5);
}

TEST(Modes, PpmRelativeAndChangeImmediately) {
    Rig r;
    r.ax.command.mode = mode::ProfilePosition;
    r.ax.params.profile_velocity = 1000;
    r.enable();
    const int32_t start = r.fb().position_actual;
    new_setpoint(r, 4000, 0x40);  // relative
    ASSERT_TRUE(target_reached_within(r, 3000));
    EXPECT_EQ(r.fb().position_demand, start + 4000);
    // A long move, replaced half-way by an immediate new target behind us.
    new_setpoint(r, start + 40000);
    r.run_ms(300);
    new_setpoint(r, start, 0x20);
    ASSERT_TRUE(target_reached_within(r, 5000));
    EXPECT_EQ(r.fb().position_demand, start);
}

TEST(Modes, PpmBufferedSetpointRunsAfterTheFirst) {
    Rig r;
    enable_profile_position(r, 3000, 30000);
    const int32_t start = r.fb().position_actual;
    new_setpoint(r, start + 6000);
    r.run_ms(20);
    r.ax.command.target_position = start - 2000;
    r.cw(0x1F);  // not immediate: buffered, acknowledged
    EXPECT_TRUE(r.sw() & sw::Bit12);
    r.cw(0x0F);
    EXPECT_TRUE(r.sw() & sw::Bit12);  // buffer full: no further set-point accepted yet
    int32_t furthest = start;
    ASSERT_TRUE(r.until(
        [&] {
            furthest = std::max(furthest, r.fb().position_demand);
            return (r.sw() & sw::TargetReached) != 0 && r.fb().position_demand == start - 2000;
        },
        5000));
    EXPECT_EQ(furthest, start + 6000);  // the first move completed first
    EXPECT_FALSE(r.sw() & sw::Bit12);
}

TEST(Modes, PpmTargetClampedBySoftwareLimitSetsInternalLimit) {
    Rig r;
    r.ax.command.mode = mode::ProfilePosition;
    const int32_t start = r.fb().position_actual;
    r.ax.params.sw_limit_max = start + 3000;
    r.enable();
    new_setpoint(r, start + 9000);
    ASSERT_TRUE(target_reached_within(r, 3000));
    EXPECT_EQ(r.fb().position_demand, start + 3000);
    EXPECT_TRUE(r.sw() & sw::InternalLimit);
}

TEST(Modes, PvmReachesVelocityAndReportsSpeedZero) {
    Rig r;
    r.ax.command.mode = mode::ProfileVelocity;
    r.ax.params.profile_acceleration = 10000;
    r.enable();
    EXPECT_TRUE(r.sw() & sw::Bit12);  // speed = 0
    r.ax.command.target_velocity = -1000;
    r.run(1);
    EXPECT_FALSE(r.sw() & sw::TargetReached);
    r.run_ms(80);
    EXPECT_NEAR(r.fb().velocity_demand, -800, 30);  // 10000 rpm/s ramp
    ASSERT_TRUE(target_reached_within(r, 500));
    r.run_ms(100);
    EXPECT_NEAR(r.rpm(), -1000, 20);
    EXPECT_FALSE(r.sw() & sw::Bit12);
}

TEST(Modes, SwitchingOnTheFlyFromCspToCsvKeepsMoving) {
    Rig r;
    r.enable();
    double p = r.fb().position_actual;
    for (int k = 0; k < 500; ++k) {
        p += 1000.0 / 60 * 2000 * 1e-3 * std::min(1.0, k / 200.0);
        r.ax.command.target_position = static_cast<int32_t>(std::lround(p));
        r.ax.command.velocity_offset = static_cast<int32_t>(1000 * std::min(1.0, k / 200.0));
        r.run(1);
    }
    EXPECT_NEAR(r.rpm(), 1000, 50);
    r.ax.command.mode = mode::CyclicSyncVelocity;
    r.ax.command.target_velocity = 1000;
    r.ax.command.velocity_offset = 0;
    for (int k = 0; k < 50; ++k) {
        r.run(1);
        EXPECT_NEAR(r.rpm(), 1000, 60);
    }
    EXPECT_EQ(r.fb().mode_display, mode::CyclicSyncVelocity);
    EXPECT_EQ(r.ax.state(), State::OperationEnabled);
}

TEST(Modes, FollowingErrorRaises8611AndRunsTheFaultReaction) {
    Rig r;
    r.enable();
    r.ax.command.target_position = r.fb().position_actual + 5000;  // a jump the loop cannot follow
    r.run(1);
    EXPECT_TRUE(r.rec.has(error_code::FollowingError));
    EXPECT_EQ(r.fb().error_code, 0x8611);
    EXPECT_EQ(r.fb().error_register, 0x81);
    EXPECT_EQ(r.ax.state(), State::FaultReactionActive);
    ASSERT_TRUE(r.until([&] { return r.ax.state() == State::Fault; }, 1000));
    r.cw(0x00);
    r.cw(0x80);
    EXPECT_EQ(r.ax.state(), State::SwitchOnDisabled);
}

TEST(Modes, FollowingErrorTimeoutDelaysTheError) {
    Rig r;
    r.ax.params.following_error_window = 100;
    r.ax.params.following_error_timeout = 5;
    r.enable();
    r.ax.command.target_position = r.fb().position_actual + 150;
    r.run(1);
    EXPECT_TRUE(r.sw() & sw::Bit13);  // window exceeded, reported
    EXPECT_FALSE(r.rec.has(error_code::FollowingError));
    r.run(3);
    EXPECT_FALSE(r.rec.has(error_code::FollowingError));  // the loop pulled it back in time
}

// A CSP target `offset` from the start position with software position limits min/max (taken relative to
// the start when `relative`), run for `cycles`: whether 0x8A82 was raised.
bool csp_target_raises_8a82(int32_t min, int32_t max, bool relative, int32_t offset, int cycles) {
    Rig r;
    const int32_t start = r.fb().position_actual;
    r.ax.params.sw_limit_min = relative ? start + min : min;
    r.ax.params.sw_limit_max = relative ? start + max : max;
    r.enable();
    r.ax.command.target_position = start + offset;
    r.run(cycles);
    return r.rec.has(error_code::SoftwarePositionLimit);
}

TEST(Modes, CspTargetOutsideSoftwareLimitRaises8A82) {
    EXPECT_TRUE(csp_target_raises_8a82(-1000, 1000, true, 1001, 1));
}

// Software position limits 0/0 (min >= max: no range, as vendors' ESIs ship 0x607D) are off, as a position
// range limit without a range is: a CSP target away from 0 is followed, no 0x8A82.
TEST(Modes, SoftwareLimitsWithoutARangeAreOff) {
    EXPECT_FALSE(csp_target_raises_8a82(0, 0, false, 50, 20));
    EXPECT_FALSE(csp_target_raises_8a82(100, -100, false, 50, 20));  // min > max: no range either
}

// Speed limits 0x607F/0x6080 of 0 (as vendors' ESIs ship them) limit nothing: a CSP move is followed,
// no 0x8A83.
TEST(Modes, SpeedLimitsOfZeroLimitNothing) {
    Rig r;
    const int32_t start = r.fb().position_actual;
    r.ax.params.max_motor_speed = 0;
    r.ax.params.max_profile_velocity = 0;
    r.enable();
    for (int k = 1; k <= 50; ++k) {
        r.ax.command.target_position = start + 10 * k;
        r.run(1);
    }
    r.run(100);
    EXPECT_FALSE(r.rec.has(error_code::MaxSpeed));
    EXPECT_NEAR(r.fb().position_actual, start + 500, 5);
}

TEST(Modes, LimitSwitchRaises8A81WhenDrivingIntoIt) {
    Rig r;
    r.ax.environment().set_positive_limit(3000);
    r.ax.command.mode = mode::ProfileVelocity;
    r.enable();
    r.ax.command.target_velocity = 300;
    ASSERT_TRUE(r.until([&] { return r.rec.has(error_code::PositiveLimitSwitch); }, 3000));
    EXPECT_TRUE(r.fb().digital_inputs & 0x2);
    EXPECT_GE(r.ax.raw_position_inc(), 2999);
    ASSERT_TRUE(r.until([&] { return r.ax.state() == State::Fault; }, 1000));
    // After the reset the axis may leave the switch the other way.
    r.cw(0x00);
    r.cw(0x80);
    r.ax.command.target_velocity = -300;
    r.cw(0x06);
    r.cw(0x0F);
    ASSERT_TRUE(r.until([&] { return !(r.fb().digital_inputs & 0x2); }, 2000));
    EXPECT_EQ(r.ax.state(), State::OperationEnabled);
}

TEST(Modes, SpeedAboveMaxMotorSpeedRaises8A83) {
    Rig r;
    r.ax.params.max_motor_speed = 800;
    r.ax.command.mode = mode::CyclicSyncTorque;
    r.enable();
    r.ax.command.target_torque = 600;  // would settle at ~1490 rpm against the friction
    ASSERT_TRUE(r.until([&] { return r.rec.has(error_code::MaxSpeed); }, 2000));
    EXPECT_GT(std::abs(r.rpm()), 780);
    EXPECT_EQ(r.fb().error_register, 0x21);
    ASSERT_TRUE(r.until([&] { return r.ax.state() == State::Fault; }, 2000));
}

TEST(Modes, SecondErrorAddsItsRegisterBitsAndBecomesTheLastError) {
    Rig r;
    r.ax.raise_error(error_code::FollowingError);
    r.ax.raise_error(error_code::Overvoltage);
    r.run(1);
    EXPECT_EQ(r.fb().error_code, error_code::Overvoltage);
    EXPECT_EQ(r.fb().error_register, 0x85);
    EXPECT_EQ(r.rec.raised.size(), 2u);
    r.ax.raise_error(error_code::Overvoltage);  // already active: no second emergency
    EXPECT_EQ(r.rec.raised.size(), 2u);
    r.cw(0x80);
    EXPECT_EQ(r.fb().error_register, 0);
    EXPECT_EQ(r.rec.cleared.size(), 2u);
}

TEST(Modes, CsvActualOutsideSoftwareLimitRaises8A82) {
    Rig r;
    const int32_t start = r.fb().position_actual;
    r.ax.params.sw_limit_max = start + 2000;
    r.ax.command.mode = mode::CyclicSyncVelocity;
    r.enable();
    r.ax.command.target_velocity = 600;
    ASSERT_TRUE(r.until([&] { return r.rec.has(error_code::SoftwarePositionLimit); }, 2000));
    EXPECT_GT(r.fb().position_actual, start + 2000);
    EXPECT_LT(r.fb().position_actual, start + 2100);
}

// CSP at the cycle times real masters use (TwinCAT 2 ms, 1 ms, fast DC 250 us / 125 us): the same master
// trajectory is followed inside the window and ends at the target.
class CspCycle : public ::testing::TestWithParam<int64_t> {};

TEST_P(CspCycle, FollowsTheSameTrajectory) {
    Rig r;
    r.dt = GetParam();
    r.enable();
    Profile master;
    master.reset(r.fb().position_actual, 0);
    const double h = static_cast<double>(r.dt) * 1e-9;
    const double target = r.fb().position_actual + 30000.0;
    int32_t worst = 0;
    for (int64_t t = 0; t < 1'500'000'000; t += r.dt) {
        master.step_position(target, 2000.0 / 60 * 2000, 20000.0 / 60 * 2000, 20000.0 / 60 * 2000, h);
        r.ax.command.target_position = static_cast<int32_t>(std::lround(master.position()));
        r.ax.command.velocity_offset = static_cast<int32_t>(std::lround(master.velocity() * 60.0 / 2000));
        r.run(1);
        worst = std::max(worst, std::abs(r.fb().following_error));
    }
    EXPECT_LT(worst, 200);  // with velocity pre-control through 0x60B1
    EXPECT_NEAR(r.fb().position_actual, target, 5);
    EXPECT_FALSE(r.rec.has(error_code::FollowingError));
}

INSTANTIATE_TEST_SUITE_P(CycleTimes, CspCycle,
                         ::testing::Values(125'000, 250'000, 1'000'000, 2'000'000, 4'000'000));

TEST(Modes, LimitSwitchWithoutErrorFunctionOnlyShowsIn60FD) {
    Rig r;
    r.ax.params.input_function[1] = 25;  // DigIN2: positive limit switch without error
    r.ax.environment().set_positive_limit(2000);
    r.ax.command.mode = mode::ProfileVelocity;
    r.enable();
    r.ax.command.target_velocity = 300;
    ASSERT_TRUE(r.until([&] { return (r.fb().digital_inputs & (1u << 25)) != 0; }, 3000));
    r.run(20);
    EXPECT_FALSE(r.rec.has(error_code::PositiveLimitSwitch));
    EXPECT_EQ(r.fb().digital_inputs & 0x2, 0u);
    EXPECT_EQ(r.fb().input_logic_state & 0x2, 0x2);
}

TEST(Modes, InputPolarityInvertsTheFunction) {
    Rig r;
    r.ax.params.input_polarity = 0x0004;  // DigIN3 low active
    r.run(1);
    EXPECT_EQ(r.fb().digital_inputs & 0x4, 0x4u);  // pin low = home switch active
    EXPECT_EQ(r.fb().input_logic_state & 0x4, 0);
    r.ax.environment().set_input(3, true);
    r.run(1);
    EXPECT_EQ(r.fb().digital_inputs & 0x4, 0u);
}

TEST(Modes, PpmHaltStopsWithQuickStopDecelerationAndResumes) {
    Rig r;
    r.ax.command.mode = mode::ProfilePosition;
    r.ax.params.profile_velocity = 2000;
    r.ax.params.quick_stop_deceleration = 40000;
    r.enable();
    const int32_t start = r.fb().position_actual;
    new_setpoint(r, start + 30000);
    r.run_ms(400);
    r.cw(0x10F);  // halt
    EXPECT_FALSE(r.sw() & sw::TargetReached);
    ASSERT_TRUE(target_reached_within(r, 500));  // halted: velocity 0
    EXPECT_LT(r.fb().position_demand, start + 30000);
    r.cw(0x0F);  // halt released: the move continues to the target
    EXPECT_FALSE(r.sw() & sw::TargetReached);
    ASSERT_TRUE(target_reached_within(r, 3000));
    EXPECT_EQ(r.fb().position_demand, start + 30000);
}

TEST(Modes, PositionRangeLimitWrapsTheReportedPosition) {
    Rig r;
    r.ax.params.range_min = 0;
    r.ax.params.range_max = 3999;
    r.ax.command.mode = mode::CyclicSyncVelocity;
    r.enable();
    r.ax.command.target_velocity = 600;  // 20 inc/ms
    bool wrapped = false;
    int32_t prev = r.fb().position_actual;
    for (int k = 0; k < 600; ++k) {
        r.run(1);
        const int32_t p = r.fb().position_actual;
        ASSERT_GE(p, 0);
        ASSERT_LE(p, 3999);
        wrapped = wrapped || p < prev - 2000;
        prev = p;
    }
    EXPECT_TRUE(wrapped);
}

TEST(Modes, CspTargetsAcrossTheRangeEndMoveTheShortWay) {
    Rig r;
    r.ax.params.range_min = 0;
    r.ax.params.range_max = 3999;
    r.enable();
    double p = r.fb().position_actual;  // continuous master position
    const double p0 = p;
    const double start_raw = r.ax.raw_position_inc();
    for (int k = 0; k < 800; ++k) {
        p += 10.0 * std::min(1.0, k / 50.0);  // 10 inc/ms = 300 rpm
        r.ax.command.target_position = static_cast<int32_t>(std::llround(p)) % 4000;
        r.ax.command.velocity_offset = static_cast<int32_t>(300 * std::min(1.0, k / 50.0));
        r.run(1);
        ASSERT_LT(std::abs(r.fb().following_error), 100) << k;
    }
    EXPECT_NEAR(r.ax.raw_position_inc() - start_raw, p - p0, 60);  // followed 1:1, no jump back
    EXPECT_GT(r.ax.raw_position_inc() - start_raw, 7000);          // went forward through two wraps
    EXPECT_FALSE(r.rec.has(error_code::FollowingError));
}

TEST(Modes, PpmAbsoluteTargetInARangeTakesTheShortWay) {
    Rig r;
    r.ax.params.range_min = 0;
    r.ax.params.range_max = 3999;
    r.ax.params.home_position = 3900;
    r.ax.params.homing_method = 37;
    r.ax.command.mode = mode::Homing;
    r.cw(0x06);
    r.cw(0x07);
    r.cw(0x17);  // method 37 while disabled: here is 3900
    ASSERT_EQ(r.fb().position_actual, 3900);
    r.ax.command.mode = mode::ProfilePosition;
    r.enable();
    const double raw0 = r.ax.raw_position_inc();
    new_setpoint(r, 100);
    ASSERT_TRUE(target_reached_within(r, 3000));
    r.run_ms(100);
    EXPECT_NEAR(r.ax.raw_position_inc() - raw0, 200, 6);  // +200, not -3800
    EXPECT_NEAR(r.fb().position_actual, 100, 5);
}
