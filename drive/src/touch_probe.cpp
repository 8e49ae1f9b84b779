// Touch probe (TouchProbe): configuration by 0x60B8, the source it selects and latching of the edges.
#include "drive/touch_probe.hpp"

namespace drive {

void TouchProbe::configure(uint16_t fn) {
    if (!(fn & 0x1)) {
        status_ = 0;
        pos_cnt_ = neg_cnt_ = 0;
    } else {
        if (!(prev_fn_ & 0x1)) {
            status_ = 0x1;
            pos_cnt_ = neg_cnt_ = 0;
        }
        // Clearing an edge's enable clears its "stored" bit; setting it again re-arms first-event mode.
        if (!(fn & 0x10) || !(prev_fn_ & 0x10)) status_ &= static_cast<uint16_t>(~0x2u);
        if (!(fn & 0x20) || !(prev_fn_ & 0x20)) status_ &= static_cast<uint16_t>(~0x4u);
    }
    prev_fn_ = fn;
}

int TouchProbe::source_bit(uint16_t fn, int16_t source) {
    // Touch-probe source (MAXPOS firmware specification §7.2.84): b3..2 = 00 TP1 input (function 26), 10 =
    // 0x60D0:01.
    const uint16_t src = (fn >> 2) & 0x3;
    int bit = -1;
    if (src == 0) bit = 26;
    if (src == 2) {
        if (source >= 1 && source <= 4) bit = 32 + source - 1;
        if (source == -2) bit = 32 + 4;
        if (source == -3) bit = 32 + 5;
    }
    return bit;
}

bool TouchProbe::index_selected(uint16_t fn, int16_t source) {
    const uint16_t src = (fn >> 2) & 0x3;
    return src == 1 || (src == 2 && source == 5);
}

void TouchProbe::latch(uint16_t fn, bool rising, int32_t value) {
    const bool continuous = fn & 0x2;
    if (rising && (fn & 0x10)) {
        if (continuous || !(status_ & 0x2)) {
            pos_ = value;
            status_ |= 0x2;
            pos_cnt_ = continuous ? static_cast<uint16_t>(pos_cnt_ + 1) : 1;
        }
    } else if (!rising && (fn & 0x20)) {
        if (continuous || !(status_ & 0x4)) {
            neg_ = value;
            status_ |= 0x4;
            neg_cnt_ = continuous ? static_cast<uint16_t>(neg_cnt_ + 1) : 1;
        }
    }
}

void TouchProbe::clear_for_homing() {
    status_ &= 0x1;
    pos_ = neg_ = 0;
    pos_cnt_ = neg_cnt_ = 0;
}

}  // namespace drive
