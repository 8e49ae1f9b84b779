// The deliberate faults of the stack (ecat/faults.hpp, `ecat-slave --fault`): each one breaks the one
// behaviour it names, and the same scenario without it behaves as ETG.1000.4/ETG.1000.6 say.
#include <cstring>

#include "fixture.hpp"

namespace ecat::test {
namespace {

using od::AlState;

// Echoes each request back (CoE), counting the requests it was given.
class Echo : public MailboxHandler {
  public:
    MailboxType type() const override { return MailboxType::CoE; }
    bool available(AlState s) const override { return s != AlState::Init; }
    void handle(std::span<const uint8_t> payload, MailboxSender& out) override {
        ++handled;
        out.send(MailboxType::CoE, payload);
    }
    int handled = 0;
};

class Faults : public StackTest {
  protected:
    // A fresh ESC and stack with the given faults (all off: the clean stack).
    void restart(const StackFaults& faults) {
        start();
        stack->set_faults(faults);
        echo = Echo{};
        stack->add_handler(echo);
    }
    std::vector<uint8_t> roundtrip(std::span<const uint8_t> message) {
        mbx_write(message);
        poll();
        return mbx_read();
    }
    static std::vector<uint8_t> outputs(uint16_t control, int32_t target) {
        std::vector<uint8_t> o(6);
        std::memcpy(o.data(), &control, 2);
        std::memcpy(o.data() + 2, &target, 4);
        return o;
    }
    Echo echo;
    const std::vector<uint8_t> sdo{0x00, 0x20, 0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0};
};

TEST_F(Faults, BootstrapRefused) {
    restart({});
    configure_bootstrap_mailbox();
    request(0x03);
    EXPECT_EQ(al_status(), 0x03);

    StackFaults f;
    f.bootstrap_refused = true;
    restart(f);
    configure_bootstrap_mailbox();
    request(0x03);
    EXPECT_EQ(al_status(), 0x01 | kErr);
    EXPECT_EQ(al_code(), 0x0013);
    // Pre-Op still works.
    request(0x01);
    go_preop();
}

TEST_F(Faults, AlCodeMissing) {
    restart({});
    configure_mailbox();
    request(0x08);
    EXPECT_EQ(al_status(), 0x01 | kErr);
    EXPECT_EQ(al_code(), 0x0011);

    StackFaults f;
    f.al_code_missing = true;
    restart(f);
    configure_mailbox();
    request(0x08);
    EXPECT_EQ(al_status(), 0x01 | kErr);  // refused, error bit set ...
    EXPECT_EQ(al_code(), 0x0000);         // ... but no code
}

TEST_F(Faults, InvalidStateSilent) {
    restart({});
    configure_mailbox();
    request(0x04);
    EXPECT_EQ(al_status(), 0x01 | kErr);
    EXPECT_EQ(al_code(), 0x0011);

    StackFaults f;
    f.invalid_request_silent = true;
    restart(f);
    configure_mailbox();
    request(0x04);
    EXPECT_EQ(al_status(), 0x01);  // no error indication
    EXPECT_EQ(al_code(), 0x0000);
    go_preop();  // valid transitions unchanged
}

TEST_F(Faults, ErrorAckIgnored) {
    for (const bool faulty : {false, true}) {
        SCOPED_TRACE(faulty ? "faulty" : "clean");
        StackFaults f;
        f.error_ack_ignored = faulty;
        restart(f);
        configure_mailbox();
        request(0x08);  // invalid: error 0x0011
        ASSERT_EQ(al_status(), 0x01 | kErr);
        request(0x02 | 0x10);  // Pre-Op with the acknowledge bit
        if (!faulty) {
            EXPECT_EQ(al_status(), 0x02);
        } else {
            EXPECT_EQ(al_status(), 0x01 | kErr);  // the acknowledge did nothing
            request(0x01);                        // a request for Init still clears it
            EXPECT_EQ(al_status(), 0x01);
        }
    }
}

TEST_F(Faults, WatchdogNever) {
    restart({});
    go_op();
    advance(150'000'000);  // default PD watchdog 100 ms without an SM2 write
    EXPECT_EQ(al_status(), 0x04 | kErr);
    EXPECT_EQ(al_code(), 0x001B);

    StackFaults f;
    f.watchdog_ignored = true;
    restart(f);
    go_op();
    advance(150'000'000);
    EXPECT_EQ(al_status(), 0x08);
    EXPECT_EQ(master.rd<uint16_t>(0x0440) & 0x0001, 0);  // the ESC's watchdog did expire
}

TEST_F(Faults, Sm2LengthUnchecked) {
    restart({});
    go_preop();
    configure_process_data(4, 6);  // RxPDO is 6 bytes
    request(0x04);
    EXPECT_EQ(al_status(), 0x02 | kErr);
    EXPECT_EQ(al_code(), 0x001D);

    StackFaults f;
    f.sm2_length_unchecked = true;
    restart(f);
    go_preop();
    configure_process_data(4, 6);
    request(0x04);
    EXPECT_EQ(al_status(), 0x04);
    // Only SM2's length: a wrong SM3 length is still refused with 0x001E.
    restart(f);
    go_preop();
    configure_process_data(6, 4);
    request(0x04);
    EXPECT_EQ(al_status(), 0x02 | kErr);
    EXPECT_EQ(al_code(), 0x001E);
}

TEST_F(Faults, InputsOpOnly) {
    for (const bool faulty : {false, true}) {
        SCOPED_TRACE(faulty ? "faulty" : "clean");
        StackFaults f;
        f.inputs_op_only = faulty;
        restart(f);
        dict.set<int32_t>(0x6064, 0, 0x01020304);
        go_safeop();
        std::vector<uint8_t> in(6);
        exchange_pd(outputs(0, 0), in);
        poll();
        exchange_pd(outputs(0, 0), in);
        EXPECT_EQ(in[2], faulty ? 0x00 : 0x04) << "inputs in Safe-Op";
        request(0x08);
        ASSERT_EQ(al_status(), 0x08);
        exchange_pd(outputs(0, 0), in);
        poll();
        exchange_pd(outputs(0, 0), in);
        EXPECT_EQ(in[2], 0x04) << "inputs in Op";
        EXPECT_EQ(in[5], 0x01);
    }
}

TEST_F(Faults, OutputsInSafeOp) {
    for (const bool faulty : {false, true}) {
        SCOPED_TRACE(faulty ? "faulty" : "clean");
        StackFaults f;
        f.outputs_in_safe_op = faulty;
        restart(f);
        go_safeop();
        std::vector<uint8_t> in(6);
        exchange_pd(outputs(0x000F, 5), in);
        poll();
        EXPECT_EQ(dict.get<uint16_t>(0x6040, 0), faulty ? 0x000F : 0x0000);
        EXPECT_EQ(dict.get<int32_t>(0x607A, 0), faulty ? 5 : 0);
    }
}

TEST_F(Faults, MailboxCounterIgnored) {
    for (const bool faulty : {false, true}) {
        SCOPED_TRACE(faulty ? "faulty" : "clean");
        StackFaults f;
        f.mailbox.counter_ignored = faulty;
        restart(f);
        go_preop();
        ASSERT_FALSE(roundtrip(mbx_message(0x3, 3, sdo)).empty());
        const auto again = roundtrip(mbx_message(0x3, 3, sdo));  // the same counter: a repeated request
        EXPECT_EQ(echo.handled, faulty ? 2 : 1);
        EXPECT_EQ(again.empty(), !faulty);
    }
}

TEST_F(Faults, MailboxRepeatIgnored) {
    for (const bool faulty : {false, true}) {
        SCOPED_TRACE(faulty ? "faulty" : "clean");
        StackFaults f;
        f.mailbox.repeat_ignored = faulty;
        restart(f);
        go_preop();
        const auto first = roundtrip(mbx_message(0x3, 1, sdo));  // "lost" on its way back
        ASSERT_FALSE(first.empty());
        master.wr<uint8_t>(0x080E, 0x01 | 0x02);  // repeat request
        poll();
        EXPECT_EQ(master.rd<uint8_t>(0x080F) & 0x02, faulty ? 0x00 : 0x02);  // repeat acknowledge
        const auto again = mbx_read();
        if (faulty) {
            EXPECT_TRUE(again.empty());
        } else {
            EXPECT_EQ(again, first);
        }
        EXPECT_EQ(echo.handled, 1);
    }
}

TEST_F(Faults, MailboxUnsupportedSilent) {
    const std::vector<uint8_t> eoe{0x00, 0x00, 0x00, 0x00};
    for (const bool faulty : {false, true}) {
        SCOPED_TRACE(faulty ? "faulty" : "clean");
        StackFaults f;
        f.mailbox.unsupported_protocol_silent = faulty;
        restart(f);
        go_preop();
        const auto reply = roundtrip(mbx_message(0x2, 1, eoe));  // EoE: not supported
        if (faulty) {
            EXPECT_TRUE(reply.empty());
        } else {
            ASSERT_GE(reply.size(), 10u);
            EXPECT_EQ(reply[5] & 0x0F, 0);  // mailbox error
            EXPECT_EQ(reply[8] | (reply[9] << 8), 0x0002);
        }
        // Other header errors are still answered: channel != 0.
        const auto channel = roundtrip(mbx_message(0x3, 2, sdo, 0, 1));
        ASSERT_GE(channel.size(), 10u);
        EXPECT_EQ(channel[8] | (channel[9] << 8), 0x0003);
    }
}

}  // namespace
}  // namespace ecat::test
