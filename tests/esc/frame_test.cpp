// Frame level (ETG.1000.4 frame structure; ESC datasheet section I, frame processing): Ethernet/EtherCAT
// headers, datagram chains, malformed frames, runts, source MAC.
#include <gtest/gtest.h>

#include <optional>

#include "esc_fixture.hpp"

using namespace esc_test;

namespace {

struct FrameHandling : EscFixture<5'000'000> {};

TEST_F(FrameHandling, SourceMacBitSetAndLengthKept) {
    auto f = build({dg_len(APRD, 0, 0x0130, 2)});
    ASSERT_EQ(f.size(), 60u);
    auto before = f;
    EXPECT_TRUE(e->process_frame(f));
    EXPECT_EQ(f.size(), 60u);
    EXPECT_EQ(f[6], 0x03);  // 0x01 | 0x02
    for (int i = 7; i < 12; ++i)
        EXPECT_EQ(f[i], 0x01);
    for (int i = 0; i < 6; ++i)
        EXPECT_EQ(f[i], 0xFF);
    // Padding untouched.
    for (std::size_t i = 16 + 14; i < 60; ++i)
        EXPECT_EQ(f[i], before[i]);
    EXPECT_EQ(parse(f)[0].data, (std::vector<uint8_t>{0x01, 0x00}));
}

TEST_F(FrameHandling, NotEtherCatIsDropped) {
    auto f = build({dg_len(APRD, 0, 0x0130, 2)});
    f[12] = 0x08;
    f[13] = 0x00;
    auto before = f;
    EXPECT_FALSE(e->process_frame(f));
    EXPECT_EQ(f, before);
    std::vector<uint8_t> tiny(10, 0);
    EXPECT_FALSE(e->process_frame(tiny));
    EXPECT_EQ(e->stats().frames_ignored, 2u);
}

TEST_F(FrameHandling, VlanTaggedFrame) {
    auto f = build({dg_len(FPRD, 0x1001, 0x0010, 2)});
    const uint8_t tag[4] = {0x81, 0x00, 0x20, 0x05};
    f.insert(f.begin() + 12, tag, tag + 4);
    EXPECT_TRUE(e->process_frame(f));
    EXPECT_EQ(f[12], 0x81);
    EXPECT_EQ(f[14], 0x20);  // tag untouched
    EXPECT_EQ(f[15], 0x05);
    // Datagram starts 4 bytes later.
    EXPECT_EQ(f[20 + 10], 0x01);
    EXPECT_EQ(f[20 + 11], 0x10);
    EXPECT_EQ(f[20 + 12], 1);  // WKC
}

TEST_F(FrameHandling, OtherEtherCatTypeForwardedUnprocessed) {
    auto f = build({dg_len(FPRD, 0x1001, 0x0010, 2)});
    f[15] = static_cast<uint8_t>((f[15] & 0x0F) | 0x50);  // type 5 (mailbox gateway)
    auto before = f;
    EXPECT_TRUE(e->process_frame(f));
    before[6] |= 0x02;
    EXPECT_EQ(f, before);
}

TEST_F(FrameHandling, RuntFrameOf29Bytes) {
    auto f = build({dg_len(FPRD, 0x1001, 0x0010, 1)}, 0);
    ASSERT_EQ(f.size(), 29u);
    EXPECT_TRUE(e->process_frame(f));
    EXPECT_EQ(f.size(), 29u);
    auto d = parse(f);
    ASSERT_EQ(d.size(), 1u);
    EXPECT_EQ(d[0].data[0], 0x01);
    EXPECT_EQ(d[0].wkc, 1);
}

TEST_F(FrameHandling, MultipleDatagramsSeeEarlierEffects) {
    auto r = run(*e, {dg(FPWR, 0x1001, 0x1000, {0xDE, 0xAD}), dg_len(FPRD, 0x1001, 0x1000, 2),
                      dg_len(APRD, 0, 0x0010, 2), dg_len(BRD, 0, 0x0000, 1)});
    ASSERT_EQ(r.size(), 4u);
    EXPECT_EQ(r[0].wkc, 1);
    EXPECT_EQ(r[1].data, (std::vector<uint8_t>{0xDE, 0xAD}));
    EXPECT_EQ(r[1].wkc, 1);
    EXPECT_EQ(r[2].u16(), 0x1001);
    EXPECT_EQ(r[2].adp, 1);
    EXPECT_EQ(r[3].data[0], 0x04);
    EXPECT_EQ(e->stats().datagrams, 1u + 4u);  // set_station + 4
}

TEST_F(FrameHandling, TruncatedDatagramStopsProcessing) {
    auto f = build({dg(FPWR, 0x1001, 0x1000, {0x11}), dg(FPWR, 0x1001, 0x1001, {0x22, 0x33, 0x44})}, 0);
    // Cut the frame inside the second datagram and shorten the header length to match the frame.
    f.resize(f.size() - 3);
    const uint16_t elen = static_cast<uint16_t>(f.size() - 16);
    f[14] = static_cast<uint8_t>(elen);
    f[15] = static_cast<uint8_t>(0x10 | (elen >> 8));
    EXPECT_TRUE(e->process_frame(f));
    EXPECT_EQ(e->read_reg<uint8_t>(0x1000), 0x11);  // first datagram executed
    EXPECT_EQ(e->read_reg<uint8_t>(0x1001), 0x00);  // second not
    EXPECT_EQ(e->stats().frames_malformed, 1u);
    EXPECT_EQ(e->read_reg<uint8_t>(0x0300), 1);
    EXPECT_EQ(e->read_reg<uint8_t>(0x030C), 1);
}

TEST_F(FrameHandling, HeaderLengthTooBig) {
    auto f = build({dg(FPWR, 0x1001, 0x1000, {0x11})});
    f[14] = 0xF0;
    f[15] = 0x17;  // 0x7F0 bytes: beyond the 60-byte frame
    auto size = f.size();
    EXPECT_TRUE(e->process_frame(f));  // forwarded as a real ESC does
    EXPECT_EQ(f.size(), size);
    EXPECT_EQ(e->read_reg<uint8_t>(0x1000), 0x00);
    EXPECT_EQ(e->stats().frames_malformed, 1u);
}

TEST_F(FrameHandling, HeaderLengthTooSmall) {
    auto f = build({dg(FPWR, 0x1001, 0x1000, {0x11, 0x22, 0x33, 0x44})});
    f[14] = 12;  // covers the datagram header but not its data
    EXPECT_TRUE(e->process_frame(f));
    EXPECT_EQ(e->read_reg<uint8_t>(0x1000), 0x00);
    EXPECT_EQ(e->stats().frames_malformed, 1u);
    auto d = f;  // WKC unchanged
    EXPECT_EQ(d[16 + 10 + 4], 0);
}

TEST_F(FrameHandling, MoreBitPastHeaderLength) {
    auto f = build({dg(FPWR, 0x1001, 0x1000, {0x11})});
    f[16 + 7] |= 0x80;  // claims a next datagram but the header length ends here
    EXPECT_TRUE(e->process_frame(f));
    EXPECT_EQ(e->read_reg<uint8_t>(0x1000), 0x11);
    EXPECT_EQ(e->stats().frames_malformed, 1u);
}

TEST_F(FrameHandling, TooShortForEtherCatHeader) {
    std::vector<uint8_t> f(15, 0);
    f[12] = 0x88;
    f[13] = 0xA4;
    EXPECT_TRUE(e->process_frame(f));
    EXPECT_EQ(e->stats().frames_malformed, 1u);
}

TEST_F(FrameHandling, BrdOrsAcrossTwoSlaves) {
    esc::Esc second({}, clk);
    second.write_reg<uint16_t>(0x1000, 0x00F0);
    e->write_reg<uint16_t>(0x1000, 0x0F01);
    auto f = build({dg(BRD, 0, 0x1000, {0x00, 0x80}), dg_len(APRD, 0xFFFF, 0x1000, 2)});
    e->process_frame(f);
    second.process_frame(f);
    auto d = parse(f);
    EXPECT_EQ(d[0].u16(), 0x8FF1);
    EXPECT_EQ(d[0].wkc, 2);
    EXPECT_EQ(d[0].adp, 2);
    EXPECT_EQ(d[1].u16(), 0x00F0);  // addressed the second slave
    EXPECT_EQ(d[1].wkc, 1);
    EXPECT_EQ(d[1].adp, 1);
}

TEST_F(FrameHandling, IrqFieldOrsMaskedEcatEvents) {
    // ECAT event request after reset: bit 2 (DL status) is set; mask it in.
    fpwr(*e, 0x0200, {0x0C, 0x00});
    e->write_reg<uint16_t>(0x0130, 0x0002);  // PDI writes AL status -> ECAT event bit 3
    auto d = run1(*e, dg_len(FPRD, 0x1001, 0x0130, 2));
    EXPECT_EQ(d.irq & 0x0008, 0x0008);
    // ECAT read of AL status cleared bit 3.
    d = run1(*e, dg_len(FPRD, 0x1001, 0x0000, 1));
    EXPECT_EQ(d.irq & 0x0008, 0);
    // Reading DL status clears bit 2.
    run1(*e, dg_len(FPRD, 0x1001, 0x0110, 2));
    d = run1(*e, dg_len(FPRD, 0x1001, 0x0000, 1));
    EXPECT_EQ(d.irq, 0);
    // Bits already set by other slaves are kept.
    Datagram in = dg_len(FPRD, 0x1001, 0x0000, 1);
    in.irq = 0x8000;
    EXPECT_EQ(run1(*e, in).irq, 0x8000);
}

TEST_F(FrameHandling, IndexAndCirculatingBitUntouched) {
    Datagram in = dg_len(FPRD, 0x1001, 0x0010, 2);
    in.idx = 0x5A;
    auto f = build({in});
    f[16 + 7] |= 0x40;
    e->process_frame(f);
    auto d = parse(f);
    EXPECT_EQ(d[0].idx, 0x5A);
    EXPECT_EQ(d[0].flags & 0x4000, 0x4000);
    EXPECT_EQ(d[0].wkc, 1);
}

}  // namespace

