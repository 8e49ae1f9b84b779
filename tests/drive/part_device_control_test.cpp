// DeviceControl alone: the CiA 402 transitions and what they ask of the other parts, through a fake of
// DeviceControl::Parts (no Axis).
#include <gtest/gtest.h>

#include <vector>

#include "drive/device_control.hpp"
#include "recorder.hpp"

using namespace drive;
using namespace drive::test;

namespace {

struct FakeParts final : DeviceControl::Parts {
    uint16_t refuse = 0;
    bool reset_ok = true;
    int powered_calls = 0, resumed_calls = 0, reset_calls = 0, acknowledged = 0;
    std::vector<StopKind> stops;
    std::vector<uint16_t> faults;
    uint16_t enable_refused() override { return refuse; }
    void powered() override { ++powered_calls; }
    // Stands in for the limit by 0x60C5 and the unit conversion: twice the rpm/s.
    double stopping(StopKind k, double decel_rpm_s) override {
        stops.push_back(k);
        return 2 * decel_rpm_s;
    }
    void resumed() override { ++resumed_calls; }
    bool fault_reset() override {
        ++reset_calls;
        return reset_ok;
    }
    void acknowledge_warnings() override { ++acknowledged; }
    void fault(uint16_t code) override { faults.push_back(code); }
};

struct DcRig {
    DeviceControl dc;
    FakeParts parts;
    Recorder rec;
    AxisFaults faults;
    DeviceControl::Options opt{0, 0, 1000, 5000};
    int64_t now = 0;

    DcRig() { dc.start(rec); }
    void cw(uint16_t c) {
        dc.command(c, faults, opt, parts, rec, now);
        dc.end_cycle(c);
        now += 1'000'000;
    }
    void enable() {
        cw(0x06);
        cw(0x0F);
    }
};

}  // namespace

TEST(DeviceControlPart, StartsInSwitchOnDisabledAndEnablesInOneCommand) {
    DcRig r;
    EXPECT_EQ(r.dc.state(), State::SwitchOnDisabled);
    r.cw(0x06);
    EXPECT_EQ(r.dc.state(), State::ReadyToSwitchOn);
    r.cw(0x0F);  // transitions 3 and 4 at once
    EXPECT_EQ(r.dc.state(), State::OperationEnabled);
    EXPECT_TRUE(r.dc.power());
    EXPECT_TRUE(r.dc.operational());
    EXPECT_EQ(r.parts.powered_calls, 1);
}

TEST(DeviceControlPart, RefusedPowerStageRaisesTheErrorAndStaysSwitchedOn) {
    DcRig r;
    r.parts.refuse = error_code::Sto;
    r.enable();
    EXPECT_EQ(r.dc.state(), State::SwitchedOn);
    EXPECT_FALSE(r.dc.power());
    ASSERT_EQ(r.parts.faults.size(), 1u);
    EXPECT_EQ(r.parts.faults[0], error_code::Sto);
    EXPECT_EQ(r.parts.powered_calls, 0);
}

TEST(DeviceControlPart, DisableOperationWithRampWaitsForTheRampAndStandstill) {
    DcRig r;
    r.opt.disable_operation = 1;  // 0x605C = 1: ramp, then disable
    r.enable();
    r.cw(0x07);  // transition 5
    ASSERT_EQ(r.parts.stops.size(), 1u);
    EXPECT_EQ(r.parts.stops[0], StopKind::Ramp);
    EXPECT_EQ(r.dc.stop_deceleration(), 2000.0);  // 0x6084, as the parts converted it
    EXPECT_TRUE(r.dc.waiting());
    EXPECT_FALSE(r.dc.operational());
    r.dc.settle(true, 10, 0xFFFF, r.rec, r.now);
    EXPECT_EQ(r.dc.state(), State::OperationEnabled);  // the ramp is not over
    EXPECT_TRUE(r.dc.power());
    r.dc.ramp_reached(true);
    r.dc.settle(false, 10, 0xFFFF, r.rec, r.now);  // ramp over, not yet still: power off, still waiting
    EXPECT_FALSE(r.dc.power());
    EXPECT_TRUE(r.dc.waiting());
    r.dc.settle(true, 10, 0xFFFF, r.rec, r.now);
    EXPECT_EQ(r.dc.state(), State::SwitchedOn);
    EXPECT_FALSE(r.dc.waiting());
    EXPECT_EQ(r.dc.stop(), StopKind::None);
}

