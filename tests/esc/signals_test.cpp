// EscSignals (esc/esc.hpp): what a runtime serving many ESCs reads instead of touching each ESC. due_ns says
// when tick() next has something to do and must never be later than that (a late one loses a SYNC0 pulse or
// a watchdog expiry); wake says that a frame or a tick raised an event the PDI interrupt line shows.
#include <gtest/gtest.h>

#include <cstdint>

#include "esc_fixture.hpp"

using namespace esc_test;

namespace {

struct Signals : EscFixture<kT0> {
    esc::EscSignals sig;
    void SetUp() override {
        EscFixture::SetUp();
        fpwr(*e, 0x0410, {0x00, 0x00});  // PDI watchdog off: due_ns shows the DC events alone
        e->set_signals(&sig);
        e->tick(clk.now_ns());
        sig.wake = 0;
    }
    void TearDown() override { e->set_signals(nullptr); }
    uint64_t start_sync0(uint32_t cycle, int64_t start_in) {
        EXPECT_EQ(fpwr(*e, 0x09A0, le(cycle, 4)).wkc, 1);
        const uint64_t start = clk.now_ns() + static_cast<uint64_t>(start_in);
        EXPECT_EQ(fpwr(*e, 0x0990, le(start, 8)).wkc, 1);
        EXPECT_EQ(fpwr(*e, 0x0981, {0x03}).wkc, 1);
        return start;
    }
};

TEST_F(Signals, DueFollowsWhatFramesAndTicksDo) {
    EXPECT_EQ(sig.due_ns, UINT64_MAX) << "nothing runs";
    const uint64_t start = start_sync0(1'000'000, 100'000);
    EXPECT_EQ(sig.due_ns, 0u) << "a frame wrote the DC registers of a running SYNC0: unknown until a tick";
    e->tick(clk.now_ns());
    EXPECT_EQ(sig.due_ns, start);
    clk.set(start);
    e->tick(start);
    EXPECT_EQ(sig.due_ns, start + 1'000'000);
    // A frame that moves nothing leaves the exact figure.
    (void)fprd(*e, 0x0130, 2);
    fpwr(*e, 0x0120, {0x01, 0x00});
    EXPECT_EQ(sig.due_ns, start + 1'000'000);
    fpwr(*e, 0x0981, {0x00});
    EXPECT_EQ(sig.due_ns, UINT64_MAX) << "deactivated by a frame: nothing scheduled, the figure is exact";
    fpwr(*e, 0x0910, le(12345, 8));  // a drift compensation write with nothing scheduled
    EXPECT_EQ(sig.due_ns, UINT64_MAX);
}

// The DC time registers (0x0900-0x097F: receive times, system time, offset, delay, speed counter, filters)
// move no timer of their own, only the SYNC pulses through the local time: a frame that writes any of them
// leaves the exact figure while no pulse is scheduled (no tick needed: a master's drift compensation writes
// 0x0910 of every ESC of a line in every cycle), and makes it unknown while one is.
TEST_F(Signals, DcTimeRegisterWritesMoveTheDueTimeOnlyWithASyncPulseScheduled) {
    for (uint16_t a = 0x0900; a < 0x0980; ++a) {
        fpwr(*e, a, {0x5A});
        EXPECT_EQ(sig.due_ns, e->next_event_ns(clk.now_ns()))
            << "nothing scheduled, write of 0x" << std::hex << a;
    }
    fpwr(*e, 0x0910, le(12345, 8));
    EXPECT_EQ(sig.due_ns, UINT64_MAX);
    for (uint16_t a = 0x0900; a < 0x0980; ++a) {
        // A fresh ESC each time: the bytes written before would move its system time off the start time.
        e.emplace(esc::EscConfig{}, clk);
        set_station(*e, 0x1001);
        fpwr(*e, 0x0410, {0x00, 0x00});
        e->set_signals(&sig);
        start_sync0(1'000'000, 100'000);
        e->tick(clk.now_ns());
        ASSERT_NE(sig.due_ns, 0u);
        ASSERT_NE(sig.due_ns, UINT64_MAX) << "SYNC0 scheduled";
        fpwr(*e, a, {0x5A});
        EXPECT_EQ(sig.due_ns, 0u) << "SYNC0 scheduled, write of 0x" << std::hex << a;
    }
}

// Whatever a frame writes into the timer registers (watchdogs, SII, FMMU, SM, DC; every byte, with or without
// a SYNC pulse scheduled), due_ns is never later than the ESC's next event afterwards: 0 (unknown) or a time
// at or before it.
TEST_F(Signals, NoFrameWriteLeavesTheDueTimeLate) {
    for (const bool sync : {false, true}) {
        for (uint16_t a = 0x0400; a < 0x0A00; ++a) {
            SCOPED_TRACE(testing::Message() << "sync " << sync << ", write of 0x" << std::hex << a);
            e.emplace(esc::EscConfig{}, clk);
            set_station(*e, 0x1001);
            fpwr(*e, 0x0410, {0x00, 0x00});
            e->set_signals(&sig);
            if (sync) start_sync0(1'000'000, 100'000);
            e->tick(clk.now_ns());
            fpwr(*e, a, {0xFF});
            const uint64_t next = e->next_event_ns(clk.now_ns());
            EXPECT_TRUE(sig.due_ns == 0 || sig.due_ns <= next) << sig.due_ns << " after " << next;
        }
    }
}

TEST_F(Signals, PdiAccessLeavesDueUnknownUntilTheNextTick) {
    fpwr(*e, 0x0410, le(1000, 2));  // PDI watchdog: 1000 increments
    const uint64_t increment = (fprd(*e, 0x0400, 2).u16() + 2ull) * 40;
    e->tick(clk.now_ns());
    (void)e->read_reg<uint16_t>(0x0130);
    EXPECT_EQ(sig.due_ns, 0u) << "the PDI watchdog restarts at the next tick";
    clk.set(clk.now_ns() + 5'000);
    e->tick(clk.now_ns());
    EXPECT_EQ(sig.due_ns, clk.now_ns() + 1000 * increment) << "restarted at the tick";
}

TEST_F(Signals, WakeOnANewMaskedEventOnly) {
    e->write_reg<uint32_t>(0x0204, 0x00000005);  // AL control and SYNC0
    sig.wake = 0;
    fpwr(*e, 0x0120, {0x02, 0x00});
    EXPECT_EQ(sig.wake, 1) << "AL control written by a frame";
    sig.wake = 0;
    fpwr(*e, 0x0120, {0x02, 0x00});
    EXPECT_EQ(sig.wake, 0) << "the event was still pending: nothing new for the PDI side";
    (void)e->read_reg<uint16_t>(0x0120);  // acknowledges it
    fpwr(*e, 0x0120, {0x04, 0x00});
    EXPECT_EQ(sig.wake, 1);
    sig.wake = 0;
    const uint64_t start = start_sync0(1'000'000, 50'000);
    clk.set(start - 1);
    e->tick(start - 1);
    EXPECT_EQ(sig.wake, 0);
    clk.set(start);
    e->tick(start);
    EXPECT_EQ(sig.wake, 1) << "SYNC0 pulse in the AL event register";
}

TEST_F(Signals, MaskedOutEventsDoNotWake) {
    e->write_reg<uint32_t>(0x0204, 0x00000004);  // SYNC0 only
    sig.wake = 0;
    fpwr(*e, 0x0120, {0x02, 0x00});
    EXPECT_EQ(sig.wake, 0);
}

TEST_F(Signals, EepromWriteWakes) {
    uint16_t written = 0;
    e->on_eeprom_write([&](uint16_t, uint16_t value) { written = value; });
    sig.wake = 0;
    EXPECT_EQ(fpwr(*e, 0x0502, {0x81, 0x02, 0x10, 0x00, 0x00, 0x00, 0xEF, 0xBE}).wkc, 1);
    EXPECT_EQ(written, 0xBEEF);
    EXPECT_EQ(sig.wake, 1) << "the firmware keeps the written words";
}

// activity: what a controller without a usable interrupt line (an SM without its PDI interrupt) would find
// changed when it reads the registers. Every frame counts, whatever it does, and a tick that fired a SYNC
// pulse or changed a watchdog; the PDI side's own accesses and a tick with nothing to do do not. Not raising
// it for a change a frame or a timer made would leave such a device unpolled (device::Line); raising it for
// nothing only costs a poll.
TEST_F(Signals, ActivityCountsFramesAndTimerEventsNotPdiAccesses) {
    const uint32_t a0 = sig.activity;
    (void)fprd(*e, 0x0130, 2);
    EXPECT_NE(sig.activity, a0) << "a frame (even one that reads)";
    uint32_t a = sig.activity;
    (void)e->read_reg<uint16_t>(0x0130);
    e->write_reg<uint16_t>(0x0134, 0);
    e->tick(clk.now_ns());
    EXPECT_EQ(sig.activity, a) << "PDI accesses and a tick that only settles them";
    const uint64_t start = start_sync0(1'000'000, 50'000);
    a = sig.activity;
    clk.set(start - 1);
    e->tick(start - 1);
    EXPECT_EQ(sig.activity, a) << "before the pulse";
    clk.set(start);
    e->tick(start);
    EXPECT_NE(sig.activity, a) << "SYNC0 fired (0x098E changed) without any AL event mapped";
    a = sig.activity;
    // The process-data watchdog expiring (0x0440 bit 0 cleared) is a change too: a write through SM0 set up
    // as a one-byte buffered output SM with the watchdog trigger starts it.
    EXPECT_EQ(fpwr(*e, 0x0981, {0x00}).wkc, 1);  // SYNC0 off: the next tick has only the watchdog to do
    EXPECT_EQ(fpwr(*e, 0x0800, {0x00, 0x10, 0x01, 0x00, 0x44, 0x00, 0x01, 0x00}).wkc, 1);
    EXPECT_EQ(fpwr(*e, 0x1000, {0x5A}).wkc, 1);
    a = sig.activity;
    const uint64_t later = clk.now_ns() + 2'000'000'000ull;  // past any watchdog time
    clk.set(later);
    e->tick(later);
    EXPECT_EQ(fprd(*e, 0x0440, 2).u16() & 1, 0) << "expired";
    EXPECT_NE(sig.activity, a) << "the watchdog's expiry";
}

}  // namespace
