#pragma once
// Distributed-clocks unit: the local time with rate correction, system time and the time-control loop,
// receive-time latches, SYNC0/SYNC1 generation (ETG.1000.4 and ESC datasheet section I, distributed clocks;
// registers 0x0900-0x09FF).
#include <cstdint>

#include "esc/esc.hpp"
#include "esc/faults.hpp"
#include "frame_time.hpp"
#include "memory.hpp"

namespace esc {

class DistributedClocks {
  public:
    // The ESC's oscillator: EscConfig::clock_drift_ppm / clock_offset_ns (local time = Clock time *
    // (1 + drift) + offset before the control loop's correction).
    DistributedClocks(Memory& m, FrameTime& t, const EscConfig& cfg);
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
    // A frame was received at port 1-3 at Clock time clock_ns: latches 0x0904/0x0908/0x090C once per arming.
    bool port_latch_armed() const { return port_armed != 0; }
    void port_received(int port, uint64_t clock_ns) {
        const uint8_t bit = static_cast<uint8_t>(1u << port);
        if (!(port_armed & bit)) return;
        port_armed = static_cast<uint8_t>(port_armed & ~bit);
        mem.w32(static_cast<uint16_t>(reg::kDcRecvTime0 + 4 * port),
                static_cast<uint32_t>(local_at(clock_ns)));
    }
    // End of an ECAT frame: the receive-time latch of a correct frame.
    void end_of_frame(bool ok) {
        if (latch_pending) latch(ok);
    }

    // SYNC0/SYNC1 generation up to now_clock; true when a pulse fired (or a single shot ended).
    bool run(uint64_t now_clock);
    // Clock time of the next SYNC pulse; UINT64_MAX if none.
    uint64_t next_event(uint64_t now_clock) const;

    // A SYNC0 or SYNC1 pulse is scheduled (next_event() has arithmetic to do).
    bool armed() const { return sync0_armed || sync1_armed; }

  private:
    void latch(bool ok);
    void set_rate(double new_rate, uint64_t at_clock);
    void fire_sync0(uint64_t t);
    void fire_sync1(uint64_t t);
    void update_readback();

    Memory& mem;
    FrameTime& time;
    const EscFaults& faults;
    const double drift;          // the oscillator's fractional deviation (50 ppm: 5e-5)
    bool latch_pending = false;  // 0x0900 written in this frame
    uint8_t port_armed = 0;      // ports 1-3 whose receive time latches with the next frame they receive
    uint64_t clock_anchor = 0;   // Clock time where the local time mapping was last re-anchored
    uint64_t local_anchor = 0;   // local time at clock_anchor
    double rate = 0.0;           // fractional rate correction of the local time (-1e-4 = 100 ppm slower)
    double speed_m1 = 0.0;       // (1 + drift) * (1 + rate) - 1: the local clock's speed against the Clock
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
