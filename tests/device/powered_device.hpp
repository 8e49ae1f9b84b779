#pragma once
// One device "powered" on a manual clock: its ESC and its firmware (device::Device), run as the slave runtime
// runs them. The master's frames go through the ESC, then the firmware; slave time moves on with each frame.
#include <cstdint>
#include <memory>
#include <sstream>
#include <vector>

#include "device/device.hpp"
#include "esc/clock.hpp"
#include "esc/esc.hpp"

#include "support/wire_link.hpp"

namespace test_device {

struct PoweredDevice {
    esc::ManualClock clock;
    std::ostringstream log;
    std::unique_ptr<esc::Esc> esc;
    std::unique_ptr<device::Device> dev;
    uint64_t frame_ns = 20'000;  // slave time that passes with each frame
    bool firmware_runs = true;   // false: the controller is busy elsewhere, only the ESC answers frames

    PoweredDevice() { clock.set(1'000'000'000); }
    // A power cycle: a new ESC, a new Device (which logs to `log`).
    void power_on(device::DeviceOptions options, const esc::EscConfig& config = {}) {
        options.log = &log;
        dev.reset();
        esc = std::make_unique<esc::Esc>(config, clock);
        dev = std::make_unique<device::Device>(*esc, options);
        service();
    }
    void service() {
        esc->tick();
        dev->poll(clock.now_ns());
    }
    // Time passes without frames; the slave runs at least every millisecond, as the runtime's timer would.
    void idle(uint64_t ns) {
        for (uint64_t t = 0; t < ns; t += 1'000'000) {
            clock.advance(1'000'000);
            service();
        }
    }
    // One frame of the master: through the ESC, then the firmware runs.
    bool frame(std::vector<uint8_t>& f) {
        clock.advance(frame_ns);
        const bool back = esc->process_frame(f);
        if (firmware_runs)
            service();
        else
            esc->tick();
        return back;
    }
};

// The master's link to the device.
struct PoweredLink final : test_support::WireLink {
    explicit PoweredLink(PoweredDevice& d) : WireLink([&d](std::vector<uint8_t>& f) { return d.frame(f); }) {}
};

}  // namespace test_device
