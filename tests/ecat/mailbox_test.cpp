// Mailbox: header checks and error replies (ETG.1000.4 mailbox, ETG.1000.6 mailbox error reply), counters,
// repeat request (ESC datasheet, SyncManager mailbox repeat), queue, Bootstrap protocol restriction, handler
// dispatch.
#include <gmock/gmock.h>

#include "fixture.hpp"

namespace ecat::test {
namespace {

using od::AlState;

// Echoes each request back with one extra byte; counts calls and polls.
class EchoHandler : public MailboxHandler {
  public:
    explicit EchoHandler(MailboxType t, bool boot_only = false) : type_(t), boot_only_(boot_only) {}
    MailboxType type() const override { return type_; }
    bool available(AlState s) const override { return boot_only_ ? s == AlState::Boot : s != AlState::Init; }
    void handle(std::span<const uint8_t> payload, MailboxSender& out) override {
        ++handled;
        last.assign(payload.begin(), payload.end());
        std::vector<uint8_t> reply(payload.begin(), payload.end());
        reply.push_back(0xEE);
        for (int i = 0; i < replies; ++i)
            sent_ok = out.send(type_, reply);
    }
    void poll(uint64_t now_ns, MailboxSender&) override {
        ++polls;
        last_poll_ns = now_ns;
    }
    void on_state_change(AlState, AlState to) override { last_state = to; }

