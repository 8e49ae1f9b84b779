// SII EEPROM access (ESC datasheet section II, 0x0500-0x050F): read sizes, busy, not-acknowledged, category
// chain, write.
#include <gtest/gtest.h>

#include "fake_bus.hpp"
#include "master/master.hpp"
#include "util/le.hpp"

using namespace master;

namespace {
MasterOptions fast() {
    MasterOptions o;
    o.timeout = std::chrono::milliseconds(5);
    return o;
}

// Header (64 words) + STRINGS(2 words) + GENERAL(16 words) + end.
std::vector<uint16_t> sample_image() {
    std::vector<uint16_t> w(0x40, 0);
    w[0x08] = 0x00FB;  // vendor
    w[0x0A] = 0x1234;  // product low
    w[0x0B] = 0x5678;
    w[0x0C] = 0x0002;
    w[0x0E] = 0xCAFE;
    w[0x3E] = 0x000F;  // 16 kbit
    for (uint16_t i = 0; i < 0x40; ++i)
        if (w[i] == 0 && i > 0x10) w[i] = static_cast<uint16_t>(0x0100 + i);  // recognisable filler
    w.insert(w.end(), {10, 2, 0x4101, 0x0042});
    w.insert(w.end(), {30, 16});
    for (int i = 0; i < 16; ++i)
        w.push_back(static_cast<uint16_t>(0xA000 + i));
    w.push_back(0xFFFF);
    w.push_back(0x0000);  // after the end: not part of the image
    return w;
}

std::vector<uint8_t> bytes(const std::vector<uint16_t>& w, std::size_t words) {
    std::vector<uint8_t> b;
    for (std::size_t i = 0; i < words; ++i)
        util::append16(b, w[i]);
    return b;
}
}  // namespace

class SiiReadSize : public ::testing::TestWithParam<bool> {};

TEST_P(SiiReadSize, ReadsWordsAndIdentityAtAnyOffset) {
    fake::Bus bus(1);
    bus.slaves[0].eeprom = sample_image();
    bus.slaves[0].read_size8 = GetParam();
    Master m(bus, fast());
    const Address a = Address::position(0);
    EXPECT_EQ(m.sii_read_u32(a, sii::VendorId).value(), 0x000000FBu);
    EXPECT_EQ(m.sii_read_u32(a, sii::ProductCode).value(), 0x56781234u);
    EXPECT_EQ(m.sii_read_word(a, sii::SerialNumber).value(), 0xCAFE);
    uint8_t odd[7];
    ASSERT_EQ(m.sii_read(a, 0x41, odd), Error::Ok);
    const auto expect = bytes(sample_image(), 0x45);
    EXPECT_EQ(std::vector<uint8_t>(odd, odd + 7),
              std::vector<uint8_t>(expect.begin() + 0x82, expect.begin() + 0x89));
}

TEST_P(SiiReadSize, ImageFollowsTheCategoryChainToItsEnd) {
    fake::Bus bus(1);
    bus.slaves[0].eeprom = sample_image();
    bus.slaves[0].read_size8 = GetParam();
    Master m(bus, fast());
    auto img = m.sii_read_image(Address::position(0));
    ASSERT_TRUE(img.ok()) << to_string(img.error());
    const std::size_t words = 0x40 + 4 + 18 + 1;
    EXPECT_EQ(*img, bytes(sample_image(), words));
}

TEST_P(SiiReadSize, WholeEepromUsesTheSizeWord) {
    fake::Bus bus(1);
    bus.slaves[0].eeprom = sample_image();
    bus.slaves[0].read_size8 = GetParam();
    Master m(bus, fast());
    auto img = m.sii_read_image(Address::position(0), true);
    ASSERT_TRUE(img.ok());
    ASSERT_EQ(img->size(), 2048u);
    auto expect = bytes(sample_image(), sample_image().size());
    expect.resize(2048, 0xFF);
    EXPECT_EQ(*img, expect);
}

INSTANTIATE_TEST_SUITE_P(FourAndEightBytes, SiiReadSize, ::testing::Values(false, true));

TEST(Sii, WaitsWhileBusy) {
    fake::Bus bus(1);
    bus.slaves[0].eeprom = sample_image();
    bus.slaves[0].busy_polls = 3;
    Master m(bus, fast());
    EXPECT_EQ(m.sii_read_word(Address::position(0), sii::VendorId).value(), 0x00FB);
}

