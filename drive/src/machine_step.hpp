#pragma once
// What the machine does after each 10 us plant step (Axis::machine_step: input edges, encoder index), inline:
// the current loop (controller.cpp) runs four steps per 40 us sample, 100 per 1 ms cycle, and one piece of
// code for the sample keeps the plant state in registers (docs/decisions/drive.md "Cost of a cycle").
// axis.cpp has the rest of the machine (on_edge, on_index) and prepare_steps(), which sets up the per-cycle
// values used here.
#include <cmath>
#include <cstdint>

#include "axis_internal.hpp"
#include "drive/axis.hpp"

namespace drive {

namespace detail {

// The turn bounds of the encoder index test, narrowed by a margin far above the rounding of the division, so
// a position strictly inside them has floor((raw - p0) / res) == k for sure; outside them (or for huge k, or
// NaN) the step divides as before. Same answer, one division less per 10 us step.
inline void index_bounds(double k, double res, double& lo, double& hi) {
    if (std::abs(k) < 1e9) {
        const double margin = res * 0x1p-20;
        lo = k * res + margin;
        hi = (k + 1.0) * res - margin;
    } else {
        lo = INFINITY;
        hi = -INFINITY;
    }
}

// static_cast<int64_t>(std::floor(x)), the same value for every x (NaN and out of range included, as x86
// converts them), without the call to libm's floor the baseline x86-64 target makes: the count is taken
// once per current-loop sample, on the sample's latency chain (docs/decisions/drive.md "Cost of a cycle").
inline int64_t floor_to_int(double x) {
    int64_t i = static_cast<int64_t>(x < 0x1p63 && x >= -0x1p63 ? x : std::floor(x));
    if (static_cast<double>(i) > x) --i;
    return i;
}

}  // namespace detail

inline uint64_t Axis::functions_now(uint16_t pins) {
    if (!fn_valid_ || pins != fn_pins_) {
        fn_pins_ = pins;
        fn_value_ = functions(pins);
        fn_valid_ = true;
    }
    return fn_value_;
}

inline void Axis::machine_step(double raw, int64_t t_ns) {
    const double prev = prev_raw_pos_;
    // Inputs: nothing to do while the pins and their functions cannot change during the cycle.
    if (!pins_fixed_ || !fn_valid_) {
        const uint16_t p = pins_fixed_ ? fixed_pins_ : env_.pins(raw, t_ns);
        const uint64_t f = functions_now(p);
        const uint64_t changed = f ^ func_;
        if (changed) edges(prev, raw, t_ns, changed);  // rare: out of line (axis.cpp)
        func_ = f;
        pins_ = p;
    }
    // Encoder index: once per revolution at the configured angle (only with a 3-channel encoder).
    if (index_on_) {
        const double d = raw - index_p0_;
        if (!(d > index_lo_ && d < index_hi_)) {
            const double p0 = index_p0_;
            const double k0 = index_k_, k1 = std::floor(d / res_);
            if (k0 != k1) on_index(pol_ * (p0 + std::max(k0, k1) * res_));
            index_k_ = k1;
            detail::index_bounds(k1, res_, index_lo_, index_hi_);
        }
    }
    prev_raw_pos_ = raw;
}

}  // namespace drive
