#pragma once
// Touch probe function 0x60B8 / status 0x60B9 with the latched positions 0x60BA/0x60BB and the edge counters
// 0x60D5/0x60D6 (IEC 61800-7-201, touch probe function; MAXPOS firmware specification §7.2.84).
#include <cstdint>

namespace drive {

struct TouchProbe {
    uint16_t prev_fn = 0;
    uint16_t status = 0;
    int32_t pos = 0, neg = 0;
    uint16_t pos_cnt = 0, neg_cnt = 0;

    // Once per cycle with the function word the master wrote: enabling, disabling and re-arming.
    void configure(uint16_t fn);
    // An edge of the selected source at position `value` (as the dictionary shows it).
    void latch(uint16_t fn, bool rising, int32_t value);
    // Homing clears the touch-probe states and latched values.
    void clear_for_homing();
};

}  // namespace drive
