// (1) Whole Ethernet frames into the emulated ESC (esc::Esc::process_frame), as they come off the wire:
// input = a sequence of frames, each a little-endian 16-bit length and the frame bytes (destination MAC
// first, no FCS). Between frames the ESC's clock advances by a byte of the input (in 10 us steps) and its
// time-driven parts run. Checked: nothing crashes (ASan, UBSan), a frame keeps its length, the PDI side
// stays readable.
#include <memory>
#include <vector>

#include "esc/clock.hpp"
#include "esc/esc.hpp"
#include "esi/sii.hpp"
#include "fuzz_support.hpp"
#include "harnesses.hpp"
#include "od/drive_profile.hpp"

namespace fuzz::esc_frame {
namespace {

const std::vector<uint8_t>& sii_image() {
    static const std::vector<uint8_t> image = [] {
        const od::DeviceDescription desc = od::default_drive_description();
        return esi::build_sii(desc, od::make_drive_dictionary(desc));
    }();
    return image;
}

}  // namespace

int fuzz_one(const uint8_t* data, std::size_t size) {
    esc::ManualClock clock;
    clock.set(1'000'000'000);
    esc::Esc e(esc::EscConfig{}, clock);
    e.load_eeprom(sii_image());
    Input in(data, size);
    std::vector<uint8_t> frame;
    frame.reserve(2048);
    while (!in.empty()) {
        const uint8_t dt = in.u8();
        const auto f = in.record();
        frame.assign(f.begin(), f.end());
        clock.advance(uint64_t{dt} * 10'000);
        e.process_frame(frame);
        FUZZ_CHECK(frame.size() == f.size());
        e.tick();
        (void)e.next_event_ns();
        (void)e.irq();
    }
    return 0;
}

}  // namespace fuzz::esc_frame
