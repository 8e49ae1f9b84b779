#pragma once
// The ESC's free-running local clock source (nanoseconds, monotonic). Tests inject a manual clock.
#include <cstdint>

namespace esc {

class Clock {
  public:
    virtual ~Clock() = default;
    virtual uint64_t now_ns() const = 0;
};

// CLOCK_MONOTONIC.
class SystemClock final : public Clock {
  public:
    uint64_t now_ns() const override;
};

// A clock that moves only when told to (unit tests, simulations).
class ManualClock final : public Clock {
  public:
    uint64_t now_ns() const override { return now_; }
    void set(uint64_t t) { now_ = t; }
    void advance(uint64_t dt) { now_ += dt; }

  private:
    uint64_t now_ = 0;
};

}  // namespace esc
