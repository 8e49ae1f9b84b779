// Cost of the firmware side per cycle: Stack::poll() after an LRW in Op (SM-synchronous), measured with
// steady_clock and reported as a test property; the bound only catches gross regressions.
#include <algorithm>
#include <chrono>

#include "fixture.hpp"

namespace ecat::test {
namespace {

using Perf = StackTest;

TEST_F(Perf, OpCyclePollCost) {
    go_op();
    std::vector<uint8_t> out(6, 0), in(6, 0);
    constexpr int kCycles = 20000;
    std::vector<int64_t> samples;
    samples.reserve(kCycles);
    for (int i = 0; i < kCycles; ++i) {
        clock.advance(1'000'000);
        out[2] = static_cast<uint8_t>(i);
        exchange_pd(out, in);
        esc->tick();
        const auto t0 = std::chrono::steady_clock::now();
        stack->poll(clock.now_ns());
        const auto t1 = std::chrono::steady_clock::now();
        samples.push_back(std::chrono::duration_cast<std::chrono::nanoseconds>(t1 - t0).count());
    }
    std::sort(samples.begin(), samples.end());
    const int64_t median = samples[kCycles / 2];
    const int64_t p99 = samples[kCycles * 99 / 100];
    RecordProperty("poll_median_ns", std::to_string(median));
    RecordProperty("poll_p99_ns", std::to_string(p99));
    std::printf("Stack::poll in Op (SM-sync, 6+6 bytes): median %lld ns, p99 %lld ns\n",
                static_cast<long long>(median), static_cast<long long>(p99));
    EXPECT_EQ(app.cycles >= kCycles, true);
    EXPECT_LT(median, 100'000);
}

}  // namespace
}  // namespace ecat::test
