#pragma once
// The 10 us machine step (Axis::plant_step) and what it needs, inline: the current loop (controller.cpp) runs
// four of them per 40 us sample, 100 per 1 ms cycle, and one piece of code for the sample keeps the state in
// registers (docs/decisions/drive.md "Cost of a cycle"). axis.cpp has the rest of the machine (on_edge,
// on_index) and prepare_steps(), which sets up the per-cycle values used here.
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

}  // namespace detail

inline uint64_t Axis::functions_now(uint16_t pins) {
    if (!fn_valid_ || pins != fn_pins_) {
        fn_pins_ = pins;
        fn_value_ = functions(pins);
        fn_valid_ = true;
    }
    return fn_value_;
}

inline void Axis::plant_step(int64_t t_ns, double u) {
    const double prev = prev_raw_pos_;
    plant_.step(pol_ * u, dc_.power);        // polarity: the motor turns the other way
    const double raw = plant_.angle() * res_ / detail::kTwoPi;  // physical positions (phys_position_inc())
    const uint16_t p = pins_fixed_ ? fixed_pins_ : env_.pins(raw, t_ns);
    const uint64_t f = functions_now(p);
    const uint64_t changed = f ^ func_;
    if (changed) {
        const int64_t t0 = t_ns - kCurrentTickNs / kPlantStepsPerTick;
        for (int bit = 0; bit < 64; ++bit) {
            const uint64_t m = 1ull << bit;
            if (!(changed & m)) continue;
            // Where between the two samples did it switch? Bisection on the straight line between them.
            double lo = 0, hi = 1;
            const bool before = func_ & m;
            for (int it = 0; it < 20; ++it) {
                const double mid = 0.5 * (lo + hi);
                const double pos = prev + (raw - prev) * mid;
                const int64_t t = t0 + static_cast<int64_t>((t_ns - t0) * mid);
                if (static_cast<bool>(functions_now(env_.pins(pos, t)) & m) == before)
                    lo = mid;
                else
                    hi = mid;
            }
            on_edge(bit, !before, pol_ * (prev + (raw - prev) * hi));
        }
    }
    func_ = f;
    pins_ = p;
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
    count_ = static_cast<int64_t>(std::floor(pol_ * raw));
    prev_raw_pos_ = raw;
}

}  // namespace drive
