// The deliberate ESC faults (esc/faults.hpp, `ecat-slave --fault`): each one breaks the one behaviour it
// names, and an ESC without it behaves as ETG.1000.4 and the ESC datasheet say.
#include <gtest/gtest.h>

#include <optional>

#include "esc/wire/sii.hpp"
#include "frame.hpp"

using namespace esc_test;

namespace {

struct Escs {
    esc::ManualClock clk;
    std::optional<esc::Esc> clean, faulty;
    explicit Escs(const esc::EscFaults& faults) {
        clk.set(kT0);
        esc::EscConfig c;
        clean.emplace(c, clk);
        c.faults = faults;
        faulty.emplace(c, clk);
        for (esc::Esc* e : {&*clean, &*faulty}) {
            set_station(*e, 0x1001);
            fpwr(*e, 0x0410, {0x00, 0x00});  // PDI watchdog off
        }
    }
};

TEST(EscFaults, WkcAprd) {
    esc::EscFaults f;
    f.wkc_aprd = true;
    Escs e(f);
    EXPECT_EQ(run1(*e.clean, dg_len(APRD, 0, 0x0000, 2)).wkc, 1);
    const Datagram d = run1(*e.faulty, dg_len(APRD, 0, 0x0000, 2));
    EXPECT_EQ(d.wkc, 2);
    EXPECT_EQ(d.data[0], 0x04);  // the data are right
    // Other slaves' APRD, and the other commands, keep their counters.
    EXPECT_EQ(run1(*e.faulty, dg_len(APRD, 1, 0x0000, 2)).wkc, 0);
    EXPECT_EQ(run1(*e.faulty, dg_len(FPRD, 0x1001, 0x0000, 2)).wkc, 1);
    EXPECT_EQ(run1(*e.faulty, dg_len(BRD, 0, 0x0000, 2)).wkc, 1);
    EXPECT_EQ(run1(*e.faulty, dg(APWR, 0, 0x0F80, {1, 2})).wkc, 1);
    EXPECT_EQ(run1(*e.faulty, dg(APRW, 0, 0x0F80, {1, 2})).wkc, 3);
}

TEST(EscFaults, AliasIgnored) {
    esc::EscFaults f;
    f.alias_ignored = true;
    Escs e(f);
    for (esc::Esc* x : {&*e.clean, &*e.faulty}) {
        x->write_reg<uint16_t>(0x0012, 0x0BAD);
        fpwr(*x, 0x0103, {0x01});  // alias enabled (DL control bit 24)
    }
    EXPECT_EQ(fprd(*e.clean, 0x0010, 2, 0x0BAD).wkc, 1);
    EXPECT_EQ(fprd(*e.faulty, 0x0010, 2, 0x0BAD).wkc, 0);
    EXPECT_EQ(fprd(*e.faulty, 0x0010, 2, 0x1001).wkc, 1);  // the station address still matches
}

TEST(EscFaults, FprdAnyAddress) {
    esc::EscFaults f;
    f.fprd_any_address = true;
    Escs e(f);
    EXPECT_EQ(fprd(*e.clean, 0x0010, 2, 0x1002).wkc, 0);
    const Datagram d = fprd(*e.faulty, 0x0010, 2, 0x1002);
    EXPECT_EQ(d.wkc, 1);
    EXPECT_EQ(d.u16(), 0x1001);
    // FPWR to another address still does nothing.
    EXPECT_EQ(fpwr(*e.faulty, 0x0F80, {1}, 0x1002).wkc, 0);
}

TEST(EscFaults, SourceMacUnchanged) {
    esc::EscFaults f;
    f.source_mac_unchanged = true;
    Escs e(f);
    auto a = build({dg_len(FPRD, 0x1001, 0x0000, 2)});
    auto b = a;
    ASSERT_EQ(a[6], 0x01);
    EXPECT_TRUE(e.clean->process_frame(a));
    EXPECT_TRUE(e.faulty->process_frame(b));
    EXPECT_EQ(a[6], 0x03);
    EXPECT_EQ(b[6], 0x01);
    EXPECT_EQ(parse(b).at(0).wkc, 1);  // processed all the same
}

TEST(EscFaults, SiiChecksum) {
    esc::EscFaults f;
    f.sii_checksum_wrong = true;
    Escs e(f);
    auto word7 = [](esc::Esc& x) {
        fpwr(x, 0x0502, {0x00, 0x01, 0x04, 0x00, 0x00, 0x00});  // read from word 4
        return fprd(x, 0x0508, 8).u16(6);
    };
    const uint16_t right = word7(*e.clean);
    EXPECT_EQ(right & 0xFF, esc::sii::crc8(e.clean->eeprom().data(), 14));
    EXPECT_EQ(word7(*e.faulty), right ^ 0x00FF);
    // The ESC itself loaded its configuration: no checksum error, EEPROM loaded.
    EXPECT_EQ(fprd(*e.faulty, 0x0502, 2).u16() & 0x0800, 0);
    EXPECT_EQ(fprd(*e.faulty, 0x0110, 2).u16() & 0x0001, 0x0001);
    EXPECT_EQ(e.faulty->read_reg<uint8_t>(0x0141), e.clean->read_reg<uint8_t>(0x0141));
}

TEST(EscFaults, DcTimeFrozen) {
    esc::EscFaults f;
    f.dc_time_frozen = true;
    Escs e(f);
    for (esc::Esc* x : {&*e.clean, &*e.faulty})
        fpwr(*x, 0x0920, le(5'000'000'000ull, 8));  // offset
    const uint64_t c1 = run1(*e.clean, dg_len(FPRD, 0x1001, 0x0910, 8), kT0 + 1'000'000).u64();
    const uint64_t c2 = run1(*e.clean, dg_len(FPRD, 0x1001, 0x0910, 8), kT0 + 2'000'000).u64();
    EXPECT_EQ(c2 - c1, 1'000'000u);
    const uint64_t f1 = run1(*e.faulty, dg_len(FPRD, 0x1001, 0x0910, 8), kT0 + 1'000'000).u64();
    const uint64_t f2 = run1(*e.faulty, dg_len(FPRD, 0x1001, 0x0910, 8), kT0 + 2'000'000).u64();
    EXPECT_EQ(f1, f2);
    // The local clock runs on: the receive-time latch and the PDI's view of the system time advance.
    EXPECT_EQ(run1(*e.faulty, dg(BWR, 0, 0x0900, {0, 0, 0, 0}), kT0 + 3'000'000).wkc, 1);
    EXPECT_EQ(fprd(*e.faulty, 0x0918, 8).u64(), kT0 + 3'000'000);
}

TEST(EscFaults, Sync0Never) {
    esc::EscFaults f;
    f.sync0_never = true;
    Escs e(f);
    for (esc::Esc* x : {&*e.clean, &*e.faulty}) {
        EXPECT_EQ(fpwr(*x, 0x09A0, le(1'000'000, 4)).wkc, 1);
        EXPECT_EQ(fpwr(*x, 0x0990, le(kT0 + 100'000, 8)).wkc, 1);
        EXPECT_EQ(fpwr(*x, 0x0981, {0x03}).wkc, 1);  // cyclic + SYNC0
    }
    e.clk.set(kT0 + 2'500'000);
    e.clean->tick();
    e.faulty->tick();
    EXPECT_EQ(e.clean->read_reg<uint32_t>(0x0220) & 0x04, 0x04u);  // SYNC0 AL event
    EXPECT_EQ(e.faulty->read_reg<uint32_t>(0x0220) & 0x04, 0x00u);
    EXPECT_EQ(fprd(*e.faulty, 0x0981, 1).data[0], 0x03);  // the activation was taken
}

}  // namespace
