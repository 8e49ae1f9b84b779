// EtherCAT state machine: one test per row of the ESM transition table (ETG.1000.6, EtherCAT State Machine),
// the AL status codes (ETG.1000.6) for the checks of each transition, error indication / acknowledge and
// device identification.
#include "fixture.hpp"

namespace ecat::test {
namespace {

using Esm = StackTest;
using od::AlState;

// ---- Init ---------------------------------------------------------------------------------------------

TEST_F(Esm, PowerOn_InitNoError) {
    EXPECT_EQ(al_status(), 0x01);
    EXPECT_EQ(al_code(), 0x0000);
    EXPECT_EQ(stack->state(), AlState::Init);
}

TEST_F(Esm, II_InitToInit_Stays) {
    request(0x01);
    EXPECT_EQ(al_status(), 0x01);
    EXPECT_EQ(al_code(), 0);
    EXPECT_TRUE(app.changes.empty());
}

TEST_F(Esm, IP_InitToPreOp_ValidMailbox) {
    configure_mailbox();
    request(0x02);
    EXPECT_EQ(al_status(), 0x02);
    EXPECT_EQ(al_code(), 0);
    ASSERT_EQ(app.changes.size(), 1u);
    EXPECT_EQ(app.changes[0], std::make_pair(AlState::Init, AlState::PreOp));
    EXPECT_TRUE(stack->mailbox().running());
}

TEST_F(Esm, IP_InitToPreOp_MailboxNotEnabled_0x0016) {
    configure_sm(0, 0x1000, 128, 0x26, false);
    configure_sm(1, 0x1080, 128, 0x22, true);
    request(0x02);
    EXPECT_EQ(al_status(), 0x01 | kErr);
    EXPECT_EQ(al_code(), 0x0016);
}

TEST_F(Esm, IP_InitToPreOp_WrongSm0Start_0x0016) {
    configure_sm(0, 0x1010, 128, 0x26, true);
    configure_sm(1, 0x1090, 128, 0x22, true);
    request(0x02);
    EXPECT_EQ(al_status(), 0x01 | kErr);
    EXPECT_EQ(al_code(), 0x0016);
}

TEST_F(Esm, IP_InitToPreOp_WrongSm1Length_0x0016) {
    configure_sm(0, 0x1000, 128, 0x26, true);
    configure_sm(1, 0x1080, 64, 0x22, true);
    request(0x02);
    EXPECT_EQ(al_status(), 0x01 | kErr);
    EXPECT_EQ(al_code(), 0x0016);
}

TEST_F(Esm, IP_InitToPreOp_WrongSm0Control_0x0016) {
    configure_sm(0, 0x1000, 128, 0x22, true);  // mailbox but read direction
    configure_sm(1, 0x1080, 128, 0x22, true);
    request(0x02);
    EXPECT_EQ(al_status(), 0x01 | kErr);
    EXPECT_EQ(al_code(), 0x0016);
}

TEST_F(Esm, IP_InitToPreOp_MailboxesOverlap_0x0016) {
    desc.standard_mailbox = {0x1000, 128, 0x1040, 128};  // a (bad) description the master follows
    desc.sync_managers[1].start = 0x1040;
    start();
    configure_sm(0, 0x1000, 128, 0x26, true);
    configure_sm(1, 0x1040, 128, 0x22, true);
    request(0x02);
    EXPECT_EQ(al_status(), 0x01 | kErr);
    EXPECT_EQ(al_code(), 0x0016);
}

TEST_F(Esm, IP_InitToPreOp_EventBitsAreMastersChoice) {
    configure_sm(0, 0x1000, 128, 0x06, true);  // mailbox, write, no PDI event
    configure_sm(1, 0x1080, 128, 0x02, true);
    request(0x02);
    EXPECT_EQ(al_status(), 0x02);
}

TEST_F(Esm, IP_InitToPreOp_ApplicationVeto_0x0014) {
    app.veto_state = AlState::PreOp;
    app.veto_code = 0x0014;
    configure_mailbox();
    request(0x02);
    EXPECT_EQ(al_status(), 0x01 | kErr);
    EXPECT_EQ(al_code(), 0x0014);
}

TEST_F(Esm, IB_InitToBoot_ValidBootstrapMailbox) {
    configure_bootstrap_mailbox();
    request(0x03);
    EXPECT_EQ(al_status(), 0x03);
    EXPECT_EQ(al_code(), 0);
    EXPECT_TRUE(stack->mailbox().running());
    EXPECT_EQ(stack->mailbox().max_payload(), 256u - 6u);
}

TEST_F(Esm, IB_InitToBoot_StandardMailbox_0x0015) {
    configure_mailbox();
    request(0x03);
    EXPECT_EQ(al_status(), 0x01 | kErr);
    EXPECT_EQ(al_code(), 0x0015);
}

TEST_F(Esm, IB_InitToBoot_NotSupported_0x0013) {
    desc.mailbox_protocols = od::mailbox_protocol::CoE;
    desc.bootstrap_mailbox = {0, 0, 0, 0};  // no bootstrap mailbox announced: no Bootstrap
    start();
    configure_bootstrap_mailbox();
    request(0x03);
    EXPECT_EQ(al_status(), 0x01 | kErr);
    EXPECT_EQ(al_code(), 0x0013);
}

// A bootstrap mailbox announced (SII words 0x14-0x17, ESI Mailbox/BootStrap) is Bootstrap supported, whether
// or not FoE is declared: what is served there is the mailbox's business.
TEST_F(Esm, IB_InitToBoot_BootstrapMailboxWithoutFoe) {
    desc.mailbox_protocols = od::mailbox_protocol::CoE;
    desc.bootstrap_mailbox = {0x1000, 256, 0x1100, 256};
    start();
    configure_bootstrap_mailbox();
    request(0x03);
    EXPECT_EQ(al_status(), 0x03);
    EXPECT_EQ(al_code(), 0x0000);
}

TEST_F(Esm, Invalid_InitToSafeOp_0x0011) {
    configure_mailbox();
    request(0x04);
    EXPECT_EQ(al_status(), 0x01 | kErr);
    EXPECT_EQ(al_code(), 0x0011);
}

TEST_F(Esm, Invalid_InitToOp_0x0011) {
    configure_mailbox();
    request(0x08);
    EXPECT_EQ(al_status(), 0x01 | kErr);
    EXPECT_EQ(al_code(), 0x0011);
}

// ---- Pre-Op -------------------------------------------------------------------------------------------

TEST_F(Esm, PP_PreOpToPreOp_Stays) {
    go_preop();
    app.changes.clear();
    request(0x02);
    EXPECT_EQ(al_status(), 0x02);
    EXPECT_TRUE(app.changes.empty());
}

TEST_F(Esm, PI_PreOpToInit_StopsMailbox) {
    go_preop();
    request(0x01);
    EXPECT_EQ(al_status(), 0x01);
    EXPECT_FALSE(stack->mailbox().running());
    EXPECT_EQ(app.changes.back(), std::make_pair(AlState::PreOp, AlState::Init));
}

TEST_F(Esm, Invalid_PreOpToBoot_0x0011) {
    go_preop();
    request(0x03);
    EXPECT_EQ(al_status(), 0x02 | kErr);
    EXPECT_EQ(al_code(), 0x0011);
}

TEST_F(Esm, Invalid_PreOpToOp_0x0011) {
    go_preop();
    request(0x08);
    EXPECT_EQ(al_status(), 0x02 | kErr);
    EXPECT_EQ(al_code(), 0x0011);
}

TEST_F(Esm, PS_PreOpToSafeOp_Valid) {
    go_preop();
    configure_process_data(6, 6);
    request(0x04);
    EXPECT_EQ(al_status(), 0x04);
    EXPECT_EQ(al_code(), 0);
    EXPECT_EQ(stack->process_data().rx_bytes(), 6u);
    EXPECT_EQ(stack->process_data().tx_bytes(), 6u);
    EXPECT_EQ(stack->sync_mode(), SyncMode::SmSync);
}

TEST_F(Esm, PS_PreOpToSafeOp_Sm2LengthNotMapping_0x001D) {
    go_preop();
    configure_process_data(4, 6);
    request(0x04);
    EXPECT_EQ(al_status(), 0x02 | kErr);
    EXPECT_EQ(al_code(), 0x001D);
}

TEST_F(Esm, PS_PreOpToSafeOp_Sm2Disabled_0x001D) {
    go_preop();
    configure_process_data(6, 6);
    configure_sm(2, kSm2Start, 6, 0x64, false);
    request(0x04);
    EXPECT_EQ(al_status(), 0x02 | kErr);
    EXPECT_EQ(al_code(), 0x001D);
}

TEST_F(Esm, PS_PreOpToSafeOp_Sm2WrongDirection_0x001D) {
    go_preop();
    configure_process_data(6, 6, 0x20);  // buffered, read direction: not an output SM
    request(0x04);
    EXPECT_EQ(al_status(), 0x02 | kErr);
    EXPECT_EQ(al_code(), 0x001D);
}

TEST_F(Esm, PS_PreOpToSafeOp_Sm2WrongStart_0x001D) {
    go_preop();
    configure_process_data(6, 6);
    configure_sm(2, 0x1400, 6, 0x64, true);
    request(0x04);
    EXPECT_EQ(al_status(), 0x02 | kErr);
    EXPECT_EQ(al_code(), 0x001D);
}

TEST_F(Esm, PS_PreOpToSafeOp_Sm3LengthNotMapping_0x001E) {
    go_preop();
    configure_process_data(6, 8);
    request(0x04);
    EXPECT_EQ(al_status(), 0x02 | kErr);
    EXPECT_EQ(al_code(), 0x001E);
}

TEST_F(Esm, PS_PreOpToSafeOp_Sm3EnabledWithoutInputs_0x001E) {
    go_preop();
    ASSERT_EQ(dict.write(0x1C13, 0, AlState::PreOp, std::vector<uint8_t>{0}), od::Status::Ok);
    configure_process_data(6, 6);
    request(0x04);
    EXPECT_EQ(al_status(), 0x02 | kErr);
    EXPECT_EQ(al_code(), 0x001E);
}

TEST_F(Esm, PS_PreOpToSafeOp_Sm2MailboxMode_0x001C) {
    go_preop();
    configure_process_data(6, 6, 0x66);  // mailbox mode on the output SM
    request(0x04);
    EXPECT_EQ(al_status(), 0x02 | kErr);
    EXPECT_EQ(al_code(), 0x001C);
}

// A device whose ESI declares its inputs SM in mailbox mode (Sm ControlByte="#x22" on Inputs, as Beckhoff's
// AX2000/AX5000, EM7004 and EL1254 files do): the one-buffer handshake is that device's process-data SM, so a
// master configuring it from the SII reaches Safe-Op, and each LRW reads the inputs the stack wrote after
// the previous outputs (ESC datasheet, SyncManager 1-buffer mode). Before, 0x001C refused it.
TEST_F(Esm, PS_PreOpToSafeOp_InputsInMailboxModeAsDeclared) {
    desc.sync_managers[3].control = 0x22;
    start();
    go_preop();
    configure_process_data(6, 6);
    configure_sm(3, kSm3Start, 6, 0x22, true);
    request(0x04);
    ASSERT_EQ(al_status(), 0x04) << "code " << std::hex << al_code();
    request(0x08);
    for (int k = 0; k < 3; ++k) {
        std::vector<uint8_t> out(6, 0), in(6, 0);
        EXPECT_EQ(exchange_pd(out, in), 3) << "cycle " << k;
        poll();
    }
    EXPECT_EQ(al_status(), 0x08) << "code " << std::hex << al_code();
}

TEST_F(Esm, PS_PreOpToSafeOp_OverlappingSms_0x0017) {
    desc.sync_managers[3].start = 0;  // no fixed start for SM3: overlap is the only thing wrong
    start();
    go_preop();
    configure_process_data(6, 6);
    configure_sm(3, kSm2Start + 12, 6, 0x20, true);  // inside SM2's three buffers
    request(0x04);
    EXPECT_EQ(al_status(), 0x02 | kErr);
    EXPECT_EQ(al_code(), 0x0017);
}

// A PDO assignment object (0x1C1n) with the PDOs given, read-only as a device without CoE has it.
od::Object array_u16(uint16_t index, std::vector<uint16_t> pdos) {
    od::Object o;
    o.index = index;
    o.code = od::ObjectCode::Array;
    o.type = od::DataType::Unsigned16;
    o.name = "SM assign";
    auto add = [&o](uint8_t sub, od::DataType type, uint64_t value) {
        od::Entry e;
        e.subindex = sub;
        e.type = type;
        e.access = od::access::RO;
        e.default_value = value;
        e.name = "Sub " + std::to_string(sub);
        o.entries.push_back(e);
    };
    add(0, od::DataType::Unsigned8, pdos.size());
    for (std::size_t k = 0; k < std::max<std::size_t>(pdos.size(), 1); ++k)
        add(static_cast<uint8_t>(k + 1), od::DataType::Unsigned16, k < pdos.size() ? pdos[k] : 0);
    return o;
}

// A digital I/O device without mailbox whose outputs are the ESC's digital-output register (0x0F00-0x0F03),
// one buffered SM of one byte per output byte (iTegva, Beckhoff EL20xx style ESIs: Sm StartAddress="#x0f02"
// ControlByte="#x44", and "#x0f03"): such SMs have no three buffers (ESC datasheet, SyncManager: one-byte
// buffered SMs; 0x0F00 digital I/O output data), so side by side they do not overlap. Before, Safe-Op
// found them overlapping, ran without process data and the inputs SM stayed deactivated: every LRW had the
// working counter 2 instead of 3.
TEST_F(Esm, PS_PreOpToSafeOp_OneByteSmsOverRegistersDoNotOverlap) {
    desc.standard_mailbox = {0, 0, 0, 0};
    desc.bootstrap_mailbox = {0, 0, 0, 0};
    desc.mailbox_protocols = 0;
    desc.sync_managers = {{od::SmKind::Outputs, 0x0F02, 1, 0x44, true},
                          {od::SmKind::Outputs, 0x0F03, 1, 0x44, true},
                          {od::SmKind::Inputs, 0x1000, 2, 0x00, true}};
    dict.add(array_u16(0x1C10, {0x1601}));
    dict.add(array_u16(0x1C11, {}));
    start();
    request(0x02);
    ASSERT_EQ(al_status(), 0x02);
    // 0x1601: eight output bits; 0x1A01: 0x6041 (16 bits).
    for (uint8_t k = 1; k <= 8; ++k) {
        const uint32_t m = 0x20000001u | (static_cast<uint32_t>(k) << 8);
        const uint8_t b[4] = {static_cast<uint8_t>(m), static_cast<uint8_t>(m >> 8),
                              static_cast<uint8_t>(m >> 16), static_cast<uint8_t>(m >> 24)};
        ASSERT_EQ(dict.write(0x1601, k, AlState::PreOp, b), od::Status::Ok);
    }
    ASSERT_EQ(dict.write(0x1601, 0, AlState::PreOp, std::vector<uint8_t>{8}), od::Status::Ok);
    ASSERT_EQ(dict.write(0x1A01, 1, AlState::PreOp, std::vector<uint8_t>{0x10, 0x00, 0x41, 0x60}),
              od::Status::Ok);
    ASSERT_EQ(dict.write(0x1A01, 0, AlState::PreOp, std::vector<uint8_t>{1}), od::Status::Ok);
    // SM2 is the inputs SM here: its assignment 0x1C12 takes 0x1A01.
    ASSERT_EQ(dict.write(0x1C12, 0, AlState::PreOp, std::vector<uint8_t>{0}), od::Status::Ok);
    ASSERT_EQ(dict.write(0x1C12, 1, AlState::PreOp, std::vector<uint8_t>{0x01, 0x1A}), od::Status::Ok);
    ASSERT_EQ(dict.write(0x1C12, 0, AlState::PreOp, std::vector<uint8_t>{1}), od::Status::Ok);
    // As SOEM configures it: both output SMs, one FMMU over both bytes, one over the inputs.
    configure_sm(0, 0x0F02, 1, 0x44, true);
    configure_sm(1, 0x0F03, 1, 0x44, true);
    configure_sm(2, 0x1000, 2, 0x00, true);
    configure_fmmu(0, kLogical, 2, 0x0F02, 2);
    configure_fmmu(1, kLogical + 2, 2, 0x1000, 1);
    request(0x04);
    ASSERT_EQ(al_status(), 0x04) << "code " << std::hex << al_code();
    poll();
    std::vector<uint8_t> image = {0xA5, 0x5A, 0, 0};
    EXPECT_EQ(master.lrw(kLogical, image), 3);  // +1 read (inputs SM), +2 write (the register SMs), once
    uint8_t dout[2] = {};
    master.read(0x0F02, dout);
    EXPECT_EQ(dout[0], 0xA5);
    EXPECT_EQ(dout[1], 0x5A);
}

TEST_F(Esm, PS_PreOpToSafeOp_InvalidOutputMapping_0x0025) {
    go_preop();
    // 0x6041 is not RxPDO-mappable.
    ASSERT_EQ(dict.write(0x1600, 0, AlState::PreOp, std::vector<uint8_t>{0}), od::Status::Ok);
    ASSERT_EQ(dict.write(0x1600, 1, AlState::PreOp, std::vector<uint8_t>{0x10, 0x00, 0x41, 0x60}),
              od::Status::Ok);
    ASSERT_EQ(dict.write(0x1600, 0, AlState::PreOp, std::vector<uint8_t>{1}), od::Status::Ok);
    configure_process_data(2, 6);
    request(0x04);
    EXPECT_EQ(al_status(), 0x02 | kErr);
    EXPECT_EQ(al_code(), 0x0025);
}

TEST_F(Esm, PS_PreOpToSafeOp_InvalidInputMapping_0x0024) {
    go_preop();
    // Bit length 8 for a 32-bit object.
    ASSERT_EQ(dict.write(0x1A00, 0, AlState::PreOp, std::vector<uint8_t>{0}), od::Status::Ok);
    ASSERT_EQ(dict.write(0x1A00, 2, AlState::PreOp, std::vector<uint8_t>{0x08, 0x00, 0x64, 0x60}),
              od::Status::Ok);
    ASSERT_EQ(dict.write(0x1A00, 0, AlState::PreOp, std::vector<uint8_t>{2}), od::Status::Ok);
    configure_process_data(6, 3);
    request(0x04);
    EXPECT_EQ(al_status(), 0x02 | kErr);
    EXPECT_EQ(al_code(), 0x0024);
}

TEST_F(Esm, PS_PreOpToSafeOp_AssignedPdoOutOfRange_0x0025) {
    go_preop();
    ASSERT_EQ(dict.write(0x1C12, 0, AlState::PreOp, std::vector<uint8_t>{0}), od::Status::Ok);
    ASSERT_EQ(dict.write(0x1C12, 1, AlState::PreOp, std::vector<uint8_t>{0x00, 0x1A}), od::Status::Ok);
    ASSERT_EQ(dict.write(0x1C12, 0, AlState::PreOp, std::vector<uint8_t>{1}), od::Status::Ok);
    configure_process_data(6, 6);
    request(0x04);
    EXPECT_EQ(al_status(), 0x02 | kErr);
    EXPECT_EQ(al_code(), 0x0025);
}

TEST_F(Esm, PS_PreOpToSafeOp_WatchdogShorterThanCycle_0x001F) {
    go_preop();
    configure_process_data(6, 6);
    master.wr<uint16_t>(0x0420, 5);  // 5 x 100 us = 0.5 ms < 1 ms cycle (0x1C32:02)
    request(0x04);
    EXPECT_EQ(al_status(), 0x02 | kErr);
    EXPECT_EQ(al_code(), 0x001F);
}

TEST_F(Esm, PS_PreOpToSafeOp_WatchdogOff_Accepted) {
    go_preop();
    configure_process_data(6, 6);
    master.wr<uint16_t>(0x0420, 0);
    request(0x04);
    EXPECT_EQ(al_status(), 0x04);
}

TEST_F(Esm, PS_PreOpToSafeOp_ApplicationVeto) {
    go_preop();
    configure_process_data(6, 6);
    app.veto_state = AlState::SafeOp;
    app.veto_code = 0x0026;
    request(0x04);
    EXPECT_EQ(al_status(), 0x02 | kErr);
    EXPECT_EQ(al_code(), 0x0026);
}

// ---- Bootstrap ----------------------------------------------------------------------------------------

TEST_F(Esm, BI_BootToInit_Restarts) {
    configure_bootstrap_mailbox();
    request(0x03);
    ASSERT_EQ(al_status(), 0x03);
    request(0x01);
    EXPECT_EQ(al_status(), 0x01);
    EXPECT_EQ(app.restarts, 1);
    EXPECT_FALSE(stack->mailbox().running());
    poll();
    EXPECT_EQ(app.restarts, 1);  // once
}

TEST_F(Esm, Invalid_BootToPreOp_0x0011) {
    configure_bootstrap_mailbox();
    request(0x03);
    request(0x02);
    EXPECT_EQ(al_status(), 0x03 | kErr);
    EXPECT_EQ(al_code(), 0x0011);
}

TEST_F(Esm, Invalid_BootToSafeOp_0x0011) {
    configure_bootstrap_mailbox();
    request(0x03);
    request(0x04);
    EXPECT_EQ(al_status(), 0x03 | kErr);
    EXPECT_EQ(al_code(), 0x0011);
}

TEST_F(Esm, Invalid_BootToOp_0x0011) {
    configure_bootstrap_mailbox();
    request(0x03);
    request(0x08);
    EXPECT_EQ(al_status(), 0x03 | kErr);
    EXPECT_EQ(al_code(), 0x0011);
}

// ---- Safe-Op ------------------------------------------------------------------------------------------

TEST_F(Esm, SP_SafeOpToPreOp_StopsProcessData) {
    go_safeop();
    request(0x02);
    EXPECT_EQ(al_status(), 0x02);
    EXPECT_EQ(stack->process_data().rx_bytes(), 0u);
    EXPECT_TRUE(stack->mailbox().running());
}

TEST_F(Esm, SI_SafeOpToInit_StopsAll) {
    go_safeop();
    request(0x01);
    EXPECT_EQ(al_status(), 0x01);
    EXPECT_FALSE(stack->mailbox().running());
    EXPECT_EQ(stack->process_data().tx_bytes(), 0u);
}

TEST_F(Esm, Invalid_SafeOpToBoot_0x0011) {
    go_safeop();
    request(0x03);
    EXPECT_EQ(al_status(), 0x04 | kErr);
    EXPECT_EQ(al_code(), 0x0011);
}

TEST_F(Esm, SO_SafeOpToOp_Valid) {
    go_op();
    EXPECT_EQ(al_code(), 0);
    EXPECT_EQ(app.changes.back(), std::make_pair(AlState::SafeOp, AlState::Op));
}

TEST_F(Esm, SO_SafeOpToOp_WaitsForFirstOutputs) {
    go_safeop();
    request(0x08);
    EXPECT_EQ(al_status(), 0x04);  // still Safe-Op, no error: waiting for outputs
    std::vector<uint8_t> out(6, 0), in(6, 0);
    exchange_pd(out, in);
    poll();
    EXPECT_EQ(al_status(), 0x08);
}

TEST_F(Esm, SO_SafeOpToOp_NoOutputs_0x001B) {
    go_safeop();
    request(0x08);
    EXPECT_EQ(al_status(), 0x04);
    advance(2'000'000'000);
    EXPECT_EQ(al_status(), 0x04 | kErr);
    EXPECT_EQ(al_code(), 0x001B);
}

TEST_F(Esm, SO_SafeOpToOp_StaleOutputs_WaitsThen0x001B) {
    go_safeop();
    std::vector<uint8_t> out(6, 0), in(6, 0);
    exchange_pd(out, in);
    poll();
    advance(150'000'000);  // the master stopped sending: the PD watchdog expires in Safe-Op
    ASSERT_EQ(al_status(), 0x04);
    request(0x08);
    EXPECT_EQ(al_status(), 0x04);  // not with stale outputs
    exchange_pd(out, in);          // fresh outputs re-arm the watchdog
    poll();
    EXPECT_EQ(al_status(), 0x08);
}

TEST_F(Esm, SO_SafeOpToOp_ApplicationVeto) {
    go_safeop();
    app.veto_state = AlState::Op;
    app.veto_code = 0x0019;
    request(0x08);
    EXPECT_EQ(al_status(), 0x04 | kErr);
    EXPECT_EQ(al_code(), 0x0019);
}

// ---- Op -----------------------------------------------------------------------------------------------

TEST_F(Esm, OS_OpToSafeOp_OutputsLost) {
    go_op();
    request(0x04);
    EXPECT_EQ(al_status(), 0x04);
    EXPECT_EQ(app.outputs_lost, 1);
}

TEST_F(Esm, OS_OpToSafeOp_NotVetoedByApplication) {
    go_op();
    app.veto_state = AlState::SafeOp;
    app.veto_code = 0x0001;
    request(0x04);
    EXPECT_EQ(al_status(), 0x04);
}

TEST_F(Esm, OP_OpToPreOp_StopsProcessData) {
    go_op();
    request(0x02);
    EXPECT_EQ(al_status(), 0x02);
    EXPECT_EQ(app.outputs_lost, 1);
    EXPECT_EQ(stack->process_data().rx_bytes(), 0u);
}

TEST_F(Esm, OI_OpToInit_StopsAll) {
    go_op();
    request(0x01);
    EXPECT_EQ(al_status(), 0x01);
    EXPECT_EQ(app.outputs_lost, 1);
    EXPECT_FALSE(stack->mailbox().running());
}

TEST_F(Esm, Invalid_OpToBoot_0x0011) {
    go_op();
    request(0x03);
    EXPECT_EQ(al_status(), 0x08 | kErr);
    EXPECT_EQ(al_code(), 0x0011);
}

TEST_F(Esm, OO_OpToOp_Stays) {
    go_op();
    request(0x08);
    EXPECT_EQ(al_status(), 0x08);
}

// ---- Unknown states, error indication and acknowledge ---------------------------------------------------

TEST_F(Esm, Unknown_State5_0x0012) {
    request(0x05);
    EXPECT_EQ(al_status(), 0x01 | kErr);
    EXPECT_EQ(al_code(), 0x0012);
}

TEST_F(Esm, Unknown_StateF_InPreOp_0x0012) {
    go_preop();
    request(0x0F);
    EXPECT_EQ(al_status(), 0x02 | kErr);
    EXPECT_EQ(al_code(), 0x0012);
}

TEST_F(Esm, ErrorInd_RequestWithoutAckIgnored) {
    go_preop();
    request(0x08);  // invalid: error
    ASSERT_EQ(al_status(), 0x02 | kErr);
    configure_process_data(6, 6);
    request(0x04);  // valid, but no acknowledge
    EXPECT_EQ(al_status(), 0x02 | kErr);
    EXPECT_EQ(al_code(), 0x0011);
}

TEST_F(Esm, ErrorAck_ClearsAndPerformsRequest) {
    go_preop();
    request(0x08);
    ASSERT_EQ(al_status(), 0x02 | kErr);
    configure_process_data(6, 6);
    request(0x04 | 0x10);
    EXPECT_EQ(al_status(), 0x04);
    EXPECT_EQ(al_code(), 0);
}

TEST_F(Esm, ErrorAck_SameState_ClearsOnly) {
    go_preop();
    request(0x08);
    request(0x12);
    EXPECT_EQ(al_status(), 0x02);
    EXPECT_EQ(al_code(), 0);
}

TEST_F(Esm, ErrorAck_InitRequestActsAsAck) {
    go_preop();
    request(0x08);
    request(0x01);
    EXPECT_EQ(al_status(), 0x01);
    EXPECT_EQ(al_code(), 0);
}

TEST_F(Esm, ErrorAck_FailingRequestSetsNewError) {
    go_preop();
    request(0x08);
    configure_process_data(2, 6);  // wrong SM2 length
    request(0x14);
    EXPECT_EQ(al_status(), 0x02 | kErr);
    EXPECT_EQ(al_code(), 0x001D);
}

// ---- Device identification ---------------------------------------------------------------------------

TEST_F(Esm, DeviceId_RequestShowsAliasInStatusCode) {
    master.wr<uint16_t>(0x0012, 0x1234);  // configured station alias (normally from SII word 4)
    request(0x21);
    EXPECT_EQ(al_status(), 0x21);
    EXPECT_EQ(al_code(), master.rd<uint16_t>(0x0012));
    request(0x01);
    EXPECT_EQ(al_status(), 0x01);
    EXPECT_EQ(al_code(), 0);
}

TEST_F(Esm, DeviceId_WithTransition) {
    configure_mailbox();
    request(0x22);
    EXPECT_EQ(al_status(), 0x22);
    EXPECT_EQ(al_code(), master.rd<uint16_t>(0x0012));
}

TEST_F(Esm, DeviceId_NotWhileErrorPending) {
    request(0x04);  // invalid from Init
    request(0x24);  // ID request without ack: ignored, error stays
    EXPECT_EQ(al_status(), 0x01 | kErr);
    EXPECT_EQ(al_code(), 0x0011);
}

// ---- Runtime fall-backs --------------------------------------------------------------------------------

TEST_F(Esm, Watchdog_InOp_SafeOpWith0x001B) {
    go_op();
    // Default PD watchdog: 1000 x 100 us = 100 ms without an SM2 write.
    advance(150'000'000);
    EXPECT_EQ(al_status(), 0x04 | kErr);
    EXPECT_EQ(al_code(), 0x001B);
    EXPECT_EQ(app.outputs_lost, 1);
    EXPECT_GE(stack->stats().watchdog_expiries, 1u);
}

TEST_F(Esm, Watchdog_RefreshedOutputsKeepOp) {
    go_op();
    std::vector<uint8_t> out(6, 0), in(6, 0);
    for (int i = 0; i < 10; ++i) {
        clock.advance(50'000'000);
        exchange_pd(out, in);
        poll();
    }
    EXPECT_EQ(al_status(), 0x08);
}

TEST_F(Esm, Watchdog_InSafeOp_NoStateChange) {
    go_safeop();
    std::vector<uint8_t> out(6, 0), in(6, 0);
    exchange_pd(out, in);
    advance(150'000'000);
    EXPECT_EQ(al_status(), 0x04);
}

TEST_F(Esm, Runtime_Sm2DisabledInOp_SafeOpWith0x001D) {
    go_op();
    master.wr<uint8_t>(0x0816, 0);  // SM2 activate = 0
    poll();
    EXPECT_EQ(al_status(), 0x04 | kErr);
    EXPECT_EQ(al_code(), 0x001D);
    EXPECT_EQ(app.outputs_lost, 1);
}

TEST_F(Esm, Runtime_Sm3DisabledInSafeOp_0x001E) {
    go_safeop();
    master.wr<uint8_t>(0x081E, 0);
    poll();
    EXPECT_EQ(al_status(), 0x04 | kErr);
    EXPECT_EQ(al_code(), 0x001E);
}

TEST_F(Esm, Runtime_RepeatRequestInOp_NoFallBack) {
    go_op();
    master.wr<uint8_t>(0x080E, 0x03);  // SM1 repeat request toggled: an activation event, SMs unchanged
    poll();
    EXPECT_EQ(al_status(), 0x08);
}

TEST_F(Esm, LocalError_FallsBack) {
    go_op();
    stack->local_error(0x001A, AlState::SafeOp);
    EXPECT_EQ(al_status(), 0x04 | kErr);
    EXPECT_EQ(al_code(), 0x001A);
    EXPECT_EQ(app.outputs_lost, 1);
}

// ---- quiet(): what a caller with many stacks may skip ------------------------------------------------

TEST_F(Esm, QuietUntilTheMasterWritesAlControlOrTheHousekeepingIsDue) {
    EXPECT_TRUE(stack->quiet(clock.now_ns()));  // first poll done, nothing signalled, no deadline
    configure_mailbox();
    master.wr<uint16_t>(0x0120, 0x02);  // AL control: the event raises the interrupt line
    EXPECT_FALSE(stack->quiet(clock.now_ns()));
    poll();
    ASSERT_EQ(al_status(), 0x02);
    EXPECT_TRUE(stack->quiet(clock.now_ns()));  // event acknowledged by the poll
    // In Pre-Op the mailbox handlers' housekeeping comes due.
    const uint64_t due = stack->next_deadline_ns();
    ASSERT_NE(due, UINT64_MAX);
    EXPECT_TRUE(stack->quiet(due - 1));
    EXPECT_FALSE(stack->quiet(due));
}

// ETG.5001.1 module ident lists: at Pre-Op -> Safe-Op the modules the master configured (0xF030) must be the
// ones the device detected (0xF050), slot by slot (a slot past a list's count is empty, ident 0); a
// difference refuses the transition with 0x0070. A configured count of 0 configures nothing.
od::Object module_ident_list(uint16_t index, uint16_t access, const std::vector<uint32_t>& idents) {
    od::Object o;
    o.index = index;
    o.code = od::ObjectCode::Array;
    o.type = od::DataType::Unsigned32;
    o.name = index == 0xF030 ? "Configured module ident list" : "Detected module ident list";
    od::Entry n;
    n.index = index;
    n.type = od::DataType::Unsigned8;
    n.bit_length = 8;
    n.access = access;
    n.default_value = uint64_t{idents.size()};
    o.entries.push_back(n);
    for (std::size_t k = 0; k < idents.size(); ++k) {
        od::Entry e = n;
        e.subindex = static_cast<uint8_t>(k + 1);
        e.type = od::DataType::Unsigned32;
        e.bit_length = 32;
        e.default_value = uint64_t{idents[k]};
        o.entries.push_back(e);
    }
    return o;
}

TEST_F(Esm, PS_PreOpToSafeOp_ConfiguredModulesNotDetected_0x0070) {
    const std::vector<uint32_t> detected = {0x1001, 0, 0x3001, 0};
    dict.add(module_ident_list(0xF050, od::access::RO, detected));
    dict.add(module_ident_list(0xF030, od::access::RW_PreOp, detected));
    start();
    struct Case {
        const char* what;
        uint8_t count;
        std::vector<uint32_t> configured;  // subindex 1.. (written in Pre-Op as a master does)
        uint16_t code;
    };
    const Case cases[] = {
        {"as detected", 4, {0x1001, 0, 0x3001, 0}, 0},
        {"another module in slot 3", 4, {0x1001, 0, 0x2001, 0}, 0x0070},
        {"a module in an empty slot", 4, {0x1001, 0x2001, 0x3001, 0}, 0x0070},
        {"slot 1 empty", 4, {0, 0, 0x3001, 0}, 0x0070},
        {"three slots, the fourth empty as detected", 3, {0x1001, 0, 0x3001, 0x2001}, 0},
        {"two slots: slot 3's module not configured", 2, {0x1001, 0, 0x3001, 0}, 0x0070},
        {"nothing configured", 0, {0x2001, 0x2001, 0x2001, 0x2001}, 0},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.what);
        request(0x11);  // Init, error acknowledged
        go_preop();
        ASSERT_EQ(dict.write(0xF030, 0, od::AlState::PreOp, std::vector<uint8_t>{0}), od::Status::Ok);
        for (std::size_t k = 0; k < c.configured.size(); ++k) {
            const uint32_t v = c.configured[k];
            const std::vector<uint8_t> b = {static_cast<uint8_t>(v), static_cast<uint8_t>(v >> 8),
                                            static_cast<uint8_t>(v >> 16), static_cast<uint8_t>(v >> 24)};
            ASSERT_EQ(dict.write(0xF030, static_cast<uint8_t>(k + 1), od::AlState::PreOp, b), od::Status::Ok);
        }
        ASSERT_EQ(dict.write(0xF030, 0, od::AlState::PreOp, std::vector<uint8_t>{c.count}), od::Status::Ok);
        configure_process_data(6, 6);
        request(0x04);
        EXPECT_EQ(al_status(), c.code ? (0x02 | kErr) : 0x04);
        EXPECT_EQ(al_code(), c.code);
    }
}

TEST_F(Esm, PS_PreOpToSafeOp_DetectedModulesWithoutConfiguredList) {
    // A device with 0xF050 only (the master cannot configure modules): nothing to compare.
    dict.add(module_ident_list(0xF050, od::access::RO, {0x1001, 0x2001}));
    start();
    go_preop();
    configure_process_data(6, 6);
    request(0x04);
    EXPECT_EQ(al_status(), 0x04);
    EXPECT_EQ(al_code(), 0);
}

}  // namespace
}  // namespace ecat::test
