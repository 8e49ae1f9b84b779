// The composed drive's cycle allocates nothing: counts global operator new calls while the master exchanges
// process data with the Device in Op (frame -> ESC -> Stack -> drive cycle -> inputs), including a fault with
// its emergency and diagnosis message. Own binary: it links the counting global operator new.
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>

#include "device/device.hpp"
#include "esc/clock.hpp"
#include "esc/esc.hpp"
#include "master/coe.hpp"
#include "master/mailbox.hpp"
#include "master/master.hpp"
#include "master/session.hpp"
#include "support/alloc_counter.hpp"
#include "support/master_bring_up.hpp"

#include "support/alloc_counter.hpp"

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
        const bool back = esc_.process_frame(std::span<uint8_t>(frame_.data(), frame.size()));
        esc_.tick();
        dev_.poll(clock_.now_ns());
        len_ = back ? frame.size() : 0;
        return true;
    }
    uint64_t step_ns = 20'000;

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
