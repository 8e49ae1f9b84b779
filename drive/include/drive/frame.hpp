#pragma once
// The frame the dictionary shows positions in: reported = raw + shift (the shift homing sets), wrapped into
// the position range limit 0x607B when one is set (modulo axis), with the software position limits 0x607D
// (MAXPOS firmware specification §7.2.53, §7.2.56). A value: built from the parameters and the home shift
// where it is needed, so no part needs the Axis for it.
#include <cstdint>
#include <limits>

namespace drive {

struct PositionFrame {
    int64_t shift = 0;                                        // reported = raw + shift
    int32_t range_min = std::numeric_limits<int32_t>::min();  // 0x607B:01 (-2^31 = off)
    int32_t range_max = std::numeric_limits<int32_t>::max();  // 0x607B:02
    int32_t sw_min = std::numeric_limits<int32_t>::min();     // 0x607D:01 (-2^31 = off)
    int32_t sw_max = std::numeric_limits<int32_t>::max();     // 0x607D:02 (2^31-1 = off)

    bool range_on() const {
        return range_min != std::numeric_limits<int32_t>::min() && range_max > range_min;
    }
    // A position as the dictionary shows it (v in the reported frame, before wrapping into the range).
    int32_t report(int64_t v) const;
    // A target of the dictionary (modulo the range), taken the short way from `near_raw`: raw increments.
    double unwrap(int32_t target, double near_raw) const;
    // An absolute target of the dictionary in raw increments.
    double to_raw(int32_t target, double near_raw) const {
        return range_on() ? unwrap(target, near_raw)
                          : static_cast<double>(target) - static_cast<double>(shift);
    }
    // The software position limits in raw increments (+-infinity when off).
    double raw_min() const;
    double raw_max() const;
    // A target (reported frame, unwrapped) outside the software position limits.
    bool outside_limits(int64_t v) const {
        return (sw_min != std::numeric_limits<int32_t>::min() && v < sw_min) ||
               (sw_max != std::numeric_limits<int32_t>::max() && v > sw_max);
    }
};

}  // namespace drive
