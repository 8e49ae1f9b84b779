#pragma once
// The ESC's lock (EscConfig::thread_safe): a mutex for an owner that calls the ESC from several threads, no
// lock at all for one that calls it from one thread only (a runtime serving frames, PDI and timers in turn,
// as the segment's does for every ESC of a line). Lockable, so std::lock_guard and std::unique_lock work as
// with a mutex; the test is one branch that never changes.
#include <mutex>

namespace esc {

class EscLock {
  public:
    explicit EscLock(bool on) : on_(on) {}
    EscLock(const EscLock&) = delete;
    EscLock& operator=(const EscLock&) = delete;

    void lock() {
        if (on_) mu_.lock();
    }
    bool try_lock() { return !on_ || mu_.try_lock(); }
    void unlock() {
        if (on_) mu_.unlock();
    }

  private:
    std::mutex mu_;
    const bool on_;
};

}  // namespace esc
