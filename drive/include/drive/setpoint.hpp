#pragma once
// The set-point generator of one axis: the active mode of operation, the profile modes (profile position
// with its buffered set-point, profile velocity) on the trajectory generator, and the linear interpolation of
// the cyclic synchronous modes (CSP; CSV and CST pass their targets through). Its output is the demand
// (position, velocity, acceleration in raw increments), which loop it feeds, and the references and
// feed-forwards it gives the loops (LoopReference). Homing (homing.hpp) moves the same profile while it is
// the mode. Positions in raw increments.
#include <algorithm>
#include <cstdint>

#include "drive/frame.hpp"
#include "drive/objects.hpp"
#include "drive/parameters.hpp"
#include "drive/profile.hpp"

namespace drive {

// Modes of operation 0x6060; the set is declared once in drive/objects.hpp.
namespace mode {
constexpr int8_t None = 0;
constexpr int8_t ProfilePosition = drive::modes::ProfilePosition;
constexpr int8_t ProfileVelocity = drive::modes::ProfileVelocity;
constexpr int8_t ProfileTorque = drive::modes::ProfileTorque;
constexpr int8_t Homing = drive::modes::Homing;
constexpr int8_t InterpolatedPosition = drive::modes::InterpolatedPosition;
constexpr int8_t CyclicSyncPosition = drive::modes::CyclicSyncPosition;
constexpr int8_t CyclicSyncVelocity = drive::modes::CyclicSyncVelocity;
constexpr int8_t CyclicSyncTorque = drive::modes::CyclicSyncTorque;
// Implemented by the drive, announced in `announced` (0x6502 bits, IEC 61800-7-201; 0 announces nothing and
// stands for every mode the drive implements) and among the modes the device can serve (`served`: the modes
// whose set-point object its dictionary has, drive::mode_setpoint_entry).
bool supported(int8_t m, uint32_t announced = supported_drive_modes(),
               uint32_t served = supported_drive_modes());
}  // namespace mode

// Which loop the set-point enters: position loop, velocity loop (CSV) or current loop (CST).
enum class Control : uint8_t { Position, Velocity, Torque };

// What a trajectory tick gives the loops: the feed-forwards (CSP and CSV offsets 0x60B1/0x60B2), and the
// reference of the loop the set-point enters when that is not the position loop.
struct LoopReference {
    double vel_ff = 0;       // rad/s
    double torque_ff_a = 0;  // A
    double vel_ref = 0;      // rad/s, Control::Velocity
    double cur_ref = 0;      // A, Control::Torque
};

// Controlword bit 4 (new set-point / homing operation start) against the previous cycle's.
struct SetpointEdge {
    bool rise = false, fall = false;
};
inline SetpointEdge new_setpoint_edge(uint16_t cw, uint16_t prev) {
    constexpr uint16_t bit = 1u << 4;
    return {(cw & bit) && !(prev & bit), !(cw & bit) && (prev & bit)};
}

// An acceleration of the dictionary (rpm/s) in inc/s^2 at `resolution` inc per turn, at least 1 rpm/s and at
// most 0x60C5 (`max_acceleration`).
inline double limited_acceleration(double rpm_s, uint32_t max_acceleration, double resolution) {
    const double a = std::min<double>(std::max(rpm_s, 1.0), static_cast<double>(max_acceleration));
    return a * resolution / 60.0;
}

class SetpointGenerator {
  public:
    // What a trajectory tick reads of the machine.
    struct Inputs {
        double actual = 0;         // encoder count, raw inc
        double speed = 0;          // estimated speed, rad/s
        double resolution = 2000;  // inc per turn
        double torque = 0;         // actual torque, per mille of the rated torque
    };

