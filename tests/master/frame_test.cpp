// Frame encoding and parsing (ETG.1000.4 frame and datagram layout).
#include <gtest/gtest.h>

#include <vector>

#include "master/frame.hpp"

using namespace master;

namespace {
const MacAddress kMac{0x01, 0x01, 0x01, 0x01, 0x01, 0x01};
}

TEST(Frame, SingleDatagramIsPaddedTo60AndLaidOutAsSpecified) {
    uint8_t data[2] = {0, 0};
    Datagram d{Command::APRD, 0, 0x0130, data};
    std::array<uint8_t, kMaxFrameSize> out{};
    const std::size_t n = encode_frame(std::span<const Datagram>(&d, 1), 0x00, kMac, out);
    ASSERT_EQ(n, 60u);
    // Worked example (APRD of AL status at position 0): 0E 10 | 01 00 00 00 30 01 02 00 00 00 | 00 00 | 00 00
    const std::vector<uint8_t> expect = {0x0E, 0x10, 0x01, 0x00, 0x00, 0x00, 0x30, 0x01,
                                         0x02, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00};
    EXPECT_EQ(std::vector<uint8_t>(out.begin() + 14, out.begin() + 30), expect);
    EXPECT_EQ(out[12], 0x88);
    EXPECT_EQ(out[13], 0xA4);
    for (int i = 0; i < 6; ++i)
        EXPECT_EQ(out[i], 0xFF);
    for (std::size_t i = 30; i < 60; ++i)
        EXPECT_EQ(out[i], 0) << i;
}

TEST(Frame, SeveralDatagramsChainWithMoreBitAndConsecutiveIndices) {
    uint8_t a[4] = {1, 2, 3, 4}, b[1] = {9}, c[6] = {};
    Datagram d[3] = {{Command::FPWR, 0x1001, 0x0508, a}, {Command::BRD, 0, 0, b}, {Command::LRW, 0, 0, c}};
    std::array<uint8_t, kMaxFrameSize> out{};
    const std::size_t n = encode_frame(d, 250, kMac, out);
    ASSERT_EQ(n, 16 + 3 * 12 + 4 + 1 + 6u);
    FrameReader r(std::span<const uint8_t>(out.data(), n));
    ASSERT_TRUE(r.valid());
    auto v0 = r.next(), v1 = r.next(), v2 = r.next();
    ASSERT_TRUE(v0 && v1 && v2);
    EXPECT_FALSE(r.next());
    EXPECT_TRUE(r.valid());
    EXPECT_EQ(v0->index, 250);
    EXPECT_EQ(v1->index, 251);
    EXPECT_EQ(v2->index, 252);
    EXPECT_TRUE(v0->more);
    EXPECT_TRUE(v1->more);
    EXPECT_FALSE(v2->more);
    EXPECT_EQ(v0->command, Command::FPWR);
    EXPECT_EQ(v0->adp, 0x1001);
    EXPECT_EQ(v0->ado, 0x0508);
    EXPECT_EQ(std::vector<uint8_t>(v0->data.begin(), v0->data.end()), (std::vector<uint8_t>{1, 2, 3, 4}));
    EXPECT_EQ(v1->data.size(), 1u);
    EXPECT_EQ(v2->data.size(), 6u);
}

TEST(Frame, LogicalAddressSplitsIntoAdpAndAdo) {
    uint8_t x[1];
    const Datagram d = Datagram::logical(Command::LRD, 0x00012345, x);
    EXPECT_EQ(d.adp, 0x2345);
    EXPECT_EQ(d.ado, 0x0001);
}

TEST(Frame, RefusesWhatDoesNotFitOneFrame) {
    std::vector<uint8_t> big(kMaxDatagramData + 1);
    Datagram d{Command::BWR, 0, 0, big};
    std::array<uint8_t, kMaxFrameSize> out{};
    EXPECT_EQ(encode_frame(std::span<const Datagram>(&d, 1), 0, kMac, out), 0u);
    std::vector<uint8_t> max(kMaxDatagramData);
    Datagram m{Command::BWR, 0, 0, max};
    EXPECT_EQ(encode_frame(std::span<const Datagram>(&m, 1), 0, kMac, out), kMaxFrameSize);
    std::vector<uint8_t> half(800);
    Datagram two[2] = {{Command::BWR, 0, 0, half}, {Command::BWR, 0, 0, half}};
    EXPECT_EQ(encode_frame(two, 0, kMac, out), 0u);
    EXPECT_EQ(encode_frame(std::span<const Datagram>(), 0, kMac, out), 0u);
    std::array<uint8_t, 40> small{};
    uint8_t one[1];
    Datagram s{Command::BRD, 0, 0, one};
    EXPECT_EQ(encode_frame(std::span<const Datagram>(&s, 1), 0, kMac, small), 0u);
}

TEST(Frame, ReaderRejectsMalformedFrames) {
    uint8_t data[2] = {};
    Datagram d{Command::APRD, 0, 0x0130, data};
    std::array<uint8_t, kMaxFrameSize> out{};
    const std::size_t n = encode_frame(std::span<const Datagram>(&d, 1), 7, kMac, out);

    auto bad = out;
    bad[13] = 0xA5;  // not EtherCAT
    EXPECT_FALSE(FrameReader(std::span<const uint8_t>(bad.data(), n)).valid());

    bad = out;
    bad[15] = 0x40;  // type 4: not a DLPDU
    EXPECT_FALSE(FrameReader(std::span<const uint8_t>(bad.data(), n)).valid());

    // The header length is not evaluated (the reader walks the chain as an ESC does, docs/decisions/esc.md
    // "Frame tolerance"): a length far past the frame still reads the datagram.
    bad = out;
    bad[14] = 0xFF;
    bad[15] = 0x17;
    FrameReader l(std::span<const uint8_t>(bad.data(), n));
    EXPECT_TRUE(l.valid());
    EXPECT_TRUE(l.next());
    EXPECT_FALSE(l.next());
    EXPECT_TRUE(l.valid());

    bad = out;
    bad[22] = 0x40;  // datagram length 64: past the end of the 60-byte frame
    FrameReader r(std::span<const uint8_t>(bad.data(), n));
    EXPECT_TRUE(r.valid());
    EXPECT_FALSE(r.next());
    EXPECT_FALSE(r.valid());

    bad = out;
    bad[23] = 0x80;  // more bit set on the last datagram, and no room for another header
    FrameReader m(std::span<const uint8_t>(bad.data(), 16 + 14));
    EXPECT_TRUE(m.next());
    EXPECT_FALSE(m.next());
    EXPECT_FALSE(m.valid());

    EXPECT_FALSE(FrameReader(std::span<const uint8_t>(out.data(), 15)).valid());
}

TEST(Frame, ReaderSkipsOneVlanTag) {
    uint8_t data[2] = {};
    Datagram d{Command::APRD, 0, 0x0130, data};
    std::array<uint8_t, kMaxFrameSize> out{};
    const std::size_t n = encode_frame(std::span<const Datagram>(&d, 1), 3, kMac, out);
    std::vector<uint8_t> tagged(out.begin(), out.begin() + 12);
    tagged.insert(tagged.end(), {0x81, 0x00, 0x00, 0x05});
    tagged.insert(tagged.end(), out.begin() + 12, out.begin() + static_cast<long>(n));
    FrameReader r(tagged);
    ASSERT_TRUE(r.valid());
    auto v = r.next();
    ASSERT_TRUE(v);
    EXPECT_EQ(v->index, 3);
    EXPECT_EQ(v->ado, 0x0130);
}
