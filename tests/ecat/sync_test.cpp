// Synchronisation: 0x1C32/0x1C33 say what really runs (free run, SM-synchronous, DC SYNC0), the cycle runs on
// the right event, misses are counted, and the DC/SM sync checks of Pre-Op -> Safe-Op give their AL codes.
#include "fixture.hpp"

namespace ecat::test {
namespace {

using od::AlState;

class Sync : public StackTest {
  protected:
    // DC SYNC0 as masters set it up (ETG.1020 Synchronization, DC start-up): cycle time, start time in the
    // near future (system time), then activation.
    void enable_dc(uint32_t cycle_ns, uint8_t activation = 0x03, uint64_t start_delay_ns = 1'000'000) {
        master.wr<uint8_t>(0x0980, 0);
        master.wr<uint32_t>(0x09A0, cycle_ns);
        const uint64_t now_sys = master.rd<uint64_t>(0x0910);
        master.wr<uint64_t>(0x0990, now_sys + start_delay_ns);
        master.wr<uint8_t>(0x0981, activation);
    }
    // A new DC session on a running SYNC0, as masters do it: 0x0980/0x0981 cleared (the start time is
    // writable only while 0x0981 bit 0 is clear: ESC datasheet, Distributed Clocks), then set up again.
    void restart_dc(uint32_t cycle_ns, uint64_t start_delay_ns) {
        master.wr<uint16_t>(0x0980, 0);
        enable_dc(cycle_ns, 0x03, start_delay_ns);
    }
    // Pre-Op, process data of 6 + 6 bytes configured, DC SYNC0 set up (enable_dc).
    void preop_dc(uint32_t cycle_ns, uint8_t activation = 0x03, uint64_t start_delay_ns = 1'000'000) {
        go_preop();
        configure_process_data(6, 6);
        enable_dc(cycle_ns, activation, start_delay_ns);
    }
    // ... and Safe-Op reached.
    void safeop_dc(uint32_t cycle_ns, uint8_t activation = 0x03, uint64_t start_delay_ns = 1'000'000) {
        preop_dc(cycle_ns, activation, start_delay_ns);
        request(0x04);
        ASSERT_EQ(al_status(), 0x04) << std::hex << al_code();
    }
    // Pre-Op, the sync mode written to 0x1C32:01 (0 free run, 1 SM synchronous, 2 DC SYNC0, 3 DC SYNC1),
    // process data of 6 + 6 bytes configured.
    void preop_with_sync_mode(uint16_t mode) {
        go_preop();
        ASSERT_EQ(master_write16(0x1C32, 1, mode), od::Status::Ok);
        configure_process_data(6, 6);
    }
    // A request for Safe-Op refused: Pre-Op with the error indication and the AL status code `code`.
    void expect_safeop_refused(uint16_t code) {
        request(0x04);
        EXPECT_EQ(al_status(), 0x02 | kErr);
        EXPECT_EQ(al_code(), code);
    }
    // Advances in steps, polling after each (the runtime's timer).
    void run_for(uint64_t total_ns, uint64_t step_ns, bool send_outputs) {
        std::vector<uint8_t> out(rx_bytes, 0), in(tx_bytes, 0);
        for (uint64_t t = 0; t < total_ns; t += step_ns) {
            clock.advance(step_ns);
            if (send_outputs) exchange_pd(out, in);
            poll();
        }
    }
    uint16_t u16(uint16_t i, uint8_t s) { return dict.get<uint16_t>(i, s); }
    uint32_t u32(uint16_t i, uint8_t s) { return dict.get<uint32_t>(i, s); }
    od::Status master_write16(uint16_t i, uint8_t s, uint16_t v) {
        return dict.write(i, s, AlState::PreOp,
                          std::vector<uint8_t>{static_cast<uint8_t>(v), static_cast<uint8_t>(v >> 8)});
    }
    od::Status master_write32(uint16_t i, uint8_t s, uint32_t v) {
        std::vector<uint8_t> b(4);
        for (int k = 0; k < 4; ++k)
            b[k] = static_cast<uint8_t>(v >> (8 * k));
        return dict.write(i, s, AlState::PreOp, b);
    }
};

TEST_F(Sync, SmSync_ReportedIn1C32And1C33) {
    go_safeop();
    EXPECT_EQ(stack->sync_mode(), SyncMode::SmSync);
    EXPECT_EQ(u16(0x1C32, 1), 1);
    EXPECT_EQ(u16(0x1C33, 1), 0x22);  // inputs follow the SM2 event
}

TEST_F(Sync, SmSync_CycleOnEachSm2Write) {
    go_op();
    const int before = app.cycles;
    std::vector<uint8_t> out(6), in(6);
    for (int i = 0; i < 5; ++i) {
        exchange_pd(out, in);
        poll();
        poll();  // no new outputs: no extra cycle
    }
    EXPECT_EQ(app.cycles - before, 5);
}

TEST_F(Sync, Dc_ModeAndCycleTimeFrom0x09A0) {
    safeop_dc(2'000'000);
    EXPECT_EQ(stack->sync_mode(), SyncMode::DcSync0);
    EXPECT_EQ(u16(0x1C32, 1), 2);
    EXPECT_EQ(u16(0x1C33, 1), 2);
    EXPECT_EQ(u32(0x1C32, 2), 2'000'000u);
    EXPECT_EQ(u32(0x1C33, 2), 2'000'000u);
}

TEST_F(Sync, Dc_CycleRunsOnSync0) {
    safeop_dc(1'000'000);
    const int before = app.cycles;
    run_for(10'500'000, 250'000, false);
    EXPECT_GE(stack->stats().sync0_events, 9u);
    EXPECT_LE(stack->stats().sync0_events, 11u);
    EXPECT_EQ(static_cast<uint64_t>(app.cycles - before), stack->stats().sync0_events);
}

TEST_F(Sync, Dc_Sync0NotMappedToAlEvent_SeenThrough0x0990) {
    // An SII whose word 1 leaves 0x0151 bit 3 clear: SYNC0 never reaches AL event bit 2.
    std::vector<uint8_t> image(esc->eeprom().begin(), esc->eeprom().end());
    ASSERT_GE(image.size(), 16u);
    image[2] = 0x00;
    image[3] = 0x00;
    uint8_t crc = 0xFF;
    for (int i = 0; i < 14; ++i) {
        crc ^= image[i];
        for (int b = 0; b < 8; ++b)
            crc = static_cast<uint8_t>((crc & 0x80) ? (crc << 1) ^ 0x07 : (crc << 1));
    }
    image[14] = crc;
    esc->load_eeprom(image);
    ASSERT_EQ(master.rd<uint8_t>(0x0151) & 0x08, 0);
    safeop_dc(1'000'000);
    // The stack asks to be polled when the next SYNC0 is due.
    EXPECT_LE(stack->next_deadline_ns(), clock.now_ns() + 1'000'000);
    run_for(10'000'000, 250'000, true);
    EXPECT_GE(stack->stats().sync0_events, 9u);
    request(0x08);
    run_for(2'000'000, 250'000, true);
    EXPECT_EQ(al_status(), 0x08);
    // Nothing else would wake it for the outputs: the SM events stay in the mask.
    EXPECT_EQ(esc->read_reg<uint32_t>(0x0204), Stack::kEventMask);
    // A runtime that only wakes on the stack's deadline still runs one cycle per SYNC0.
    const int before = app.cycles;
    for (int i = 0; i < 5; ++i) {
        clock.set(stack->next_deadline_ns());
        poll();
    }
    EXPECT_EQ(app.cycles - before, 5);
    EXPECT_EQ(stack->stats().cycles_exceeded, 0u);
}

// In Op, DC-synchronous with SYNC0 in the AL event register, the frame's SM2/SM3 events are masked (0x0204,
// as a DC-synchronous firmware sets its interrupt mask): a frame leaves the interrupt line low and the stack
// quiet, and the cycle at SYNC0 still takes the outputs the frame brought (no SM event counted missed).
// Safe-Op and every state below keep the full mask; an ESC reset in Op is still noticed.
TEST_F(Sync, Dc_OpMasksTheProcessDataSmEvents) {
    constexpr uint32_t kSm2Sm3 = 0x0C00;
    safeop_dc(1'000'000);
    EXPECT_EQ(esc->read_reg<uint32_t>(0x0204), Stack::kEventMask);
    run_for(3'000'000, 250'000, true);
    request(0x08);
    ASSERT_EQ(al_status(), 0x08);
    EXPECT_EQ(esc->read_reg<uint32_t>(0x0204), Stack::kEventMask & ~kSm2Sm3);
    run_for(2'000'000, 250'000, true);
    const uint64_t missed = stack->stats().sm_events_missed;
    std::vector<uint8_t> out{0x0F, 0x00, 0x44, 0x33, 0x22, 0x11}, in(6);
    for (int k = 0; k < 3; ++k) {
        exchange_pd(out, in);
        EXPECT_FALSE(esc->irq());
        EXPECT_TRUE(stack->quiet(clock.now_ns()));
        const int cycles = app.cycles;
        clock.set(stack->next_deadline_ns());  // the next SYNC0
        poll();
        EXPECT_EQ(app.cycles, cycles + 1);
    }
    EXPECT_EQ(stack->stats().sm_events_missed, missed);
    EXPECT_EQ(u16(0x6040, 0), 0x000F);  // RxPDO 0x1600 = {0x6040, 0x607A}: taken at SYNC0
    EXPECT_EQ(u32(0x607A, 0), 0x11223344u);
    request(0x04);
    EXPECT_EQ(al_status(), 0x04);
    EXPECT_EQ(esc->read_reg<uint32_t>(0x0204), Stack::kEventMask);
    request(0x08);
    run_for(2'000'000, 250'000, true);
    ASSERT_EQ(al_status(), 0x08);
    for (uint8_t c : {uint8_t{'R'}, uint8_t{'E'}, uint8_t{'S'}})
        master.wr<uint8_t>(0x0040, c);
    run_for(2'000'000, 250'000, false);
    EXPECT_EQ(stack->state(), AlState::Init);
    EXPECT_EQ(stack->stats().esc_resets, 1u);
    EXPECT_EQ(esc->read_reg<uint32_t>(0x0204), Stack::kEventMask);
}

TEST_F(Sync, Dc_SafeOpToOp_WaitsForSync0) {
    ASSERT_NO_FATAL_FAILURE(safeop_dc(1'000'000, 0x03, 5'000'000));  // first SYNC0 5 ms from now
    std::vector<uint8_t> out(6), in(6);
    exchange_pd(out, in);
    poll();
    request(0x08);
    EXPECT_EQ(al_status(), 0x04);  // waiting, no error
    run_for(8'000'000, 500'000, true);
    EXPECT_EQ(al_status(), 0x08);
}

TEST_F(Sync, Dc_SafeOpToOp_NoSync0_0x002D) {
    ASSERT_NO_FATAL_FAILURE(safeop_dc(1'000'000, 0x03, 60'000'000'000ull));  // start time a minute away
    std::vector<uint8_t> out(6), in(6);
    exchange_pd(out, in);
    poll();
    request(0x08);
    run_for(1'500'000'000, 50'000'000, true);
    EXPECT_EQ(al_status(), 0x04 | kErr);
    EXPECT_EQ(al_code(), 0x002D);
}

TEST_F(Sync, Dc_SmEventMissedCountedAndSyncError) {
    safeop_dc(1'000'000);
    run_for(3'000'000, 250'000, true);
    request(0x08);
    ASSERT_EQ(al_status(), 0x08);
    run_for(3'000'000, 250'000, true);
    EXPECT_EQ(u16(0x1C32, 0x0B), 0);
    EXPECT_EQ(dict.get<uint8_t>(0x1C32, 0x20), 0);
    run_for(3'000'000, 250'000, false);  // SYNC0 keeps coming, outputs do not
    EXPECT_GE(u16(0x1C32, 0x0B), 2);
    EXPECT_EQ(u16(0x1C33, 0x0B), u16(0x1C32, 0x0B));
    EXPECT_EQ(dict.get<uint8_t>(0x1C32, 0x20), 1);
    EXPECT_EQ(al_status(), 0x08);  // counted, not fatal
}

TEST_F(Sync, Dc_CycleExceededCounted) {
    safeop_dc(1'000'000);
    run_for(3'000'000, 250'000, true);
    request(0x08);
    ASSERT_EQ(al_status(), 0x08);
    run_for(2'000'000, 250'000, true);
    const uint16_t before = u16(0x1C32, 0x0C);
    run_for(5'000'000, 5'000'000, true);  // the runtime stalls for 5 cycles
    EXPECT_GE(u16(0x1C32, 0x0C), before + 3);
}

TEST_F(Sync, Dc_SyncLoss_0x002C) {
    safeop_dc(1'000'000);
    run_for(3'000'000, 250'000, true);
    request(0x08);
    ASSERT_EQ(al_status(), 0x08);
    master.wr<uint8_t>(0x0981, 0);  // SYNC0 stops
    run_for(20'000'000, 1'000'000, true);
    EXPECT_EQ(al_status(), 0x04 | kErr);
    EXPECT_EQ(al_code(), 0x002C);
    EXPECT_EQ(app.outputs_lost, 1);
}

TEST_F(Sync, Dc_StartTimeRewrittenWhileStopped_NoSpuriousCycle) {
    safeop_dc(1'000'000);
    run_for(3'000'000, 250'000, true);
    master.wr<uint8_t>(0x0981, 0);
    const int before = app.cycles;
    master.wr<uint64_t>(0x0990, master.rd<uint64_t>(0x0910) + 50'000'000);
    poll();
    poll();
    EXPECT_EQ(app.cycles, before);
}

// Two DC sessions in a row, as `ecatctl pd --dc` twice does: the first ends in Pre-Op with SYNC0 still
// running (its event latched in 0x0220 bit 2, unacknowledged outside the process-data states); the second
// deactivates 0x0981, programs a start time 100 ms away and activates again. The pulses of the first
// activation say nothing of the second: Op waits for the new first SYNC0, and no sync error follows (a drive
// may be started and stopped any number of times).
TEST_F(Sync, Dc_SecondSessionWaitsForItsOwnStartTime) {
    safeop_dc(1'000'000);
    run_for(3'000'000, 250'000, true);
    request(0x08);
    ASSERT_EQ(al_status(), 0x08);
    run_for(5'000'000, 250'000, true);
    request(0x02);
    ASSERT_EQ(al_status(), 0x02);
    run_for(5'000'000, 1'000'000, false);  // Pre-Op: SYNC0 goes on, nobody acknowledges it

    configure_process_data(6, 6);
    restart_dc(1'000'000, 100'000'000);
    request(0x04);
    ASSERT_EQ(al_status(), 0x04) << std::hex << al_code();
    std::vector<uint8_t> out(6), in(6);
    exchange_pd(out, in);
    poll();
    request(0x08);
    EXPECT_EQ(al_status(), 0x04);  // waiting for the first SYNC0 of this activation, no error
    run_for(50'000'000, 500'000, true);
    EXPECT_EQ(al_status(), 0x04) << std::hex << al_code();
    run_for(60'000'000, 500'000, true);
    EXPECT_EQ(al_status(), 0x08) << std::hex << al_code();
    run_for(30'000'000, 500'000, true);
    EXPECT_EQ(al_status(), 0x08) << std::hex << al_code();
    EXPECT_EQ(stack->stats().cycles_exceeded, 0u);
}

// SYNC0 deactivated and activated again with a later start time while in Safe-Op (a master that sets SYNC0 up
// after Safe-Op): the jump of 0x0990 is a new activation, not periods without a cycle, and Op waits for it.
TEST_F(Sync, Dc_ReactivatedInSafeOp_WaitsForNewStart) {
    safeop_dc(1'000'000);
    run_for(3'000'000, 250'000, true);
    const uint64_t exceeded = stack->stats().cycles_exceeded;
    restart_dc(1'000'000, 40'000'000);
    std::vector<uint8_t> out(6), in(6);
    exchange_pd(out, in);
    poll();
    request(0x08);
    run_for(20'000'000, 500'000, true);
    EXPECT_EQ(al_status(), 0x04) << std::hex << al_code();
    run_for(30'000'000, 500'000, true);
    EXPECT_EQ(al_status(), 0x08) << std::hex << al_code();
    run_for(20'000'000, 500'000, true);
    EXPECT_EQ(al_status(), 0x08) << std::hex << al_code();
    EXPECT_EQ(stack->stats().cycles_exceeded, exceeded);
}

// SYNC0 activated again in Op with a start time in the future: judged from that start time on; if the new
// activation never delivers a pulse, the loss is still fatal (0x002C).
TEST_F(Sync, Dc_ReactivatedInOp_JudgedFromNewStart_LossStillFatal) {
    safeop_dc(1'000'000);
    run_for(3'000'000, 250'000, true);
    request(0x08);
    ASSERT_EQ(al_status(), 0x08);
    restart_dc(1'000'000, 30'000'000);
    run_for(25'000'000, 500'000, true);
    EXPECT_EQ(al_status(), 0x08) << std::hex << al_code();  // before the new start: nothing to judge
    run_for(20'000'000, 500'000, true);
    EXPECT_EQ(al_status(), 0x08) << std::hex << al_code();  // pulses of the new activation came
    master.wr<uint8_t>(0x0981, 0);                          // and stop
    run_for(20'000'000, 1'000'000, true);
    EXPECT_EQ(al_status(), 0x04 | kErr);
    EXPECT_EQ(al_code(), 0x002C);
}

TEST_F(Sync, Dc_Sync0CycleBelowMinimum_0x0036) {
    preop_dc(50'000);  // 0x1C32:05 = 100 us
    expect_safeop_refused(0x0036);
}

TEST_F(Sync, Dc_StartTimeInThePast_0x0030) {
    go_preop();
    configure_process_data(6, 6);
    master.wr<uint32_t>(0x09A0, 1'000'000);
    master.wr<uint64_t>(0x0990, master.rd<uint64_t>(0x0910) - 5'000'000);
    master.wr<uint8_t>(0x0981, 0x03);
    expect_safeop_refused(0x0030);
}

TEST_F(Sync, Dc_Sync0CycleZero_0x0035) {
    preop_dc(0);
    expect_safeop_refused(0x0035);
}

TEST_F(Sync, Dc_Sync1WithoutSync0_0x0030) {
    preop_dc(1'000'000, 0x05);
    expect_safeop_refused(0x0030);
}

TEST_F(Sync, Dc_SyncModeSaysDcButNotActivated_0x0030) {
    ASSERT_NO_FATAL_FAILURE(preop_with_sync_mode(2));
    expect_safeop_refused(0x0030);
}

TEST_F(Sync, SmSyncRequestedButDcActive_0x0030) {
    ASSERT_NO_FATAL_FAILURE(preop_with_sync_mode(1));
    enable_dc(1'000'000);
    expect_safeop_refused(0x0030);
}

TEST_F(Sync, Dc_SyncModeWrittenAndActivated_Accepted) {
    ASSERT_NO_FATAL_FAILURE(preop_with_sync_mode(2));
    enable_dc(1'000'000);
    request(0x04);
    EXPECT_EQ(al_status(), 0x04);
    EXPECT_EQ(stack->sync_mode(), SyncMode::DcSync0);
}

TEST_F(Sync, FreeRunNotSupported_0x0027) {
    ASSERT_NO_FATAL_FAILURE(preop_with_sync_mode(0));
    expect_safeop_refused(0x0027);
}

// A device whose 0x1C32:04 declares no mode at all (0, as SOES-based devices' ESIs do) is not refused: the
// entry says nothing, the modes are those of a device without it.
TEST_F(Sync, SyncModesSupportedZero_SaysNothing) {
    ASSERT_EQ(dict.set<uint16_t>(0x1C32, 4, 0), od::Status::Ok);
    go_safeop();
    EXPECT_EQ(stack->sync_mode(), SyncMode::SmSync);
}

// ... nor does one with no mode bit at all (0x0400: an ESI's DefaultData "0004" written big-endian): DC runs.
TEST_F(Sync, SyncModesSupportedWithoutModeBits_SaysNothing) {
    ASSERT_EQ(dict.set<uint16_t>(0x1C32, 4, 0x0400), od::Status::Ok);
    safeop_dc(1'000'000);
    EXPECT_EQ(stack->sync_mode(), SyncMode::DcSync0);
}

// A synchronization type written to 0x1C32:01 / 0x1C33:01 is refused when the device does not announce it in
// :04 (abort 0x06090030), every type against every announcement: free run is always taken (as the SSC; a
// device without it refuses Safe-Op, 0x0027, above), 34 (SM2 event) only by the inputs' 0x1C33, a value that
// names no type never. What was refused leaves the entry as it was.
TEST_F(Sync, SyncTypeWrite_TakenOnlyWhereAnnounced) {
    go_preop();
    const uint16_t types[] = {0, 1, 2, 3, 4, 7, 0x21, 0x22, 0xFFFF};
    for (const uint16_t supported :
         {0x0001, 0x0002, 0x0004, 0x0006, 0x0007, 0x0008, 0x000B, 0x000F, 0x400C}) {
        ASSERT_EQ(dict.set<uint16_t>(0x1C32, 4, supported), od::Status::Ok);
        ASSERT_EQ(dict.set<uint16_t>(0x1C33, 4, supported), od::Status::Ok);
        for (const uint16_t index : {uint16_t{0x1C32}, uint16_t{0x1C33}}) {
            for (const uint16_t type : types) {
                const uint16_t before = u16(index, 1);
                const bool announced = type == 0 || (type == 1 && (supported & 0x2)) ||
                                       (type == 2 && (supported & 0x4)) || (type == 3 && (supported & 0x8)) ||
                                       (type == 0x22 && index == 0x1C33 && (supported & 0x2));
                const od::Status st = master_write16(index, 1, type);
                EXPECT_EQ(st, announced ? od::Status::Ok : od::Status::InvalidValue)
                    << std::hex << index << ":01 = " << type << " with :04 = " << supported;
                EXPECT_EQ(u16(index, 1), announced ? type : before);
            }
        }
    }
}

// A device with inputs only has 0x1C33 alone (ETG.1020): its 0x1C33:04 is the announcement. Free run only
// (0x8001, as Beckhoff's inputs-only system terminals declare): 1 is refused when written, and the device
// runs free, not SM-synchronous, at PREOP -> SAFEOP.
TEST_F(Sync, InputsOnlyDevice_0x1C33AnnouncesItsTypes) {
    od::Dictionary inputs_only;
    for (const od::Object& o : dict.objects())
        if (o.index != 0x1C32) inputs_only.add(o);
    dict = std::move(inputs_only);
    ASSERT_EQ(dict.set<uint16_t>(0x1C33, 4, 0x8001), od::Status::Ok);
    start();
    go_preop();
    EXPECT_EQ(master_write16(0x1C33, 1, 1), od::Status::InvalidValue);
    EXPECT_EQ(master_write16(0x1C33, 1, 0), od::Status::Ok);
    configure_process_data(6, 6);
    request(0x04);
    ASSERT_EQ(al_status(), 0x04) << std::hex << al_code();
    EXPECT_EQ(stack->sync_mode(), SyncMode::FreeRun);
}

// A :04 without any mode bit announces every type but DC SYNC1, as configure() runs them (0x0400: an ESI's
// DefaultData "0004" written big-endian).
TEST_F(Sync, SyncTypeWrite_NoModeBitsTakesWhatRuns) {
    go_preop();
    ASSERT_EQ(dict.set<uint16_t>(0x1C32, 4, 0x0400), od::Status::Ok);
    for (const uint16_t type : {0, 1, 2})
        EXPECT_EQ(master_write16(0x1C32, 1, type), od::Status::Ok) << type;
    EXPECT_EQ(master_write16(0x1C32, 1, 3), od::Status::InvalidValue);
}

// A device that announces DC SYNC1 but not SYNC0 (0x1C32:04 0x000B: free run, SM, SYNC1; Beckhoff's counter
// and motion terminals) runs DC SYNC1 when the master activates SYNC0 and SYNC1 (AssignActivate 0x0700), and
// refuses SYNC0 alone.
TEST_F(Sync, Dc_Sync1OnlyDevice_RunsSync1WithSync0AndSync1Activated) {
    ASSERT_EQ(dict.set<uint16_t>(0x1C32, 4, 0x000B), od::Status::Ok);
    ASSERT_NO_FATAL_FAILURE(safeop_dc(1'000'000, 0x07));
    EXPECT_EQ(stack->sync_mode(), SyncMode::DcSync1);
}

TEST_F(Sync, Dc_Sync1OnlyDevice_RefusesSync0Alone_0x0028) {
    ASSERT_EQ(dict.set<uint16_t>(0x1C32, 4, 0x000B), od::Status::Ok);
    ASSERT_NO_FATAL_FAILURE(preop_dc(1'000'000, 0x03));
    expect_safeop_refused(0x0028);
}

TEST_F(Sync, SmSync_CycleTimeTooSmall_0x002E) {
    go_preop();
    ASSERT_EQ(master_write32(0x1C32, 2, 50'000), od::Status::Ok);
    configure_process_data(6, 6);
    expect_safeop_refused(0x002E);
}

TEST_F(Sync, FreeRun_TimerDrivesCycle) {
    ASSERT_EQ(dict.set<uint16_t>(0x1C32, 4, 0x0007), od::Status::Ok);  // a device that supports free run
    go_preop();
    ASSERT_EQ(master_write16(0x1C32, 1, 0), od::Status::Ok);
    ASSERT_EQ(master_write32(0x1C32, 2, 2'000'000), od::Status::Ok);
    configure_process_data(6, 6);
    request(0x04);
    ASSERT_EQ(al_status(), 0x04) << std::hex << al_code();
    EXPECT_EQ(stack->sync_mode(), SyncMode::FreeRun);
    EXPECT_EQ(u16(0x1C33, 1), 0);
    EXPECT_EQ(stack->next_deadline_ns(), clock.now_ns() + 2'000'000);
    const int before = app.cycles;
    run_for(10'000'000, 1'000'000, false);
    EXPECT_EQ(app.cycles - before, 5);
}

TEST_F(Sync, SmTypesReflectedIn1C00) {
    EXPECT_EQ(dict.get<uint8_t>(0x1C00, 1), 1);
    EXPECT_EQ(dict.get<uint8_t>(0x1C00, 2), 2);
    EXPECT_EQ(dict.get<uint8_t>(0x1C00, 3), 3);
    EXPECT_EQ(dict.get<uint8_t>(0x1C00, 4), 4);
}

}  // namespace
}  // namespace ecat::test
