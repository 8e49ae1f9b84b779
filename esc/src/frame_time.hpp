#pragma once
// Time of the frame being processed: every access of one frame sees the same clock and local time.
#include <cstdint>

#include "esc/clock.hpp"

namespace esc {

struct FrameTime {
    explicit FrameTime(const Clock& c) : clock(c) {}
    const Clock& clock;
    uint64_t frame_clock = 0;  // Clock time of the frame being processed
    uint64_t frame_local = 0;  // DC local time of that frame
    bool in_frame = false;
    uint64_t now_clock() const { return in_frame ? frame_clock : clock.now_ns(); }
};

}  // namespace esc
