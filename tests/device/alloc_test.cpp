// The composed drive's cycle allocates nothing: counts global operator new calls while the master exchanges
// process data with the Device in Op (frame -> ESC -> Stack -> drive cycle -> inputs), including a fault with
// its emergency and diagnosis message. Own binary: it links the counting global operator new.
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <sstream>

#include "device/control.hpp"
#include "device/device.hpp"
#include "esc/clock.hpp"
#include "esc/esc.hpp"
#include "master/coe.hpp"
#include "master/mailbox.hpp"
#include "master/master.hpp"
#include "master/session.hpp"
#include "products.hpp"
#include "support/alloc_counter.hpp"
#include "support/master_bring_up.hpp"

namespace {

// A link that hands each frame to the ESC and runs the Device, with fixed buffers (allocates nothing).
class FixedLink final : public esc::Link {
  public:
    FixedLink(esc::ManualClock& clock, esc::Esc& esc, device::Device& dev)
        : clock_(clock), esc_(esc), dev_(dev) {}
    int fd() const override { return -1; }
    std::size_t receive(std::span<uint8_t> buf) override {
        if (len_ == 0) return 0;
        const std::size_t n = std::min(buf.size(), len_);
        std::memcpy(buf.data(), frame_.data(), n);
        len_ = 0;
        return n;
    }
    bool send(std::span<const uint8_t> frame) override {
        if (frame.size() > frame_.size()) return false;
        std::memcpy(frame_.data(), frame.data(), frame.size());
        clock_.advance(step_ns);
        const auto t0 = std::chrono::steady_clock::now();
        const bool back = esc_.process_frame(std::span<uint8_t>(frame_.data(), frame.size()));
        const auto t1 = std::chrono::steady_clock::now();
        esc_.tick();
        const auto t2 = std::chrono::steady_clock::now();
        dev_.poll(clock_.now_ns());
        tick_ns +=
            static_cast<uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(t2 - t1).count());
        firmware_ns += static_cast<uint64_t>(
            std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - t1)
                .count());
        esc_ns +=
            static_cast<uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(t1 - t0).count());
        len_ = back ? frame.size() : 0;
        return true;
    }
    uint64_t step_ns = 20'000;
    uint64_t esc_ns = 0;       // time in the ESC's frame processing
    uint64_t firmware_ns = 0;  // time in esc.tick() + Device::poll() (stack, application)
    uint64_t tick_ns = 0;      // of which esc.tick()

  private:
    esc::ManualClock& clock_;
    esc::Esc& esc_;
    device::Device& dev_;
    std::array<uint8_t, 1600> frame_{};
    std::size_t len_ = 0;
};

}  // namespace

