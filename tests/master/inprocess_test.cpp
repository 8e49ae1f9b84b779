// The master against the real emulated ESC (esc::Esc), connected in-process through a tiny Link that
// hands every frame to Esc::process_frame(): what the integration tests check on a veth pair, without
// sockets or privileges.
#include <gtest/gtest.h>

#include <vector>

#include "esc/clock.hpp"
#include "esc/esc.hpp"
#include "esc/wire/sii.hpp"
#include "master/master.hpp"
#include "support/sii_image.hpp"
#include "support/wire_link.hpp"
#include "util/le.hpp"

using namespace master;

namespace {

std::vector<uint8_t> image(uint8_t esc_config = 0x0C) {
    return test_support::small_sii_image(esc_config);
}

constexpr std::size_t kImageEnd = test_support::kSmallSiiImageEnd;

struct Rig {
    esc::ManualClock clock;
    esc::Esc esc{esc::EscConfig{}, clock};
    test_support::WireLink link{[this](std::vector<uint8_t>& f) { return esc.process_frame(f); }};
    Master m{link, [] {
                 MasterOptions o;
                 o.timeout = std::chrono::milliseconds(20);
                 o.al_timeout = std::chrono::milliseconds(200);
                 return o;
             }()};
    explicit Rig(uint8_t esc_config = 0x0C) { esc.load_eeprom(image(esc_config)); }
};

}  // namespace

TEST(MasterWithEsc, CountsOneSlaveAndAssignsItsAddress) {
    Rig r;
    auto n = r.m.count_slaves();
    ASSERT_TRUE(n.ok()) << to_string(n.error());
    EXPECT_EQ(*n, 1);
    ASSERT_EQ(r.m.assign_station_addresses(1), Error::Ok);
    EXPECT_EQ(r.esc.read_reg<uint16_t>(0x0010), 0x1001);
    EXPECT_EQ(r.m.read_reg<uint16_t>(Address::station(0x1001), reg::StationAddress).value(), 0x1001);
    EXPECT_EQ(r.m.read_reg<uint8_t>(Address::position(1), reg::Type).error(), Error::WorkingCounter);
}

TEST(MasterWithEsc, RegistersRoundTripAndReadOnlyStaysUnchanged) {
    Rig r;
    const Address a = Address::position(0);
    ASSERT_EQ(r.m.write_reg<uint32_t>(a, 0x0F80, 0xA1B2C3D4), Error::Ok);
    EXPECT_EQ(r.m.read_reg<uint32_t>(a, 0x0F80).value(), 0xA1B2C3D4u);
    EXPECT_EQ(r.esc.read_reg<uint32_t>(0x0F80), 0xA1B2C3D4u);
    const uint8_t type = r.m.read_reg<uint8_t>(a, reg::Type).value();
    (void)r.m.write_reg<uint8_t>(a, reg::Type, static_cast<uint8_t>(~type));
    EXPECT_EQ(r.m.read_reg<uint8_t>(a, reg::Type).value(), type);
}

TEST(MasterWithEsc, SiiImageAndIdentity) {
    Rig r;
    const Address a = Address::position(0);
    EXPECT_EQ(r.m.sii_read_u32(a, sii::VendorId).value(), 0x000000FBu);
    EXPECT_EQ(r.m.sii_read_u32(a, sii::ProductCode).value(), 0x30010000u);
    EXPECT_EQ(r.m.sii_read_u32(a, sii::Revision).value(), 0x01200000u);
    EXPECT_EQ(r.m.sii_read_u32(a, sii::SerialNumber).value(), 0x00004321u);
    auto img = r.m.sii_read_image(a);
    ASSERT_TRUE(img.ok()) << to_string(img.error());
    const auto full = image();
    EXPECT_EQ(*img, std::vector<uint8_t>(full.begin(), full.begin() + kImageEnd));
    auto all = r.m.sii_read_image(a, true);
    ASSERT_TRUE(all.ok());
    EXPECT_EQ(*all, full);
}

TEST(MasterWithEsc, SiiWriteReachesTheEepromAndItsOwner) {
    Rig r;
    std::vector<std::pair<uint16_t, uint16_t>> writes;
    r.esc.on_eeprom_write([&](uint16_t word, uint16_t value) { writes.emplace_back(word, value); });
    const Address a = Address::position(0);
    ASSERT_EQ(r.m.sii_write_word(a, 0x0E, 0xBEEF), Error::Ok);
    EXPECT_EQ(r.m.sii_read_word(a, 0x0E).value(), 0xBEEF);
    EXPECT_EQ(r.esc.eeprom()[0x1C], 0xEF);
    EXPECT_EQ(r.esc.eeprom()[0x1D], 0xBE);
    ASSERT_EQ(writes.size(), 1u);
    EXPECT_EQ(writes[0], (std::pair<uint16_t, uint16_t>{0x0E, 0xBEEF}));
}

TEST(MasterWithEsc, AlStateFollowsWithDeviceEmulation) {
    Rig r(0x0D);  // 0x0141 bit 0: device emulation, AL status mirrors AL control
    const Address a = Address::position(0);
    AlStatus st;
    ASSERT_EQ(r.m.request_state(a, AlState::PreOp, &st), Error::Ok);
    EXPECT_EQ(st.state, 0x02);
    ASSERT_EQ(r.m.request_state(a, AlState::Init, &st), Error::Ok);
    EXPECT_EQ(st.state, 0x01);
}

TEST(MasterWithEsc, FrameWithManyDatagramsIsAnsweredInOne) {
    Rig r;
    std::array<std::array<uint8_t, 2>, 20> bufs{};
    std::array<Datagram, 20> d;
    for (std::size_t i = 0; i < d.size(); ++i)
        d[i] = Datagram{Command::APRD, 0, static_cast<uint16_t>(2 * i), bufs[i]};
    ASSERT_EQ(r.m.exchange(d), Error::Ok);
    for (const Datagram& x : d)
        EXPECT_EQ(x.wkc, 1);
    EXPECT_EQ(bufs[0][0], r.esc.read_reg<uint8_t>(0x0000));
    EXPECT_EQ(r.m.stats().frames_sent, 1u);
}
