// Distributed clocks (local time with rate correction, system time, time-control loop, SYNC0/SYNC1) and the
// process-data / PDI watchdogs.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>

#include "esc_impl.hpp"

namespace esc {

namespace {
constexpr uint64_t kNever = std::numeric_limits<uint64_t>::max();
// 0x0930 below the datasheet's minimum (0x0080) acts as the minimum: the correction stays within
// +-1/128 of the local clock's rate, so the clock never stops nor runs at twice its rate.
constexpr uint16_t kMinSpeedCounterStart = 0x0080;
// Rate limit of the local clock for any correction, a guard for the divisions by the speed.
constexpr double kMaxRate = 1.0 / kMinSpeedCounterStart;
}  // namespace

// ---------------------------------------------------------------------------------------- local time

uint64_t Esc::Impl::local_at(uint64_t c) const {
    const int64_t dt = static_cast<int64_t>(c - clock_anchor);
    const int64_t corr = static_cast<int64_t>(std::llround(static_cast<double>(dt) * rate));
    return local_anchor + static_cast<uint64_t>(dt + corr);
}

uint64_t Esc::Impl::clock_at_local(uint64_t local) const {
    constexpr double kTwo64 = 18446744073709551616.0;
    const double speed = 1.0 + std::clamp(rate, -kMaxRate, kMaxRate);  // > 0: never a division by zero
    // Saturated at both ends (a start time centuries away): no overflow, no undefined conversion.
    if (local >= local_anchor) {
        const double dc = std::ceil(static_cast<double>(local - local_anchor) / speed);
        if (!(dc < kTwo64)) return kNever;
        const uint64_t d = static_cast<uint64_t>(dc);
        return d > kNever - clock_anchor ? kNever : clock_anchor + d;
    }
    const double dc = std::floor(static_cast<double>(local_anchor - local) / speed);
    if (!(dc < kTwo64)) return 0;
    const uint64_t d = static_cast<uint64_t>(dc);
    return d >= clock_anchor ? 0 : clock_anchor - d;
}

void Esc::Impl::set_rate(double new_rate, uint64_t at) {
    if (static_cast<int64_t>(at - clock_anchor) > 0) {
        local_anchor = local_at(at);
        clock_anchor = at;
    }
    rate = std::clamp(new_rate, -kMaxRate, kMaxRate);
}

// ---------------------------------------------------------------------------------------- control loop

void Esc::Impl::dc_reset_filters() {
    w32(reg::kDcDiff, 0);
    w16(reg::kDcSpeedDiff, 0);
    dc_filter_primed = false;
    dc_diff_filtered = 0.0;
    dc_have_prev = false;
    rate_integral = 0.0;
    set_rate(0.0, cur_clock());
}

// ECAT write of the system time: compare the local copy with the received value and steer the local clock's
// rate so that the difference goes to zero (a PI loop whose output is the rate correction).
void Esc::Impl::dc_system_time_written(uint32_t received) {
    const uint64_t copy = frame_local + r64(reg::kDcOffset) - r32(reg::kDcDelay);
    const int32_t e = static_cast<int32_t>(static_cast<uint32_t>(copy) - received);

    // 0x092C: mean difference, filter depth 0x0934.
    const unsigned d1 = r8(reg::kDcFilterDiff) & 0x0F;
    if (!dc_filter_primed) {
        dc_diff_filtered = e;
        dc_filter_primed = true;
    } else {
        dc_diff_filtered += (e - dc_diff_filtered) / static_cast<double>(1u << d1);
    }
    const double mag = std::min(std::fabs(dc_diff_filtered), 2147483647.0);
    w32(reg::kDcDiff, static_cast<uint32_t>(std::llround(mag)) | (dc_diff_filtered < 0 ? 0x80000000u : 0));

    if (dc_have_prev && frame_local > dc_prev_local) {
        const double dt = static_cast<double>(frame_local - dc_prev_local);
        const uint16_t start = r16(reg::kDcSpeedStart) & 0x7FFF;
        // Bandwidth: 0x1000 -> 244 ppm; at most 1/0x0080 (0x0930 = 0 is not a 100 % correction).
        const double max_rate = 1.0 / std::max(start, kMinSpeedCounterStart);
        // PI loop. Proportional gain 2^-d1 (0x0934, default 4 -> 1/16 of the error per interval), integral
        // gain 2^-(d2-2) (0x0935, default 12 -> 1/1024): critically damped for the defaults, and kept below
        // half the proportional gain so that any register setting stays stable.
        const int d2 = r8(reg::kDcFilterSpeed) & 0x0F;
        // Depths below 4 act as 4: silicon timestamps are exact, ours jitter by microseconds (SOEM writes 0).
        const int kp_shift = std::max(static_cast<int>(d1), 4);
        const int ki_shift = std::max(d2 - 2, kp_shift + 1);
        const double ratio = e / dt;
        const double p = ratio / static_cast<double>(1u << kp_shift);
        // No integration while the proportional term alone saturates (a large phase error is being slewed
        // away, e.g. before the master wrote the offset): the drift estimate does not wind up.
        if (std::fabs(p) < max_rate)
            rate_integral =
                std::clamp(rate_integral - ratio / static_cast<double>(1u << ki_shift), -max_rate, max_rate);
        const double r = std::clamp(rate_integral - p, -max_rate, max_rate);
        set_rate(r, frame_clock);
        // 0x0932: the drift estimate in units of 0.1 ppm.
        const double sd = std::clamp(rate_integral * 1e7, -32768.0, 32767.0);
        w16(reg::kDcSpeedDiff, static_cast<uint16_t>(static_cast<int16_t>(std::lround(sd))));
    }
    dc_have_prev = true;
    dc_prev_local = frame_local;
}

// ---------------------------------------------------------------------------------------- SYNC generation

void Esc::Impl::dc_start_time_written(bool only_low32) {
    const uint8_t act = r8(reg::kDcActivation);
    if (only_low32 && (act & 0x10)) {
        const uint64_t sys = cur_local() + r64(reg::kDcOffset);
        uint64_t v = (sys & ~0xFFFFFFFFull) | r32(reg::kDcStartTime);
        if (v < sys) v += 0x100000000ull;
        w64(reg::kDcStartTime, v);
    }
    if (act & 0x08) {  // auto-activate by writing the start time
        w8(reg::kDcActivation, static_cast<uint8_t>(act | 0x01));
        dc_activation_written(act, static_cast<uint8_t>(act | 0x01));
    }
}

void Esc::Impl::dc_activation_written(uint8_t old, uint8_t v) {
    const bool was = old & 0x01, now = v & 0x01;
    if (now && !was) {
        sync_running = true;
        sync0_armed = sync1_armed = false;
        uint8_t status = 0;
        if (v & 0x02) status |= 0x01;
        if (v & 0x04) status |= 0x02;
        const bool unit_on = r8(reg::kEscConfig) & 0x04;
        if (unit_on) {  // the cyclic unit runs; bits 1/2 gate the outputs when a pulse is due
            const uint64_t sys = cur_local() + r64(reg::kDcOffset);
            uint64_t start = r64(reg::kDcStartTime);
            bool fire = true;
            if (start < sys) {
                status |= 0x04;  // start time not in the near future
                if (v & 0x20) {
                    start = sys;  // plausibility check on: start at once
                } else {
                    fire = false;  // as silicon: waits for a counter wrap, i.e. never
                }
            }
            if (fire && !cfg.faults.sync0_never) {
                sync0_armed = true;
                next_sync0 = start;
            }
        }
        w8(reg::kDcActivationStatus, status);
    } else if (!now && was) {
        sync_running = sync0_armed = sync1_armed = false;
        w8(reg::kDcActivationStatus, 0);
    }
    dc_update_readback();
}

void Esc::Impl::dc_update_readback() {
    if (sync0_armed) w64(reg::kDcStartTime, next_sync0);
    w64(reg::kDcNextSync1, sync1_armed ? next_sync1 : 0);
}

void Esc::Impl::dc_fire_sync0(uint64_t t) {
    last_sync0 = t;
    sync0_ack = true;
    w8(reg::kDcActivationStatus, static_cast<uint8_t>(r8(reg::kDcActivationStatus) & ~0x01));
    if (r8(reg::kSyncLatchConfig) & 0x08) set_al_event(alev::kSync0);
}

void Esc::Impl::dc_fire_sync1(uint64_t t) {
    last_sync1 = t;
    sync1_ack = true;
    w8(reg::kDcActivationStatus, static_cast<uint8_t>(r8(reg::kDcActivationStatus) & ~0x02));
    if (r8(reg::kSyncLatchConfig) & 0x80) set_al_event(alev::kSync1);
}

void Esc::Impl::dc_run(uint64_t now_clock) {
    if (!sync0_armed && !sync1_armed) return;
    const uint64_t sys = local_at(now_clock) + r64(reg::kDcOffset);
    const uint8_t act = r8(reg::kDcActivation);
    for (int guard = 0; guard < 16; ++guard) {
        const uint64_t t0 = sync0_armed ? next_sync0 : kNever;
        const uint64_t t1 = sync1_armed ? next_sync1 : kNever;
        if (std::min(t0, t1) > sys) break;
        if (t0 <= t1) {
            // Internal SYNC0 event (drives SYNC1 even when the SYNC0 output is off).
            if (act & 0x02) dc_fire_sync0(t0);
            const uint32_t c0 = r32(reg::kDcSync0Cycle);
            const uint32_t c1 = r32(reg::kDcSync1Cycle);
            if (act & 0x04) {
                if (c1 == 0) {
                    dc_fire_sync1(t0);
                } else if (!sync1_armed) {
                    sync1_armed = true;
                    next_sync1 = t0 + c1;
                }
            }
            if (c0 == 0) {
                sync0_armed = false;  // single shot
            } else {
                uint64_t nx = t0 + c0;
                if (nx <= sys) nx = t0 + ((sys - t0) / c0 + 1) * c0;  // pulses missed: skip to the grid
                next_sync0 = nx;
            }
        } else {
            if (act & 0x04) dc_fire_sync1(t1);
            sync1_armed = false;
        }
    }
    dc_update_readback();
}

// ---------------------------------------------------------------------------------------- watchdogs

void Esc::Impl::wd_pd_trigger() {
    pd_wd_last = cur_clock();
    if (r16(reg::kWdTimePd) != 0) {
        pd_wd_armed = true;
        w16(reg::kWdStatusPd, static_cast<uint16_t>(r16(reg::kWdStatusPd) | 0x0001));
    }
}

void Esc::Impl::wd_run(uint64_t now) {
    const uint64_t inc = wd_increment_ns();
    const uint64_t tpd = r16(reg::kWdTimePd) * inc;
    if (tpd == 0) {
        pd_wd_armed = false;
        w16(reg::kWdStatusPd, static_cast<uint16_t>(r16(reg::kWdStatusPd) | 0x0001));
    } else if (pd_wd_armed && now >= pd_wd_last + tpd) {
        pd_wd_armed = false;
        w16(reg::kWdStatusPd, static_cast<uint16_t>(r16(reg::kWdStatusPd) & ~0x0001));
        count_error(reg::kWdCounterPd);
        set_al_event(alev::kWatchdogPd);
    }
    const uint64_t tpdi = r16(reg::kWdTimePdi) * inc;
    const uint16_t dl = r16(reg::kDlStatus);
    if (pdi_touched) {
        pdi_touched = false;
        pdi_wd_last = now;
        pdi_wd_armed = true;
    }
    uint16_t ndl = dl;
    if (tpdi == 0) {
        pdi_wd_armed = false;
        ndl = static_cast<uint16_t>(dl | 0x0002);
    } else if (pdi_wd_armed) {
        if (now >= pdi_wd_last + tpdi) {
            pdi_wd_armed = false;
            ndl = static_cast<uint16_t>(dl & ~0x0002);
            count_error(reg::kWdCounterPdi);
        } else {
            ndl = static_cast<uint16_t>(dl | 0x0002);
        }
    }
    if (ndl != dl) {
        w16(reg::kDlStatus, ndl);
        set_ecat_event(ecev::kDlStatus);
    }
}

uint64_t Esc::Impl::next_event() const {
    uint64_t r = kNever;
    const uint64_t offset = r64(reg::kDcOffset);
    const uint64_t now_clock = clock.now_ns();
    const uint64_t now_local = local_at(now_clock);
    auto sync_at = [&](uint64_t sys) {
        const uint64_t local = sys - offset;  // the event's local time
        return local <= now_local ? now_clock : clock_at_local(local);
    };
    if (sync0_armed) r = std::min(r, sync_at(next_sync0));
    if (sync1_armed) r = std::min(r, sync_at(next_sync1));
    const uint64_t inc = wd_increment_ns();
    const uint64_t tpd = r16(reg::kWdTimePd) * inc;
    if (pd_wd_armed && tpd) r = std::min(r, pd_wd_last + tpd);
    const uint64_t tpdi = r16(reg::kWdTimePdi) * inc;
    if (tpdi) {
        if (pdi_touched && !pdi_wd_armed) {
            r = std::min(r, clock.now_ns());  // start the PDI watchdog
        } else if (pdi_wd_armed) {
            r = std::min(r, pdi_wd_last + tpdi);
        }
    }
    return r;
}

}  // namespace esc
