// The slave runtime takes each frame at its arrival (the link's receive time stamp), not when it gets to it:
// a slave process stopped or descheduled while the master's frames keep coming must look, to the master, like
// an ESC whose firmware paused. The ESC saw every write when it came: its process-data watchdog, refreshed by
// each frame in time, does not expire, and its SYNC0 pulses come in order with the frames (ESC datasheet,
// watchdogs 0x0400/0x0420 and distributed clocks 0x0990/0x09A0).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <deque>
#include <functional>
#include <vector>

#include "esc/clock.hpp"
#include "esc/esc.hpp"
#include "esc/link.hpp"
#include "esc/wire/datagram.hpp"
#include "esc/wire/frame_builder.hpp"
#include "slave/firmware.hpp"
#include "slave/runtime.hpp"

namespace {

// The link's time base: as far from the runtime's clock as CLOCK_REALTIME is from CLOCK_MONOTONIC.
constexpr uint64_t kStampBase = 1'700'000'000'000'000'000ull;

// A link whose frames carry receive time stamps, on a time base of their own (the ManualClock + kStampBase).
// No descriptor: the runtime looks at it on every pass.
class StampedLink final : public esc::Link {
  public:
    explicit StampedLink(const esc::ManualClock& clock) : clock_(clock) {}
    int fd() const override { return -1; }
    std::size_t receive(std::span<uint8_t> buf) override {
        if (queue_.empty()) return 0;
        const Queued& q = queue_.front();
        const std::size_t n = std::min(q.frame.size(), buf.size());
        std::memcpy(buf.data(), q.frame.data(), n);
        stamp_ = q.stamp;
        queue_.pop_front();
        return n;
    }
    bool send(std::span<const uint8_t> frame) override {
        sent.emplace_back(frame.begin(), frame.end());
        return true;
    }
    uint64_t rx_stamp_ns() const override { return stamp_; }
    uint64_t stamp_now_ns() const override { return clock_.now_ns() + kStampBase; }
    // A frame that arrived at clock time `at`.
    void arrive(std::vector<uint8_t> frame, uint64_t at) {
        queue_.push_back({std::move(frame), at + kStampBase});
    }

    std::vector<std::vector<uint8_t>> sent;

  private:
    struct Queued {
        std::vector<uint8_t> frame;
        uint64_t stamp;
    };
    const esc::ManualClock& clock_;
    std::deque<Queued> queue_;
    uint64_t stamp_ = 0;
};

// Firmware that, once armed, stops the process in its poll: the clock jumps and frames arrive meanwhile.
struct StoppingFirmware : slave::Firmware {
    void poll(uint64_t) override {
        if (!stop) return;
        auto s = std::move(stop);
        stop = nullptr;
        s();
    }
    std::function<void()> stop;
};

constexpr uint16_t kOutputs = 0x1100;
constexpr uint64_t kMs = 1'000'000;
constexpr uint64_t kT0 = 1'000 * kMs;
constexpr uint64_t kSync0Start = kT0 + 5 * kMs;
constexpr uint32_t kSync0Cycle = 20 * kMs;

std::vector<uint8_t> le_bytes(uint64_t v, std::size_t n) {
    std::vector<uint8_t> b(n);
    for (std::size_t i = 0; i < n; ++i)
        b[i] = static_cast<uint8_t>(v >> (8 * i));
    return b;
}

std::vector<uint8_t> apwr_frame(uint16_t ado, const std::vector<uint8_t>& data) {
    return esc::wire::FrameBuilder().add(esc::Command::APWR, 0, 0, ado, data).build();
}

// A cycle's frame: the outputs (the watchdog is refreshed) and a read of the next SYNC0 time (0x0990).
std::vector<uint8_t> cycle_frame(uint8_t n) {
    const std::vector<uint8_t> out{n, 0, 0, 0};
    return esc::wire::FrameBuilder()
        .add(esc::Command::APWR, n, 0, kOutputs, out)
        .add_zero(esc::Command::APRD, n, 0, 0x0990, 8)
        .build();
}

// The next SYNC0 time a cycle frame's reply read, 0 if the reply is not one.
uint64_t next_sync0_read(const std::vector<uint8_t>& reply) {
    esc::wire::DatagramReader r(reply);
    esc::wire::DatagramView v;
    if (!r.next(v) || !r.next(v) || v.data.size() != 8 || v.wkc != 1) return 0;
    uint64_t t = 0;
    for (std::size_t i = 0; i < 8; ++i)
        t |= static_cast<uint64_t>(v.data[i]) << (8 * i);
    return t;
}

TEST(RuntimeArrival, FramesThatCameWhileTheProcessWasStoppedAreTakenWhenTheyCame) {
    esc::ManualClock clock;
    clock.set(kT0);
    esc::Esc e(esc::EscConfig{}, clock);
    // Set up as a master does before OP: the outputs' SM with the watchdog trigger, the process-data watchdog
    // at 1000 x 100 us = 100 ms, SYNC0 every 20 ms from kSync0Start.
    for (const auto& f : {apwr_frame(0x0810, {0x00, 0x11, 4, 0, 0x64, 0, 1, 0}),
                          apwr_frame(0x0420, le_bytes(1000, 2)), apwr_frame(0x09A0, le_bytes(kSync0Cycle, 4)),
                          apwr_frame(0x0990, le_bytes(kSync0Start, 8)), apwr_frame(0x0981, {0x03})}) {
        auto frame = f;
        ASSERT_TRUE(e.process_frame(frame));
    }
    StampedLink link(clock);
    slave::Runtime runtime(link, e, clock);
    StoppingFirmware fw;
    runtime.set_firmware(&fw);

    // Cycle 0 arrives at kT0 and is served; then the process is stopped for 150 ms while cycles 1..15 arrive,
    // one every 10 ms: more than the watchdog's time without service, never more than 10 ms between writes.
    link.arrive(cycle_frame(0), kT0);
    std::vector<uint64_t> arrivals{kT0};
    fw.stop = [&] {
        for (uint8_t n = 1; n <= 15; ++n) {
            arrivals.push_back(kT0 + n * 10 * kMs);
            link.arrive(cycle_frame(n), arrivals.back());
        }
        clock.set(kT0 + 150 * kMs);
    };
    ASSERT_TRUE(runtime.run_once(0));
    ASSERT_FALSE(fw.stop) << "the process was stopped";
    // One more pass, as the loop would go on (nothing is left to do).
    ASSERT_TRUE(runtime.run_once(0));

    std::array<uint8_t, 2> status{};
    e.read(0x0440, std::span<uint8_t>(status.data(), 2));
    EXPECT_EQ(status[0] & 0x01, 0x01) << "process-data watchdog expired";
    std::array<uint8_t, 1> counter{};
    e.read(0x0442, counter);
    EXPECT_EQ(counter[0], 0) << "process-data watchdog expiries";

    // Every frame answered in order, each after the SYNC0 pulses due before it came and before those due
    // after: the next SYNC0 it read is the first one after its arrival.
    ASSERT_EQ(link.sent.size(), arrivals.size());
    for (std::size_t n = 0; n < arrivals.size(); ++n) {
        uint64_t next = kSync0Start;
        while (next <= arrivals[n])
            next += kSync0Cycle;
        EXPECT_EQ(link.sent[n][17], n) << "reply order";
        EXPECT_EQ(next_sync0_read(link.sent[n]), next)
            << "cycle " << n << " (arrived at +" << (arrivals[n] - kT0) / kMs << " ms)";
    }
}

}  // namespace
