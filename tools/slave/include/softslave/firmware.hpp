#pragma once
// The firmware: the code that runs on the slave's microcontroller behind the PDI (the EtherCAT state
// machine, mailbox protocols, the drive). The runtime calls it after every burst of frames (after the
// replies went out, so it never delays a frame) and whenever its deadline passes.
// Time base: the runtime's clock, CLOCK_MONOTONIC nanoseconds, the same as the ESC's local time.
#include <cstdint>
#include <limits>

namespace softslave {

class Firmware {
  public:
    virtual ~Firmware() = default;
    // Does whatever is due at now_ns (reads the ESC through its PDI, answers mailboxes, runs the drive).
    virtual void poll(uint64_t now_ns) = 0;
    // Monotonic time (ns) at which poll() must run again even if no frame arrives; UINT64_MAX if never.
    virtual uint64_t next_deadline_ns() const { return std::numeric_limits<uint64_t>::max(); }
};

// Adapts any object with poll(uint64_t) and next_deadline_ns() (e.g. ecat::Stack, which cannot depend on
// this library) to Firmware without owning it.
template <typename T>
class FirmwareAdapter final : public Firmware {
  public:
    explicit FirmwareAdapter(T& target) : target_(target) {}
    void poll(uint64_t now_ns) override { target_.poll(now_ns); }
    uint64_t next_deadline_ns() const override { return target_.next_deadline_ns(); }

  private:
    T& target_;
};

}  // namespace softslave
