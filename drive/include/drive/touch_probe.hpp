#pragma once
// Touch probe function 0x60B8 / status 0x60B9 with the latched positions 0x60BA/0x60BB and the edge counters
// 0x60D5/0x60D6 (IEC 61800-7-201, touch probe function; MAXPOS firmware specification §7.2.84). Axis tells it
// the function word once per cycle and every edge of an input or the encoder index; it answers which source
// the function word selects and latches what it is given.
#include <cstdint>

namespace drive {

class TouchProbe {
  public:
    // Once per cycle with the function word the master wrote: enabling, disabling and re-arming.
    void configure(uint16_t fn);
    // The function bit (bit 26 = the touch-probe input, bits 32.. = the pins) whose edges the function word
    // `fn` selects with 0x60D0:01 = `source`; -1 for none (the encoder index is index_selected()).
    static int source_bit(uint16_t fn, int16_t source);
    // The function word selects the encoder index.
    static bool index_selected(uint16_t fn, int16_t source);
    // The probe takes edges: enabled, and not in homing (they are mutually exclusive, MAXPOS firmware
    // specification §4.5).
    static bool armed(uint16_t fn, bool homing) { return (fn & 0x1) && !homing; }
    // An edge of the selected source at position `value` (as the dictionary shows it).
    void latch(uint16_t fn, bool rising, int32_t value);
    // Homing clears the touch-probe states and latched values.
    void clear_for_homing();

    uint16_t status() const { return status_; }
    int32_t position_rising() const { return pos_; }
    int32_t position_falling() const { return neg_; }
    uint16_t count_rising() const { return pos_cnt_; }
    uint16_t count_falling() const { return neg_cnt_; }

  private:
    uint16_t prev_fn_ = 0;
    uint16_t status_ = 0;
    int32_t pos_ = 0, neg_ = 0;
    uint16_t pos_cnt_ = 0, neg_cnt_ = 0;
};

}  // namespace drive
