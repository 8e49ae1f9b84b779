// Hot paths allocate nothing: the process-data cycle and a mailbox request/reply, counted with the counting
// global operator new (tests/support/alloc_counter.hpp) while only Stack::poll() runs.

#include "fixture.hpp"
#include "support/alloc_counter.hpp"

namespace ecat::test {
namespace {

// Answers each CoE request with a fixed 10-byte payload from a member buffer.
class StaticHandler : public MailboxHandler {
  public:
    MailboxType type() const override { return MailboxType::CoE; }
    bool available(od::AlState s) const override { return s != od::AlState::Init; }
    void handle(std::span<const uint8_t>, MailboxSender& out) override {
        ++handled;
        out.send(MailboxType::CoE, reply_);
    }
    int handled = 0;

  private:
    uint8_t reply_[10] = {0x00, 0x30, 0x43, 0x00, 0x10, 0x00, 1, 2, 3, 4};
};

class Alloc : public StackTest {
  protected:
    std::size_t counted_poll() {
        esc->tick();
        const alloc_counter::Scope counting;
        stack->poll(clock.now_ns());
        return counting.count();
    }
};

TEST_F(Alloc, CycleAndMailboxAllocateNothing) {
    StaticHandler coe;
    stack->add_handler(coe);
    go_op();
    std::vector<uint8_t> out(6, 0), in(6, 0);
    const std::vector<uint8_t> sdo{0x00, 0x20, 0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0};
    std::size_t total = 0;
    const int cycles_before = app.cycles;
    for (int i = 0; i < 50; ++i) {
        clock.advance(1'000'000);
        out[2] = static_cast<uint8_t>(i);
        exchange_pd(out, in);
        if (i % 10 == 0) mbx_write(mbx_message(0x3, static_cast<uint8_t>(i / 10 % 7 + 1), sdo));
        total += counted_poll();
        if (i % 10 == 1) {
            EXPECT_FALSE(mbx_read().empty());
        }
    }
    EXPECT_EQ(total, 0u);
    EXPECT_EQ(app.cycles - cycles_before, 50);
    EXPECT_EQ(coe.handled, 5);
}

}  // namespace
}  // namespace ecat::test

namespace ecat::test {
namespace {

TEST(AllocCounter, CountsAllocations) {
    const alloc_counter::Scope counting;
    // volatile: the pointer escapes, so the compiler cannot elide the new/delete pair.
    std::vector<int>* volatile p = new std::vector<int>(4);
    const auto allocations = counting.count();
    delete p;
    EXPECT_GE(allocations, 2u);
}

}  // namespace
}  // namespace ecat::test
