// The runtime in segment mode allocates nothing per frame: frames walked through a line of ESCs, replies
// held by a delayed hop and released by the timer, the firmware of every device polled after each burst.
#include <gtest/gtest.h>

#include <array>
#include <memory>
#include <vector>

#include "esc/esc.hpp"
#include "esc/link_loopback.hpp"
#include "esc/segment.hpp"
#include "esc/wire/frame_builder.hpp"
#include "slave/runtime.hpp"
#include "support/alloc_counter.hpp"

namespace {

struct NullFirmware : slave::Firmware {
    void poll(uint64_t) override { ++polls; }
    int polls = 0;
};

TEST(SegmentRuntimeAllocation, WalkingHoldingAndReleasingAllocateNothing) {
    esc::SystemClock clock;
    auto links = esc::LoopbackLink::make_pair(256);
    std::vector<std::unique_ptr<esc::Esc>> escs;
    esc::Segment segment;
    for (int k = 0; k < 10; ++k) {
        escs.push_back(std::make_unique<esc::Esc>(esc::EscConfig{}, clock));
        segment.add(*escs.back());
        if (k > 0) segment.connect(k - 1, 1, k, 0);
    }
    slave::Runtime runtime(*links.second, segment, clock);
    NullFirmware fw;
    runtime.set_firmware(&fw);
    const std::vector<std::vector<uint8_t>> frames = {
        esc::wire::FrameBuilder().add_zero(esc::Command::BRD, 0, 0, 0x0000, 1).build(),
        esc::wire::FrameBuilder().add_zero(esc::Command::APRD, 0, 0, 0x0130, 2).build(),
        esc::wire::FrameBuilder().add_zero(esc::Command::LRW, 0, 0, 0x0000, 32).build(),
        esc::wire::FrameBuilder().add_zero(esc::Command::FRMW, 0, 0x1001, 0x0910, 8).build(),
    };
    std::array<uint8_t, esc::kMaxFrameSize> sink{};
    auto exchange_all = [&](int rounds) {
        for (int r = 0; r < rounds; ++r)
            for (const auto& f : frames)
                ASSERT_TRUE(links.first->send(f));
        std::size_t got = 0;
        for (int i = 0; i < 100000 && got < rounds * frames.size(); ++i) {
            ASSERT_TRUE(runtime.run_once(10));
            while (links.first->receive(sink) > 0)
                ++got;
        }
        ASSERT_EQ(got, rounds * frames.size());
    };
    esc::HopFaults delayed;
    delayed.hold_ns = 200'000;                 // replies held 200 us
    ASSERT_NO_FATAL_FAILURE(exchange_all(1));  // warm-up
    segment.set_hop_faults(5, delayed);
    ASSERT_NO_FATAL_FAILURE(exchange_all(1));
    const uint64_t held_before = runtime.stats().frames_held;
    {
        const alloc_counter::Scope counting;
        ASSERT_NO_FATAL_FAILURE(exchange_all(20));
        EXPECT_EQ(counting.count(), 0u) << "with a delayed hop";
    }
    EXPECT_EQ(runtime.stats().frames_held, held_before + 20 * frames.size());
    segment.set_hop_faults(5, esc::HopFaults{});
    {
        const alloc_counter::Scope counting;
        ASSERT_NO_FATAL_FAILURE(exchange_all(20));
        EXPECT_EQ(counting.count(), 0u) << "without";
    }
    EXPECT_GT(fw.polls, 0);
}

}  // namespace
