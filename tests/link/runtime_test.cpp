// The slave runtime (tools/lib/slave) over a LoopbackLink with a real esc::Esc.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <thread>
#include <vector>

#include "esc/esc.hpp"
#include "esc/link_capture.hpp"
#include "esc/link_loopback.hpp"
#include "esc/wire/frame_builder.hpp"
#include "netns_util.hpp"
#include "pcap_records.hpp"
#include "slave/netif.hpp"
#include "slave/runtime.hpp"

namespace {

// BRD of the ESC type register (0x0000, 1 byte): every ESC answers with WKC 1.
std::vector<uint8_t> brd_type_frame(std::size_t total = 60) {
    return esc::wire::FrameBuilder().add_zero(esc::Command::BRD, 0x42, 0, 0x0000, 1).build(total);
}
constexpr std::size_t kWkcOffset = 16 + 10 + 1;

struct RecordingFirmware : slave::Firmware {
    explicit RecordingFirmware(esc::LoopbackLink& master_end) : master(master_end) {}
    void poll(uint64_t now_ns) override {
        ++polls;
        last_now = now_ns;
        replies_waiting_at_poll = master.pending();
        if (deadline != 0 && now_ns >= deadline) deadline_hit = true;
    }
    uint64_t next_deadline_ns() const override {
        return deadline_hit || deadline == 0 ? UINT64_MAX : deadline;
    }

