// Touch probe (TouchProbe): configuration by 0x60B8 and latching of the edges.
#include "drive/touch_probe.hpp"

#include <cmath>

#include "drive/axis.hpp"

namespace drive {

void TouchProbe::configure(uint16_t fn) {
    if (!(fn & 0x1)) {
        status = 0;
        pos_cnt = neg_cnt = 0;
    } else {
        if (!(prev_fn & 0x1)) {
            status = 0x1;
            pos_cnt = neg_cnt = 0;
        }
        // Clearing an edge's enable clears its "stored" bit; setting it again re-arms first-event mode.
        if (!(fn & 0x10) || !(prev_fn & 0x10)) status &= static_cast<uint16_t>(~0x2u);
        if (!(fn & 0x20) || !(prev_fn & 0x20)) status &= static_cast<uint16_t>(~0x4u);
    }
    prev_fn = fn;
}

void TouchProbe::latch(uint16_t fn, bool rising, int32_t value) {
    const bool continuous = fn & 0x2;
    if (rising && (fn & 0x10)) {
        if (continuous || !(status & 0x2)) {
            pos = value;
            status |= 0x2;
            pos_cnt = continuous ? static_cast<uint16_t>(pos_cnt + 1) : 1;
        }
    } else if (!rising && (fn & 0x20)) {
        if (continuous || !(status & 0x4)) {
            neg = value;
            status |= 0x4;
            neg_cnt = continuous ? static_cast<uint16_t>(neg_cnt + 1) : 1;
        }
    }
}

void TouchProbe::clear_for_homing() {
    status &= 0x1;
    pos = neg = 0;
    pos_cnt = neg_cnt = 0;
}

void Axis::tp_latch(bool rising, double raw_pos) {
    const uint16_t fn = command.touch_probe_function;
    // Touch probe and homing are mutually exclusive (MAXPOS firmware specification §4.5).
    if (!(fn & 0x1) || sp_.mode == mode::Homing) return;
    tp_.latch(fn, rising, report(static_cast<int64_t>(std::floor(raw_pos)) + shift_));
}

}  // namespace drive
