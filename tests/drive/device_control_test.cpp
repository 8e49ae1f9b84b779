// Device control on a running axis: transitions 0..16 with their actions, option codes 0x6007,
// 0x605A..0x605E, standstill gating (0x30E0), fault reaction and fault reset, warnings.
#include "rig.hpp"

using namespace drive;
using namespace drive::test;

namespace {
// Spin the motor in PVM at `rpm` and return once it is there.
void spin(Rig& r, int32_t rpm) {
    r.ax.command.mode = mode::ProfileVelocity;
    r.ax.command.target_velocity = rpm;
    r.cw(0x06);
    r.cw(0x07);
    r.cw(0x0F);
    ASSERT_TRUE(r.until([&] { return std::abs(r.rpm() - rpm) < 20; }, 2000));
}
// Deceleration (rpm/s) measured over the next `ms` milliseconds.
double decel_over(Rig& r, double ms) {
    const double v0 = r.rpm();
    r.run_ms(ms);
    return (v0 - r.rpm()) / (ms * 1e-3);
}
}  // namespace

TEST(DeviceControl, T0T1_StartsInSwitchOnDisabled) {
    Rig r;
    EXPECT_EQ(r.ax.state(), State::SwitchOnDisabled);
    EXPECT_EQ(r.state_bits(), 0x40);
    EXPECT_TRUE(r.sw() & sw::Remote);
}

TEST(DeviceControl, T2T3T4_ShutdownSwitchOnEnable) {
    Rig r;
    r.cw(0x06);
    EXPECT_EQ(r.state_bits(), 0x21);
    r.cw(0x07);
    EXPECT_EQ(r.state_bits(), 0x23);
    EXPECT_FALSE(r.ax.power_on());
    r.cw(0x0F);
    EXPECT_EQ(r.state_bits(), 0x37);
    EXPECT_TRUE(r.ax.power_on());
}

TEST(DeviceControl, T3T4_SwitchOnAndEnableFromReady) {
    Rig r;
    r.cw(0x06);
    r.cw(0x0F);
    EXPECT_EQ(r.ax.state(), State::OperationEnabled);
}

TEST(DeviceControl, T4_TorqueConstantZeroRaises8331) {
    Rig r;
    r.ax.params.torque_constant = 0;
    r.cw(0x06);
    r.cw(0x07);
    r.cw(0x0F, 5);
    EXPECT_TRUE(r.rec.has(error_code::TorqueFault));
    EXPECT_EQ(r.ax.state(), State::Fault);
    EXPECT_EQ(r.fb().error_code, 0x8331);
    EXPECT_EQ(r.fb().error_register, 0x21);
    // Cause still present: fault reset refused.
    r.cw(0x00);
    r.cw(0x80);
    EXPECT_EQ(r.ax.state(), State::Fault);
    r.ax.params.torque_constant = 25500;
    r.cw(0x00);
    r.cw(0x80);
    EXPECT_EQ(r.ax.state(), State::SwitchOnDisabled);
    EXPECT_EQ(r.fb().error_code, 0);
    EXPECT_EQ(r.fb().error_register, 0);
}

TEST(DeviceControl, T6T7T10_BackFromSwitchedOnAndReady) {
    Rig r;
    r.cw(0x06);
    r.cw(0x07);
    r.cw(0x06);
    EXPECT_EQ(r.ax.state(), State::ReadyToSwitchOn);  // 6
    r.cw(0x00);
    EXPECT_EQ(r.ax.state(), State::SwitchOnDisabled);  // 7 by disable voltage
    r.cw(0x06);
    r.cw(0x02);
    EXPECT_EQ(r.ax.state(), State::SwitchOnDisabled);  // 7 by quick stop
    r.cw(0x06);
    r.cw(0x07);
    r.cw(0x0B);
    EXPECT_EQ(r.ax.state(), State::SwitchOnDisabled);  // 10 by quick stop
    r.cw(0x06);
    r.cw(0x07);
    r.cw(0x00);
    EXPECT_EQ(r.ax.state(), State::SwitchOnDisabled);  // 10 by disable voltage
}

