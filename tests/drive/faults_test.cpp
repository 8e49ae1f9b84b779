// The deliberate CiA 402 faults (drive/faults.hpp, `ecat-slave --fault`): each one breaks the one behaviour
// it names, and the same commands to an axis without it do what IEC 61800-7-201 prescribes.
#include "rig.hpp"

namespace drive::test {
namespace {

TEST(AxisFaults, QuickStopIgnored) {
    for (const bool faulty : {false, true}) {
        SCOPED_TRACE(faulty ? "faulty" : "clean");
        Rig r;
        r.ax.faults.quick_stop_ignored = faulty;
        r.enable();
        r.cw(0x0B);  // quick stop
        EXPECT_EQ(r.ax.state(), faulty ? State::OperationEnabled : State::QuickStopActive);
        EXPECT_EQ(r.state_bits() & 0x6F, faulty ? 0x27 : 0x07);  // quick stop bit 5 stays set when ignored
        // Disable voltage still works.
        r.cw(0x00, 200);
        EXPECT_EQ(r.ax.state(), State::SwitchOnDisabled);
    }
}

TEST(AxisFaults, FaultResetIgnored) {
    for (const bool faulty : {false, true}) {
        SCOPED_TRACE(faulty ? "faulty" : "clean");
        Rig r;
        r.ax.faults.fault_reset_ignored = faulty;
        r.ax.raise_error(error_code::SoftwareParameter);
        r.run(100);
        ASSERT_EQ(r.ax.state(), State::Fault);
        r.cw(0x80);  // rising edge of bit 7
        EXPECT_EQ(r.ax.state(), faulty ? State::Fault : State::SwitchOnDisabled);
        EXPECT_EQ(r.fb().error_code, faulty ? error_code::SoftwareParameter : 0);
    }
}

TEST(AxisFaults, ModeDisplayStuck) {
    for (const bool faulty : {false, true}) {
        SCOPED_TRACE(faulty ? "faulty" : "clean");
        Rig r;  // runs its first cycle in CSP
        r.ax.faults.mode_display_stuck = faulty;
        ASSERT_EQ(r.fb().mode_display, mode::CyclicSyncPosition);
        r.ax.command.mode = mode::CyclicSyncTorque;
        r.run(2);
        EXPECT_EQ(r.ax.active_mode(), mode::CyclicSyncTorque);  // the mode itself changes
        EXPECT_EQ(r.fb().mode_display, faulty ? mode::CyclicSyncPosition : mode::CyclicSyncTorque);
    }
}

}  // namespace
}  // namespace drive::test
