// Cycle timing measured by the stack: the fixed-size latency histogram, the lateness of each DC cycle
// against its SYNC0 pulse (0x0910 vs. 0x0990 - 0x09A0), and the SM2-event-to-cycle latency (0x09F0).
#include <ostream>
#include <sstream>

#include "ecat/latency.hpp"
#include "fixture.hpp"

namespace ecat::test {
namespace {

TEST(LatencyHistogram, EmptyGivesZeros) {
    LatencyHistogram h;
    EXPECT_EQ(h.count(), 0u);
    EXPECT_EQ(h.percentile_ns(0.5), 0u);
    EXPECT_EQ(h.percentile_ns(0.99), 0u);
    EXPECT_EQ(h.max_ns(), 0u);
    EXPECT_EQ(h.min_ns(), 0u);
    EXPECT_EQ(h.mean_ns(), 0u);
}

TEST(LatencyHistogram, SingleSampleIsExact) {
    LatencyHistogram h;
    h.add(1234);
    EXPECT_EQ(h.percentile_ns(0.5), 1234u);  // bin edge clamped to the exact min/max
    EXPECT_EQ(h.percentile_ns(0.99), 1234u);
    EXPECT_EQ(h.max_ns(), 1234u);
}

TEST(LatencyHistogram, PercentilesWithinOneBin) {
    LatencyHistogram h;
    for (uint64_t us = 1; us <= 100; ++us)
        h.add(us * 1000);  // 1 us .. 100 us
    EXPECT_EQ(h.count(), 100u);
    // Nearest rank: p50 is the 50th sample (50 us), p99 the 99th (99 us); a bin is 100 ns wide.
    EXPECT_GE(h.percentile_ns(0.5), 50'000u);
    EXPECT_LT(h.percentile_ns(0.5), 50'100u);
    EXPECT_GE(h.percentile_ns(0.99), 99'000u);
    EXPECT_LT(h.percentile_ns(0.99), 99'100u);
    EXPECT_EQ(h.percentile_ns(1.0), 100'000u);
    EXPECT_EQ(h.min_ns(), 1'000u);
    EXPECT_EQ(h.mean_ns(), 50'500u);
}

TEST(LatencyHistogram, CoarseRangeAndOverflow) {
    LatencyHistogram h;
    for (int i = 0; i < 98; ++i)
        h.add(2'000);
    h.add(5'000'123);       // coarse bins: 10 us wide
    h.add(20'000'000'000);  // 20 s: overflow, max still exact
    EXPECT_EQ(h.overflow(), 1u);
    EXPECT_EQ(h.max_ns(), 20'000'000'000u);
    EXPECT_LT(h.percentile_ns(0.98), 2'100u);
    EXPECT_GE(h.percentile_ns(0.99), 5'000'123u);
    EXPECT_LT(h.percentile_ns(0.99), 5'010'000u);
    EXPECT_EQ(h.percentile_ns(1.0), 20'000'000'000u);
    // Out-of-range quantiles are clamped.
    EXPECT_EQ(h.percentile_ns(-1.0), 2'000u);
    EXPECT_EQ(h.percentile_ns(7.0), 20'000'000'000u);
}

TEST(LatencyHistogram, PrintsKeyValueLines) {
    LatencyHistogram h;
    h.add(700);
    std::ostringstream out;
    h.print(out, "x");
    EXPECT_NE(out.str().find("x.count 1\n"), std::string::npos);
    EXPECT_NE(out.str().find("x.p99_ns 700\n"), std::string::npos);
    EXPECT_NE(out.str().find("x.max_ns 700\n"), std::string::npos);
}

class CycleTiming : public StackTest {
  protected:
    static constexpr uint32_t kCycle = 1'000'000;
    // DC SYNC0 as masters set it up; returns the clock time of the first pulse.
    uint64_t safeop_dc() {
        go_preop();
        configure_process_data(6, 6);
        master.wr<uint8_t>(0x0980, 0);
        master.wr<uint32_t>(0x09A0, kCycle);
        const uint64_t sys = master.rd<uint64_t>(0x0910);
        const uint64_t clock_minus_sys = clock.now_ns() - sys;
        master.wr<uint64_t>(0x0990, sys + 2'000'000);
        master.wr<uint8_t>(0x0981, 0x03);
        request(0x04);
        EXPECT_EQ(al_status(), 0x04) << std::hex << al_code();
        return sys + 2'000'000 + clock_minus_sys;
    }
};

TEST_F(CycleTiming, Dc_LatenessAgainstSync0Pulse) {
    const uint64_t first = safeop_dc();
    std::vector<uint8_t> out(6), in(6);
    // The runtime wakes 3 us after each pulse for 10 pulses.
    for (int k = 0; k < 10; ++k) {
        clock.set(first + k * uint64_t{kCycle} + 3'000);
        exchange_pd(out, in);
        poll();
    }
    const auto& h = stack->stats().sync0_latency;
    EXPECT_EQ(h.count(), 10u);
    EXPECT_EQ(h.min_ns(), 3'000u);
    EXPECT_EQ(h.max_ns(), 3'000u);
    EXPECT_EQ(h.percentile_ns(0.99), 3'000u);
    // One wake-up 250 us late: it is the max, p50 stays.
    clock.set(first + 10 * uint64_t{kCycle} + 250'000);
    poll();
    EXPECT_EQ(h.count(), 11u);
    EXPECT_EQ(h.max_ns(), 250'000u);
    EXPECT_GE(h.percentile_ns(0.5), 3'000u);  // within its 100 ns bin
    EXPECT_LT(h.percentile_ns(0.5), 3'100u);
    EXPECT_EQ(stack->stats().cycles_exceeded, 0u);
}

TEST_F(CycleTiming, Dc_MissedPeriodsCountedLatenessFromLatestPulse) {
    const uint64_t first = safeop_dc();
    clock.set(first + 1'000);
    poll();
    // Stalled for three periods: the cycle follows the latest pulse, two periods had no cycle.
    clock.set(first + 3 * uint64_t{kCycle} + 7'000);
    poll();
    const auto& s = stack->stats();
    EXPECT_EQ(s.cycles_exceeded, 2u);
    EXPECT_EQ(s.sync0_latency.count(), 2u);
    EXPECT_EQ(s.sync0_latency.max_ns(), 7'000u);
    EXPECT_EQ(s.sync0_latency.min_ns(), 1'000u);
}

TEST_F(CycleTiming, Dc_NoSampleWithoutCycle) {
    safeop_dc();
    poll();  // before the first pulse
    EXPECT_EQ(stack->stats().sync0_latency.count(), 0u);
    EXPECT_EQ(stack->stats().sm2_latency.count(), 0u);
}

// The soft ESC latches 0x09F0 (local time of the start of the frame that changed an SM buffer): the stack's
// SM2-to-cycle latency is the local time at the cycle start minus that.
TEST_F(CycleTiming, SmSync_LatencyFromBufferChangeTime) {
    go_op();
    ASSERT_EQ(stack->sync_mode(), SyncMode::SmSync);
    std::vector<uint8_t> out(6), in(6);
    master.wr<uint64_t>(0x0920, 5'000'000'000ull);  // the master's clock offset: local time = system - offset
    const uint64_t before = stack->stats().sm2_latency.count();
    for (int k = 0; k < 5; ++k) {
        clock.advance(1'000'000);  // the next cycle's frame
        exchange_pd(out, in);
        clock.advance(4'000 + 1'000 * static_cast<uint64_t>(k));  // the firmware runs 4..8 us later
        poll();
    }
    const auto& h = stack->stats().sm2_latency;
    EXPECT_EQ(h.count() - before, 5u);
    EXPECT_EQ(h.max_ns(), 8'000u);
    // A poll without a new buffer change takes no sample.
    clock.advance(100'000);
    poll();
    EXPECT_EQ(h.count() - before, 5u);
}

// An ESC that does not latch 0x09F0 (reads 0 there, as some do): the stack takes no samples rather than
// nonsense ones.
class PdiWithout09F0 : public esc::Pdi {
  public:
    explicit PdiWithout09F0(esc::Esc& e) : esc_(e) {}
    void read(uint16_t address, std::span<uint8_t> out) override {
        esc_.read(address, out);
        for (std::size_t i = 0; i < out.size(); ++i) {
            const unsigned a = address + i;
            if (a >= 0x09F0 && a < 0x09F4) out[i] = 0;
        }
    }
    void write(uint16_t address, std::span<const uint8_t> in) override { esc_.write(address, in); }

  private:
    esc::Esc& esc_;
};

TEST_F(CycleTiming, SmSync_EscWithout0x09F0_NoSamples) {
    PdiWithout09F0 pdi(*esc);
    stack = std::make_unique<Stack>(pdi, dict, desc, app, [this] { return esc->irq(); });
    poll();
    go_op();
    std::vector<uint8_t> out(6), in(6);
    for (int k = 0; k < 5; ++k) {
        exchange_pd(out, in);
        clock.advance(10'000);
        poll();
    }
    EXPECT_GE(stack->stats().cycles, 5u);
    EXPECT_EQ(stack->stats().sm2_latency.count(), 0u);
}

TEST_F(CycleTiming, ReportPrintsStackLines) {
    const uint64_t first = safeop_dc();
    clock.set(first + 2'500);
    poll();
    std::ostringstream out;
    stack->report(out);
    EXPECT_NE(out.str().find("stack.sync0_events 1\n"), std::string::npos) << out.str();
    EXPECT_NE(out.str().find("stack.sync0_latency.count 1\n"), std::string::npos) << out.str();
    EXPECT_NE(out.str().find("stack.sync0_latency.max_ns 2500\n"), std::string::npos) << out.str();
}

}  // namespace
}  // namespace ecat::test
