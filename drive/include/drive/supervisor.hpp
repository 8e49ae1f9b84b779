#pragma once
// Supervision of one axis: the active errors and warnings with the error register, the following-error
// timer and standstill detection (0x30E0). Axis raises the errors and runs the reactions (axis.hpp).
#include <algorithm>
#include <array>
#include <cstdint>

namespace drive {

struct Supervisor {
    std::array<uint16_t, 8> active{};
    std::array<uint16_t, 8> warnings{};
    uint16_t last_error = 0;
    uint8_t error_register = 0;
    double ferr_time_ms = 0;
    double still_ms = 0;
    bool still = false;

    bool error_active(uint16_t code) const {
        return std::find(active.begin(), active.end(), code) != active.end() && code != 0;
    }
    bool warning() const {
        return std::any_of(warnings.begin(), warnings.end(), [](uint16_t w) { return w != 0; });
    }
    // Standstill detection: |averaged speed| within `window` rpm (0xFFFFFFFF = detection off) for `time_ms`.
    void standstill(double vel_avg_rpm, uint32_t window, uint16_t time_ms, int64_t dt_ns);
};

}  // namespace drive
