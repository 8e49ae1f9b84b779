#pragma once
// Constants and small helpers shared by the translation units of Axis and of its parts.
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "drive/parameters.hpp"

namespace drive::detail {

constexpr double kTwoPi = 6.283185307179586;
constexpr double kTick = static_cast<double>(kCurrentTickNs) * 1e-9;
constexpr double kPlantStep = kTick / kPlantStepsPerTick;
constexpr double kVelH = kTick * kVelocityDivider;
constexpr double kPosH = kTick * kPositionDivider;
constexpr double kObserverHz = 250.0;
// First-order low-pass coefficient for the averaged values (50 Hz, as 0x30D1), per current tick.
inline const double kAvgAlpha = 1.0 - std::exp(-kTwoPi * 50.0 * kTick);
constexpr uint32_t kNoWindow = 0xFFFFFFFFu;
// The following error window 0x6065 switches the following error monitoring off with 0xFFFFFFFF, and with 0
// (CiA 402-2 / IEC 61800-7-201, 0x6065: "If the value of the following error window is FFFF FFFFh or
// 0000 0000h, the following control shall be switched off"; the value vendors' ESIs default to when the
// drive's own tuning sets the window, as Ingenia's and Elmo's do).
constexpr bool following_error_checked(uint32_t window) {
    return window != kNoWindow && window != 0;
}

inline int32_t wrap32(int64_t v) {
    return static_cast<int32_t>(static_cast<uint32_t>(static_cast<uint64_t>(v)));
}
inline int16_t sat16(double v) {
    return static_cast<int16_t>(std::clamp(std::lround(v), -32768L, 32767L));
}

}  // namespace drive::detail