TEST(DeviceAllocation, ProcessDataCyclesInOpAllocateNothing) {
    char pattern[] = "/tmp/softdrive-alloc-XXXXXX";
    const std::filesystem::path dir = ::mkdtemp(pattern);
    esc::ManualClock clock;
    clock.set(1'000'000'000);
    esc::Esc esc(esc::EscConfig{}, clock);
    device::DeviceOptions options;
    options.state_dir = dir;
    auto dev = std::make_unique<device::Device>(esc, options);
    FixedLink link(clock, esc, *dev);
    master::MasterOptions mo;
    mo.timeout = std::chrono::milliseconds(5);
    master::Master m(link, mo);
    const auto a = master::Address::station(0x1001);
    master::Mailbox mbx(m, a);
    ASSERT_NO_FATAL_FAILURE(test_support::one_slave_in_preop(m, mbx, a));
    master::SdoClient sdo(mbx);
    master::ProcessDataSession pd(m, a, sdo);
    ASSERT_EQ(pd.discover(), master::Error::Ok);
    ASSERT_EQ(pd.configure(), master::Error::Ok);
    // Default mapping 0x1600: controlword @0, target position @2, ..., modes of operation @16.
    auto out = pd.outputs();
    auto set = [&](uint16_t cw, int32_t target) {
        std::memcpy(out.data(), &cw, 2);
        std::memcpy(out.data() + 2, &target, 4);
        out[16] = 8;
    };
    set(0, 0);
    ASSERT_EQ(pd.request_state(master::AlState::SafeOp, std::chrono::microseconds(50)), master::Error::Ok);
    ASSERT_EQ(pd.request_state(master::AlState::Op, std::chrono::microseconds(50)), master::Error::Ok);
    link.step_ns = 1'000'000;
    for (uint16_t cw : {0x06, 0x07, 0x0F})
        for (int i = 0; i < 10; ++i) {
            set(cw, 0);
            ASSERT_EQ(pd.cycle(), master::Error::Ok);
        }
    uint16_t sw = 0;
    std::memcpy(&sw, pd.inputs().data(), 2);
    ASSERT_EQ(sw & 0x6F, 0x27) << std::hex << sw;
    // Warm-up: every path once (cycles, a fault, its emergency waiting in the mailbox).
    for (int i = 0; i < 200; ++i) {
        set(0x0F, i * 5);
        ASSERT_EQ(pd.cycle(), master::Error::Ok);
    }

    const alloc_counter::Scope cycles;
    int32_t target = 1000;
    for (int i = 0; i < 2000; ++i) {
        target += 5;
        set(0x0F, target);
        ASSERT_EQ(pd.cycle(), master::Error::Ok);
    }
    const uint64_t cycles_allocs = cycles.count();
    EXPECT_EQ(cycles_allocs, 0u) << "allocations in 2000 process-data cycles in Op";

    // A fault inside the measured window: STO drops, the drive raises 0x8A88 (emergency + 0x10F3).
    const uint64_t errors = dev->stats().emergencies;
    dev->set_input(5, false);
    dev->set_input(6, false);
    const alloc_counter::Scope fault;
    for (int i = 0; i < 50; ++i) {
        set(0x0F, target);
        ASSERT_EQ(pd.cycle(), master::Error::Ok);
    }
    EXPECT_GT(dev->stats().emergencies, errors);
    EXPECT_EQ(fault.count(), 0u) << "allocations while a fault is raised and reported";
    dev.reset();
    std::filesystem::remove_all(dir);
}

// A device without application (the IO model: outputs taken, inputs mirrored and counted) allocates nothing
// per cycle; the time per cycle in the firmware (ESC tick + Device::poll) and in the ESC's frame processing
// is printed (a figure, no assertion: the machine is shared).
TEST(DeviceAllocation, IoModelCyclesAllocateNothing) {
    char pattern[] = "/tmp/softecat-io-alloc-XXXXXX";
    const std::filesystem::path dir = ::mkdtemp(pattern);
    esc::ManualClock clock;
    clock.set(1'000'000'000);
    esc::Esc esc(esc::EscConfig{}, clock);
    device::DeviceOptions options;
    options.state_dir = dir;
    options.product = test_products::io_terminal();
    std::ostringstream log;
    options.log = &log;
    auto dev = std::make_unique<device::Device>(esc, options);
    FixedLink link(clock, esc, *dev);
    master::MasterOptions mo;
    mo.timeout = std::chrono::milliseconds(5);
    master::Master m(link, mo);
    const auto a = master::Address::station(0x1001);
    ASSERT_NO_FATAL_FAILURE(test_support::one_slave_addressed(m));
    ASSERT_EQ(m.request_state(a, master::AlState::PreOp), master::Error::Ok);
    master::ProcessDataSession pd(m, std::span<const master::Address>(&a, 1));
    ASSERT_EQ(pd.discover_sii(0), master::Error::Ok);
    ASSERT_EQ(pd.configure(), master::Error::Ok);
    ASSERT_EQ(pd.request_state(master::AlState::SafeOp, std::chrono::microseconds(50)), master::Error::Ok);
    ASSERT_EQ(pd.request_state(master::AlState::Op, std::chrono::microseconds(50)), master::Error::Ok);
    link.step_ns = 1'000'000;
    ASSERT_EQ(device::ControlSocket::apply(*dev, "set Status 5").rfind("ok", 0), 0u);
    for (int i = 0; i < 200; ++i)
        ASSERT_EQ(pd.cycle(), master::Error::Ok);
    const uint64_t cycles_before = dev->stats().cycles;
    link.esc_ns = link.firmware_ns = link.tick_ns = 0;
    const alloc_counter::Scope scope;
    constexpr int kCycles = 5000;
    for (int i = 0; i < kCycles; ++i) {
        pd.outputs()[0] = static_cast<uint8_t>(i);
        ASSERT_EQ(pd.cycle(), master::Error::Ok);
    }
    EXPECT_EQ(scope.count(), 0u) << "allocations in process-data cycles of a device without application";
    EXPECT_EQ(dev->stats().cycles - cycles_before, static_cast<uint64_t>(kCycles));
    // The inputs a frame reads were written after the frame before: they mirror the outputs of that one.
    EXPECT_EQ(pd.inputs()[0], static_cast<uint8_t>(kCycles - 2)) << "the input mirrors the output";
    std::printf(
        "io terminal: %.0f ns per cycle in the firmware (%.0f ns ESC tick, the rest stack + IO model), "
        "%.0f ns in the ESC's frame processing\n",
        static_cast<double>(link.firmware_ns) / kCycles, static_cast<double>(link.tick_ns) / kCycles,
        static_cast<double>(link.esc_ns) / kCycles);
    dev.reset();
    std::filesystem::remove_all(dir);
}