TEST(Sii, StaysBusyTooLongIsReported) {
    fake::Bus bus(1);
    bus.slaves[0].eeprom = sample_image();
    bus.slaves[0].busy_polls = 1'000'000;
    MasterOptions o = fast();
    o.sii_timeout = std::chrono::milliseconds(20);
    Master m(bus, o);
    EXPECT_EQ(m.sii_read_word(Address::position(0), sii::VendorId).error(), Error::SiiBusy);
}

TEST(Sii, RepeatsACommandThatWasNotAcknowledged) {
    fake::Bus bus(1);
    bus.slaves[0].eeprom = sample_image();
    bus.slaves[0].nacks = 2;
    Master m(bus, fast());
    EXPECT_EQ(m.sii_read_word(Address::position(0), sii::VendorId).value(), 0x00FB);
    EXPECT_EQ(bus.slaves[0].nacks, 0);
}

TEST(Sii, GivesUpWhenNeverAcknowledged) {
    fake::Bus bus(1);
    bus.slaves[0].eeprom = sample_image();
    bus.slaves[0].nacks = 1000;
    Master m(bus, fast());
    EXPECT_EQ(m.sii_read_word(Address::position(0), sii::VendorId).error(), Error::SiiNack);
}

TEST(Sii, ClearsAStaleErrorBeforeTheCommand) {
    fake::Bus bus(1);
    bus.slaves[0].eeprom = sample_image();
    fake::put16(&bus.slaves[0].mem[0x0502], 0x2000);  // left over from someone else
    Master m(bus, fast());
    EXPECT_EQ(m.sii_read_word(Address::position(0), sii::VendorId).value(), 0x00FB);
}

TEST(Sii, TakesTheEepromBackFromThePdi) {
    fake::Bus bus(1);
    bus.slaves[0].eeprom = sample_image();
    bus.slaves[0].mem[0x0500] = 0x01;
    Master m(bus, fast());
    EXPECT_EQ(m.sii_read_word(Address::position(0), sii::VendorId).value(), 0x00FB);
    EXPECT_EQ(bus.slaves[0].mem[0x0500], 0x00);
}

TEST(Sii, ChainThatNeverEndsIsAFormatError) {
    fake::Bus bus(1);
    auto img = sample_image();
    img.resize(0x40);
    bus.slaves[0].eeprom = img;
    bus.slaves[0].beyond_eeprom = 0x0000;  // NOP categories of length 0 forever
    bus.slaves[0].read_size8 = true;
    Master m(bus, fast());
    EXPECT_EQ(m.sii_read_image(Address::position(0)).error(), Error::SiiFormat);
}

TEST(Sii, WritesAWordWithWriteEnable) {
    fake::Bus bus(1);
    bus.slaves[0].eeprom = sample_image();
    Master m(bus, fast());
    ASSERT_EQ(m.assign_station_addresses(1), Error::Ok);
    ASSERT_EQ(m.sii_write_word(Address::station(0x1001), 0x0004, 0x0777), Error::Ok);
    EXPECT_EQ(bus.slaves[0].eeprom[4], 0x0777);
    EXPECT_EQ(m.sii_read_word(Address::station(0x1001), 0x0004).value(), 0x0777);
    // Data word and command travel in one frame, data first (so that no ESC can run the command
    // with a stale data register).
    bool seen = false;
    for (const auto& f : bus.sent) {
        if (f.size() < 16 + 12 + 2 + 12 + 6) continue;
        const uint8_t* d0 = &f[16];
        const uint8_t* d1 = d0 + 12 + 2;
        if (fake::get16(d0 + 4) == 0x0508 && (fake::get16(d0 + 6) & 0x8000) &&
            fake::get16(d1 + 4) == 0x0502 && d1[10] == 0x01 && d1[11] == 0x02 &&
            fake::get16(d0 + 10) == 0x0777 && fake::get16(d1 + 12) == 0x0004)
            seen = true;
    }
    EXPECT_TRUE(seen);
}

TEST(Sii, RefusedWriteIsReported) {
    fake::Bus bus(1);
    bus.slaves[0].eeprom = sample_image();
    bus.slaves[0].write_protect = true;
    Master m(bus, fast());
    EXPECT_EQ(m.sii_write_word(Address::position(0), 0x0004, 0x0777), Error::SiiWriteDisabled);
    EXPECT_EQ(bus.slaves[0].eeprom[4], 0x0000);
}
