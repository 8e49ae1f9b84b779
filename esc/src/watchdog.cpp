// Watchdog unit (watchdog.hpp).
#include "watchdog.hpp"

#include <algorithm>
#include <limits>

namespace esc {

void Watchdogs::reset() {
    pd_armed = pdi_armed = pdi_touched = false;
}

void Watchdogs::pd_trigger() {
    pd_last = time.now_clock();
    if (mem.r16(reg::kWdTimePd) != 0) {
        if (!pd_armed) pd_started = true;
        pd_armed = true;
        mem.w16(reg::kWdStatusPd, static_cast<uint16_t>(mem.r16(reg::kWdStatusPd) | 0x0001));
    }
}

bool Watchdogs::run(uint64_t now) {
    bool changed = false;
    const uint64_t inc = increment_ns();
    const uint64_t tpd = mem.r16(reg::kWdTimePd) * inc;
    if (tpd == 0) {
        pd_armed = false;
        const uint16_t st = mem.r16(reg::kWdStatusPd);
        changed = (st & 0x0001) == 0;
        mem.w16(reg::kWdStatusPd, static_cast<uint16_t>(st | 0x0001));
    } else if (pd_armed && now >= pd_last + tpd) {
        pd_armed = false;
        mem.w16(reg::kWdStatusPd, static_cast<uint16_t>(mem.r16(reg::kWdStatusPd) & ~0x0001));
        mem.count_error(reg::kWdCounterPd);
        mem.set_al_event(alev::kWatchdogPd);
        changed = true;
    }
    const uint64_t tpdi = mem.r16(reg::kWdTimePdi) * inc;
    const uint16_t dl = mem.r16(reg::kDlStatus);
    if (pdi_touched) {
        pdi_touched = false;
        pdi_last = now;
        pdi_armed = true;
    }
    uint16_t ndl = dl;
    if (tpdi == 0) {
        pdi_armed = false;
        ndl = static_cast<uint16_t>(dl | 0x0002);
    } else if (pdi_armed) {
        if (now >= pdi_last + tpdi) {
            pdi_armed = false;
            ndl = static_cast<uint16_t>(dl & ~0x0002);
            mem.count_error(reg::kWdCounterPdi);
            changed = true;
        } else {
            ndl = static_cast<uint16_t>(dl | 0x0002);
        }
    }
    if (ndl != dl) {
        mem.w16(reg::kDlStatus, ndl);
        mem.set_ecat_event(ecev::kDlStatus);
        changed = true;
    }
    return changed;
}

uint64_t Watchdogs::next_event(uint64_t now_clock) const {
    uint64_t r = std::numeric_limits<uint64_t>::max();
    const uint64_t inc = increment_ns();
    const uint64_t tpd = mem.r16(reg::kWdTimePd) * inc;
    if (pd_armed && tpd) r = std::min(r, pd_last + tpd);
    const uint64_t tpdi = mem.r16(reg::kWdTimePdi) * inc;
    if (tpdi) {
        if (pdi_touched && !pdi_armed) {
            r = std::min(r, now_clock);  // start the PDI watchdog
        } else if (pdi_armed) {
            r = std::min(r, pdi_last + tpdi);
        }
    }
    return r;
}

bool Watchdogs::settled() const {
    const uint16_t dl = mem.r16(reg::kDlStatus);
    if (mem.r16(reg::kWdTimePd) == 0 && !(mem.r16(reg::kWdStatusPd) & 0x0001)) return false;
    if (mem.r16(reg::kWdTimePdi) == 0 || pdi_armed) return (dl & 0x0002) != 0;
    return true;
}

}  // namespace esc