    // A new mode of operation: it takes over from the current demand without a jump (from `actual` without
    // power).
    void switch_mode(int8_t m, bool power, double actual);
    // Once per cycle, the master's set-points: halt, the profile position set-point on bit 4 (`enabled`: the
    // drive follows set-points), the new CSP target to interpolate over the cycle (`interpolate`: 0x60C2
    // set).
    void command(const Command& c, uint16_t cw_prev, bool enabled, const PositionFrame& f, bool interpolate,
                 int64_t now_ns, int64_t dt_ns);
    // One trajectory tick of `h` s at time t_ns with the drive powered, in the modes other than homing.
    LoopReference tick(const Command& c, const Parameters& p, const Inputs& in, const PositionFrame& f,
                       int64_t t_ns, double h);
    // Power off: the demand follows the actual position.
    void follow(double actual);
    // One tick of a stop ramp of `decel` inc/s^2; true at zero speed.
    bool ramp(double decel, double h);
    // One tick of a stop at the current limit: the current loop brakes (the caller gives it the current),
    // the demand follows the motor (`actual` inc, `speed` inc/s). True once the motor has stopped (its speed
    // within `still` inc/s of zero, or past zero against the direction it had when the stop began); the
    // demand then holds there.
    bool brake(double actual, double speed, double still);
    // The demand is the profile's (homing moves the profile).
    void from_profile();
    // Transition 4: the demand starts at `actual`, at rest.
    void power_on(double actual);
    // Transition 16: hold where the quick-stop ramp got to.
    void resume();
    // A stop ramp starts from the actual motion.
    void ramp_from(double actual, double speed_inc_s);
    // The position frame changed (resolution or polarity): the demand is the actual position.
    void reset_to(double actual);

    Profile& profile() { return profile_; }
    const Profile& profile() const { return profile_; }
    int8_t mode() const { return mode_; }
    bool halted() const { return halted_; }
    Control control() const { return control_; }
    double demand_position() const { return demand_pos_; }
    double demand_velocity() const { return demand_vel_; }
    double demand_acceleration() const { return demand_acc_; }
    bool target_reached() const { return halted_ ? profile_.velocity() == 0.0 : !ppm_moving_; }  // PPM
    bool setpoint_acknowledged() const { return ppm_ack_; }                                      // PPM
    bool target_limited() const { return ppm_limited_; }                 // PPM target clamped by 0x607D
    bool target_outside_limits() const { return csp_limit_violation_; }  // CSP/IP target outside 0x607D
    // Interpolated position mode: the interpolation runs (controlword bit 4 in Operation enabled, no halt);
    // the axis has come to rest at the last set-point (or, without the interpolation or with halt, at all).
    bool ip_active() const { return ip_active_; }
    bool ip_target_reached() const {
        return ip_active_ ? ip_from_ == ip_to_ && demand_pos_ == ip_to_ : profile_.velocity() == 0.0;
    }
    // Profile torque mode: the torque demand (per mille of the rated torque) has reached the target torque
    // (with halt: the axis stands still).
    double torque_demand() const { return pt_demand_; }
    bool torque_reached() const { return halted_ ? profile_.velocity() == 0.0 : pt_demand_ == pt_target_; }

  private:
    // Hold at `pos`: no interpolation pending, no profile move.
    void hold(double pos);
    // A profile position target (raw) within the software position limits.
    void move_to(double target, const PositionFrame& f);
    // The position set-point of the cyclic modes (CSP 0x607A + 0x60B0, IP 0x60C1:01) for this cycle:
    // interpolated linearly over the cycle when `interpolate`, else taken at once.
    void next_setpoint(int64_t target, const PositionFrame& f, bool interpolate, int64_t now_ns,
                       int64_t dt_ns);
    // The interpolation of the cyclic set-points at t_ns: the demand (CSP, IP).
    void interpolate_at(int64_t t_ns, double h);
    // Profile torque: one tick of the torque ramp (0x6087, 0x6088) toward `target` per mille.
    void torque_ramp(double target, const Parameters& p, double h);

    int8_t mode_ = mode::None;
    bool halted_ = false;
    Profile profile_;
    // profile position mode
    bool ppm_moving_ = false, ppm_buffered_ = false, ppm_ack_ = false;
    double ppm_target_ = 0;
    bool ppm_next_rel_ = false;
    int32_t ppm_next_raw_ = 0;
    bool ppm_limited_ = false;
    double stop_direction_ = 0;  // sign of the speed when the stop began (ramp_from)
    // CSP interpolation (raw increments)
    double ip_from_ = 0, ip_to_ = 0;
    int64_t ip_t0_ = 0, ip_period_ = 0;
    bool csp_limit_violation_ = false;
    bool ip_active_ = false;  // interpolated position mode: controlword bit 4 took the interpolation on
    // profile torque (per mille): the demand, its ramp's start, end and the target it runs to; the sin^2
    // ramp's time (s); `pt_restart_`: the next tick starts the ramp from the actual torque
    double pt_demand_ = 0, pt_from_ = 0, pt_target_ = 0, pt_time_ = 0;
    bool pt_restart_ = true;
    // demand (raw increments, inc/s, inc/s^2)
    Control control_ = Control::Position;
    double demand_pos_ = 0, demand_vel_ = 0, demand_acc_ = 0;
};

}  // namespace drive
