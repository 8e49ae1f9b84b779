#pragma once
// Watchdog unit: the process-data watchdog (0x0420, 0x0440, 0x0442) and the PDI watchdog (0x0410, DL status
// bit 1, 0x0443), both counting in steps of the watchdog divider 0x0400 (ESC datasheet section I, watchdogs).
#include <cstdint>

#include "frame_time.hpp"
#include "memory.hpp"

namespace esc {

class Watchdogs {
  public:
    Watchdogs(Memory& m, const FrameTime& t) : mem(m), time(t) {}
    void reset();
    // Watchdog time increment (ns) from the divider 0x0400.
    uint64_t increment_ns() const { return (static_cast<uint64_t>(mem.r16(reg::kWdDivider)) + 2) * 40; }
    // A SyncManager with watchdog trigger enabled saw a write (ECAT side).
    void pd_trigger();
    // Whether a trigger started the process-data watchdog (it was not running) since the last call.
    bool take_started() {
        const bool s = pd_started;
        pd_started = false;
        return s;
    }
    // A PDI access happened: restarts the PDI watchdog at the next run().
    void pdi_touch() { pdi_touched = true; }
    // True when it changed a register (a watchdog expired, a status bit changed).
    bool run(uint64_t now_clock);
    // Clock time at which run() has something to do next; UINT64_MAX if nothing.
    uint64_t next_event(uint64_t now_clock) const;
    // False while run() would change a status bit whatever the time (a watchdog time written to 0, an armed
    // PDI watchdog whose DL status bit is not yet set): run() is due at once then.
    bool settled() const;

  private:
    Memory& mem;
    const FrameTime& time;
    bool pd_armed = false;
    bool pd_started = false;  // see take_started()
    uint64_t pd_last = 0;     // Clock time of the last trigger
    bool pdi_armed = false;
    bool pdi_touched = false;
    uint64_t pdi_last = 0;
};

}  // namespace esc
