// FMMU logical addressing (ESC datasheet section I, FMMU; ETG.1000.4 logical addressing): bit mapping,
// read/write/both types, WKC, register and SM targets.
#include <gtest/gtest.h>

#include <optional>
#include <random>

#include "esc_fixture.hpp"

using namespace esc_test;

namespace {

struct FmmuCfg {
    uint32_t la;
    uint16_t len;
    uint8_t lstart, lstop;
    uint16_t pa;
    uint8_t pstart;
    uint8_t type;
};

std::vector<uint8_t> fmmu_bytes(const FmmuCfg& c) {
    std::vector<uint8_t> b = le(c.la, 4);
    auto l = le(c.len, 2);
    b.insert(b.end(), l.begin(), l.end());
    b.push_back(c.lstart);
    b.push_back(c.lstop);
    auto p = le(c.pa, 2);
    b.insert(b.end(), p.begin(), p.end());
    b.push_back(c.pstart);
    b.push_back(c.type);
    b.push_back(0x01);  // activate
    b.push_back(0);
    b.push_back(0);
    b.push_back(0);
    return b;
}

struct FmmuMapping : EscFixture<> {
    void fmmu(unsigned n, const FmmuCfg& c) {
        ASSERT_EQ(fpwr(*e, static_cast<uint16_t>(0x0600 + 16 * n), fmmu_bytes(c)).wkc, 1);
    }
    void smcfg(unsigned n, uint16_t start, uint16_t len, uint8_t ctrl) {
        std::vector<uint8_t> b = le(start, 2);
        auto l = le(len, 2);
        b.insert(b.end(), l.begin(), l.end());
        b.push_back(ctrl);
        b.push_back(0);
        b.push_back(1);
        b.push_back(0);
        ASSERT_EQ(fpwr(*e, static_cast<uint16_t>(0x0800 + 8 * n), b).wkc, 1);
    }
};

TEST_F(FmmuMapping, B1ExampleWriteBits) {
    // 14 bits from logical 0x00010011.3 to 0x00010013.0 -> physical 0x0F01.1 .. 0x0F02.6.
    fmmu(0, {0x00010011, 3, 3, 0, 0x0F01, 1, 0x02});
    Datagram d = run1(*e, lg(LWR, 0x00010010, {0xFF, 0xFF, 0xFF, 0xFF, 0xFF}));
    EXPECT_EQ(d.wkc, 1);
    EXPECT_EQ(e->read_reg<uint32_t>(0x0F00), 0x007FFE00u);
}

TEST_F(FmmuMapping, B1ExampleReadBits) {
    fmmu(0, {0x00010011, 3, 3, 0, 0x0F01, 1, 0x01});
    fpwr(*e, 0x0F00, {0xFF, 0xFF, 0xFF, 0xFF});
    Datagram d = run1(*e, lg(LRD, 0x00010010, {0x00, 0x00, 0x00, 0x00, 0x00}));
    EXPECT_EQ(d.wkc, 1);
    EXPECT_EQ(d.data, (std::vector<uint8_t>{0x00, 0xF8, 0xFF, 0x01, 0x00}));
    // Bits not mapped keep the incoming frame data.
    d = run1(*e, lg(LRD, 0x00010010, {0xAA, 0x05, 0x00, 0xF0, 0x55}));
    EXPECT_EQ(d.data, (std::vector<uint8_t>{0xAA, 0xFD, 0xFF, 0xF1, 0x55}));
}

TEST_F(FmmuMapping, ShiftedBitMappingMatchesReference) {
    // Random data through a mapping with a bit shift of 5: compare with a bit-by-bit model.
    const FmmuCfg c{0x00000100, 6, 2, 4, 0x1003, 7, 0x02};
    fmmu(0, c);
    std::mt19937 rng(7);
    std::vector<uint8_t> data(8);
    for (auto& b : data)
        b = static_cast<uint8_t>(rng());
    std::vector<uint8_t> before(16);
    for (auto& b : before)
        b = static_cast<uint8_t>(rng());
    for (unsigned i = 0; i < 16; ++i)
        e->write_reg<uint8_t>(static_cast<uint16_t>(0x1000 + i), before[i]);
    EXPECT_EQ(run1(*e, lg(LWR, 0x000000FF, data)).wkc, 1);
    std::vector<uint8_t> expect = before;
    const unsigned nbits = (c.len - 1) * 8 + (c.lstop - c.lstart + 1);
    for (unsigned k = 0; k < nbits; ++k) {
        const unsigned lbit = (c.la - 0xFF) * 8 + c.lstart + k;  // bit index in the datagram data
        const unsigned pbit = 3 * 8 + c.pstart + k;              // bit index from 0x1000
        const bool v = (data[lbit / 8] >> (lbit % 8)) & 1;
        expect[pbit / 8] = static_cast<uint8_t>((expect[pbit / 8] & ~(1u << (pbit % 8))) | (v << (pbit % 8)));
    }
    for (unsigned i = 0; i < 16; ++i)
        EXPECT_EQ(e->read_reg<uint8_t>(static_cast<uint16_t>(0x1000 + i)), expect[i]) << "byte " << i;
    // And back through a read FMMU of the same mapping.
    fmmu(1, {c.la, c.len, c.lstart, c.lstop, c.pa, c.pstart, 0x01});
    Datagram d = run1(*e, lg(LRD, 0x000000FF, std::vector<uint8_t>(8, 0)));
    for (unsigned k = 0; k < nbits; ++k) {
        const unsigned lbit = 8 + c.lstart + k;
        EXPECT_EQ((d.data[lbit / 8] >> (lbit % 8)) & 1, (data[lbit / 8] >> (lbit % 8)) & 1) << "bit " << k;
    }
}

struct WkcCase {
    uint8_t cmd;
    uint32_t la;
    uint16_t len;
    uint16_t wkc;
};

class FmmuWkc : public FmmuMapping, public ::testing::WithParamInterface<WkcCase> {};

TEST_P(FmmuWkc, PerDirection) {
    fmmu(0, {0x10000, 4, 0, 7, 0x1000, 0, 0x02});  // outputs (write)
    fmmu(1, {0x10004, 4, 0, 7, 0x1100, 0, 0x01});  // inputs (read)
    fmmu(2, {0x10008, 2, 0, 7, 0x1200, 0, 0x03});  // both
    fmmu(3, {0x1000A, 2, 0, 7, 0x1202, 0, 0x02});  // second write FMMU
    const WkcCase& c = GetParam();
    EXPECT_EQ(run1(*e, lg(c.cmd, c.la, std::vector<uint8_t>(c.len, 0x5A))).wkc, c.wkc);
}

INSTANTIATE_TEST_SUITE_P(Fmmu, FmmuWkc,
                         ::testing::Values(WkcCase{LRW, 0x10000, 8, 3}, WkcCase{LRW, 0x10000, 4, 2},
                                           WkcCase{LRW, 0x10004, 4, 1}, WkcCase{LRD, 0x10000, 8, 1},
                                           WkcCase{LWR, 0x10000, 8, 1}, WkcCase{LRD, 0x10000, 4, 0},
                                           WkcCase{LWR, 0x10004, 4, 0}, WkcCase{LRW, 0x10008, 2, 3},
                                           WkcCase{LWR, 0x10008, 4, 1},  // two write FMMUs: counted once
                                           WkcCase{LRW, 0x20000, 8, 0}, WkcCase{LRW, 0x0FFFC, 5, 2}));

TEST_F(FmmuMapping, LrwReadsBeforeWriting) {
    // One FMMU of type read+write: the frame returns the old memory, memory takes the frame data.
    fmmu(0, {0x0, 2, 0, 7, 0x1000, 0, 0x03});
    e->write_reg<uint16_t>(0x1000, 0x1234);
    Datagram d = run1(*e, lg(LRW, 0x0, {0xCD, 0xAB}));
    EXPECT_EQ(d.u16(), 0x1234);
    EXPECT_EQ(d.wkc, 3);
    EXPECT_EQ(e->read_reg<uint16_t>(0x1000), 0xABCD);
}

TEST_F(FmmuMapping, InactiveFmmuIgnored) {
    auto b = fmmu_bytes({0x0, 2, 0, 7, 0x1000, 0, 0x03});
    b[12] = 0;  // not activated
    fpwr(*e, 0x0600, b);
    EXPECT_EQ(run1(*e, lg(LRW, 0x0, {1, 2})).wkc, 0);
}

TEST_F(FmmuMapping, MapsSm1StatusRegisterForMailboxPolling) {
    smcfg(1, 0x1080, 8, 0x22);  // mailbox, ECAT reads
    fmmu(2, {0x00090000, 1, 0, 7, 0x080D, 0, 0x01});
    Datagram d = run1(*e, lg(LRD, 0x00090000, {0x00}));
    EXPECT_EQ(d.wkc, 1);
    EXPECT_EQ(d.data[0] & 0x08, 0);
    std::vector<uint8_t> msg(8, 0x33);
    e->write(0x1080, msg);
    d = run1(*e, lg(LRD, 0x00090000, {0x00}));
    EXPECT_EQ(d.data[0] & 0x08, 0x08);
}

TEST_F(FmmuMapping, ProcessDataThroughBufferedSyncManagers) {
    smcfg(2, 0x1100, 4, 0x64);  // outputs, ECAT writes, watchdog
    smcfg(3, 0x1180, 4, 0x20);  // inputs, ECAT reads
    fmmu(0, {0x0, 4, 0, 7, 0x1100, 0, 0x02});
    fmmu(1, {0x4, 4, 0, 7, 0x1180, 0, 0x01});
    e->write(0x1180, std::vector<uint8_t>{1, 2, 3, 4});
    Datagram d = run1(*e, lg(LRW, 0x0, {9, 8, 7, 6, 0, 0, 0, 0}));
    EXPECT_EQ(d.wkc, 3);
    EXPECT_EQ(d.data, (std::vector<uint8_t>{9, 8, 7, 6, 1, 2, 3, 4}));
    std::vector<uint8_t> out(4);
    e->read(0x1100, out);
    EXPECT_EQ(out, (std::vector<uint8_t>{9, 8, 7, 6}));
    // An FMMU that does not start at the SM start cannot open the buffer: no WKC for that direction.
    fmmu(0, {0x0, 3, 0, 7, 0x1101, 0, 0x02});
    d = run1(*e, lg(LRW, 0x0, {9, 8, 7, 6, 0, 0, 0, 0}));
    EXPECT_EQ(d.wkc, 1);
}

TEST_F(FmmuMapping, MailboxThroughFmmuObeysSmRules) {
    smcfg(0, 0x1000, 4, 0x26);  // mailbox, ECAT writes
    fmmu(0, {0x100, 4, 0, 7, 0x1000, 0, 0x02});
    EXPECT_EQ(run1(*e, lg(LWR, 0x100, {1, 2, 3, 4})).wkc, 1);
    EXPECT_EQ(run1(*e, lg(LWR, 0x100, {5, 6, 7, 8})).wkc, 0);  // full
    std::vector<uint8_t> m(4);
    e->read(0x1000, m);
    EXPECT_EQ(m, (std::vector<uint8_t>{1, 2, 3, 4}));
}

// Issue 14, finding 1 (FMMU side): an FMMU whose physical area runs over the registers and far past the RAM
// maps what exists and captures nothing: physical accesses, its own registers included, are unchanged.
TEST_F(FmmuMapping, FmmuBeyondTheRamCapturesNoPhysicalAddress) {
    fmmu(0, {0x00010000, 0x8000, 0, 7, 0x0100, 0, 0x03});
    EXPECT_EQ(fprd(*e, 0x0100, 4).u32(), 0x00070001u);
    EXPECT_EQ(fprd(*e, 0x0600, 16).wkc, 1);
    Datagram d = run1(*e, lg(LRD, 0x00010000, {0, 0, 0, 0}));
    EXPECT_EQ(d.wkc, 1);
    EXPECT_EQ(d.u32(), 0x00070001u);  // DL control through the mapping
    EXPECT_EQ(run1(*e, lg(LRD, 0x00010000 + 0x3000 - 0x0100, {0, 0})).wkc, 0);  // past the RAM end
    EXPECT_EQ(fpwr(*e, 0x1800, {0x42}).wkc, 1);
    EXPECT_EQ(run1(*e, lg(LRD, 0x00010000 + 0x1800 - 0x0100, {0})).data[0], 0x42);
    // An FMMU running past 0xFFFF: nothing beyond the memory, no wrap to 0x0000.
    fmmu(1, {0x00200000, 0x100, 0, 7, 0xFFF0, 0, 0x01});
    EXPECT_EQ(run1(*e, lg(LRD, 0x00200000, std::vector<uint8_t>(0x100, 0))).wkc, 0);
    // Disabled again by the master.
    EXPECT_EQ(fpwr(*e, 0x060C, {0x00}).wkc, 1);
    EXPECT_EQ(fprd(*e, 0x060C, 1).data[0], 0x00);
}

}  // namespace
