#pragma once
// Distributed-clocks unit: the local time with rate correction, system time and the time-control loop,
// receive-time latches, SYNC0/SYNC1 generation (ETG.1000.4 and ESC datasheet section I, distributed clocks;
// registers 0x0900-0x09FF).
#include <cstdint>

#include "esc/faults.hpp"
#include "frame_time.hpp"
#include "memory.hpp"

namespace esc {

class DistributedClocks {
  public:
    DistributedClocks(Memory& m, FrameTime& t, const EscFaults& f);
    // Power-on / ESC reset state (registers already reset).
    void reset();

    // Local time of this ESC at a Clock time, and back (saturating).
    uint64_t local_at(uint64_t clock_ns) const;
    uint64_t clock_at_local(uint64_t local) const;
    // Local time now (the frame's when inside a frame).
    uint64_t cur_local() const { return time.in_frame ? time.frame_local : local_at(time.clock.now_ns()); }

    // Register reads: values computed at the moment of the access (system time, SYNC status), and the
    // PDI reads that acknowledge SYNC0/SYNC1.
    void before_read(uint16_t a, uint16_t e, Side side);
    void after_pdi_read(uint16_t a, uint16_t e);
    // ECAT writes.
    void receive_time_written() { latch_pending = true; }
    void system_time_written(uint32_t received);
    void reset_filters();
    // Writes of the side that owns the SYNC unit (0x0980).
    void activation_written(uint8_t old_value, uint8_t value);
    void start_time_written(bool only_low32);
    // End of an ECAT frame: the receive-time latch of a correct frame.
    void end_of_frame(bool ok) {
        if (latch_pending) latch(ok);
    }

    // SYNC0/SYNC1 generation up to now_clock.
    void run(uint64_t now_clock);
    // Clock time of the next SYNC pulse; UINT64_MAX if none.
    uint64_t next_event() const;

  private:
    void latch(bool ok);
    void set_rate(double new_rate, uint64_t at_clock);
    void fire_sync0(uint64_t t);
    void fire_sync1(uint64_t t);
    void update_readback();

    Memory& mem;
    FrameTime& time;
    const EscFaults& faults;
    bool latch_pending = false;  // 0x0900 written in this frame
    uint64_t clock_anchor = 0;   // Clock time where the local time mapping was last re-anchored
    uint64_t local_anchor = 0;   // local time at clock_anchor
    double rate = 0.0;           // fractional rate correction of the local time (-1e-4 = 100 ppm slower)
    double rate_integral = 0.0;
    bool have_prev = false;
    uint64_t prev_local = 0;
    bool filter_primed = false;
    double diff_filtered = 0.0;
    bool sync_running = false;  // 0x0981 bit 0 and the generation started
    bool sync0_armed = false;   // a SYNC0 pulse is scheduled at next_sync0
    bool sync1_armed = false;
    uint64_t next_sync0 = 0;  // system time
    uint64_t next_sync1 = 0;
    uint64_t last_sync0 = 0;
    uint64_t last_sync1 = 0;
    bool sync0_ack = false;  // 0x098E bit 0 latched (acknowledge mode)
    bool sync1_ack = false;
};

}  // namespace esc
