// SyncManagers over the register space (ESC datasheet section I, SyncManager and watchdogs; section II,
// 0x0F00 digital I/O output data, 0x0400 watchdog divider, 0x0420 watchdog time process data, 0x0440 watchdog
// status process data). A digital-output ESC's master configures a SyncManager on the output registers 0x0F00
// with the watchdog trigger (EL2xxx-like terminals: control 0x44, 1 to 4 bytes). Such an SM has no buffer of
// its own: the bytes keep their register rules, the access of its last byte closes it as the single-byte SM
// in the RAM is closed (status, events, watchdog trigger), whatever its length, mode and the command that
// reaches it.
#include <gtest/gtest.h>

#include <string>

#include "esc_fixture.hpp"

using namespace esc_test;

namespace {

// FMMU n: logical la, len bytes (whole bytes), physical pa, type (1 read, 2 write, 3 both), enabled.
std::vector<uint8_t> fmmu(uint32_t la, uint16_t len, uint16_t pa, uint8_t type) {
    std::vector<uint8_t> b = le(la, 4);
    auto l = le(len, 2);
    b.insert(b.end(), l.begin(), l.end());
    b.push_back(0);  // logical start bit
    b.push_back(7);  // logical stop bit
    auto p = le(pa, 2);
    b.insert(b.end(), p.begin(), p.end());
    b.push_back(0);  // physical start bit
    b.push_back(type);
    b.push_back(1);
    b.insert(b.end(), 3, 0);
    return b;
}

constexpr uint32_t kLogical = 0x00010000;

struct RegisterSm : EscFixture<> {
    uint8_t status(unsigned n) { return fprd(*e, static_cast<uint16_t>(0x0805 + 8 * n), 1).data[0]; }
    uint32_t al_event() { return e->read_reg<uint32_t>(0x0220); }
    uint16_t wd_status() { return fprd(*e, 0x0440, 2).u16(); }
    uint8_t wd_expiries() { return fprd(*e, 0x0442, 1).data[0]; }
    std::vector<uint8_t> pdi_read(uint16_t a, std::size_t n) {
        std::vector<uint8_t> b(n);
        e->read(a, b);
        return b;
    }
    // SM2 on the digital outputs, len bytes, watchdog trigger (0x44) or as given; watchdog 1 ms.
    void outputs_sm(uint16_t len, uint8_t control = 0x44, uint16_t start = 0x0F00) {
        ASSERT_EQ(fpwr(*e, 0x0810, sm_bytes(start, len, control, 1)).wkc, 1);
        ASSERT_EQ(fpwr(*e, 0x0420, le(10, 2)).wkc, 1);  // 10 x 100 us
        ASSERT_EQ(fpwr(*e, 0x0410, le(0, 2)).wkc, 1);   // PDI watchdog off: next_event_ns() is the SM's
        e->read_reg<uint8_t>(0x0816);                   // acknowledge the SM activation event
    }
    // The watchdog ran out 1 ms after `since` (clock ns) and not before.
    void expect_expiry_after_1ms(uint64_t since) {
        EXPECT_EQ(e->next_event_ns(), since + 1'000'000u);
        clk.set(since + 999'000);
        e->tick();
        EXPECT_EQ(wd_status() & 1, 1);
        EXPECT_EQ(wd_expiries(), 0);
        clk.set(since + 1'000'000);
        e->tick();
        EXPECT_EQ(wd_status() & 1, 0);
        EXPECT_EQ(wd_expiries(), 1);
        EXPECT_EQ(al_event() & 0x40, 0x40u);  // process-data watchdog event
    }
};

// Every command that writes the outputs, every SM length a digital-output ESC offers (1 to 4 bytes).
struct WriteCase {
    const char* name;
    uint16_t len;
};

class DigitalOutputs : public RegisterSm, public ::testing::WithParamInterface<WriteCase> {
  protected:
    // Writes data to 0x0F00 with the command of the case; returns the working counter.
    uint16_t write_outputs(const std::string& how, const std::vector<uint8_t>& data) {
        const uint16_t n = static_cast<uint16_t>(data.size());
        if (how == "FPWR") return fpwr(*e, 0x0F00, data).wkc;
        if (how == "APWR") return run1(*e, dg(APWR, 0, 0x0F00, data)).wkc;
        if (how == "BWR") return run1(*e, dg(BWR, 0, 0x0F00, data)).wkc;
        if (how == "FPRW") return run1(*e, dg(FPRW, 0x1001, 0x0F00, data)).wkc;
        if (how == "LWR" || how == "LRW") {
            EXPECT_EQ(fpwr(*e, 0x0600, fmmu(kLogical, n, 0x0F00, how == "LWR" ? 0x02 : 0x03)).wkc, 1);
            return run1(*e, lg(how == "LWR" ? LWR : LRW, kLogical, data)).wkc;
        }
        ADD_FAILURE() << how;
        return 0;
    }
};

TEST_P(DigitalOutputs, WriteReachesTheRegistersClosesTheSmAndTriggersTheWatchdog) {
    const WriteCase c = GetParam();
    std::string how = c.name;
    how = how.substr(0, how.find('_'));
    outputs_sm(c.len);
    std::vector<uint8_t> data(c.len);
    for (uint16_t i = 0; i < c.len; ++i)
        data[i] = static_cast<uint8_t>(0xA1 + i);
    const uint16_t expected_wkc = how == "LRW" || how == "FPRW" ? 3 : 1;
    clk.set(2'000'000);
    EXPECT_EQ(write_outputs(how, data), expected_wkc);
    // The data is in the registers, for both sides (0x0F00 is ECAT read/write, PDI read).
    EXPECT_EQ(fprd(*e, 0x0F00, c.len).data, data);
    EXPECT_EQ(status(2) & 0x03, 0x01);  // written, not read
    // The PDI takes the outputs: the consumer's read of the last byte closes it the other way.
    EXPECT_EQ(pdi_read(0x0F00, c.len), data);
    EXPECT_EQ(status(2) & 0x03, 0x02);
    expect_expiry_after_1ms(2'000'000);
    // Retriggered by the next write of the outputs.
    clk.set(3'500'000);
    EXPECT_EQ(write_outputs(how, data), expected_wkc);
    e->tick();
    EXPECT_EQ(wd_status() & 1, 1);
}

INSTANTIATE_TEST_SUITE_P(
    EveryCommandAndLength, DigitalOutputs,
    ::testing::Values(WriteCase{"FPWR_1", 1}, WriteCase{"FPWR_4", 4}, WriteCase{"APWR_2", 2},
                      WriteCase{"BWR_1", 1}, WriteCase{"FPRW_3", 3}, WriteCase{"LWR_1", 1},
                      WriteCase{"LWR_2", 2}, WriteCase{"LRW_1", 1}, WriteCase{"LRW_4", 4}),
    [](const ::testing::TestParamInfo<WriteCase>& i) { return std::string(i.param.name); });

// The watchdog counts in steps of the divider 0x0400: (0x0400 + 2) x 40 ns.
TEST_F(RegisterSm, WatchdogTimeFollowsTheDivider) {
    outputs_sm(1);
    ASSERT_EQ(fpwr(*e, 0x0400, le(98, 2)).wkc, 1);   // 4 us steps
    ASSERT_EQ(fpwr(*e, 0x0420, le(250, 2)).wkc, 1);  // 1 ms
    clk.set(2'000'000);
    EXPECT_EQ(fpwr(*e, 0x0F00, {0x01}).wkc, 1);
    expect_expiry_after_1ms(2'000'000);
}

// An SM of several bytes is closed by its last byte: a write that stops before it neither signals nor
// triggers; the bytes are written all the same.
TEST_F(RegisterSm, WriteWithoutTheLastByteDoesNotClose) {
    outputs_sm(2);
    clk.set(2'000'000);
    EXPECT_EQ(fpwr(*e, 0x0F00, {0x55}).wkc, 1);
    EXPECT_EQ(fprd(*e, 0x0F00, 1).data[0], 0x55);
    EXPECT_EQ(status(2) & 0x01, 0x00);
    EXPECT_EQ(e->next_event_ns(), UINT64_MAX);   // nothing armed
    EXPECT_EQ(fpwr(*e, 0x0F01, {0x66}).wkc, 1);  // the last byte alone closes it
    EXPECT_EQ(status(2) & 0x01, 0x01);
    expect_expiry_after_1ms(2'000'000);
}

// Without the watchdog trigger bit (control 0x04) the write signals, but does not trigger the watchdog.
TEST_F(RegisterSm, NoTriggerWithoutTheWatchdogEnable) {
    outputs_sm(1, 0x04);
    EXPECT_EQ(fpwr(*e, 0x0F00, {0x01}).wkc, 1);
    EXPECT_EQ(status(2) & 0x01, 0x01);
    EXPECT_EQ(e->next_event_ns(), UINT64_MAX);
}

// The register rules stay: a write stopped by the register write protection (0x0021) reaches neither the
// register nor the SM; the SM never denies an access in the register space (its own registers could lie
// under it), whatever its mode and direction.
TEST_F(RegisterSm, TheRegisterRulesDecideWhatIsWritten) {
    outputs_sm(1);
    ASSERT_EQ(fpwr(*e, 0x0021, {0x01}).wkc, 1);  // register write protection on
    EXPECT_EQ(fpwr(*e, 0x0F00, {0x77}).wkc, 0);
    EXPECT_EQ(fprd(*e, 0x0F00, 1).data[0], 0x00);
    EXPECT_EQ(status(2) & 0x01, 0x00);
    EXPECT_EQ(e->next_event_ns(), UINT64_MAX);
    // Enabled for this frame by 0x0020 first: written and closed.
    const auto r = run(*e, {dg(FPWR, 0x1001, 0x0020, {0x01}), dg(FPWR, 0x1001, 0x0F00, {0x77})});
    EXPECT_EQ(r.at(1).wkc, 1);
    EXPECT_EQ(fprd(*e, 0x0F00, 1).data[0], 0x77);
    EXPECT_EQ(status(2) & 0x01, 0x01);
}

TEST_F(RegisterSm, NoAccessIsDeniedInTheRegisterSpace) {
    outputs_sm(2, 0x26);  // mailbox mode, write direction: never "full", never gates
    EXPECT_EQ(fpwr(*e, 0x0F00, {1, 2}).wkc, 1);
    EXPECT_EQ(fpwr(*e, 0x0F00, {3, 4}).wkc, 1);
    EXPECT_EQ(fprd(*e, 0x0F00, 2).data, (std::vector<uint8_t>{3, 4}));  // the producer reads too
    EXPECT_EQ(status(2) & 0x08, 0x00);
    // An SM over its own registers: the master still disables it.
    ASSERT_EQ(fpwr(*e, 0x0818, sm_bytes(0x0818, 8, 0x26, 1)).wkc, 1);
    EXPECT_EQ(fpwr(*e, 0x081E, {0x00}).wkc, 1);
    EXPECT_EQ(fprd(*e, 0x081E, 1).data[0], 0x00);
}

// A read-direction SM in the user RAM (0x0F80-0x0FFF): the PDI's write of the last byte signals the master,
// the master's read of it signals the PDI, with the events the control byte enables (AL event 8+n, ECAT event
// 4+n).
TEST_F(RegisterSm, ReadDirectionSmInTheUserRamSignalsBothSides) {
    ASSERT_EQ(fpwr(*e, 0x0818, sm_bytes(0x0F80, 4, 0x30, 1)).wkc, 1);  // ECAT reads, both events
    e->read_reg<uint8_t>(0x081E);
    e->write(0x0F80, std::vector<uint8_t>{9, 8, 7, 6});
    EXPECT_EQ(status(3) & 0x03, 0x01);
    EXPECT_EQ(fprd(*e, 0x0210, 2).u16() & 0x0080, 0x0080);  // ECAT event SM3
    Datagram d = fprd(*e, 0x0F80, 4);
    EXPECT_EQ(d.data, (std::vector<uint8_t>{9, 8, 7, 6}));
    EXPECT_EQ(status(3) & 0x03, 0x02);
    EXPECT_EQ(al_event() & 0x0800, 0x0800u);  // AL event SM3
}

// Deactivated by the PDI (0x0807 + 8n bit 0): the registers are served, the SM signals nothing.
TEST_F(RegisterSm, PdiDeactivatedSmSignalsNothing) {
    outputs_sm(1);
    e->write_reg<uint8_t>(0x0817, 0x01);
    EXPECT_EQ(fpwr(*e, 0x0F00, {0x01}).wkc, 1);
    EXPECT_EQ(fprd(*e, 0x0F00, 1).data[0], 0x01);
    EXPECT_EQ(status(2) & 0x01, 0x00);
    EXPECT_EQ(e->next_event_ns(), UINT64_MAX);
}

// Across the register/RAM edge: the bytes keep their own rules (user RAM, plain process RAM), the last byte
// (in the RAM) closes it.
TEST_F(RegisterSm, SmAcrossTheRamEdgeClosesAtItsLastByte) {
    outputs_sm(16, 0x44, 0x0FF8);
    clk.set(2'000'000);
    const std::vector<uint8_t> data{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16};
    EXPECT_EQ(fpwr(*e, 0x0FF8, data).wkc, 1);
    EXPECT_EQ(pdi_read(0x0FF8, 16), data);
    EXPECT_EQ(status(2) & 0x03, 0x02);
    expect_expiry_after_1ms(2'000'000);
}

// Disabled by the master: the registers are plain registers again.
TEST_F(RegisterSm, DisabledSmSignalsNothing) {
    outputs_sm(1);
    ASSERT_EQ(fpwr(*e, 0x0816, {0x00}).wkc, 1);
    EXPECT_EQ(fpwr(*e, 0x0F00, {0x01}).wkc, 1);
    EXPECT_EQ(status(2) & 0x01, 0x00);
    EXPECT_EQ(e->next_event_ns(), UINT64_MAX);
}

}  // namespace
