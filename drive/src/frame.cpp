// The reported frame of positions (PositionFrame).
#include "drive/frame.hpp"

#include <cmath>

#include "axis_internal.hpp"

namespace drive {

using namespace detail;

int32_t PositionFrame::report(int64_t v) const {
    if (!range_on()) return wrap32(v);
    const int64_t span = static_cast<int64_t>(range_max) - range_min + 1;
    int64_t m = (v - range_min) % span;
    if (m < 0) m += span;
    return static_cast<int32_t>(range_min + m);
}

double PositionFrame::unwrap(int32_t target, double near_raw) const {
    // The target inside the range, taken the short way from where the axis is (raw increments).
    const double span = static_cast<double>(range_max) - range_min + 1.0;
    const double here = std::round(near_raw + static_cast<double>(shift));
    const double here_wrapped = static_cast<double>(report(static_cast<int64_t>(here)));
    double d = static_cast<double>(target) - here_wrapped;
    d -= span * std::round(d / span);
    return here + d - static_cast<double>(shift);
}

double PositionFrame::raw_min() const {
    return sw_min == std::numeric_limits<int32_t>::min() ? -INFINITY : static_cast<double>(sw_min) - shift;
}

double PositionFrame::raw_max() const {
    return sw_max == std::numeric_limits<int32_t>::max() ? INFINITY : static_cast<double>(sw_max) - shift;
}

}  // namespace drive
