// Datagram commands and working counters (ETG.1000.4, datagram commands; ESC datasheet section I, frame
// processing).
#include <gtest/gtest.h>

#include <algorithm>
#include <optional>
#include <string>

#include "esc_fixture.hpp"

using namespace esc_test;

namespace {

struct CommandCase {
    std::string name;
    uint8_t cmd;
    uint16_t adp;
    std::vector<uint8_t> in;
    std::vector<uint8_t> out;  // data returned
    uint16_t wkc;
    uint16_t adp_after;
    std::vector<uint8_t> mem_after;  // RAM 0x1000..0x1001 afterwards
};

class Command : public ::testing::TestWithParam<CommandCase> {};

TEST_P(Command, DataWkcAdpAndMemory) {
    const CommandCase& c = GetParam();
    esc::ManualClock clk;
    clk.set(1'000'000);
    esc::Esc e({}, clk);
    set_station(e, 0x1001);
    e.write_reg<uint16_t>(0x1000, 0x2211);  // PDI writes the memory the commands address
    Datagram d = run1(e, dg(c.cmd, c.adp, 0x1000, c.in));
    EXPECT_EQ(d.data, c.out);
    EXPECT_EQ(d.wkc, c.wkc);
    EXPECT_EQ(d.adp, c.adp_after);
    EXPECT_EQ(d.ado, 0x1000);
    EXPECT_EQ(e.read_reg<uint16_t>(0x1000), static_cast<uint16_t>(c.mem_after[0] | (c.mem_after[1] << 8)));
}

const std::vector<uint8_t> kMem{0x11, 0x22};
const std::vector<uint8_t> kIn{0xA5, 0x0F};
const std::vector<uint8_t> kZero{0x00, 0x00};

INSTANTIATE_TEST_SUITE_P(
    Commands, Command,
    ::testing::Values(CommandCase{"NOP", NOP, 0, kIn, kIn, 0, 0, kMem},
                      CommandCase{"APRD_addressed", APRD, 0, kZero, kMem, 1, 1, kMem},
                      CommandCase{"APRD_other", APRD, 0xFFFF, kZero, kZero, 0, 0, kMem},
                      CommandCase{"APWR_addressed", APWR, 0, kIn, kIn, 1, 1, kIn},
                      CommandCase{"APWR_other", APWR, 0xFFFE, kIn, kIn, 0, 0xFFFF, kMem},
                      CommandCase{"APRW_addressed", APRW, 0, kIn, kMem, 3, 1, kIn},
                      CommandCase{"APRW_other", APRW, 7, kIn, kIn, 0, 8, kMem},
                      CommandCase{"FPRD_match", FPRD, 0x1001, kZero, kMem, 1, 0x1001, kMem},
                      CommandCase{"FPRD_other", FPRD, 0x1002, kZero, kZero, 0, 0x1002, kMem},
                      CommandCase{"FPWR_match", FPWR, 0x1001, kIn, kIn, 1, 0x1001, kIn},
                      CommandCase{"FPWR_other", FPWR, 0x0000, kIn, kIn, 0, 0x0000, kMem},
                      CommandCase{"FPRW_match", FPRW, 0x1001, kIn, kMem, 3, 0x1001, kIn},
                      CommandCase{"FPRW_other", FPRW, 0x1000, kIn, kIn, 0, 0x1000, kMem},
                      CommandCase{"BRD_ors", BRD, 0x1234, kIn, {0xB5, 0x2F}, 1, 0x1235, kMem},
                      CommandCase{"BWR", BWR, 0xFFFF, kIn, kIn, 1, 0x0000, kIn},
                      CommandCase{"BRW", BRW, 0, kIn, {0xB5, 0x2F}, 3, 1, kIn},
                      CommandCase{"ARMW_addressed_reads", ARMW, 0, kIn, kMem, 1, 1, kMem},
                      CommandCase{"ARMW_other_writes", ARMW, 0xFFFF, kIn, kIn, 1, 0, kIn},
                      CommandCase{"FRMW_match_reads", FRMW, 0x1001, kIn, kMem, 1, 0x1001, kMem},
                      CommandCase{"FRMW_other_writes", FRMW, 0x2000, kIn, kIn, 1, 0x2000, kIn},
                      CommandCase{"Unknown_0x20", 0x20, 0, kIn, kIn, 0, 0, kMem},
                      CommandCase{"EXT_0xFF", 0xFF, 0, kIn, kIn, 0, 0, kMem}),
    [](const auto& p) { return p.param.name; });

using Fixture = EscFixture<>;

using Addressing = Fixture;

TEST_F(Addressing, AliasOnlyWithDlControlBit24) {
    e->write_reg<uint16_t>(0x0012, 0x0BAD);
    EXPECT_EQ(fprd(*e, 0x0010, 2, 0x0BAD).wkc, 0);
    fpwr(*e, 0x0103, {0x01});
    Datagram d = fprd(*e, 0x0010, 2, 0x0BAD);
    EXPECT_EQ(d.wkc, 1);
    EXPECT_EQ(d.u16(), 0x1001);
    EXPECT_EQ(fprd(*e, 0x0010, 2, 0x1001).wkc, 1);  // station address still matches
}

TEST_F(Addressing, AliasNotWritableFromEcat) {
    EXPECT_EQ(fpwr(*e, 0x0012, {0x34, 0x12}).wkc, 1);  // register exists, write ignored
    EXPECT_EQ(fprd(*e, 0x0012, 2).u16(), 0x0000);
}

TEST_F(Addressing, AccessSpanningRegistersAndRam) {
    e->write_reg<uint8_t>(0x0FFF, 0x5A);
    e->write_reg<uint8_t>(0x1000, 0xA5);
    Datagram d = fprd(*e, 0x0FFF, 2);
    EXPECT_EQ(d.wkc, 1);
    EXPECT_EQ(d.data, (std::vector<uint8_t>{0x5A, 0xA5}));
    EXPECT_EQ(fpwr(*e, 0x0FFF, {0x01, 0x02}).wkc, 1);
    EXPECT_EQ(e->read_reg<uint16_t>(0x0FFF), 0x0201);
}

TEST_F(Addressing, BeyondProcessRamIsNotAccessible) {
    // 8 KiB RAM: 0x1000..0x2FFF.
    EXPECT_EQ(fprd(*e, 0x3000, 4).wkc, 0);
    EXPECT_EQ(fpwr(*e, 0x3000, {1, 2}).wkc, 0);
    EXPECT_EQ(fprd(*e, 0x2FFF, 2).wkc, 1);  // one byte accessible is enough
    EXPECT_EQ(fprd(*e, 0xFFFF, 2).wkc, 0);  // no wrap into 0x0000
}

TEST_F(Addressing, ReadOnlyRegistersIgnoreEcatWrites) {
    EXPECT_EQ(fpwr(*e, 0x0000, {0xFF, 0xFF, 0xFF, 0xFF}).wkc, 1);
    Datagram d = fprd(*e, 0x0000, 10);
    EXPECT_EQ(d.data[0], 0x04);  // type
    EXPECT_EQ(d.data[4], 8);     // FMMUs
    EXPECT_EQ(d.data[5], 8);     // SMs
    EXPECT_EQ(d.data[6], 8);     // RAM KiB
    EXPECT_EQ(d.data[7], 0x0F);
    EXPECT_EQ(d.u16(8), 0x01CC);
    fpwr(*e, 0x0130, {0x08, 0x00});  // AL status: PDI only
    EXPECT_EQ(fprd(*e, 0x0130, 2).u16(), 0x0001);
}

TEST_F(Addressing, ResetValues) {
    EXPECT_EQ(fprd(*e, 0x0100, 4).u32(), 0x00070001u);  // every port's loop "auto"
    EXPECT_EQ(fprd(*e, 0x0110, 2).u16(), 0x5613);       // single port, EEPROM loaded
    EXPECT_EQ(fprd(*e, 0x0120, 2).u16(), 0x0001);
    EXPECT_EQ(fprd(*e, 0x0130, 2).u16(), 0x0001);
    EXPECT_EQ(fprd(*e, 0x0204, 4).u32(), 0x00FFFF2Fu);
    EXPECT_EQ(fprd(*e, 0x0400, 2).u16(), 0x09C2);
    EXPECT_EQ(fprd(*e, 0x0410, 2).u16(), 0x03E8);
    EXPECT_EQ(fprd(*e, 0x0420, 2).u16(), 0x03E8);
    EXPECT_EQ(fprd(*e, 0x0930, 2).u16(), 0x1000);
    EXPECT_EQ(fprd(*e, 0x0934, 2).u16(), 0x0C04);
    EXPECT_EQ(fprd(*e, 0x0805, 1).data[0], 0x30);
}

TEST_F(Addressing, RegisterWriteProtection) {
    fpwr(*e, 0x0021, {0x01});
    EXPECT_EQ(fpwr(*e, 0x0010, {0x02, 0x10}).wkc, 0);  // protected: not written, not counted
    EXPECT_EQ(fprd(*e, 0x0010, 2).u16(), 0x1001);
    // Write enable in the same frame, then the write.
    auto r = run(*e, {dg(FPWR, 0x1001, 0x0020, {0x01}), dg(FPWR, 0x1001, 0x0010, {0x02, 0x10})});
    EXPECT_EQ(r[1].wkc, 1);
    EXPECT_EQ(fprd(*e, 0x0010, 2, 0x1002).u16(), 0x1002);
    // Enable does not carry over to the next frame.
    EXPECT_EQ(fpwr(*e, 0x0010, {0x01, 0x10}, 0x1002).wkc, 0);
    // User RAM 0x0F80.. is not protected.
    EXPECT_EQ(fpwr(*e, 0x0F80, {0x77}, 0x1002).wkc, 1);
    EXPECT_EQ(e->read_reg<uint8_t>(0x0F80), 0x77);
}

TEST_F(Addressing, EscWriteProtectionCoversRam) {
    fpwr(*e, 0x0031, {0x01});
    EXPECT_EQ(fpwr(*e, 0x1000, {0x42}).wkc, 0);
    auto r = run(*e, {dg(FPWR, 0x1001, 0x0030, {0x01}), dg(FPWR, 0x1001, 0x1000, {0x42})});
    EXPECT_EQ(r[1].wkc, 1);
    EXPECT_EQ(e->read_reg<uint8_t>(0x1000), 0x42);
}

TEST_F(Addressing, EscResetSequence) {
    fpwr(*e, 0x0F80, {0x99});
    fpwr(*e, 0x0200, {0x0C, 0x00});
    fpwr(*e, 0x0040, {0x52});
    EXPECT_EQ(fprd(*e, 0x0040, 1).data[0], 0x01);
    fpwr(*e, 0x0040, {0x45});
    EXPECT_EQ(fprd(*e, 0x0040, 1).data[0], 0x02);
    fpwr(*e, 0x0040, {0x53});
    // Registers back at reset values: station address 0 now.
    EXPECT_EQ(fprd(*e, 0x0010, 2).wkc, 0);
    Datagram d = run1(*e, dg_len(APRD, 0, 0x0200, 2));
    EXPECT_EQ(d.u16(), 0x0000);
    EXPECT_EQ(run1(*e, dg_len(APRD, 0, 0x0040, 1)).data[0], 0x00);
}

TEST_F(Addressing, EscResetWrongSequenceRestarts) {
    fpwr(*e, 0x0040, {0x52});
    fpwr(*e, 0x0040, {0x53});
    EXPECT_EQ(fprd(*e, 0x0040, 1).data[0], 0x00);
    fpwr(*e, 0x0040, {0x45});
    EXPECT_EQ(fprd(*e, 0x0010, 2).wkc, 1);  // no reset happened
}

TEST_F(Addressing, ErrorCountersClearOnWrite) {
    std::vector<uint8_t> bad = build({dg_len(FPRD, 0x1001, 0x0130, 2)});
    bad[16 + 6] = 0xFF;  // datagram length beyond the frame
    EXPECT_FALSE(e->process_frame(bad));
    EXPECT_EQ(e->stats().frames_malformed, 1u);
    esc::FrameCheck check;
    check.crc_bad = true;
    auto f = bad;
    e->receive(f, 0, 0, check);  // a bad FCS: an invalid frame at port 0
    EXPECT_EQ(fprd(*e, 0x0300, 1).wkc, 1);
    EXPECT_EQ(fprd(*e, 0x0300, 1).data[0], 1);
    EXPECT_EQ(fprd(*e, 0x030C, 1).data[0], 1);
    fpwr(*e, 0x0300, std::vector<uint8_t>(0x14, 0xAB));
    EXPECT_EQ(fprd(*e, 0x0300, 1).data[0], 0);
    EXPECT_EQ(fprd(*e, 0x030C, 1).data[0], 0);
}

// A write clears a whole group of error counters whatever byte of the group it hits (ESC datasheet section
// II): 0x0300-0x030B together, 0x030C alone, 0x0310-0x0313 together. Every byte of each group is tried.
TEST_F(Addressing, ErrorCounterWriteClearsItsWholeGroup) {
    auto raise_every_counter = [&] {
        esc::FrameCheck check;
        check.crc_bad = true;
        std::vector<uint8_t> f = build({dg_len(FPRD, 0x1001, 0x0130, 2)});
        e->set_link(1, true);
        (void)e->receive(f, 0, 0, check);  // invalid frame + RX error at port 0
        esc::FrameCheck marked;
        marked.crc_bad = true;
        marked.marked = true;
        f = build({dg_len(FPRD, 0x1001, 0x0130, 2)});
        (void)e->receive(f, 1, 0, marked);  // forwarded RX error at port 1
        std::vector<uint8_t> bad = build({dg_len(FPRD, 0x1001, 0x0130, 2)});
        bad[16 + 6] = 0xFF;
        (void)e->process_frame(bad);  // length error: processing unit
        e->set_link(1, false);        // lost link at port 1
        ASSERT_NE(fprd(*e, 0x0300, 1).data[0], 0);
        ASSERT_NE(fprd(*e, 0x0309, 1).data[0], 0);
        ASSERT_NE(fprd(*e, 0x030C, 1).data[0], 0);
        ASSERT_NE(fprd(*e, 0x0311, 1).data[0], 0);
    };
    auto all_zero = [&](uint16_t from, uint16_t len) {
        const auto d = fprd(*e, from, len).data;
        return std::all_of(d.begin(), d.end(), [](uint8_t b) { return b == 0; });
    };
    for (uint16_t a = 0x0300; a < 0x030C; ++a) {
        raise_every_counter();
        fpwr(*e, a, std::vector<uint8_t>{0x5A});
        EXPECT_TRUE(all_zero(0x0300, 0x0C)) << std::hex << a;
        EXPECT_NE(fprd(*e, 0x030C, 1).data[0], 0) << std::hex << a;
        EXPECT_NE(fprd(*e, 0x0311, 1).data[0], 0) << std::hex << a;
    }
    for (uint16_t a = 0x0310; a < 0x0314; ++a) {
        raise_every_counter();
        fpwr(*e, a, std::vector<uint8_t>{0x5A});
        EXPECT_TRUE(all_zero(0x0310, 4)) << std::hex << a;
        EXPECT_NE(fprd(*e, 0x0300, 1).data[0], 0) << std::hex << a;
    }
    raise_every_counter();
    fpwr(*e, 0x030C, std::vector<uint8_t>{0x5A});
    EXPECT_EQ(fprd(*e, 0x030C, 1).data[0], 0);
    EXPECT_NE(fprd(*e, 0x0300, 1).data[0], 0);
    EXPECT_NE(fprd(*e, 0x0311, 1).data[0], 0);
}

}  // namespace