namespace {

// Random frames (valid Ethernet/EtherCAT headers, random datagrams, random register/SM/FMMU writes) must
// never read or write outside the frame or the ESC's memory (run under ASan), and the frame length never
// changes.
class FrameRobustness : public ::testing::TestWithParam<esc::EscConfig> {};

TEST_P(FrameRobustness, RandomFramesNeverCrash) {
    esc::ManualClock clk;
    clk.set(1'000'000);
    esc::Esc e(GetParam(), clk);
    uint32_t s = 12345;
    auto rnd = [&]() {
        s = s * 1103515245u + 12345u;
        return (s >> 8) & 0xFFFF;
    };
    for (int iter = 0; iter < 20000; ++iter) {
        std::vector<Datagram> dgs;
        const int n = 1 + static_cast<int>(rnd() % 4);
        for (int k = 0; k < n; ++k) {
            Datagram d;
            d.cmd = static_cast<uint8_t>(rnd() % 16);
            d.adp = static_cast<uint16_t>(rnd() % 3 == 0 ? 0 : rnd());
            // Bias towards interesting places: registers, SM/FMMU config, RAM, the end of the address space.
            static const uint16_t bases[] = {0x0000, 0x0120, 0x0500, 0x0600, 0x0800,
                                             0x0900, 0x0980, 0x1000, 0x2FF0, 0xFFF0};
            d.ado = static_cast<uint16_t>(bases[rnd() % 10] + rnd() % 64);
            d.data.resize(rnd() % 48);
            for (auto& b : d.data)
                b = static_cast<uint8_t>(rnd());
            if (d.cmd == LRW || d.cmd == LRD || d.cmd == LWR) d.ado = static_cast<uint16_t>(rnd() % 4);
            dgs.push_back(d);
        }
        auto f = build(dgs, rnd() % 2 ? 60 : 0);
        // Corrupt lengths now and then.
        if (rnd() % 8 == 0) f[14] = static_cast<uint8_t>(rnd());
        if (rnd() % 8 == 0 && f.size() > 23) f[16 + 6] = static_cast<uint8_t>(rnd());
        if (rnd() % 8 == 0 && f.size() > 20) f.resize(20 + rnd() % (f.size() - 20));
        const auto size = f.size();
        EXPECT_TRUE(e.process_frame(f, clk.now_ns()));
        ASSERT_EQ(f.size(), size);
        uint8_t buf[64];
        e.read(static_cast<uint16_t>(rnd()), std::span<uint8_t>(buf, rnd() % 64));
        e.write(static_cast<uint16_t>(0x1000 + rnd() % 0x2000), std::span<const uint8_t>(buf, rnd() % 64));
        clk.advance(rnd() * 100);
        e.tick();
    }
    EXPECT_GT(e.stats().frames_processed, 0u);
}

esc::EscConfig config(uint8_t fmmus, uint8_t sms, uint32_t kib) {
    esc::EscConfig c;
    c.fmmu_count = fmmus;
    c.sm_count = sms;
    c.process_ram_kib = kib;
    return c;
}

INSTANTIATE_TEST_SUITE_P(Configs, FrameRobustness,
                         ::testing::Values(esc::EscConfig{}, config(16, 16, 64), config(0, 0, 0),
                                           config(3, 4, 1)));

}  // namespace
