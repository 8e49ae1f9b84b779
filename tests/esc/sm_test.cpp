// SyncManagers (ESC datasheet section I, SyncManager): mailbox and buffered modes, both sides, events, lock
// rule (E3), repeat, PDI control.
#include <gtest/gtest.h>

#include <optional>

#include "esc_fixture.hpp"

using namespace esc_test;

namespace {

struct SyncManagerRules : EscFixture<> {
    void SetUp() override {
        EscFixture::SetUp();
        // SOEM style: clear all SMs, then start/length/control + activate in one write each.
        ASSERT_EQ(run1(*e, dg(BWR, 0, 0x0800, std::vector<uint8_t>(32, 0))).wkc, 1);
        ASSERT_EQ(fpwr(*e, 0x0800, sm_bytes(0x1000, 8, 0x26, 1)).wkc, 1);  // mailbox out
        ASSERT_EQ(fpwr(*e, 0x0808, sm_bytes(0x1080, 8, 0x22, 1)).wkc, 1);  // mailbox in
        ASSERT_EQ(fpwr(*e, 0x0810, sm_bytes(0x1100, 4, 0x64, 1)).wkc, 1);  // outputs
        ASSERT_EQ(fpwr(*e, 0x0818, sm_bytes(0x1180, 4, 0x20, 1)).wkc, 1);  // inputs
        e->read_reg<uint8_t>(0x0806);  // acknowledge the SM activation event
    }
    uint8_t status(unsigned n) { return fprd(*e, static_cast<uint16_t>(0x0805 + 8 * n), 1).data[0]; }
    uint32_t al_event() { return e->read_reg<uint32_t>(0x0220); }
    std::vector<uint8_t> pdi_read(uint16_t a, std::size_t n) {
        std::vector<uint8_t> b(n);
        e->read(a, b);
        return b;
    }
};

const std::vector<uint8_t> kMsgA{1, 2, 3, 4, 5, 6, 7, 8};
const std::vector<uint8_t> kMsgB{9, 9, 9, 9, 9, 9, 9, 9};

TEST_F(SyncManagerRules, ConfigurationAndActivateInOneWriteIsTaken) {
    Datagram d = fprd(*e, 0x0800, 8);
    EXPECT_EQ(d.u16(0), 0x1000);
    EXPECT_EQ(d.u16(2), 8);
    EXPECT_EQ(d.data[4], 0x26);
    EXPECT_EQ(d.data[6], 0x01);
}

TEST_F(SyncManagerRules, ConfigLockedWhileEnabled) {
    fpwr(*e, 0x0800, sm_bytes(0x1400, 16, 0x22, 1));
    Datagram d = fprd(*e, 0x0800, 8);
    EXPECT_EQ(d.u16(0), 0x1000);
    EXPECT_EQ(d.u16(2), 8);
    EXPECT_EQ(d.data[4], 0x26);
    // One write that disables and reconfigures only disables.
    fpwr(*e, 0x0800, sm_bytes(0x1400, 16, 0x22, 0));
    d = fprd(*e, 0x0800, 8);
    EXPECT_EQ(d.u16(0), 0x1000);
    EXPECT_EQ(d.data[6], 0x00);
    // Now disabled: configuration is writable.
    fpwr(*e, 0x0800, sm_bytes(0x1400, 16, 0x22, 1));
    d = fprd(*e, 0x0800, 8);
    EXPECT_EQ(d.u16(0), 0x1400);
    EXPECT_EQ(d.u16(2), 16);
}

// A slave stack deactivates SM0/SM1 through the PDI (0x0807.0) when it enters INIT (Beckhoff SSC
// MBX_StopMailboxHandler, SOES ESC_stopmbx). Such an SM is not operating: a master that goes down to INIT and
// writes the bootstrap mailbox over the still-activated SMs (libethercat, SOEM's firm_update) reconfigures
// it.
TEST_F(SyncManagerRules, ConfigWritableWhileDeactivatedByThePdi) {
    e->write_reg<uint8_t>(0x0807, 0x01);
    e->write_reg<uint8_t>(0x080F, 0x01);
    fpwr(*e, 0x0800, sm_bytes(0x1400, 16, 0x26, 1));
    fpwr(*e, 0x0808, sm_bytes(0x1800, 16, 0x22, 1));
    Datagram d = fprd(*e, 0x0800, 16);
    EXPECT_EQ(d.u16(0), 0x1400);
    EXPECT_EQ(d.u16(2), 16);
    EXPECT_EQ(d.data[6], 0x01);
    EXPECT_EQ(d.u16(8), 0x1800);
    EXPECT_EQ(d.u16(10), 16);
    // Active again from the PDI side: locked again.
    e->write_reg<uint8_t>(0x0807, 0x00);
    fpwr(*e, 0x0800, sm_bytes(0x1000, 8, 0x26, 1));
    EXPECT_EQ(fprd(*e, 0x0800, 2).u16(0), 0x1400);
    // The new mailbox works.
    EXPECT_EQ(fpwr(*e, 0x1400, std::vector<uint8_t>(16, 0x5A)).wkc, 1);
    EXPECT_EQ(status(0) & 0x08, 0x08);
}

TEST_F(SyncManagerRules, ActivateWriteRaisesAlEventClearedByPdiRead) {
    EXPECT_EQ(al_event() & 0x10, 0u);
    fpwr(*e, 0x080E, {0x01});
    EXPECT_EQ(al_event() & 0x10, 0x10u);
    e->read_reg<uint8_t>(0x080E);
    EXPECT_EQ(al_event() & 0x10, 0u);
}

TEST_F(SyncManagerRules, MailboxWriteFullThenBlocked) {
    EXPECT_EQ(fpwr(*e, 0x1000, kMsgA).wkc, 1);
    EXPECT_EQ(status(0) & 0x09, 0x09);          // full + interrupt write
    EXPECT_EQ(al_event() & 0x100, 0x100u);      // SM0 event to the PDI (control bit 5)
    EXPECT_EQ(fpwr(*e, 0x1000, kMsgB).wkc, 0);  // write while full
    EXPECT_EQ(fprd(*e, 0x1000, 8).wkc, 0);      // wrong direction
    EXPECT_EQ(pdi_read(0x1000, 8), kMsgA);      // PDI reads to the last byte
    EXPECT_EQ(status(0) & 0x0B, 0x02);          // empty, interrupt read
    EXPECT_EQ(al_event() & 0x100, 0u);
    EXPECT_EQ(fpwr(*e, 0x1000, kMsgB).wkc, 1);
    EXPECT_EQ(pdi_read(0x1000, 8), kMsgB);
}

TEST_F(SyncManagerRules, MailboxMustOpenAtStart) {
    EXPECT_EQ(fpwr(*e, 0x1002, {1, 2, 3, 4, 5, 6}).wkc, 0);
    EXPECT_EQ(fpwr(*e, 0x1000, {1, 2, 3, 4}).wkc, 1);  // opened, not complete
    EXPECT_EQ(status(0) & 0x08, 0);
    EXPECT_EQ(status(0) & 0x80, 0x80);                 // write buffer in use
    EXPECT_EQ(fpwr(*e, 0x1004, {5, 6, 7, 8}).wkc, 1);  // continue and close
    EXPECT_EQ(status(0) & 0x88, 0x08);
    EXPECT_EQ(pdi_read(0x1000, 8), kMsgA);
}

TEST_F(SyncManagerRules, MailboxCommitAtEndOfFrame) {
    auto r = run(*e, {dg(FPWR, 0x1001, 0x1000, kMsgA), dg_len(FPRD, 0x1001, 0x0805, 1),
                      dg(FPWR, 0x1001, 0x1000, kMsgB)});
    EXPECT_EQ(r[0].wkc, 1);
    EXPECT_EQ(r[1].data[0] & 0x08, 0);  // not yet full inside the frame
    EXPECT_EQ(r[2].wkc, 0);             // the end address cannot be accessed twice in one frame
    EXPECT_EQ(status(0) & 0x08, 0x08);
    EXPECT_EQ(pdi_read(0x1000, 8), kMsgA);
}

TEST_F(SyncManagerRules, MailboxWriteInMalformedFrameIsDiscarded) {
    auto f = build({dg(FPWR, 0x1001, 0x1000, kMsgA), dg_len(FPRD, 0x1001, 0x0000, 2)}, 0);
    f.resize(f.size() - 2);  // second datagram truncated: a frame length error
    EXPECT_FALSE(e->process_frame(f));
    EXPECT_EQ(status(0) & 0x88, 0x00);
    EXPECT_EQ(fpwr(*e, 0x1000, kMsgB).wkc, 1);  // still writable
}

TEST_F(SyncManagerRules, MailboxReadEmptyThenFull) {
    EXPECT_EQ(fprd(*e, 0x1080, 8).wkc, 0);
    e->write(0x1080, kMsgA);
    EXPECT_EQ(status(1) & 0x09, 0x09);
    Datagram d = fprd(*e, 0x1080, 8);
    EXPECT_EQ(d.wkc, 1);
    EXPECT_EQ(d.data, kMsgA);
    EXPECT_EQ(status(1) & 0x0B, 0x02);      // read, empty again
    EXPECT_EQ(al_event() & 0x200, 0x200u);  // SM1 event: master read the mailbox
    EXPECT_EQ(fprd(*e, 0x1080, 8).wkc, 0);
    e->write(0x1080, kMsgB);  // PDI write clears the read interrupt
    EXPECT_EQ(al_event() & 0x200, 0u);
    EXPECT_EQ(fprd(*e, 0x1080, 8).data, kMsgB);
}

TEST_F(SyncManagerRules, PdiCannotWriteFullMailbox) {
    e->write(0x1080, kMsgA);
    e->write(0x1080, kMsgB);
    EXPECT_EQ(fprd(*e, 0x1080, 8).data, kMsgA);
}

TEST_F(SyncManagerRules, RepeatRequestAndAcknowledge) {
    e->write(0x1080, kMsgA);
    EXPECT_EQ(fprd(*e, 0x1080, 8).wkc, 1);  // reply "lost"
    fpwr(*e, 0x080E, {0x03});               // toggle repeat request
    EXPECT_EQ(al_event() & 0x10, 0x10u);
    const uint8_t act = e->read_reg<uint8_t>(0x080E);
    EXPECT_EQ(act & 0x02, 0x02);
    EXPECT_EQ(al_event() & 0x10, 0u);
    e->write(0x1080, kMsgA);              // firmware re-writes the backup
    e->write_reg<uint8_t>(0x080F, 0x02);  // and acknowledges
    EXPECT_EQ(fprd(*e, 0x080F, 1).data[0] & 0x02, 0x02);
    EXPECT_EQ(fprd(*e, 0x1080, 8).data, kMsgA);
    // The SM stayed enabled (bit 0 unchanged), so it was not reset.
    EXPECT_EQ(fprd(*e, 0x080E, 1).data[0] & 0x01, 0x01);
}

TEST_F(SyncManagerRules, PdiDeactivationProtectsArea) {
    e->write(0x1080, kMsgA);
    e->write_reg<uint8_t>(0x080F, 0x01);
    EXPECT_EQ(fprd(*e, 0x080F, 1).data[0] & 0x01, 0x01);
    EXPECT_EQ(fprd(*e, 0x1080, 8).wkc, 0);  // protected, state reset
    EXPECT_EQ(status(1) & 0x08, 0);
    e->write_reg<uint8_t>(0x080F, 0x00);
    EXPECT_EQ(fprd(*e, 0x1080, 8).wkc, 0);  // empty after re-activation
    e->write(0x1080, kMsgB);
    EXPECT_EQ(fprd(*e, 0x1080, 8).data, kMsgB);
}

TEST_F(SyncManagerRules, DisablingByEcatResetsState) {
    EXPECT_EQ(fpwr(*e, 0x1000, kMsgA).wkc, 1);
    fpwr(*e, 0x0806, {0x00});
    EXPECT_EQ(status(0) & 0x08, 0);
    // Disabled SM area is plain RAM.
    EXPECT_EQ(fprd(*e, 0x1000, 8).wkc, 1);
    fpwr(*e, 0x0806, {0x01});
    EXPECT_EQ(fpwr(*e, 0x1000, kMsgB).wkc, 1);
    EXPECT_EQ(pdi_read(0x1000, 8), kMsgB);
}

TEST_F(SyncManagerRules, BufferedConsumerGetsNewest) {
    for (uint8_t v = 1; v <= 3; ++v)
        EXPECT_EQ(fpwr(*e, 0x1100, {v, v, v, v}).wkc, 1);
    EXPECT_EQ(status(2) & 0x01, 0x01);
    EXPECT_EQ(pdi_read(0x1100, 4), (std::vector<uint8_t>{3, 3, 3, 3}));
    EXPECT_EQ(status(2) & 0x01, 0x00);
    EXPECT_EQ(pdi_read(0x1100, 4), (std::vector<uint8_t>{3, 3, 3, 3}));  // no new data: same buffer
}

TEST_F(SyncManagerRules, BufferedThreeBufferExchange) {
    fpwr(*e, 0x1100, {1, 1, 1, 1});
    // PDI opens the buffer (reads the first half), ECAT completes a newer one meanwhile.
    EXPECT_EQ(pdi_read(0x1100, 2), (std::vector<uint8_t>{1, 1}));
    EXPECT_EQ(status(2) & 0x40, 0x40);  // read buffer in use
    fpwr(*e, 0x1100, {2, 2, 2, 2});
    fpwr(*e, 0x1100, {3, 3, 3, 3});
    EXPECT_EQ(pdi_read(0x1102, 2), (std::vector<uint8_t>{1, 1}));  // the open buffer stays consistent
    EXPECT_EQ(pdi_read(0x1100, 4), (std::vector<uint8_t>{3, 3, 3, 3}));
}

TEST_F(SyncManagerRules, BufferedLastWrittenStatus) {
    EXPECT_EQ(status(2) & 0x30, 0x30);  // none written yet
    fpwr(*e, 0x1100, {1, 1, 1, 1});
    const uint8_t first = (status(2) >> 4) & 3;
    EXPECT_NE(first, 3);
    fpwr(*e, 0x1100, {2, 2, 2, 2});
    EXPECT_NE((status(2) >> 4) & 3, first);
}

TEST_F(SyncManagerRules, BufferedOpenAtStartOnly) {
    EXPECT_EQ(fpwr(*e, 0x1102, {7, 7}).wkc, 0);
    EXPECT_EQ(fpwr(*e, 0x1104, {7, 7}).wkc, 0);  // buffers 2/3 are not directly accessible
    EXPECT_EQ(fpwr(*e, 0x1100, {5, 5}).wkc, 1);
    EXPECT_EQ(fpwr(*e, 0x1102, {6, 6}).wkc, 1);
    EXPECT_EQ(pdi_read(0x1100, 4), (std::vector<uint8_t>{5, 5, 6, 6}));
}

TEST_F(SyncManagerRules, BufferedInputsAlwaysReadable) {
    Datagram d = fprd(*e, 0x1180, 4);
    EXPECT_EQ(d.wkc, 1);
    e->write(0x1180, std::vector<uint8_t>{4, 3, 2, 1});
    EXPECT_EQ(fprd(*e, 0x1180, 4).data, (std::vector<uint8_t>{4, 3, 2, 1}));
    EXPECT_EQ(fprd(*e, 0x1180, 4).data, (std::vector<uint8_t>{4, 3, 2, 1}));
    EXPECT_EQ(fpwr(*e, 0x1180, {0, 0, 0, 0}).wkc, 0);  // wrong direction
}

TEST_F(SyncManagerRules, EcatEventsForSmWhenEnabled) {
    // SM1 with ECAT event enable (control bit 4): master sees the mailbox full via 0x0210 bit 5.
    fpwr(*e, 0x080E, {0x00});
    fpwr(*e, 0x0808, sm_bytes(0x1080, 8, 0x32, 1));
    fpwr(*e, 0x0200, {0x20, 0x00});
    e->write(0x1080, kMsgA);
    EXPECT_EQ(fprd(*e, 0x0210, 2).u16() & 0x0020, 0x0020);
    EXPECT_EQ(run1(*e, dg_len(FPRD, 0x1001, 0x1080, 8)).irq & 0x0020, 0x0020);
    EXPECT_EQ(fprd(*e, 0x0210, 2).u16() & 0x0020, 0x0000);
}

TEST_F(SyncManagerRules, ProcessDataWatchdog) {
    fpwr(*e, 0x0420, le(10, 2));  // 10 x 100 us = 1 ms
    e->tick();                    // arms the PDI watchdog (100 ms) after the PDI accesses of SetUp
    EXPECT_EQ(fpwr(*e, 0x1100, {1, 2, 3, 4}).wkc, 1);
    EXPECT_EQ(e->next_event_ns(), 1'000'000u + 1'000'000u);
    clk.advance(999'000);
    e->tick();
    EXPECT_EQ(fprd(*e, 0x0440, 2).u16() & 1, 1);
    clk.advance(1'000);
    e->tick();
    EXPECT_EQ(fprd(*e, 0x0440, 2).u16() & 1, 0);
    EXPECT_EQ(fprd(*e, 0x0442, 1).data[0], 1);
    EXPECT_EQ(al_event() & 0x40, 0x40u);
    EXPECT_TRUE(e->irq());
    e->read_reg<uint16_t>(0x0440);
    EXPECT_EQ(al_event() & 0x40, 0u);
    // Retriggered by the next output write; counters cleared by writing 0x0442.
    fpwr(*e, 0x1100, {1, 2, 3, 4});
    EXPECT_EQ(fprd(*e, 0x0440, 2).u16() & 1, 1);
    fpwr(*e, 0x0442, {0x00});
    EXPECT_EQ(fprd(*e, 0x0442, 2).u16(), 0);
}

TEST_F(SyncManagerRules, InputsDoNotTriggerWatchdog) {
    fpwr(*e, 0x0420, le(10, 2));
    e->write(0x1180, std::vector<uint8_t>{1, 2, 3, 4});
    fprd(*e, 0x1180, 4);
    clk.advance(5'000'000);
    e->tick();
    EXPECT_EQ(fprd(*e, 0x0442, 1).data[0], 0);
}

}  // namespace

// 0x09F0 (ECAT buffer change event time): local time of the beginning of a frame that completed an ECAT-side
// buffer access; frames that leave the buffers alone, a partial access or a malformed frame do not move it.
TEST_F(SyncManagerRules, EcatBufferChangeTimeLatchesTheFrameStart) {
    auto change_time = [&] { return e->read_reg<uint32_t>(0x09F0); };
    EXPECT_EQ(change_time(), 0u);
    clk.set(5'000'000);
    const uint64_t first = e->local_time_ns();
    EXPECT_EQ(fpwr(*e, 0x1100, {1, 2, 3, 4}).wkc, 1);  // outputs, whole buffer
    EXPECT_EQ(change_time(), static_cast<uint32_t>(first));

    clk.set(6'000'000);
    EXPECT_EQ(fprd(*e, 0x0000, 4).wkc, 1);       // no buffer touched
    EXPECT_EQ(fpwr(*e, 0x1100, {9, 9}).wkc, 1);  // buffer opened, not completed
    EXPECT_EQ(change_time(), static_cast<uint32_t>(first));

    clk.set(7'000'000);
    const uint64_t second = e->local_time_ns();
    EXPECT_EQ(fprd(*e, 0x1180, 4).wkc, 1);  // inputs read by the master: also a buffer change
    EXPECT_EQ(change_time(), static_cast<uint32_t>(second));

    // Not writable from either side.
    EXPECT_EQ(fpwr(*e, 0x09F0, {0, 0, 0, 0}).wkc, 1);
    EXPECT_EQ(change_time(), static_cast<uint32_t>(second));
}

// Issue 14, finding 1: FPWR 0x0820 <- 00 01 00 80 20 00 01 00 (SM4: start 0x0100, length 0x8000, buffered,
// enabled) made every address from 0x0100 up unreachable, the SM registers included. SM buffers live in the
// process RAM only: an SM over the register space or beyond the RAM captures nothing (one over the register
// space is closed at its last byte: register_sm_test.cpp).
TEST_F(SyncManagerRules, SmOverTheRegisterSpaceCapturesNoAddress) {
    EXPECT_EQ(fpwr(*e, 0x0820, {0x00, 0x01, 0x00, 0x80, 0x20, 0x00, 0x01, 0x00}).wkc, 1);
    e->read_reg<uint8_t>(0x0826);  // acknowledge the SM activation event
    // The SM's own registers: readable, and the activate byte is writable (the master can disable it).
    Datagram d = fprd(*e, 0x0820, 8);
    EXPECT_EQ(d.wkc, 1);
    EXPECT_EQ(d.u16(0), 0x0100);
    EXPECT_EQ(d.u16(2), 0x8000);
    EXPECT_EQ(d.data[6], 0x01);
    // Registers from 0x0100 up answer from both sides.
    EXPECT_EQ(fprd(*e, 0x0100, 4).u32(), 0x00070001u);
    EXPECT_EQ(fprd(*e, 0x0130, 2).wkc, 1);
    EXPECT_EQ(fprd(*e, 0x0130, 2).u16(), 0x0001);
    EXPECT_EQ(fpwr(*e, 0x0120, {0x02, 0x00}).wkc, 1);
    EXPECT_EQ(al_event() & 0x01, 0x01u);
    EXPECT_EQ(e->read_reg<uint16_t>(0x0120), 0x0002);    // the stack's PDI read of AL control
    EXPECT_EQ(al_event() & 0x01, 0x00u);                 // ... with its side effect
    EXPECT_EQ(e->read_reg<uint8_t>(0x0805), status(0));  // SM status through the PDI
    EXPECT_EQ(fpwr(*e, 0x0F80, {0xA5}).wkc, 1);
    EXPECT_EQ(fprd(*e, 0x0F80, 1).data[0], 0xA5);
    // Process RAM outside the other SMs is plain RAM, the mailbox SM still works.
    EXPECT_EQ(fpwr(*e, 0x1800, {0x5A}).wkc, 1);
    EXPECT_EQ(fprd(*e, 0x1800, 1).data[0], 0x5A);
    EXPECT_EQ(fpwr(*e, 0x1000, kMsgA).wkc, 1);
    EXPECT_EQ(status(0) & 0x08, 0x08);
    EXPECT_EQ(pdi_read(0x1000, 8), kMsgA);
    // Disabled again by the master.
    EXPECT_EQ(fpwr(*e, 0x0826, {0x00}).wkc, 1);
    EXPECT_EQ(fprd(*e, 0x0826, 1).data[0], 0x00);
}

TEST_F(SyncManagerRules, SmAreaInsideTheRegistersOrAcrossTheRamEdgesBuffersNothing) {
    // A mailbox SM on DL control: the registers keep their register rules.
    EXPECT_EQ(fpwr(*e, 0x0820, sm_bytes(0x0100, 16, 0x26, 1)).wkc, 1);
    EXPECT_EQ(fprd(*e, 0x0100, 4).u32(), 0x00070001u);
    EXPECT_EQ(fprd(*e, 0x0100, 4).wkc, 1);
    // Across the register/RAM boundary: user RAM and process RAM stay plain memory.
    EXPECT_EQ(fpwr(*e, 0x0828, sm_bytes(0x0FF8, 16, 0x26, 1)).wkc, 1);
    EXPECT_EQ(fpwr(*e, 0x0FF8, {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16}).wkc, 1);
    EXPECT_EQ(status(5) & 0x08, 0x00);  // no mailbox was filled: the SM has no buffer there
    EXPECT_EQ(pdi_read(0x0FF8, 16),
              (std::vector<uint8_t>{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16}));
    // Past the end of the RAM (8 KiB: 0x1000-0x2FFF): the RAM below the end stays plain.
    EXPECT_EQ(fpwr(*e, 0x0830, sm_bytes(0x2F00, 0x100, 0x20, 1)).wkc, 1);  // 3 x 256 bytes do not fit
    EXPECT_EQ(fpwr(*e, 0x2F00, {0x77}).wkc, 1);
    EXPECT_EQ(fprd(*e, 0x2F00, 1).data[0], 0x77);
    EXPECT_EQ(e->read_reg<uint8_t>(0x2F00), 0x77);
}
