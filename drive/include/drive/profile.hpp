#pragma once
// Online trapezoidal profile generator (0x6086 = 0, linear ramps). Works from any start state (position and
// velocity), so a new target, a change-immediately set-point, a halt or a quick stop can take over at any
// time without a jump. Units are whatever the caller uses consistently (the drive uses increments and inc/s).
namespace drive {

class Profile {
  public:
    void reset(double position, double velocity = 0.0) {
        pos_ = position;
        vel_ = velocity;
        acc_ = 0;
    }
    // Advance by h toward a target position; vmax, acc, dec > 0. Returns true once the target is reached
    // (position == target and velocity == 0).
    bool step_position(double target, double vmax, double acc, double dec, double h);
    // Advance by h toward a target velocity with the given ramps. Returns true when velocity == target.
    bool step_velocity(double target, double acc, double dec, double h);

    double position() const { return pos_; }
    double velocity() const { return vel_; }
    double acceleration() const { return acc_; }  // of the last step

  private:
    double pos_ = 0, vel_ = 0, acc_ = 0;
};

}  // namespace drive