TEST(DeviceControl, T5_DisableOperationRampsWithProfileDecelerationThenWaitsForStandstill) {
    Rig r;
    r.ax.params.disable_operation = 1;  // default: slow-down ramp
    r.ax.params.profile_deceleration = 5000;
    spin(r, 1000);
    r.cw(0x07);
    EXPECT_EQ(r.ax.state(), State::OperationEnabled);  // completes only at standstill
    EXPECT_NEAR(decel_over(r, 100), 5000, 600);
    ASSERT_TRUE(r.until([&] { return r.ax.state() == State::SwitchedOn; }, 1000));
    EXPECT_LT(std::abs(r.rpm()), 30);
    EXPECT_FALSE(r.ax.power_on());
}

TEST(DeviceControl, T5_DisableOperationCode0CutsPowerAtOnce) {
    Rig r;
    r.ax.params.disable_operation = 0;
    spin(r, 1000);
    r.cw(0x07);
    EXPECT_FALSE(r.ax.power_on());
    // The motor coasts (friction only) until standstill, then transition 5 completes.
    ASSERT_TRUE(r.until([&] { return r.ax.state() == State::SwitchedOn; }, 2000));
}

TEST(DeviceControl, T8_ShutdownOptionCodes) {
    for (int16_t code : {0, 1}) {
        Rig r;
        r.ax.params.shutdown = code;
        r.ax.params.profile_deceleration = 20000;
        spin(r, 1000);
        r.cw(0x06);
        EXPECT_EQ(r.ax.power_on(), code == 1);
        ASSERT_TRUE(r.until([&] { return r.ax.state() == State::ReadyToSwitchOn; }, 2000)) << code;
        EXPECT_EQ(r.state_bits(), 0x21);
    }
}

TEST(DeviceControl, T9_DisableVoltageFromOperationEnabled) {
    Rig r;
    spin(r, 500);
    r.cw(0x00);
    EXPECT_FALSE(r.ax.power_on());
    ASSERT_TRUE(r.until([&] { return r.ax.state() == State::SwitchOnDisabled; }, 2000));
}

TEST(DeviceControl, T11T16_QuickStopRampsWith6085AndStaysUntilEnable) {
    Rig r;
    r.ax.params.quick_stop_deceleration = 15000;
    spin(r, 1500);
    r.cw(0x0B);
    EXPECT_EQ(r.ax.state(), State::QuickStopActive);
    EXPECT_EQ(r.state_bits(), 0x17);
    EXPECT_NEAR(decel_over(r, 50), 15000, 1500);
    r.run_ms(300);
    EXPECT_EQ(r.ax.state(), State::QuickStopActive);  // 0x605A = 6: stay
    EXPECT_TRUE(r.ax.power_on());
    EXPECT_TRUE(r.sw() & sw::TargetReached);
    EXPECT_LT(std::abs(r.rpm()), 5);
    r.cw(0x0F);
    EXPECT_EQ(r.ax.state(), State::OperationEnabled);  // 16
}

TEST(DeviceControl, T12_DisableVoltageFromQuickStopActive) {
    Rig r;
    spin(r, 500);
    r.cw(0x0B);
    r.run_ms(200);
    r.cw(0x00);
    ASSERT_TRUE(r.until([&] { return r.ax.state() == State::SwitchOnDisabled; }, 1000));
    EXPECT_FALSE(r.ax.power_on());
}

TEST(DeviceControl, StandstillTimeoutForcesCompletion) {
    Rig r;
    r.ax.params.standstill_window = 0;  // never "still" while it coasts
    r.ax.params.standstill_timeout = 100;
    r.ax.params.shutdown = 0;  // power off at once, the motor coasts for ~300 ms
    spin(r, 1000);
    r.cw(0x06);
    r.run_ms(60);
    EXPECT_EQ(r.ax.state(), State::OperationEnabled);
    EXPECT_GT(std::abs(r.rpm()), 100);
    r.run_ms(60);
    EXPECT_EQ(r.ax.state(), State::ReadyToSwitchOn);
}

