// (1) Whole Ethernet frames into the emulated ESC (esc::Esc::receive), as they come off the wire: a
// four-port junction ESC with a link on every port. Input = a sequence of records, each a control byte and a
// frame (a little-endian 16-bit length and the frame bytes, destination MAC first, no FCS). A control byte
// below 0x80 advances the ESC's clock by that many 10 us steps and the frame comes in at port 0 (the seed
// corpus records the time between a master's frames so); from 0x80 on, bits 0-1 are the port, bit 2 marks
// the FCS bad (FrameCheck) and bits 3-6 the 10 us steps. After each frame the time-driven parts run. Checked:
// nothing crashes (ASan, UBSan), a frame keeps its length, it leaves through an existing port or is
// destroyed, the PDI side stays readable.
#include <memory>
#include <vector>

#include "esc/clock.hpp"
#include "esc/esc.hpp"
#include "esi/sii.hpp"
#include "fuzz_support.hpp"
#include "harnesses.hpp"
#include "maxpos/maxpos.hpp"

namespace fuzz::esc_frame {
namespace {

const std::vector<uint8_t>& sii_image() {
    static const std::vector<uint8_t> image = [] {
        const od::DeviceDescription desc = maxpos::description();
        return esi::build_sii(desc, maxpos::dictionary(desc));
    }();
    return image;
}

}  // namespace

int fuzz_one(const uint8_t* data, std::size_t size) {
    esc::ManualClock clock;
    clock.set(1'000'000'000);
    esc::EscConfig config;
    config.port_descriptor = 0xFF;  // ports 0-3
    esc::Esc e(config, clock);
    e.load_eeprom(sii_image());
    for (int p = 1; p < esc::kPortCount; ++p)
        e.set_link(p, true);
    for_each_frame(data, size, [&](uint8_t control, std::vector<uint8_t>& frame) {
        const std::size_t length = frame.size();
        const bool varied = (control & 0x80) != 0;
        const unsigned steps = varied ? (control >> 3) & 0x0Fu : control;
        clock.advance(uint64_t{steps} * 10'000);
        esc::FrameCheck check;
        check.crc_bad = varied && (control & 0x04) != 0;
        const int out = e.receive(frame, varied ? control & 0x03 : 0, 0, check);
        FUZZ_CHECK(out >= -1 && out < esc::kPortCount);
        FUZZ_CHECK(frame.size() == length);
        e.tick();
        (void)e.next_event_ns();
        (void)e.irq();
    });
    return 0;
}

}  // namespace fuzz::esc_frame