    esc::LoopbackLink& master;
    int polls = 0;
    uint64_t last_now = 0;
    std::size_t replies_waiting_at_poll = 0;
    uint64_t deadline = 0;
    bool deadline_hit = false;
};

struct Fixture : ::testing::Test {
    Fixture()
        : links(esc::LoopbackLink::make_pair()),
          esc(esc::EscConfig{}, clock),
          runtime(*links.second, esc, clock) {}
    esc::LoopbackLink& master() { return *links.first; }
    esc::SystemClock clock;
    std::pair<std::unique_ptr<esc::LoopbackLink>, std::unique_ptr<esc::LoopbackLink>> links;
    esc::Esc esc;
    slave::Runtime runtime;
};

using Runtime = Fixture;

TEST_F(Runtime, ProcessesAFrameAndSendsTheReplyBeforeTheFirmwareRuns) {
    RecordingFirmware fw(master());
    runtime.set_firmware(&fw);
    const auto f = brd_type_frame();
    ASSERT_TRUE(master().send(f));
    ASSERT_TRUE(runtime.run_once(1000));
    std::array<uint8_t, esc::kMaxFrameSize> buf{};
    ASSERT_EQ(master().receive(buf), f.size());
    EXPECT_EQ(buf[6], 0x03) << "source MAC bit 1 set by the ESC";
    EXPECT_EQ(buf[kWkcOffset], 1) << "BRD answered";
    EXPECT_EQ(fw.polls, 1);
    EXPECT_EQ(fw.replies_waiting_at_poll, 1u) << "the reply was already sent when the firmware ran";
    EXPECT_EQ(runtime.stats().frames_received, 1u);
    EXPECT_EQ(runtime.stats().frames_sent, 1u);
}

TEST_F(Runtime, ABurstOfFramesIsAnsweredInOrderThenTheFirmwareRunsOnce) {
    RecordingFirmware fw(master());
    runtime.set_firmware(&fw);
    for (uint8_t i = 0; i < 10; ++i) {
        auto f = brd_type_frame();
        f[17] = i;
        ASSERT_TRUE(master().send(f));
    }
    ASSERT_TRUE(runtime.run_once(1000));
    EXPECT_EQ(fw.polls, 1);
    EXPECT_EQ(fw.replies_waiting_at_poll, 10u);
    std::array<uint8_t, esc::kMaxFrameSize> buf{};
    for (uint8_t i = 0; i < 10; ++i) {
        ASSERT_EQ(master().receive(buf), 60u);
        EXPECT_EQ(buf[17], i);
    }
}

// A frame that arrives while the firmware works (here: between the two devices of a pass, and while the
// control socket is served) is answered before the work that follows, not after the whole pass.
TEST_F(Runtime, AFrameArrivingDuringTheFirmwaresWorkIsAnsweredBeforeTheNextPartOfIt) {
    struct TwoDevices : slave::Firmware {
        explicit TwoDevices(esc::LoopbackLink& m) : master(m) {}
        void poll(uint64_t) override {
            ++polls;
            if (polls != 2) return;
            const std::size_t waiting = master.pending();  // the reply to the frame before this poll
            ASSERT_TRUE(master.send(brd_type_frame()));    // comes in while device 0 works
            served = serve_frames();
            replies_before_device_1 = master.pending() - waiting;
        }
        esc::LoopbackLink& master;
        int polls = 0;
        int served = -1;
        std::size_t replies_before_device_1 = 0;
    } fw(master());
    runtime.set_firmware(&fw);
    ASSERT_TRUE(master().send(brd_type_frame()));
    ASSERT_TRUE(runtime.run_once(1000));  // poll 1 after the first frame
    std::array<uint8_t, esc::kMaxFrameSize> buf{};
    ASSERT_EQ(master().receive(buf), 60u);
    ASSERT_TRUE(master().send(brd_type_frame()));
    ASSERT_TRUE(runtime.run_once(1000));  // poll 2: a frame comes in between its two devices
    EXPECT_EQ(fw.served, 1);
    EXPECT_EQ(fw.replies_before_device_1, 1u) << "answered between the devices, not after the pass";
    EXPECT_EQ(runtime.stats().frames_before_work, 1u);
    EXPECT_EQ(runtime.stats().frames_received, 3u);
    EXPECT_EQ(runtime.stats().frames_sent, 3u);
    runtime.set_firmware(nullptr);
}

TEST_F(Runtime, RuntFramesComeBackAtTheirLength) {
    const auto f = brd_type_frame(29);
    ASSERT_TRUE(master().send(f));
    ASSERT_TRUE(runtime.run_once(1000));
    std::array<uint8_t, esc::kMaxFrameSize> buf{};
    ASSERT_EQ(master().receive(buf), 29u);
    EXPECT_EQ(buf[kWkcOffset], 1);
}

TEST_F(Runtime, NonEtherCatFramesAreNotSentBack) {
    auto f = brd_type_frame();
    f[12] = 0x08;
    f[13] = 0x00;
    ASSERT_TRUE(master().send(f));
    ASSERT_TRUE(runtime.run_once(1000));
    std::array<uint8_t, esc::kMaxFrameSize> buf{};
    EXPECT_EQ(master().receive(buf), 0u);
    EXPECT_EQ(runtime.stats().frames_dropped, 1u);
}

TEST_F(Runtime, TheTimerWakesTheFirmwareAtItsDeadlineWithoutFrames) {
    RecordingFirmware fw(master());
    fw.deadline = clock.now_ns() + 20'000'000;  // 20 ms
    runtime.set_firmware(&fw);
    const uint64_t start = clock.now_ns();
    int rounds = 0;
    while (!fw.deadline_hit && rounds < 100) {
        ASSERT_TRUE(runtime.run_once(2000));
        ++rounds;
    }
    EXPECT_TRUE(fw.deadline_hit);
    EXPECT_GE(fw.last_now, fw.deadline);
    EXPECT_LT(clock.now_ns() - start, 1'000'000'000ull) << "woken by the timer, not by the 2 s poll timeout";
    EXPECT_GE(runtime.stats().timer_expiries, 1u);
}

TEST_F(Runtime, TheTimerMovesEarlierAtOnceButLaterOnlyAfterFiring) {
    struct Movable : slave::Firmware {
        void poll(uint64_t now_ns) override { last = now_ns; }
        uint64_t next_deadline_ns() const override { return deadline; }
        uint64_t deadline = UINT64_MAX;
        uint64_t last = 0;
    } fw;
    runtime.set_firmware(&fw);
    // Deadlines of a few hundred ms: the three run_once(0) calls below must all happen before the first one
    // fires, even on a loaded host that deschedules this thread for tens of ms.
    const uint64_t t0 = clock.now_ns();
    fw.deadline = t0 + 200'000'000;
    ASSERT_TRUE(runtime.run_once(0));
    const uint64_t arms = runtime.stats().timer_arms;
    EXPECT_GE(arms, 1u);
    fw.deadline = t0 + 600'000'000;  // later: no re-arm (a watchdog re-triggered per frame costs no syscall)
    ASSERT_TRUE(runtime.run_once(0));
    EXPECT_EQ(runtime.stats().timer_arms, arms);
    fw.deadline = t0 + 400'000'000;  // earlier than 600 ms but later than the armed 200 ms: still none
    ASSERT_TRUE(runtime.run_once(0));
    EXPECT_EQ(runtime.stats().timer_arms, arms);
    // The timer fires early at 200 ms, is re-armed for 400 ms, and the firmware runs at or after 400 ms.
    for (int i = 0; i < 100 && fw.last < fw.deadline; ++i)
        ASSERT_TRUE(runtime.run_once(2000));
    EXPECT_GE(fw.last, t0 + 400'000'000);
    EXPECT_LT(clock.now_ns() - t0, 5'000'000'000ull);
    EXPECT_GE(runtime.stats().timer_expiries, 2u);
    EXPECT_GE(runtime.stats().timer_arms, arms + 1);
    // An earlier deadline re-arms at once.
    fw.deadline = clock.now_ns() + 50'000'000;
    ASSERT_TRUE(runtime.run_once(0));
    const uint64_t arms2 = runtime.stats().timer_arms;
    fw.deadline = clock.now_ns() + 5'000'000;
    ASSERT_TRUE(runtime.run_once(0));
    EXPECT_EQ(runtime.stats().timer_arms, arms2 + 1);
    runtime.set_firmware(nullptr);
}

// Deadlines that come within Runtime::kChainNs of each other (the SYNC0 pulses of a line of ESCs) are
// served by one wake-up: after the first, the runtime waits for the next awake instead of sleeping again.
TEST_F(Runtime, DeadlinesMicrosecondsApartAreServedByOneWakeUp) {
    struct TwoDeadlines : slave::Firmware {
        void poll(uint64_t now_ns) override {
            ++polls;
            while (next < 2 && now_ns >= at[next])
                ++next;
        }
        uint64_t next_deadline_ns() const override { return next < 2 ? at[next] : UINT64_MAX; }
        uint64_t at[2] = {UINT64_MAX, UINT64_MAX};
        int next = 0;
        int polls = 0;
    } fw;
    runtime.set_firmware(&fw);
    ASSERT_TRUE(runtime.run_once(0));        // the first service: nothing due yet
    fw.at[0] = clock.now_ns() + 20'000'000;  // 20 ms
    fw.at[1] = fw.at[0] + 5'000;             // 5 us later
    ASSERT_TRUE(runtime.run_once(0));        // takes the new deadlines
    const uint64_t expiries = runtime.stats().timer_expiries;
    for (int i = 0; i < 100 && fw.next < 2; ++i)
        ASSERT_TRUE(runtime.run_once(2000));
    EXPECT_EQ(fw.next, 2);
    EXPECT_EQ(runtime.stats().timer_expiries, expiries + 1) << "one wake-up for both";
    EXPECT_GE(clock.now_ns(), fw.at[1]);
    runtime.set_firmware(nullptr);
}

// --spin-us: the timer is armed spin_ns before the deadline and the runtime busy-waits the rest; the deadline
// is serviced by that same wake-up, at or after its time, and the wait is counted. A wake-up that a loaded
// host delays past the deadline has nothing left to spin (correctly): the deadline is still served by that
// one wake-up, and the attempt is made again, up to 5 times, until one wake-up comes early enough to spin.
TEST_F(Runtime, SpinWakesEarlyAndServicesTheDeadlineInTheSameWakeUp) {
    runtime.set_spin(30'000'000);  // 30 ms
    bool spun = false;
    for (int attempt = 0; attempt < 5 && !spun; ++attempt) {
        SCOPED_TRACE(attempt);
        RecordingFirmware fw(master());
        const uint64_t expiries = runtime.stats().timer_expiries, spins = runtime.stats().spin_waits;
        const uint64_t spin_ns = runtime.stats().spin_ns_total;
        fw.deadline = clock.now_ns() + 60'000'000;  // 60 ms: the timer is armed for 30 ms
        runtime.set_firmware(&fw);
        int rounds = 0;
        while (!fw.deadline_hit && rounds < 100) {
            ASSERT_TRUE(runtime.run_once(2000));
            ++rounds;
        }
        runtime.set_firmware(nullptr);
        ASSERT_TRUE(fw.deadline_hit);
        EXPECT_GE(fw.last_now, fw.deadline);
        EXPECT_EQ(runtime.stats().timer_expiries, expiries + 1) << "one early wake-up, the rest was spun";
        EXPECT_EQ(fw.polls, 1) << "polled at the deadline only, not at the early wake-up";
        const uint64_t spun_now = runtime.stats().spin_waits - spins;
        ASSERT_LE(spun_now, 1u);
        EXPECT_EQ(spun_now == 1, runtime.stats().spin_ns_total > spin_ns)
            << "a spin is timed, and only a spin";
        spun = spun_now == 1;
    }
    EXPECT_TRUE(spun) << "no wake-up of 5 came before its deadline";
}

// Frames that arrive while the runtime spins towards a deadline are answered at once (not after the deadline)
// and the firmware is polled for them as after any frame.
TEST_F(Runtime, FramesArrivingDuringASpinAreAnsweredBeforeTheDeadline) {
    struct Watching : RecordingFirmware {
        using RecordingFirmware::RecordingFirmware;
        void poll(uint64_t now_ns) override {
            RecordingFirmware::poll(now_ns);
            if (first_reply_seen == 0 && master.pending() > 0) first_reply_seen = now_ns;
        }
        uint64_t first_reply_seen = 0;
    } fw(master());
    runtime.set_firmware(&fw);
    runtime.set_spin(10'000'000'000);            // longer than the wait: spins from the first wake-up
    fw.deadline = clock.now_ns() + 300'000'000;  // 300 ms
    std::thread sender([this] {
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
        const auto f = brd_type_frame();
        (void)master().send(f);
    });
    ASSERT_TRUE(runtime.run_once(2000));
    sender.join();
    EXPECT_TRUE(fw.deadline_hit) << "one run_once spun all the way to the deadline";
    EXPECT_EQ(runtime.stats().frames_sent, 1u);
    ASSERT_NE(fw.first_reply_seen, 0u);
    EXPECT_LT(fw.first_reply_seen, fw.deadline) << "the reply went out during the spin";
    EXPECT_GE(fw.polls, 2) << "polled for the frame and at the deadline";
    runtime.set_firmware(nullptr);
}

TEST_F(Runtime, RequestStopEndsASpin) {
    RecordingFirmware fw(master());
    runtime.set_firmware(&fw);
    runtime.set_spin(60'000'000'000);
    fw.deadline = clock.now_ns() + 30'000'000'000;  // 30 s away, spun from the start
    std::thread stopper([this] {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        runtime.request_stop();
    });
    EXPECT_FALSE(runtime.run_once(2000));
    stopper.join();
    EXPECT_FALSE(fw.deadline_hit);
    runtime.set_firmware(nullptr);
}

// --busy-poll: run_once never blocks, never arms the timer, and still answers frames and meets deadlines.
TEST_F(Runtime, BusyPollNeverSleepsNorArmsTheTimer) {
    RecordingFirmware fw(master());
    runtime.set_firmware(&fw);
    runtime.set_busy_poll(true);
    std::atomic<bool> done{false};
    std::thread stopper([this, &done] {  // if run_once blocked, this would end it and the check below fails
        for (int i = 0; i < 500 && !done.load(); ++i)
            std::this_thread::sleep_for(std::chrono::milliseconds(10));
        if (!done.load()) runtime.request_stop();
    });
    EXPECT_TRUE(runtime.run_once(-1)) << "returned without waiting for anything";
    fw.deadline = clock.now_ns() + 10'000'000;
    const auto f = brd_type_frame();
    ASSERT_TRUE(master().send(f));
    int passes = 0;
    while (!fw.deadline_hit && runtime.run_once(-1))
        ++passes;
    EXPECT_TRUE(fw.deadline_hit);
    EXPECT_GE(fw.last_now, fw.deadline);
    EXPECT_GT(passes, 1);
    EXPECT_EQ(runtime.stats().timer_arms, 0u);
    EXPECT_EQ(runtime.stats().frames_sent, 1u);
    done.store(true);
    stopper.join();
    runtime.request_stop();
    EXPECT_FALSE(runtime.run_once(-1));
    runtime.set_firmware(nullptr);
}

TEST_F(Runtime, FirmwareAdapterDrivesAnyObjectWithPollAndDeadline) {
    struct Stackish {
        void poll(uint64_t now) { seen = now; }
        uint64_t next_deadline_ns() const { return deadline; }
        uint64_t seen = 0;
        uint64_t deadline = 0;
    } stack;
    stack.deadline = clock.now_ns() + 5'000'000;
    slave::FirmwareAdapter<Stackish> adapter(stack);
    EXPECT_EQ(adapter.next_deadline_ns(), stack.deadline);
    runtime.set_firmware(&adapter);
    const uint64_t start = clock.now_ns();
    for (int i = 0; i < 100 && stack.seen < stack.deadline; ++i)
        ASSERT_TRUE(runtime.run_once(2000));
    EXPECT_GE(stack.seen, stack.deadline);
    EXPECT_LT(clock.now_ns() - start, 1'000'000'000ull) << "woken by the timer, not by the poll timeout";
    EXPECT_GE(runtime.stats().timer_expiries, 1u);
    runtime.set_firmware(nullptr);
}

TEST_F(Runtime, RequestStopEndsRunFromAnotherThread) {
    std::thread stopper([this] {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        runtime.request_stop();
    });
    runtime.run();  // returns, or the test times out
    stopper.join();
    EXPECT_TRUE(runtime.stop_requested());
}

TEST_F(Runtime, SigtermEndsRun) {
    slave::install_stop_signals();
    slave::set_signal_target(&runtime);
    std::thread killer([] {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        ::kill(::getpid(), SIGTERM);
    });
    runtime.run();
    killer.join();
    slave::set_signal_target(nullptr);
    EXPECT_TRUE(slave::stop_signalled());
}

TEST_F(Runtime, CapturedFramesReachTheFileWithinTheFlushIntervalWithoutMoreTraffic) {
    const std::string path =
        (std::filesystem::temp_directory_path() / ("runtime-flush-" + std::to_string(::getpid()) + ".pcap"))
            .string();
    esc::PcapWriter capture(path);
    runtime.set_capture(&capture);
    for (int i = 0; i < 3; ++i) {
        ASSERT_TRUE(master().send(brd_type_frame()));
        ASSERT_TRUE(runtime.run_once(1000));
    }
    // The first burst flushes at once (nothing flushed yet); later ones wait for the interval, and the
    // timer brings the runtime back for it even though no frame arrives.
    const uint64_t start = clock.now_ns();
    const auto expected = 24u + 6u * (16u + 60u);
    while (std::filesystem::file_size(path) < expected && clock.now_ns() - start < 2'000'000'000ull)
        ASSERT_TRUE(runtime.run_once(1000));
    EXPECT_EQ(std::filesystem::file_size(path), expected);
    EXPECT_LT(clock.now_ns() - start, 1'000'000'000ull);
    runtime.set_capture(nullptr);
    std::remove(path.c_str());
}

TEST_F(Runtime, CaptureRecordsTheFrameAsReceivedAndAsSent) {
    const std::string path =
        (std::filesystem::temp_directory_path() / ("runtime-capture-" + std::to_string(::getpid()) + ".pcap"))
            .string();
    {
        esc::PcapWriter capture(path);
        runtime.set_capture(&capture);
        ASSERT_TRUE(master().send(brd_type_frame()));
        ASSERT_TRUE(runtime.run_once(1000));
        runtime.set_capture(nullptr);
    }
    const auto cap = linktest::read_pcap(path);
    ASSERT_TRUE(cap.opened) << cap.error;
    ASSERT_EQ(cap.records.size(), 2u) << "the frame as it came in and the reply";
    EXPECT_EQ(cap.records[0].size(), 60u);
    EXPECT_EQ(cap.records[0][6], 0x01) << "first record: the frame as it came in";
    EXPECT_EQ(cap.records[0][kWkcOffset], 0);
    EXPECT_EQ(cap.records[1][6], 0x03) << "second record: the reply";
    EXPECT_EQ(cap.records[1][kWkcOffset], 1);
    std::remove(path.c_str());
}

class RuntimeOnVeth : public ::testing::TestWithParam<std::string> {
  protected:
    void SetUp() override {
        if (!linktest::is_root()) GTEST_SKIP() << "needs root (network namespace, veth)";
    }
};

TEST_P(RuntimeOnVeth, StopsWhenTheInterfaceIsRemoved) {
    std::unique_ptr<esc::Link> link;
    int ns = -1;
    linktest::in_new_netns([&] {
        slave::create_veth("s0", "m0");
        slave::set_interface_up("s0");
        slave::set_interface_up("m0");
        link = esc::open_link("s0", GetParam());
        ns = ::open("/proc/thread-self/ns/net", O_RDONLY | O_CLOEXEC);
    });
    ASSERT_GE(ns, 0);
    esc::SystemClock clock;
    esc::Esc esc(esc::EscConfig{}, clock);
    slave::Runtime runtime(*link, esc, clock);
    bool exists = true;
    runtime.set_link_check([&] {
        linktest::in_netns(ns, [&] { exists = slave::interface_exists("s0"); });
        return exists;
    });
    EXPECT_TRUE(runtime.run_once(50));  // nothing happens: still running
    EXPECT_FALSE(runtime.link_lost());
    linktest::in_netns(ns, [] { slave::delete_interface("s0"); });
    bool running = true;
    for (int i = 0; i < 20 && running; ++i)
        running = runtime.run_once(100);
    EXPECT_FALSE(running);
    EXPECT_TRUE(runtime.link_lost());
    EXPECT_FALSE(exists);
    ::close(ns);
}

INSTANTIATE_TEST_SUITE_P(Backends, RuntimeOnVeth,
                         ::testing::Values(std::string("pcap"), std::string("packet")),
                         [](const ::testing::TestParamInfo<std::string>& param_info) {
                             return param_info.param;
                         });

}  // namespace