TEST(DeviceControl, T13T14_FaultReactionQuickStopRampThenFault) {
    Rig r;
    r.ax.params.fault_reaction = 2;
    r.ax.params.quick_stop_deceleration = 20000;
    spin(r, 1000);
    r.ax.raise_error(error_code::SoftwareParameter);  // an "f" error
    r.run(1);
    EXPECT_EQ(r.ax.state(), State::FaultReactionActive);
    EXPECT_EQ(r.state_bits(), 0x1F);  // power still on during the ramp
    EXPECT_NEAR(decel_over(r, 20), 20000, 3000);
    ASSERT_TRUE(r.until([&] { return r.ax.state() == State::Fault; }, 1000));
    EXPECT_EQ(r.state_bits(), 0x08);
    EXPECT_FALSE(r.ax.power_on());
    EXPECT_EQ(r.fb().error_code, error_code::SoftwareParameter);
}

TEST(DeviceControl, FaultReactionCode1UsesProfileDeceleration) {
    Rig r;
    r.ax.params.fault_reaction = 1;
    r.ax.params.profile_deceleration = 4000;
    spin(r, 1000);
    r.ax.raise_error(error_code::SoftwareParameter);
    r.run(1);
    EXPECT_NEAR(decel_over(r, 50), 4000, 600);
}

TEST(DeviceControl, FaultReactionCode0AndDErrorsDisableAtOnce) {
    {
        Rig r;
        r.ax.params.fault_reaction = 0;
        spin(r, 1000);
        r.ax.raise_error(error_code::SoftwareParameter);
        r.run(1);
        EXPECT_FALSE(r.ax.power_on());
        EXPECT_EQ(r.state_bits(), 0x0F);  // Fault Reaction Active with the power stage off
    }
    {
        Rig r;
        spin(r, 1000);
        r.ax.raise_error(error_code::Overcurrent);  // "d": whatever 0x605E says
        r.run(1);
        EXPECT_FALSE(r.ax.power_on());
        ASSERT_TRUE(r.until([&] { return r.ax.state() == State::Fault; }, 2000));
        EXPECT_EQ(r.fb().error_register, 0x03);
    }
}

TEST(DeviceControl, FaultReactionMinus1IsAWarningOnly) {
    Rig r;
    r.ax.params.fault_reaction = -1;
    spin(r, 500);
    r.ax.raise_error(error_code::SoftwareParameter);
    r.run(5);
    EXPECT_EQ(r.ax.state(), State::OperationEnabled);
    EXPECT_TRUE(r.sw() & sw::Warning);
    r.cw(0x8F);  // fault reset edge acknowledges warnings
    r.cw(0x0F);
    EXPECT_FALSE(r.sw() & sw::Warning);
    EXPECT_EQ(r.ax.state(), State::OperationEnabled);
}

TEST(DeviceControl, T15_FaultResetNeedsTheEdgeAndClearsErrors) {
    Rig r;
    r.ax.raise_error(error_code::SoftwareParameter);
    r.run(100);
    ASSERT_EQ(r.ax.state(), State::Fault);
    r.cw(0x80);  // rising edge from 0
    EXPECT_EQ(r.ax.state(), State::SwitchOnDisabled);
    EXPECT_EQ(r.fb().error_code, 0);
    ASSERT_EQ(r.rec.cleared.size(), 1u);
    EXPECT_EQ(r.rec.cleared[0], error_code::SoftwareParameter);
}

TEST(DeviceControl, ConnectionLostFollows6007) {
    {  // 3: quick stop ramp, then Fault
        Rig r;
        spin(r, 1000);
        r.ax.connection_lost();
        EXPECT_EQ(r.ax.state(), State::FaultReactionActive);
        EXPECT_TRUE(r.ax.power_on());
        EXPECT_EQ(r.fb().error_code, 0x8180);
        EXPECT_EQ(r.fb().error_register, 0x11);
        ASSERT_TRUE(r.until([&] { return r.ax.state() == State::Fault; }, 1000));
    }
    {  // 2: disable voltage
        Rig r;
        r.ax.params.abort_connection = 2;
        spin(r, 1000);
        r.ax.connection_lost();
        EXPECT_FALSE(r.ax.power_on());
    }
    {  // 1: fault signal only
        Rig r;
        r.ax.params.abort_connection = 1;
        spin(r, 1000);
        r.ax.connection_lost();
        r.run(2);
        EXPECT_EQ(r.ax.state(), State::OperationEnabled);
        EXPECT_TRUE(r.sw() & sw::Warning);
    }
}

