#pragma once
// The set-point generator of one axis: the active mode of operation, the profile modes (profile position
// with its buffered set-point, profile velocity) on the trajectory generator, and the linear interpolation of
// the cyclic synchronous modes (CSP; CSV and CST pass their targets through). Its output is the demand
// (position, velocity, acceleration in raw increments) and which loop it feeds. Positions in raw increments.
#include <cstdint>

#include "drive/profile.hpp"
#include "od/drive_objects.hpp"

namespace drive {

// Modes of operation 0x6060; the set is declared once in od/drive_objects.hpp (also the 0x6060 validator's).
namespace mode {
constexpr int8_t None = 0;
constexpr int8_t ProfilePosition = od::modes::ProfilePosition;
constexpr int8_t ProfileVelocity = od::modes::ProfileVelocity;
constexpr int8_t Homing = od::modes::Homing;
constexpr int8_t CyclicSyncPosition = od::modes::CyclicSyncPosition;
constexpr int8_t CyclicSyncVelocity = od::modes::CyclicSyncVelocity;
constexpr int8_t CyclicSyncTorque = od::modes::CyclicSyncTorque;
bool supported(int8_t m);
}  // namespace mode

// Which loop the set-point enters: position loop, velocity loop (CSV) or current loop (CST).
enum class Control : uint8_t { Position, Velocity, Torque };

struct SetpointGenerator {
    int8_t mode = mode::None;
    bool halted = false;
    Profile profile;
    // profile position mode
    bool ppm_moving = false, ppm_buffered = false, ppm_ack = false;
    double ppm_target = 0, ppm_next_target = 0;
    bool ppm_next_rel = false;
    int32_t ppm_next_raw = 0;
    bool ppm_limited = false;
    // CSP interpolation (raw increments)
    double ip_from = 0, ip_to = 0;
    int64_t ip_t0 = 0, ip_period = 0;
    bool csp_limit_violation = false;
    // demand (raw increments, inc/s, inc/s^2)
    Control control = Control::Position;
    double demand_pos = 0, demand_vel = 0, demand_acc = 0;

    // Hold at `pos`: no interpolation pending, no profile move.
    void hold(double pos) {
        ip_from = ip_to = pos;
        ip_period = 0;
        ppm_moving = ppm_buffered = false;
    }
};

}  // namespace drive
