// Distributed-clocks unit (dc.hpp): local time with rate correction, system time, time-control loop,
// receive-time latches, SYNC0/SYNC1.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>

#include "dc.hpp"

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

uint64_t DistributedClocks::local_at(uint64_t c) const {
    const int64_t dt = static_cast<int64_t>(c - clock_anchor);
    const int64_t corr = static_cast<int64_t>(std::llround(static_cast<double>(dt) * speed_m1));
    return local_anchor + static_cast<uint64_t>(dt + corr);
}

uint64_t DistributedClocks::clock_at_local(uint64_t local) const {
    constexpr double kTwo64 = 18446744073709551616.0;
    // > 0: never a division by zero (the drift is clamped to +-1/128 at construction too).
    const double speed = (1.0 + drift) * (1.0 + std::clamp(rate, -kMaxRate, kMaxRate));
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

void DistributedClocks::set_rate(double new_rate, uint64_t at) {
    if (static_cast<int64_t>(at - clock_anchor) > 0) {
        local_anchor = local_at(at);
        clock_anchor = at;
    }
    rate = std::clamp(new_rate, -kMaxRate, kMaxRate);
    speed_m1 = (1.0 + drift) * (1.0 + rate) - 1.0;
}

// ---------------------------------------------------------------------------------------- control loop

void DistributedClocks::reset_filters() {
    mem.w32(reg::kDcDiff, 0);
    mem.w16(reg::kDcSpeedDiff, 0);
    filter_primed = false;
    diff_filtered = 0.0;
    have_prev = false;
    rate_integral = 0.0;
    set_rate(0.0, time.now_clock());
}

// ECAT write of the system time: compare the local copy with the received value and steer the local clock's
// rate so that the difference goes to zero (a PI loop whose output is the rate correction).
void DistributedClocks::system_time_written(uint32_t received) {
    const uint64_t copy = time.frame_local + mem.r64(reg::kDcOffset) - mem.r32(reg::kDcDelay);
    const int32_t e = static_cast<int32_t>(static_cast<uint32_t>(copy) - received);

    // 0x092C: mean difference, filter depth 0x0934.
    const unsigned d1 = mem.r8(reg::kDcFilterDiff) & 0x0F;
    if (!filter_primed) {
        diff_filtered = e;
        filter_primed = true;
    } else {
        diff_filtered += (e - diff_filtered) / static_cast<double>(1u << d1);
    }
    const double mag = std::min(std::fabs(diff_filtered), 2147483647.0);
    mem.w32(reg::kDcDiff, static_cast<uint32_t>(std::llround(mag)) | (diff_filtered < 0 ? 0x80000000u : 0));

    if (have_prev && time.frame_local > prev_local) {
        const double dt = static_cast<double>(time.frame_local - prev_local);
        const uint16_t start = mem.r16(reg::kDcSpeedStart) & 0x7FFF;
        // Bandwidth: 0x1000 -> 244 ppm; at most 1/0x0080 (0x0930 = 0 is not a 100 % correction).
        const double max_rate = 1.0 / std::max(start, kMinSpeedCounterStart);
        // PI loop. Proportional gain 2^-d1 (0x0934, default 4 -> 1/16 of the error per interval), integral
        // gain 2^-(d2-2) (0x0935, default 12 -> 1/1024): critically damped for the defaults, and kept below
        // half the proportional gain so that any register setting stays stable.
        const int d2 = mem.r8(reg::kDcFilterSpeed) & 0x0F;
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
        set_rate(r, time.frame_clock);
        // 0x0932: the drift estimate in units of 0.1 ppm.
        const double sd = std::clamp(rate_integral * 1e7, -32768.0, 32767.0);
        mem.w16(reg::kDcSpeedDiff, static_cast<uint16_t>(static_cast<int16_t>(std::lround(sd))));
    }
    have_prev = true;
    prev_local = time.frame_local;
}

// ---------------------------------------------------------------------------------------- SYNC generation

void DistributedClocks::start_time_written(bool only_low32) {
    const uint8_t act = mem.r8(reg::kDcActivation);
    if (only_low32 && (act & 0x10)) {
        const uint64_t sys = cur_local() + mem.r64(reg::kDcOffset);
        uint64_t v = (sys & ~0xFFFFFFFFull) | mem.r32(reg::kDcStartTime);
        if (v < sys) v += 0x100000000ull;
        mem.w64(reg::kDcStartTime, v);
    }
    if (act & 0x08) {  // auto-activate by writing the start time
        mem.w8(reg::kDcActivation, static_cast<uint8_t>(act | 0x01));
        activation_written(act, static_cast<uint8_t>(act | 0x01));
    }
}

void DistributedClocks::activation_written(uint8_t old, uint8_t v) {
    const bool was = old & 0x01, now = v & 0x01;
    if (now && !was) {
        sync_running = true;
        sync0_armed = sync1_armed = false;
        uint8_t status = 0;
        if (v & 0x02) status |= 0x01;
        if (v & 0x04) status |= 0x02;
        const bool unit_on = mem.r8(reg::kEscConfig) & 0x04;
        if (unit_on) {  // the cyclic unit runs; bits 1/2 gate the outputs when a pulse is due
            const uint64_t sys = cur_local() + mem.r64(reg::kDcOffset);
            uint64_t start = mem.r64(reg::kDcStartTime);
            bool fire = true;
            if (start < sys) {
                status |= 0x04;  // start time not in the near future
                if (v & 0x20) {
                    start = sys;  // plausibility check on: start at once
                } else {
                    fire = false;  // as silicon: waits for a counter wrap, i.e. never
                }
            }
            if (fire && !faults.sync0_never) {
                sync0_armed = true;
                next_sync0 = start;
            }
        }
        mem.w8(reg::kDcActivationStatus, status);
    } else if (!now && was) {
        sync_running = sync0_armed = sync1_armed = false;
        mem.w8(reg::kDcActivationStatus, 0);
    }
    update_readback();
}

void DistributedClocks::update_readback() {
    if (sync0_armed) mem.w64(reg::kDcStartTime, next_sync0);
    mem.w64(reg::kDcNextSync1, sync1_armed ? next_sync1 : 0);
}

void DistributedClocks::fire_sync0(uint64_t t) {
    last_sync0 = t;
    sync0_ack = true;
    mem.w8(reg::kDcActivationStatus, static_cast<uint8_t>(mem.r8(reg::kDcActivationStatus) & ~0x01));
    if (mem.r8(reg::kSyncLatchConfig) & 0x08) mem.set_al_event(alev::kSync0);
}

void DistributedClocks::fire_sync1(uint64_t t) {
    last_sync1 = t;
    sync1_ack = true;
    mem.w8(reg::kDcActivationStatus, static_cast<uint8_t>(mem.r8(reg::kDcActivationStatus) & ~0x02));
    if (mem.r8(reg::kSyncLatchConfig) & 0x80) mem.set_al_event(alev::kSync1);
}

bool DistributedClocks::run(uint64_t now_clock) {
    if (!sync0_armed && !sync1_armed) return false;
    bool fired = false;
    const uint64_t sys = local_at(now_clock) + mem.r64(reg::kDcOffset);
    const uint8_t act = mem.r8(reg::kDcActivation);
    for (int guard = 0; guard < 16; ++guard) {
        const uint64_t t0 = sync0_armed ? next_sync0 : kNever;
        const uint64_t t1 = sync1_armed ? next_sync1 : kNever;
        if (std::min(t0, t1) > sys) break;
        fired = true;
        if (t0 <= t1) {
            // Internal SYNC0 event (drives SYNC1 even when the SYNC0 output is off).
            if (act & 0x02) fire_sync0(t0);
            const uint32_t c0 = mem.r32(reg::kDcSync0Cycle);
            const uint32_t c1 = mem.r32(reg::kDcSync1Cycle);
            if (act & 0x04) {
                if (c1 == 0) {
                    fire_sync1(t0);
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
            if (act & 0x04) fire_sync1(t1);
            sync1_armed = false;
        }
    }
    update_readback();
    return fired;
}

// ---------------------------------------------------------------------------------------- construction

DistributedClocks::DistributedClocks(Memory& m, FrameTime& t, const EscConfig& cfg)
    : mem(m),
      time(t),
      faults(cfg.faults),
      drift(std::isfinite(cfg.clock_drift_ppm) ? std::clamp(cfg.clock_drift_ppm * 1e-6, -kMaxRate, kMaxRate)
                                               : 0.0) {
    // Local time = Clock time * (1 + drift) + offset (modulo 2^64, as the 64-bit DC counter wraps).
    clock_anchor = time.clock.now_ns();
    const int64_t skew = static_cast<int64_t>(std::llround(static_cast<double>(clock_anchor) * drift));
    local_anchor = clock_anchor + static_cast<uint64_t>(skew) + static_cast<uint64_t>(cfg.clock_offset_ns);
    speed_m1 = drift;
}

void DistributedClocks::reset() {
    latch_pending = false;
    port_armed = 0;
    sync_running = sync0_armed = sync1_armed = false;
    sync0_ack = sync1_ack = false;
    rate_integral = 0.0;
    set_rate(0.0, time.clock.now_ns());
    have_prev = false;
    filter_primed = false;
    diff_filtered = 0.0;
}

// ---------------------------------------------------------------------------------------- register access

void DistributedClocks::before_read(uint16_t a, uint16_t e, Side side) {
    if (overlaps(a, e, reg::kDcSystemTime, 8)) {
        const uint64_t local = side == Side::Ecat && faults.dc_time_frozen ? 0 : cur_local();
        uint64_t st = local + mem.r64(reg::kDcOffset);
        if (side == Side::Ecat) st -= mem.r32(reg::kDcDelay);
        mem.w64(reg::kDcSystemTime, st);
    }
    if (overlaps(a, e, reg::kDcSync0Status, 2)) {
        const uint16_t pulse = mem.r16(reg::kDcPulseLength);
        const uint64_t sys = cur_local() + mem.r64(reg::kDcOffset);
        const uint64_t len = static_cast<uint64_t>(pulse) * 10;
        const bool s0 = pulse == 0 ? sync0_ack : (last_sync0 != 0 && sys < last_sync0 + len);
        const bool s1 = pulse == 0 ? sync1_ack : (last_sync1 != 0 && sys < last_sync1 + len);
        mem.w8(reg::kDcSync0Status, s0 ? 1 : 0);
        mem.w8(reg::kDcSync1Status, s1 ? 1 : 0);
    }
}

void DistributedClocks::after_pdi_read(uint16_t a, uint16_t e) {
    if (overlaps(a, e, reg::kDcSync0Status, 1)) {
        mem.clear_al_event(alev::kSync0);
        sync0_ack = false;
    }
    if (overlaps(a, e, reg::kDcSync1Status, 1)) {
        mem.clear_al_event(alev::kSync1);
        sync1_ack = false;
    }
}

void DistributedClocks::latch(bool ok) {
    latch_pending = false;
    if (!ok) return;
    // Port 0: this frame's arrival (the processing unit sits behind port 0's receive side). Ports 1-3: the
    // next frame each of them receives (Ports / Esc::receive call port_received()).
    mem.w32(reg::kDcRecvTime0, static_cast<uint32_t>(time.frame_local));
    mem.w64(reg::kDcRecvTimePu, time.frame_local);
    port_armed = 0x0E;
}

uint64_t DistributedClocks::next_event(uint64_t now_clock) const {
    uint64_t r = kNever;
    if (!sync0_armed && !sync1_armed) return r;
    const uint64_t offset = mem.r64(reg::kDcOffset);
    const uint64_t now_local = local_at(now_clock);
    auto sync_at = [&](uint64_t sys) {
        const uint64_t local = sys - offset;  // the event's local time
        return local <= now_local ? now_clock : clock_at_local(local);
    };
    if (sync0_armed) r = std::min(r, sync_at(next_sync0));
    if (sync1_armed) r = std::min(r, sync_at(next_sync1));
    return r;
}

}  // namespace esc
