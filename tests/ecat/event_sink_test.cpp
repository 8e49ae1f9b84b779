// The stack reports state changes, refused requests (with their AL status code), local errors and watchdog
// expiries to its EventSink (ecat/event_sink.hpp), and prints nothing itself.
#include <string>
#include <vector>

#include "ecat/event_sink.hpp"
#include "fixture.hpp"

namespace ecat::test {
namespace {

using od::AlState;

struct RecordingSink : EventSink {
    std::vector<std::string> calls;
    void state_changed(AlState from, AlState to) override {
        calls.push_back("changed " + std::to_string(int(from)) + "->" + std::to_string(int(to)));
    }
    void state_refused(AlState current, uint8_t requested, uint16_t code) override {
        calls.push_back("refused " + std::to_string(int(current)) + "->" + std::to_string(requested) + " " +
                        std::to_string(code));
    }
    void local_error(AlState state, uint16_t code) override {
        calls.push_back("error " + std::to_string(int(state)) + " " + std::to_string(code));
    }
    void watchdog_expired(AlState state) override {
        calls.push_back("watchdog " + std::to_string(int(state)));
    }
};

class StackEvents : public StackTest {
  protected:
    RecordingSink sink;
    void SetUp() override {
        start();
        stack->set_event_sink(&sink);
    }
};

TEST_F(StackEvents, StateChangeAndRefusedRequestsAreReportedWithTheirCode) {
    request(0x08);  // Init -> Op: invalid state change 0x0011
    ASSERT_EQ(sink.calls.size(), 1u);
    EXPECT_EQ(sink.calls[0], "refused 1->8 17");
    request(0x11);  // acknowledge, back to Init: no change
    request(0x0F);  // no such state: 0x0012
    ASSERT_EQ(sink.calls.size(), 2u);
    EXPECT_EQ(sink.calls[1], "refused 1->15 18");
    request(0x11);
    configure_mailbox();
    request(0x02);
    ASSERT_EQ(sink.calls.size(), 3u);
    EXPECT_EQ(sink.calls[2], "changed 1->2");
    request(0x01);
    ASSERT_EQ(sink.calls.size(), 4u);
    EXPECT_EQ(sink.calls[3], "changed 2->1");
}

TEST_F(StackEvents, WatchdogInOpIsReportedWithTheFallBackItCauses) {
    go_op();
    sink.calls.clear();
    advance(150'000'000);  // no SM2 write for longer than the 100 ms watchdog
    ASSERT_EQ(sink.calls.size(), 3u) << ::testing::PrintToString(sink.calls);
    EXPECT_EQ(sink.calls[0], "watchdog 8");
    EXPECT_EQ(sink.calls[1], "changed 8->4");
    EXPECT_EQ(sink.calls[2], "error 4 27");  // 0x001B
}

TEST_F(StackEvents, WatchdogOutsideOpIsNotReported) {
    go_safeop();
    std::vector<uint8_t> out(6, 0), in(6, 0);
    exchange_pd(out, in);
    sink.calls.clear();
    advance(150'000'000);
    EXPECT_TRUE(sink.calls.empty()) << ::testing::PrintToString(sink.calls);
}

TEST_F(StackEvents, WithoutASinkNothingIsReported) {
    stack->set_event_sink(nullptr);
    request(0x08);
    EXPECT_TRUE(sink.calls.empty());
    EXPECT_EQ(al_code(), 0x0011);
}

}  // namespace
}  // namespace ecat::test
