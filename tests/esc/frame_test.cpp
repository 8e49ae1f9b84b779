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

// ---- Frame tolerance (docs/decisions/esc.md, "Frame tolerance"; ESC datasheet section I, Table 2 and
// Table 57): the header Length is not evaluated, the datagrams are walked by their own lengths and More bits
// up to the real end of the frame; a length error loses the frame, discards all its operations and counts in
// 0x030C only.

void set_header_length(std::vector<uint8_t>& f, std::size_t len) {
    f[14] = static_cast<uint8_t>(len);
    f[15] = static_cast<uint8_t>((f[15] & 0xF8) | ((len >> 8) & 0x07));
}

// libethercat writes the length of the whole frame; other values a master may leave there.
TEST_F(FrameHandling, HeaderLengthIsNotEvaluated) {
    for (std::size_t len : {std::size_t{60}, std::size_t{0x7FF}, std::size_t{0}, std::size_t{12}}) {
        auto f = build({dg(FPWR, 0x1001, 0x1000, {0x11, 0x22}), dg_len(FPRD, 0x1001, 0x1000, 2)});
        set_header_length(f, len);
        EXPECT_TRUE(e->process_frame(f)) << len;
        EXPECT_EQ(f.size(), 60u);
        auto d = parse(f);
        ASSERT_EQ(d.size(), 2u) << len;
        EXPECT_EQ(d[0].wkc, 1) << len;
        EXPECT_EQ(d[1].data, (std::vector<uint8_t>{0x11, 0x22})) << len;
        EXPECT_EQ(d[1].wkc, 1) << len;
        EXPECT_EQ(f[14], static_cast<uint8_t>(len)) << len;  // the header is forwarded as it came
        e->write_reg<uint16_t>(0x1000, 0);
    }
    EXPECT_EQ(e->stats().frames_malformed, 0u);
    EXPECT_EQ(e->read_reg<uint8_t>(0x030C), 0);
}

// A frame with a length error (a datagram past the end of the frame) is lost to the master; none of its
// operations take effect; only the processing unit error counter counts it.
TEST_F(FrameHandling, DatagramPastTheEndIsALengthError) {
    auto f = build({dg(FPWR, 0x1001, 0x1000, {0x11}), dg(FPWR, 0x1001, 0x1001, {0x22, 0x33, 0x44})}, 0);
    f.resize(f.size() - 3);  // the frame ends inside the second datagram
    set_header_length(f, f.size() - 16);
    EXPECT_FALSE(e->process_frame(f));
    EXPECT_EQ(e->read_reg<uint8_t>(0x1000), 0x00);  // the first datagram is not executed either
    EXPECT_EQ(e->read_reg<uint8_t>(0x1001), 0x00);
    EXPECT_EQ(e->stats().frames_malformed, 1u);
    EXPECT_EQ(e->stats().malformed_datagram, 1u);
    EXPECT_EQ(e->read_reg<uint8_t>(0x0300), 0);  // not an invalid frame at the port (Table 57)
    EXPECT_EQ(e->read_reg<uint8_t>(0x030C), 1);
}

TEST_F(FrameHandling, DatagramLengthPastTheEnd) {
    auto f = build({dg(FPWR, 0x1001, 0x1000, {0x11})});
    f[16 + 6] = 0x40;  // 0x40 data bytes: past the 60-byte frame
    EXPECT_FALSE(e->process_frame(f));
    EXPECT_EQ(e->read_reg<uint8_t>(0x1000), 0x00);
    EXPECT_EQ(e->read_reg<uint8_t>(0x030C), 1);
}

// More bit on the last datagram: what follows is read as the next datagram header. Zero padding reads as a
// NOP with M = 0, so a 60-byte frame is processed as an ESC walks it; where the frame ends before the
// promised header, it is a length error.
TEST_F(FrameHandling, MoreBitOnTheLastDatagram) {
    auto f = build({dg(FPWR, 0x1001, 0x1000, {0x11})});
    f[16 + 7] |= 0x80;
    EXPECT_TRUE(e->process_frame(f));
    EXPECT_EQ(e->read_reg<uint8_t>(0x1000), 0x11);
    EXPECT_EQ(e->stats().frames_malformed, 0u);
    f = build({dg(FPWR, 0x1001, 0x1001, {0x22})}, 0);
    f[16 + 7] |= 0x80;
    EXPECT_FALSE(e->process_frame(f));
    EXPECT_EQ(e->read_reg<uint8_t>(0x1001), 0x00);
    EXPECT_EQ(e->stats().frames_malformed, 1u);
    EXPECT_EQ(e->read_reg<uint8_t>(0x030C), 1);
}

// Up to 64 bytes after the last datagram are padding; more is a length error (Table 57, "padding > 64 byte").
TEST_F(FrameHandling, PaddingUpTo64BytesMoreIsALengthError) {
    auto f = build({dg_len(APRD, 0, 0x0130, 2)}, 0);
    const std::size_t chain_end = f.size();
    f.resize(chain_end + 64, 0xA5);
    EXPECT_TRUE(e->process_frame(f));
    EXPECT_EQ(parse(f)[0].wkc, 1);
    EXPECT_EQ(f[chain_end], 0xA5);  // padding untouched
    f = build({dg_len(APRD, 0, 0x0130, 2)}, 0);
    f.resize(chain_end + 65, 0);
    EXPECT_FALSE(e->process_frame(f));
    EXPECT_EQ(e->stats().malformed_length, 1u);
    EXPECT_EQ(e->read_reg<uint8_t>(0x030C), 1);
}

