// The per-frame path allocates nothing: counts global operator new calls around the runtime's handling of
// frames (LoopbackLink -> Esc::process_frame -> send -> capture -> tick -> firmware).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <utility>
#include <vector>

#include "esc/esc.hpp"
#include "esc/link_capture.hpp"
#include "esc/link_loopback.hpp"
#include "esc/wire/frame_builder.hpp"
#include "slave/runtime.hpp"
#include "support/alloc_counter.hpp"

namespace {

// One datagram of len zero bytes (index 0), padded to the minimum frame size.
std::vector<uint8_t> frame_with(uint8_t cmd, uint16_t adp, uint16_t ado, std::size_t len) {
    return esc::wire::FrameBuilder().add_zero(cmd, 0, adp, ado, len).build();
}

// A runtime over a loopback link with a real ESC; `master` is the other end.
struct LoopbackSlave {
    LoopbackSlave()
        : links(esc::LoopbackLink::make_pair(256)),
          esc(esc::EscConfig{}, clock),
          runtime(*links.second, esc, clock) {}
    esc::LoopbackLink& master() { return *links.first; }
    esc::LoopbackLink& slave_end() { return *links.second; }
    std::pair<std::unique_ptr<esc::LoopbackLink>, std::unique_ptr<esc::LoopbackLink>> links;
    esc::SystemClock clock;
    esc::Esc esc;
    slave::Runtime runtime;
};

struct NullFirmware : slave::Firmware {
    void poll(uint64_t) override { ++polls; }
    int polls = 0;
};

TEST(RuntimeAllocation, HandlingFramesAllocatesNothing) {
    LoopbackSlave s;
    auto& runtime = s.runtime;
    NullFirmware fw;
    runtime.set_firmware(&fw);
    const std::string path =
        (std::filesystem::temp_directory_path() / ("alloc-capture-" + std::to_string(::getpid()) + ".pcap"))
            .string();
    esc::PcapWriter capture(path);
    runtime.set_capture(&capture);
    const std::vector<std::vector<uint8_t>> frames = {
        frame_with(7, 0, 0x0000, 1),    // BRD type
        frame_with(1, 0, 0x0130, 2),    // APRD AL status
        frame_with(8, 0, 0x1000, 64),   // BWR process RAM
        frame_with(12, 0, 0x0000, 32),  // LRW without FMMUs
        frame_with(4, 0, 0x0910, 8),    // FPRD system time
        frame_with(14, 0, 0x0910, 8),   // FRMW system time
    };
    // Warm up once (first-use allocations of the ESC, if any, are not per-frame).
    for (const auto& f : frames)
        ASSERT_TRUE(s.master().send(f));
    ASSERT_TRUE(runtime.run_once(1000));
    std::vector<uint8_t> sink(esc::kMaxFrameSize);
    while (s.master().receive(sink) > 0) {
    }

    for (int round = 0; round < 20; ++round)
        for (const auto& f : frames)
            ASSERT_TRUE(s.master().send(f));
    const alloc_counter::Scope counting;
    while (s.slave_end().pending() > 0)
        ASSERT_TRUE(runtime.run_once(1000));
    EXPECT_EQ(counting.count(), 0u) << "allocations while handling " << 20 * frames.size() << " frames";
    EXPECT_EQ(runtime.stats().frames_sent, 21 * frames.size());
    EXPECT_GT(fw.polls, 0);
    runtime.set_capture(nullptr);
    std::remove(path.c_str());
}

// The other ways of waiting (--spin-us, --busy-poll) allocate nothing either, frames and deadlines alike.
struct TickingFirmware : slave::Firmware {
    void poll(uint64_t now) override {
        ++polls;
        next = now + 200'000;  // a cycle every 200 us
    }
    uint64_t next_deadline_ns() const override { return next; }
    int polls = 0;
    uint64_t next = 0;
};

TEST(RuntimeAllocation, SpinningAndBusyPollingAllocateNothing) {
    for (const bool busy : {false, true}) {
        LoopbackSlave s;
        auto& runtime = s.runtime;
        TickingFirmware fw;
        runtime.set_firmware(&fw);
        if (busy)
            runtime.set_busy_poll(true);
        else
            runtime.set_spin(150'000);
        const auto f = frame_with(12, 0, 0x0000, 32);  // LRW
        ASSERT_TRUE(s.master().send(f));
        for (int i = 0; i < 100; ++i)
            ASSERT_TRUE(runtime.run_once(10));  // warm-up
        std::vector<uint8_t> sink(esc::kMaxFrameSize);
        while (s.master().receive(sink) > 0) {
        }
        for (int i = 0; i < 100; ++i)
            ASSERT_TRUE(s.master().send(f));
        const int polls_before = fw.polls;
        const alloc_counter::Scope counting;
        for (int i = 0; i < 100000 && (s.slave_end().pending() > 0 || fw.polls < polls_before + 20); ++i)
            ASSERT_TRUE(runtime.run_once(10));
        EXPECT_EQ(counting.count(), 0u) << (busy ? "busy-poll" : "spin");
        EXPECT_EQ(s.slave_end().pending(), 0u);
        EXPECT_GE(fw.polls, polls_before + 20);
        if (!busy) {
            EXPECT_GT(runtime.stats().spin_waits, 0u);
        }
        runtime.set_firmware(nullptr);
    }
}

}  // namespace