TEST(DeviceControlPart, StandstillTimeoutCompletesTheTransition) {
    DcRig r;
    r.enable();
    r.cw(0x06);  // transition 8, 0x605B = 0: disable at once
    EXPECT_EQ(r.parts.stops.back(), StopKind::Disable);
    r.dc.settle(false, 10, 5, r.rec, r.now);  // 1 ms after the command: not yet
    EXPECT_EQ(r.dc.state(), State::OperationEnabled);
    r.dc.settle(false, 10, 5, r.rec, r.now + 5'000'000);
    EXPECT_EQ(r.dc.state(), State::ReadyToSwitchOn);
}

TEST(DeviceControlPart, QuickStopRampsAndEnableOperationResumes) {
    DcRig r;
    r.enable();
    r.cw(0x0B);  // transition 11
    EXPECT_EQ(r.dc.state(), State::QuickStopActive);
    EXPECT_EQ(r.dc.stop(), StopKind::Ramp);
    EXPECT_EQ(r.dc.stop_deceleration(), 10000.0);  // 0x6085
    r.cw(0x0F);                                    // transition 16
    EXPECT_EQ(r.dc.state(), State::OperationEnabled);
    EXPECT_EQ(r.dc.stop(), StopKind::None);
    EXPECT_EQ(r.parts.resumed_calls, 1);
}

TEST(DeviceControlPart, DeliberateQuickStopFaultIgnoresTheCommand) {
    DcRig r;
    r.faults.quick_stop_ignored = true;
    r.enable();
    r.cw(0x0B);
    EXPECT_EQ(r.dc.state(), State::OperationEnabled);
}

TEST(DeviceControlPart, FaultReactionRampsWhilePoweredAndEndsInFault) {
    DcRig r;
    r.enable();
    r.dc.react(Reaction::FaultReactionCode, 1, false, r.opt, r.parts, r.rec,
               r.now);  // 0x605E = 1: profile ramp
    EXPECT_EQ(r.dc.state(), State::FaultReactionActive);
    EXPECT_EQ(r.dc.stop(), StopKind::Ramp);
    EXPECT_EQ(r.dc.stop_deceleration(), 2000.0);
    r.cw(0x0F);  // no command while the reaction runs
    EXPECT_EQ(r.dc.state(), State::FaultReactionActive);
    r.dc.ramp_reached(true);
    r.dc.settle(true, 10, 0xFFFF, r.rec, r.now);
    EXPECT_EQ(r.dc.state(), State::Fault);
    EXPECT_FALSE(r.dc.power());
}

TEST(DeviceControlPart, UnpoweredAtRestEntersFaultAtOnce) {
    DcRig r;
    r.dc.react(Reaction::FaultReactionCode, 2, true, r.opt, r.parts, r.rec, r.now);
    EXPECT_EQ(r.dc.state(), State::Fault);
    EXPECT_EQ(r.parts.stops.back(), StopKind::Disable);
}

TEST(DeviceControlPart, FaultResetAsksSupervisionAndLeavesFaultOnlyWhenAccepted) {
    DcRig r;
    r.dc.react(Reaction::Disable, 0, true, r.opt, r.parts, r.rec, r.now);
    ASSERT_EQ(r.dc.state(), State::Fault);
    r.parts.reset_ok = false;
    r.cw(0x00);
    r.cw(0x80);
    EXPECT_EQ(r.parts.reset_calls, 1);
    EXPECT_EQ(r.dc.state(), State::Fault);
    r.parts.reset_ok = true;
    r.cw(0x00);
    r.cw(0x80);
    EXPECT_EQ(r.parts.reset_calls, 2);
    EXPECT_EQ(r.dc.state(), State::SwitchOnDisabled);
}

TEST(DeviceControlPart, FaultResetOutsideFaultAcknowledgesWarnings) {
    DcRig r;
    r.cw(0x00);
    r.cw(0x80);
    EXPECT_EQ(r.parts.acknowledged, 1);
    EXPECT_EQ(r.parts.reset_calls, 0);
    EXPECT_EQ(r.dc.state(), State::SwitchOnDisabled);
}
