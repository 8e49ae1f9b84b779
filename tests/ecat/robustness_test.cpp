// Bad input never crashes or corrupts: random AL control values, SM configurations, mailbox messages,
// process-data frames and time steps, with a fixed seed; after every poll the AL status must be a valid
// state that matches the stack's own, and the error flag must come with a non-zero code.
#include <random>

#include "fixture.hpp"

namespace ecat::test {
namespace {

class EchoCoe : public MailboxHandler {
  public:
    MailboxType type() const override { return MailboxType::CoE; }
    bool available(od::AlState s) const override { return s != od::AlState::Init && s != od::AlState::Boot; }
    void handle(std::span<const uint8_t> payload, MailboxSender& out) override {
        out.send(MailboxType::CoE, payload.subspan(0, std::min(payload.size(), out.max_payload())));
    }
};

using Robustness = StackTest;

TEST_F(Robustness, RandomMasterNeverBreaksTheStack) {
    EchoCoe coe;
    stack->add_handler(coe);
    std::mt19937 rng(12345);
    auto rnd = [&](uint32_t n) { return static_cast<uint32_t>(rng() % n); };
    const uint16_t states[] = {0x01, 0x02, 0x03, 0x04, 0x08, 0x11, 0x12, 0x14, 0x18, 0x21, 0x05, 0x0F, 0x00};
    int reached_op = 0;
    for (int i = 0; i < 4000; ++i) {
        switch (rnd(8)) {
            case 0:
                request(states[rnd(sizeof states / sizeof states[0])]);
                break;
            case 1: {
                const unsigned n = rnd(4);
                const uint16_t starts[] = {0x1000, 0x1080, kSm2Start, kSm3Start, 0x1100};
                const uint16_t lengths[] = {0, 1, 6, 128, 256, 3};
                const uint8_t controls[] = {0x26, 0x22, 0x64, 0x20, 0x00, 0x02, 0x66};
                configure_sm(n, starts[rnd(5)], lengths[rnd(6)], controls[rnd(7)], rnd(4) != 0);
                break;
            }
            case 2: {
                std::vector<uint8_t> m(rnd(140));
                for (auto& b : m)
                    b = static_cast<uint8_t>(rng());
                if (m.size() >= 6 && rnd(2)) {
                    m[5] = static_cast<uint8_t>((m[5] & 0xF0) | 0x03);
                    m[4] = 0;
                }
                const uint16_t sm0_len = master.rd<uint16_t>(0x0802);
                std::vector<uint8_t> full(sm0_len, 0);
                std::copy(m.begin(), m.begin() + std::min<std::size_t>(m.size(), full.size()), full.begin());
                master.write(master.rd<uint16_t>(0x0800), full);
                break;
            }
            case 3: {
                std::vector<uint8_t> out(6), in(6);
                for (auto& b : out)
                    b = static_cast<uint8_t>(rng());
                exchange_pd(out, in);
                break;
            }
            case 4:
                mbx_read();
                break;
            case 5:
                master.wr<uint8_t>(0x080E, static_cast<uint8_t>(rng() & 0x03));
                break;
            case 6: {
                const uint16_t regs[] = {0x0981, 0x09A0, 0x0420, 0x0400};
                const uint16_t r = regs[rnd(4)];
                if (r == 0x0981)
                    master.wr<uint8_t>(r, static_cast<uint8_t>(rng()));
                else if (r == 0x09A0)
                    master.wr<uint32_t>(r, rnd(3'000'000));
                else
                    master.wr<uint16_t>(r, static_cast<uint16_t>(rnd(2000)));
                break;
            }
            default:
                if (rnd(8) == 0) {
                    // A well-behaved master brings the slave to Op, so the random steps also hit Op.
                    request(0x11);
                    configure_mailbox();
                    request(0x12);
                    master.wr<uint8_t>(0x0981, 0);
                    master.wr<uint16_t>(0x0420, 1000);
                    configure_process_data(6, 6);
                    request(0x14);
                    std::vector<uint8_t> out(6), in(6);
                    exchange_pd(out, in);
                    poll();
                    request(0x18);
                }
                break;
        }
        clock.advance(rnd(3'000'000));
        poll();
        const uint16_t status = al_status();
        const unsigned s = status & 0x0F;
        ASSERT_TRUE(s == 1 || s == 2 || s == 3 || s == 4 || s == 8) << "iteration " << i;
        ASSERT_EQ(s, static_cast<unsigned>(stack->state())) << "iteration " << i;
        if (status & 0x10) {
            ASSERT_NE(al_code(), 0) << "iteration " << i;
        }
        if (s == 8) ++reached_op;
    }
    RecordProperty("iterations_in_op", reached_op);
    EXPECT_GT(reached_op, 0);  // the walk did exercise Op
}

}  // namespace
}  // namespace ecat::test