    MailboxType type_;
    bool boot_only_;
    int handled = 0;
    int polls = 0;
    int replies = 1;
    bool sent_ok = false;
    uint64_t last_poll_ns = 0;
    AlState last_state = AlState::Init;
    std::vector<uint8_t> last;
};

class MailboxOverStack : public StackTest {
  protected:
    void SetUp() override {
        StackTest::SetUp();
        stack->add_handler(coe);
        stack->add_handler(foe);
    }
    std::vector<uint8_t> roundtrip(std::span<const uint8_t> message) {
        mbx_write(message);
        poll();
        return mbx_read();
    }
    // Asserts that reply is a mailbox error reply with the given detail.
    static void expect_error(const std::vector<uint8_t>& reply, MailboxError detail) {
        ASSERT_GE(reply.size(), 10u);
        EXPECT_EQ(reply[0] | (reply[1] << 8), 4);       // length
        EXPECT_EQ(reply[5] & 0x0F, 0);                  // type: error
        EXPECT_EQ(reply[6] | (reply[7] << 8), 0x0001);  // mailbox command error
        EXPECT_EQ(reply[8] | (reply[9] << 8), static_cast<int>(detail));
    }
    EchoHandler coe{MailboxType::CoE};
    EchoHandler foe{MailboxType::FoE, true};
    const std::vector<uint8_t> sdo{0x00, 0x20, 0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0};
};

TEST_F(MailboxOverStack, Dispatch_ReplyInSm1) {
    go_preop();
    const auto reply = roundtrip(mbx_message(0x3, 1, sdo));
    ASSERT_EQ(reply.size(), 128u);  // the whole SM1 is read
    EXPECT_EQ(coe.handled, 1);
    EXPECT_EQ(coe.last, sdo);
    EXPECT_EQ(reply[0] | (reply[1] << 8), static_cast<int>(sdo.size() + 1));
    EXPECT_EQ(reply[5] & 0x0F, 0x3);
    EXPECT_EQ((reply[5] >> 4) & 7, 1);  // first slave counter is 1
    EXPECT_TRUE(std::equal(sdo.begin(), sdo.end(), reply.begin() + 6));
    EXPECT_EQ(reply[6 + sdo.size()], 0xEE);
}

TEST_F(MailboxOverStack, Sm1EmptyWithoutReply_Wkc0) {
    go_preop();
    EXPECT_TRUE(mbx_read().empty());
}

TEST_F(MailboxOverStack, AddressEchoedInReply) {
    go_preop();
    const auto reply = roundtrip(mbx_message(0x3, 1, sdo, 0x1001));
    ASSERT_FALSE(reply.empty());
    EXPECT_EQ(reply[2] | (reply[3] << 8), 0x1001);
}

TEST_F(MailboxOverStack, Error_InvalidHeader_TypeZero) {
    go_preop();
    expect_error(roundtrip(mbx_message(0x0, 1, sdo)), MailboxError::InvalidHeader);
    EXPECT_EQ(coe.handled, 0);
}

TEST_F(MailboxOverStack, Error_InvalidSize_LengthBeyondSm0) {
    go_preop();
    auto m = mbx_message(0x3, 1, sdo);
    m[0] = 123;  // 6 + 123 > 128
    expect_error(roundtrip(m), MailboxError::InvalidSize);
    EXPECT_EQ(coe.handled, 0);
}

TEST_F(MailboxOverStack, Error_SizeTooShort_LengthZero) {
    go_preop();
    expect_error(roundtrip(mbx_message(0x3, 1, {})), MailboxError::SizeTooShort);
}

TEST_F(MailboxOverStack, Error_SizeTooShort_BelowCoeHeader) {
    go_preop();
    const std::vector<uint8_t> one{0x00};
    expect_error(roundtrip(mbx_message(0x3, 1, one)), MailboxError::SizeTooShort);
}

TEST_F(MailboxOverStack, Error_InvalidChannel) {
    go_preop();
    expect_error(roundtrip(mbx_message(0x3, 1, sdo, 0, 5)), MailboxError::InvalidChannel);
}

TEST_F(MailboxOverStack, Error_UnsupportedProtocol) {
    go_preop();
    expect_error(roundtrip(mbx_message(0x5, 1, sdo)), MailboxError::UnsupportedProtocol);  // SoE
}

TEST_F(MailboxOverStack, Error_ProtocolNotAvailableInState) {
    go_preop();
    const std::vector<uint8_t> foe_req{0x01, 0, 0, 0, 0, 0, 'x'};
    expect_error(roundtrip(mbx_message(0x4, 1, foe_req)), MailboxError::UnsupportedProtocol);
    EXPECT_EQ(foe.handled, 0);
}

TEST_F(MailboxOverStack, Bootstrap_ServesFoeOnly) {
    configure_bootstrap_mailbox();
    request(0x03);
    ASSERT_EQ(al_status(), 0x03);
    expect_error(roundtrip(mbx_message(0x3, 1, sdo)), MailboxError::UnsupportedProtocol);
    EXPECT_EQ(coe.handled, 0);
    const std::vector<uint8_t> foe_req{0x02, 0, 0, 0, 0, 0, 'f', 'w'};
    const auto reply = roundtrip(mbx_message(0x4, 2, foe_req));
    ASSERT_EQ(reply.size(), 256u);  // bootstrap SM1 length
    EXPECT_EQ(reply[5] & 0x0F, 0x4);
    EXPECT_EQ(foe.handled, 1);
}

TEST_F(MailboxOverStack, Counter_RepeatedRequestNotExecutedTwice) {
    go_preop();
    ASSERT_FALSE(roundtrip(mbx_message(0x3, 3, sdo)).empty());
    EXPECT_TRUE(roundtrip(mbx_message(0x3, 3, sdo)).empty());
    EXPECT_EQ(coe.handled, 1);
    EXPECT_EQ(stack->mailbox().stats().duplicates, 1u);
    ASSERT_FALSE(roundtrip(mbx_message(0x3, 4, sdo)).empty());
    EXPECT_EQ(coe.handled, 2);
}

TEST_F(MailboxOverStack, Counter_ZeroAlwaysExecuted) {
    go_preop();
    roundtrip(mbx_message(0x3, 0, sdo));
    roundtrip(mbx_message(0x3, 0, sdo));
    EXPECT_EQ(coe.handled, 2);
}

TEST_F(MailboxOverStack, Counter_SlaveCounterWraps1To7NeverZero) {
    go_preop();
    std::vector<int> counters;
    for (int i = 0; i < 9; ++i) {
        const auto reply = roundtrip(mbx_message(0x3, static_cast<uint8_t>(i % 7 + 1), sdo));
        ASSERT_FALSE(reply.empty());
        counters.push_back((reply[5] >> 4) & 7);
    }
    EXPECT_THAT(counters, ::testing::ElementsAre(1, 2, 3, 4, 5, 6, 7, 1, 2));
}

TEST_F(MailboxOverStack, Counter_ResetWhenMailboxRestarts) {
    go_preop();
    roundtrip(mbx_message(0x3, 1, sdo));
    request(0x01);
    go_preop();
    // Same counter as before the restart: a new session, executed.
    const auto reply = roundtrip(mbx_message(0x3, 1, sdo));
    EXPECT_EQ(coe.handled, 2);
    ASSERT_FALSE(reply.empty());
    EXPECT_EQ((reply[5] >> 4) & 7, 1);
}

// Issue 14, finding 4: 'R','E','S' written to 0x0040 in Pre-Op put the ESC into Init, but the stack stayed in
// Pre-Op with its old mailbox counter and dropped the master's next request as a repeat. An ESC reset is a
// reset of everything behind the PDI: the stack restarts in Init, the application restarts with it.
void esc_reset(Master& m) {
    for (uint8_t c : {uint8_t{'R'}, uint8_t{'E'}, uint8_t{'S'}})
        m.wr<uint8_t>(0x0040, c);
}

// SM1's "read by the master" event stays set until the next message is written: it is not in the AL event
// mask, so it does not hold the interrupt line high once the last reply was fetched. A reply still waiting
// for SM1 keeps the stack from being quiet instead.
TEST_F(MailboxOverStack, QuietOnceTheLastReplyWasFetched_NotWhileRepliesWait) {
    go_preop();
    ASSERT_FALSE(roundtrip(mbx_message(0x3, 1, sdo)).empty());
    EXPECT_NE(esc->read_reg<uint32_t>(0x0220) & 0x0200, 0u);  // SM1 event pending
    EXPECT_TRUE(stack->quiet(clock.now_ns()));
    coe.replies = 2;
    mbx_write(mbx_message(0x3, 2, sdo));
    poll();  // the first reply in SM1, the second queued behind it
    EXPECT_EQ(stack->mailbox().queued(), 1u);
    EXPECT_FALSE(stack->quiet(clock.now_ns()));
    ASSERT_FALSE(mbx_read().empty());
    EXPECT_FALSE(stack->quiet(clock.now_ns()));
    poll();  // SM1 is free: the second goes out
    EXPECT_EQ(stack->mailbox().queued(), 0u);
    EXPECT_TRUE(stack->quiet(clock.now_ns()));
    EXPECT_FALSE(mbx_read().empty());
    EXPECT_TRUE(stack->quiet(clock.now_ns()));
}

TEST_F(MailboxOverStack, EscResetRestartsTheStack) {
    go_preop();
    ASSERT_FALSE(roundtrip(mbx_message(0x3, 1, sdo)).empty());
    esc_reset(master);
    EXPECT_EQ(al_status(), 0x01);  // the ESC's reset value
    // The interrupt line is low with the reset mask: the next timer-driven poll notices.
    advance(Stack::kHousekeepingNs);
    EXPECT_EQ(stack->state(), AlState::Init);
    EXPECT_EQ(stack->stats().esc_resets, 1u);
    EXPECT_EQ(app.restarts, 1);
    EXPECT_EQ(coe.last_state, AlState::Init);  // the handlers dropped their transfers
    EXPECT_EQ(esc->read_reg<uint32_t>(0x0204), Stack::kEventMask);
    EXPECT_EQ(al_status(), 0x01);
    // The master starts over: mailbox configured again, Pre-Op, and its counter from 1 again is executed.
    go_preop();
    const auto reply = roundtrip(mbx_message(0x3, 1, sdo));
    ASSERT_FALSE(reply.empty());
    EXPECT_EQ(coe.handled, 2);
    EXPECT_EQ((reply[5] >> 4) & 7, 1);  // the slave's counter starts over as well
    EXPECT_EQ(stack->mailbox().stats().duplicates, 0u);
    // Nothing is seen as a reset while the ESC keeps the stack's set-up.
    advance(50'000'000);
    EXPECT_EQ(stack->stats().esc_resets, 1u);
    EXPECT_EQ(app.restarts, 1);
}

TEST_F(MailboxOverStack, EscResetInSafeOpStopsProcessDataAndMailbox) {
    go_safeop();
    esc_reset(master);
    advance(20'000'000);  // no master activity: the next timer-driven poll notices
    EXPECT_EQ(stack->state(), AlState::Init);
    EXPECT_FALSE(stack->mailbox().running());
    EXPECT_EQ(al_status(), 0x01);
    EXPECT_EQ(app.restarts, 1);
    ASSERT_FALSE(app.changes.empty());
    EXPECT_EQ(app.changes.back(), std::make_pair(AlState::SafeOp, AlState::Init));
}

TEST_F(MailboxOverStack, EscResetWhileTheMasterAlreadyAsksForPreOp) {
    go_preop();
    ASSERT_FALSE(roundtrip(mbx_message(0x3, 1, sdo)).empty());
    esc_reset(master);
    // The master does not wait for the firmware: mailbox and Pre-Op request right after the reset.
    configure_mailbox();
    request(0x02);
    EXPECT_EQ(al_status(), 0x02) << std::hex << al_code();
    EXPECT_EQ(stack->stats().esc_resets, 1u);
    ASSERT_FALSE(roundtrip(mbx_message(0x3, 1, sdo)).empty());
    EXPECT_EQ(coe.handled, 2);
}

// Toggles the repeat request bit in SM1 activate and polls until the slave acknowledges it.
void repeat_request(Master& m, bool& toggle) {
    toggle = !toggle;
    m.wr<uint8_t>(0x080E, static_cast<uint8_t>(0x01 | (toggle ? 0x02 : 0)));
}

TEST_F(MailboxOverStack, Repeat_ResendsLostReply) {
    go_preop();
    const auto first = roundtrip(mbx_message(0x3, 1, sdo));  // "lost" on its way back
    ASSERT_FALSE(first.empty());
    bool toggle = false;
    repeat_request(master, toggle);
    poll();
    EXPECT_EQ(master.rd<uint8_t>(0x080F) & 0x02, 0x02);  // acknowledged
    const auto again = mbx_read();
    EXPECT_EQ(again, first);
    EXPECT_EQ(coe.handled, 1);
    // Once more, toggling back.
    repeat_request(master, toggle);
    poll();
    EXPECT_EQ(master.rd<uint8_t>(0x080F) & 0x02, 0x00);
    EXPECT_EQ(mbx_read(), first);
}

TEST_F(MailboxOverStack, Repeat_WithNewerMessagePending) {
    go_preop();
    coe.replies = 2;  // two replies: B waits in SM1 after A was read
    mbx_write(mbx_message(0x3, 1, sdo));
    poll();
    const auto a = mbx_read();
    ASSERT_FALSE(a.empty());
    poll();  // B goes into SM1
    bool toggle = false;
    repeat_request(master, toggle);
    poll();
    EXPECT_EQ(master.rd<uint8_t>(0x080F) & 0x02, 0x02);
    EXPECT_EQ(mbx_read(), a);  // A again
    poll();
    const auto b = mbx_read();  // then B
    ASSERT_FALSE(b.empty());
    EXPECT_EQ((b[5] >> 4) & 7, 2);
    poll();
    EXPECT_TRUE(mbx_read().empty());
}

TEST_F(MailboxOverStack, Queue_HoldsRepliesUntilRead) {
    go_preop();
    coe.replies = 3;
    mbx_write(mbx_message(0x3, 1, sdo));
    poll();
    EXPECT_EQ(stack->mailbox().queued(), 2u);
    std::vector<int> counters;
    for (int i = 0; i < 3; ++i) {
        const auto r = mbx_read();
        ASSERT_FALSE(r.empty());
        counters.push_back((r[5] >> 4) & 7);
        poll();
    }
    EXPECT_THAT(counters, ::testing::ElementsAre(1, 2, 3));
    EXPECT_EQ(stack->mailbox().queued(), 0u);
}

TEST_F(MailboxOverStack, Queue_FullRefusesWithoutBlocking) {
    go_preop();
    coe.replies = static_cast<int>(Mailbox::kQueueCapacity) + 3;
    mbx_write(mbx_message(0x3, 1, sdo));
    poll();
    EXPECT_FALSE(coe.sent_ok);
    EXPECT_GE(stack->mailbox().stats().queue_full, 1u);
    // Draining works and a later request is still served.
    for (std::size_t i = 0; i < Mailbox::kQueueCapacity + 1; ++i) {
        mbx_read();
        poll();
    }
    coe.replies = 1;
    const auto reply = roundtrip(mbx_message(0x3, 2, sdo));
    EXPECT_FALSE(reply.empty());
    EXPECT_EQ(coe.handled, 2);
}

TEST_F(MailboxOverStack, Send_TooLargeRefused) {
    go_preop();
    std::vector<uint8_t> big(123, 0);
    EXPECT_FALSE(stack->mailbox().send(MailboxType::CoE, big));
    std::vector<uint8_t> fits(122, 0);
    EXPECT_TRUE(stack->mailbox().send(MailboxType::CoE, fits));
    EXPECT_EQ(stack->mailbox().max_payload(), 122u);
}

TEST_F(MailboxOverStack, Send_SpontaneousMessageHasAddressZero) {
    go_preop();
    roundtrip(mbx_message(0x3, 1, sdo, 0x1001));  // a request with an address, answered and read
    const std::vector<uint8_t> emergency{0x00, 0x10, 0x10, 0x82, 0x11, 0, 0, 0, 0, 0};
    ASSERT_TRUE(stack->mailbox().send(MailboxType::CoE, emergency));
    poll();
    const auto m = mbx_read();
    ASSERT_FALSE(m.empty());
    EXPECT_EQ(m[2] | (m[3] << 8), 0);
    EXPECT_EQ(m[0], emergency.size());
    EXPECT_EQ((m[5] >> 4) & 7, 2);
}

TEST_F(MailboxOverStack, Send_RefusedInInit) {
    std::vector<uint8_t> small(4, 0);
    EXPECT_FALSE(stack->mailbox().send(MailboxType::CoE, small));
}

TEST_F(MailboxOverStack, Handlers_PolledAndToldStateChanges) {
    go_preop();
    const int before = coe.polls;
    advance(Stack::kHousekeepingNs);
    EXPECT_GT(coe.polls, before);
    EXPECT_EQ(coe.last_poll_ns, clock.now_ns());
    EXPECT_EQ(coe.last_state, AlState::PreOp);
    EXPECT_LE(stack->next_deadline_ns(), clock.now_ns() + Stack::kHousekeepingNs);
}

TEST_F(MailboxOverStack, Sm0ReadToLastByte_MasterCanWriteAgain) {
    go_preop();
    mbx_write(mbx_message(0x3, 1, sdo));
    poll();
    EXPECT_EQ(master.rd<uint8_t>(0x0805) & 0x08, 0);  // SM0 no longer full
    mbx_read();
    mbx_write(mbx_message(0x3, 2, sdo));
    poll();
    EXPECT_EQ(coe.handled, 2);
}

TEST_F(MailboxOverStack, SafeOpAndOp_MailboxKeepsRunning) {
    go_op();
    const auto reply = roundtrip(mbx_message(0x3, 1, sdo));
    EXPECT_FALSE(reply.empty());
    EXPECT_EQ(coe.last_state, AlState::Op);
}

}  // namespace
}  // namespace ecat::test

namespace ecat::test {
namespace {

TEST_F(MailboxOverStack, NoPdiEventBits_MailboxStillServedAtOnce) {
    configure_sm(0, 0x1000, 128, 0x06, true);  // no PDI event: the interrupt line will not tell us
    configure_sm(1, 0x1080, 128, 0x02, true);
    request(0x02);
    ASSERT_EQ(al_status(), 0x02);
    const auto reply = roundtrip(mbx_message(0x3, 1, sdo));  // no clock advance in between
    EXPECT_FALSE(reply.empty());
    EXPECT_EQ(coe.handled, 1);
}

}  // namespace
}  // namespace ecat::test
