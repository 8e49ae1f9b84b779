#pragma once
// Homing mode (6) of one axis (IEC 61800-7-201 homing mode; MAXPOS firmware specification §4.5): the methods
// of 0x60E3 as a small phase machine that moves the set-point generator's profile, the status it shows
// (statusword bits 10, 12, 13) and the reference it finds: whether the axis is referenced and the shift from
// raw to reported positions. Axis tells it the input edges and index pulses where they happened
// (edge(), index_pulse()) and runs tick() in the position-loop rate while homing is the mode.
#include <cstdint>

#include "drive/event_sink.hpp"
#include "drive/parameters.hpp"
#include "drive/profile.hpp"

namespace drive {

enum class HomingStatus : uint8_t { Idle, InProgress, Done, Error, Interrupted };
enum class HomingPhase : uint8_t { Search, Backoff, ToIndex, Offset, Stopping, Finished };

class Homing {
  public:
    // Speeds and acceleration of the methods in raw increments per s (0x6099:01/02) and per s^2 (0x609A).
    struct Motion {
        double fast = 0, slow = 0, acc = 0;
    };
    // What a homing tick reads of the machine.
    struct Inputs {
        bool halted = false;     // controlword bit 8 (halt)
        double current = 0;      // |motor current|, A
        uint64_t functions = 0;  // 0x60FD-style input functions
        double actual = 0;       // encoder count, raw inc
        int32_t resolution = 1;  // inc per turn
    };

    // A new set-point in homing mode with the drive enabled: starts the method of 0x6098 (the caller clears
    // the touch probe and puts the profile where the demand is). Refuses an unknown method, or an index
    // method without an index (encoder 0x3010:02 bit 0): homing error.
    void start(const Parameters& p, uint64_t functions, double actual, EventSink& sink);
    // Method 37 while disabled: no move, the actual position `count` becomes the home position.
    void set_here(int32_t home_position, int64_t count, EventSink& sink);
    // One position-loop tick of `h` s: moves `profile` as the phase requires.
    void tick(Profile& profile, const Motion& m, const Inputs& in, const Parameters& p, EventSink& sink,
              double h);
    // An edge of function bit `bit` at raw position `raw_pos`, the profile moving at `v`.
    void edge(int bit, bool rising, double v, double raw_pos);
    // An encoder index pulse at raw position `raw_pos`, the profile moving at `v`.
    void index_pulse(double v, double raw_pos);

    // Something ended a running homing (stop, mode change): interrupted, to be started again.
    void interrupt(HomingPhase next) {
        if (status_ == HomingStatus::InProgress) {
            status_ = HomingStatus::Interrupted;
            phase_ = next;
        }
    }
    // The mode changed away from homing: a running homing is interrupted where it was.
    void interrupt() { interrupt(phase_); }
    // An error became active while homing runs.
    void error() {
        if (status_ == HomingStatus::InProgress) status_ = HomingStatus::Error;
    }
    // Homing became the mode: idle unless homing was attained.
    void entered() {
        if (status_ != HomingStatus::Done) status_ = HomingStatus::Idle;
    }
    // The resolution or the polarity changed: the reference is lost.
    void invalidate() {
        referenced_ = false;
        shift_ = 0;
    }

    HomingStatus status() const { return status_; }
    HomingPhase phase() const { return phase_; }
    bool running() const { return status_ == HomingStatus::InProgress; }
    bool referenced() const { return referenced_; }
    int64_t shift() const { return shift_; }  // reported = raw + shift

  private:
    void fail(EventSink& sink);
    void finish(Profile& profile, const Parameters& p, EventSink& sink);
    // The edge/index arrives moving the way the phase expects (an overshoot during a reversal must not be
    // taken for the awaited event).
    bool moving_on(double v) const { return (dir_ > 0 && v > 0) || (dir_ < 0 && v < 0); }

    HomingStatus status_ = HomingStatus::Idle;
    HomingPhase phase_ = HomingPhase::Finished;
    int dir_ = 1;        // current search direction
    bool edge_ = false;  // the awaited event happened
    double ref_ = 0;     // reference point (raw inc)
    double event_pos_ = 0;
    int bit_ = -1;        // function bit awaited (-1 none)
    bool rise_ = true;    // awaited edge direction
    bool index_ = false;  // index seen in ToIndex
    int settle_ = 0;      // position ticks at constant search speed (current-threshold methods)
    double search_origin_ = 0;
    bool referenced_ = false;
    int64_t shift_ = 0;
    int8_t method_ = 0;
};

}  // namespace drive
