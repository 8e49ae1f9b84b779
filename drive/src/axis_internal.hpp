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

inline int32_t wrap32(int64_t v) {
    return static_cast<int32_t>(static_cast<uint32_t>(static_cast<uint64_t>(v)));
}
inline int16_t sat16(double v) {
    return static_cast<int16_t>(std::clamp(std::lround(v), -32768L, 32767L));
}

}  // namespace drive::detail