TEST(DeviceControl, StoWhileEnabledDisablesAndBlocksReset) {
    Rig r;
    r.enable();
    r.ax.environment().set_sto(false);
    r.run(2);
    EXPECT_TRUE(r.rec.has(error_code::Sto));
    EXPECT_FALSE(r.ax.power_on());
    ASSERT_TRUE(r.until([&] { return r.ax.state() == State::Fault; }, 2000));
    r.cw(0x00);
    r.cw(0x80);
    EXPECT_EQ(r.ax.state(), State::Fault);
    r.ax.environment().set_sto(true);
    r.cw(0x00);
    r.cw(0x80);
    EXPECT_EQ(r.ax.state(), State::SwitchOnDisabled);
}

TEST(DeviceControl, HaltInPvmUsesQuickStopDecelerationAndStaysEnabled) {
    Rig r;
    r.ax.params.quick_stop_deceleration = 12000;
    spin(r, 1200);
    r.cw(0x10F);
    EXPECT_NEAR(decel_over(r, 50), 12000, 1500);
    ASSERT_TRUE(r.until([&] { return (r.sw() & sw::TargetReached) != 0; }, 500));
    EXPECT_EQ(r.ax.state(), State::OperationEnabled);
    r.run_ms(100);
    EXPECT_LT(std::abs(r.rpm()), 5);
    r.cw(0x0F);  // halt released: back to the target velocity
    EXPECT_TRUE(r.until([&] { return std::abs(r.rpm() - 1200) < 20; }, 1000));
}

TEST(DeviceControl, ACommandCompletesBeforeTheNextIsTaken) {
    Rig r;
    r.ax.params.disable_operation = 1;
    r.ax.params.profile_deceleration = 2000;
    spin(r, 1000);
    r.cw(0x07);      // transition 5 with a 0.5 s ramp
    r.cw(0x0F, 50);  // "enable operation" during the ramp is not taken
    EXPECT_LT(r.rpm(), 950);
    ASSERT_TRUE(r.until([&] { return r.ax.state() == State::SwitchedOn; }, 2000));
    r.cw(0x0F);
    EXPECT_EQ(r.ax.state(), State::OperationEnabled);  // now it is
}

TEST(DeviceControl, ErrorsReachTheSinkWithStateAndModeAndStateChangesAsDiagnosis) {
    struct Sink : EventSink {
        std::array<uint8_t, 5> mfr{};
        uint16_t code = 0;
        int diags = 0;
        void raise(uint16_t c, uint8_t, const std::array<uint8_t, 5>& m) override { code = c, mfr = m; }
        void clear(uint16_t, uint8_t) override {}
        void diag(Severity, uint16_t, std::string_view) override { ++diags; }
    } sink;
    Rig r;
    r.ax.set_event_sink(&sink);
    r.ax.command.mode = mode::CyclicSyncVelocity;
    r.enable();
    EXPECT_GE(sink.diags, 3);  // Ready, Switched On, Operation Enabled
    r.ax.raise_error(error_code::FollowingError);
    EXPECT_EQ(sink.code, 0x8611);
    EXPECT_EQ(sink.mfr[0], static_cast<uint8_t>(State::OperationEnabled));
    EXPECT_EQ(sink.mfr[1], static_cast<uint8_t>(mode::CyclicSyncVelocity));
}

TEST(DeviceControl, ConnectionLostWhileDisabledIsNoFault) {
    Rig r;
    r.cw(0x06);
    r.ax.connection_lost();
    r.run(2);
    EXPECT_EQ(r.ax.state(), State::ReadyToSwitchOn);
    EXPECT_FALSE(r.rec.has(error_code::EthercatStateMachine));
}
