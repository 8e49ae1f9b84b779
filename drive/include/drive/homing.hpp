#pragma once
// The state of homing mode (6): status (statusword bits 10, 12, 13), the phase of the method being run, the
// awaited event and the reference point. The phase machine itself runs in Axis (drive/src/homing.cpp), as it
// moves the set-point generator and reads the inputs.
#include <cstdint>

namespace drive {

enum class HomingStatus : uint8_t { Idle, InProgress, Done, Error, Interrupted };
enum class HomingPhase : uint8_t { Search, Backoff, ToIndex, Offset, Stopping, Finished };

struct Homing {
    HomingStatus status = HomingStatus::Idle;
    HomingPhase phase = HomingPhase::Finished;
    int dir = 1;        // current search direction
    bool edge = false;  // the awaited event happened
    double ref = 0;     // reference point (raw inc)
    double event_pos = 0;
    int bit = -1;        // function bit awaited (-1 none)
    bool rise = true;    // awaited edge direction
    bool index = false;  // index seen in ToIndex
    int settle = 0;      // position ticks at constant search speed (current-threshold methods)
    double search_origin = 0;
    bool referenced = false;
    int8_t method = 0;

    bool running() const { return status == HomingStatus::InProgress; }
    // Something ended a running homing (stop, mode change): interrupted, to be started again.
    void interrupt(HomingPhase next) {
        if (status == HomingStatus::InProgress) {
            status = HomingStatus::Interrupted;
            phase = next;
        }
    }
};

}  // namespace drive