TEST_F(FrameHandling, TooShortForEtherCatHeader) {
    std::vector<uint8_t> f(15, 0);
    f[12] = 0x88;
    f[13] = 0xA4;
    EXPECT_FALSE(e->process_frame(f));
    EXPECT_EQ(e->stats().frames_malformed, 1u);
    EXPECT_EQ(e->stats().malformed_no_header, 1u);
    EXPECT_EQ(e->read_reg<uint8_t>(0x030C), 1);
}

// Non-EtherCAT frames: destroyed and counted in 0x030C with the forwarding rule 0x0100[0] = 1 (reset value),
// forwarded unchanged with 0.
TEST_F(FrameHandling, NonEtherCatFollowsTheForwardingRule) {
    auto f = build({dg_len(APRD, 0, 0x0130, 2)});
    f[12] = 0x86;
    f[13] = 0xDD;  // IPv6
    auto before = f;
    EXPECT_FALSE(e->process_frame(f));
    EXPECT_EQ(e->read_reg<uint8_t>(0x030C), 1);
    EXPECT_EQ(fpwr(*e, 0x0100, {0x00}).wkc, 1);
    f = before;
    EXPECT_TRUE(e->process_frame(f));
    EXPECT_EQ(f, before);
    EXPECT_EQ(e->read_reg<uint8_t>(0x030C), 1);
}

// EtherCAT in UDP/IP (ESC datasheet section I, "UDP/IP", Table 8): EtherType 0x0800, IP version 4, header
// length 5, protocol 0x11, UDP destination port 0x88A4; nothing else of IP/UDP evaluated; the UDP checksum
// cleared; IP addresses and ports kept.
std::vector<uint8_t> in_udp(const std::vector<uint8_t>& ecat, uint8_t version_ihl = 0x45,
                            uint8_t proto = 0x11, uint16_t port = 0x88A4) {
    std::vector<uint8_t> f(ecat.begin(), ecat.begin() + 12);
    f.push_back(0x08);
    f.push_back(0x00);
    const std::size_t payload = ecat.size() - 14;
    const std::size_t udp_len = 8 + payload;
    const uint8_t ip[20] = {version_ihl,
                            0,
                            static_cast<uint8_t>((20 + udp_len) >> 8),
                            static_cast<uint8_t>(20 + udp_len),
                            0x12,
                            0x34,
                            0,
                            0,
                            64,
                            proto,
                            0xAB,
                            0xCD,
                            192,
                            168,
                            1,
                            1,
                            192,
                            168,
                            1,
                            255};
    f.insert(f.end(), ip, ip + 20);
    const uint8_t udp[8] = {0x88,
                            0xA4,
                            static_cast<uint8_t>(port >> 8),
                            static_cast<uint8_t>(port),
                            static_cast<uint8_t>(udp_len >> 8),
                            static_cast<uint8_t>(udp_len),
                            0x5A,
                            0x5B};
    f.insert(f.end(), udp, udp + 8);
    f.insert(f.end(), ecat.begin() + 14, ecat.end());
    return f;
}

TEST_F(FrameHandling, EtherCatInUdpIsProcessed) {
    auto f = in_udp(build({dg_len(FPRD, 0x1001, 0x0010, 2)}, 0));
    const auto before = f;
    EXPECT_TRUE(e->process_frame(f));
    EXPECT_EQ(f[6], before[6] | 0x02);
    EXPECT_EQ(f[40], 0);  // UDP checksum cleared
    EXPECT_EQ(f[41], 0);
    EXPECT_TRUE(std::equal(f.begin() + 12, f.begin() + 40, before.begin() + 12));  // IP, UDP ports and length
    const std::size_t dg0 = 14 + 28 + 2;
    EXPECT_EQ(f[dg0 + 10], 0x01);  // configured station address 0x1001
    EXPECT_EQ(f[dg0 + 11], 0x10);
    EXPECT_EQ(f[dg0 + 12], 1);  // WKC
    // With one VLAN tag in front.
    auto v = in_udp(build({dg_len(FPRD, 0x1001, 0x0010, 2)}, 0));
    const uint8_t tag[4] = {0x81, 0x00, 0x00, 0x07};
    v.insert(v.begin() + 12, tag, tag + 4);
    EXPECT_TRUE(e->process_frame(v));
    EXPECT_EQ(v[dg0 + 4 + 12], 1);
}

TEST_F(FrameHandling, UdpOtherThanEtherCatIsNotProcessed) {
    const auto ecat = build({dg(FPWR, 0x1001, 0x1000, {0x77})}, 0);
    for (auto f : {in_udp(ecat, 0x46), in_udp(ecat, 0x65), in_udp(ecat, 0x45, 0x06),
                   in_udp(ecat, 0x45, 0x11, 0x88A5)}) {
        EXPECT_FALSE(e->process_frame(f));
        EXPECT_EQ(e->read_reg<uint8_t>(0x1000), 0);
    }
    EXPECT_EQ(e->stats().frames_processed, 1u);  // set_station only
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
        // Corrupt lengths now and then. The header length is not evaluated: a frame with only that changed
        // is processed; a datagram length or a cut frame may make it a frame length error (dropped).
        if (rnd() % 8 == 0) f[14] = static_cast<uint8_t>(rnd());
        bool broken = false;
        if (rnd() % 8 == 0 && f.size() > 23) {
            f[16 + 6] = static_cast<uint8_t>(rnd());
            broken = true;
        }
        if (rnd() % 8 == 0 && f.size() > 20) {
            f.resize(20 + rnd() % (f.size() - 20));
            broken = true;
        }
        const auto size = f.size();
        const bool forwarded = e.process_frame(f, clk.now_ns());
        if (!broken) {
            EXPECT_TRUE(forwarded);
        }
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
