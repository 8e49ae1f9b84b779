// The stack on the real drive's description and dictionary (maxpos::description(),
// maxpos::dictionary()): what a master meets on the wire.
#include "fixture.hpp"
#include "maxpos/maxpos.hpp"

namespace ecat::test {
namespace {

using od::AlState;

class RealDrive : public StackTest {
  protected:
    void SetUp() override {
        desc = maxpos::description();
        dict = maxpos::dictionary(desc);
        StackTest::SetUp();
    }
    uint16_t default_rx() const { return desc.sync_managers.at(2).default_size; }
    uint16_t default_tx() const { return desc.sync_managers.at(3).default_size; }
};

TEST_F(RealDrive, DefaultMapping_InitToOp_SmSync) {
    configure_mailbox();
    request(0x02);
    ASSERT_EQ(al_status(), 0x02) << std::hex << al_code();
    configure_process_data(default_rx(), default_tx());
    request(0x04);
    ASSERT_EQ(al_status(), 0x04) << std::hex << al_code();
    EXPECT_EQ(stack->process_data().rx_bytes(), default_rx());
    EXPECT_EQ(stack->process_data().tx_bytes(), default_tx());
    EXPECT_EQ(dict.get<uint16_t>(0x1C32, 1), 1);  // SM-synchronous: what really runs
    EXPECT_EQ(dict.get<uint16_t>(0x1C33, 1), 0x22);
    std::vector<uint8_t> out(default_rx(), 0), in(default_tx(), 0);
    out[0] = 0x06;  // controlword: shutdown
    exchange_pd(out, in);
    poll();
    request(0x08);
    ASSERT_EQ(al_status(), 0x08) << std::hex << al_code();
    exchange_pd(out, in);
    poll();
    EXPECT_EQ(dict.get<uint16_t>(0x6040, 0), 0x0006);
}

TEST_F(RealDrive, Dc_ModeReported) {
    configure_mailbox();
    request(0x02);
    configure_process_data(default_rx(), default_tx());
    master.wr<uint32_t>(0x09A0, 1'000'000);
    master.wr<uint64_t>(0x0990, master.rd<uint64_t>(0x0910) + 1'000'000);
    master.wr<uint8_t>(0x0981, 0x03);
    request(0x04);
    ASSERT_EQ(al_status(), 0x04) << std::hex << al_code();
    EXPECT_EQ(dict.get<uint16_t>(0x1C32, 1), 2);
    EXPECT_EQ(dict.get<uint16_t>(0x1C33, 1), 2);
    EXPECT_EQ(dict.get<uint32_t>(0x1C32, 2), 1'000'000u);
}

TEST_F(RealDrive, Bootstrap_1024ByteMailbox) {
    configure_sm(0, desc.bootstrap_mailbox.out_start, desc.bootstrap_mailbox.out_size, 0x26, true);
    configure_sm(1, desc.bootstrap_mailbox.in_start, desc.bootstrap_mailbox.in_size, 0x22, true);
    request(0x03);
    EXPECT_EQ(al_status(), 0x03) << std::hex << al_code();
    EXPECT_EQ(stack->mailbox().max_payload(), 1024u - 6u);
}

}  // namespace
}  // namespace ecat::test
