#pragma once
// The firmware: the code that runs on the slave's microcontroller behind the PDI (the EtherCAT state
// machine, mailbox protocols, the drive). The runtime calls it after every burst of frames (after the
// replies went out, so it never delays a frame) and whenever its deadline passes; it answers the frames
// that arrived meanwhile before it calls it.
// Time base: the runtime's clock, CLOCK_MONOTONIC nanoseconds, the same as the ESC's local time.
#include <cstdint>
#include <iosfwd>
#include <limits>

namespace slave {

// What the runtime offers the firmware while it runs: answering the frames that arrived meanwhile.
class FrameService {
  public:
    virtual ~FrameService() = default;
    // Answers every frame waiting on the link (walks it, sends the reply); returns how many. Cheap when none
    // waits (a look at the receive ring). Must not be called from within a frame's processing.
    virtual int serve_frames() = 0;
};

class Firmware {
  public:
    virtual ~Firmware() = default;
    // Does whatever is due at now_ns (reads the ESC through its PDI, answers mailboxes, runs the drive).
    virtual void poll(uint64_t now_ns) = 0;
    // Monotonic time (ns) at which poll() must run again even if no frame arrives; UINT64_MAX if never.
    // The runtime asks after each poll() (and when the firmware is set): the answer may change only there.
    virtual uint64_t next_deadline_ns() const { return std::numeric_limits<uint64_t>::max(); }
    // An extra descriptor the runtime watches with the link, for input that is not EtherCAT (e.g. a control
    // socket that toggles the simulated machine's inputs); -1: none. Read once, when the firmware is set.
    virtual int control_fd() const { return -1; }
    // control_fd() is readable; poll(now_ns) follows in the same wakeup.
    virtual void on_control(uint64_t /*now_ns*/) {}
    // Statistics for the end of the run ("name value" lines, e.g. ecat::print_stats()); printed by
    // run_slave() at exit with --verbose and written to SlaveOptions::stats_file. Default: nothing.
    virtual void report(std::ostream& /*out*/) const {}

    // Set by the runtime (null: none). A firmware whose poll() is a pass over several devices calls
    // serve_frames() between them, so a frame never waits for the whole pass: a hardware ESC answers a
    // frame whatever its microcontroller is doing.
    void set_frame_service(FrameService* service) { frame_service_ = service; }

  protected:
    int serve_frames() { return frame_service_ != nullptr ? frame_service_->serve_frames() : 0; }

  private:
    FrameService* frame_service_ = nullptr;
};

// Adapts any object with poll(uint64_t) and next_deadline_ns() (e.g. ecat::Stack, which cannot depend on
// this library) to Firmware without owning it.
template <typename T>
class FirmwareAdapter final : public Firmware {
  public:
    explicit FirmwareAdapter(T& target) : target_(target) {}
    void poll(uint64_t now_ns) override { target_.poll(now_ns); }
    uint64_t next_deadline_ns() const override { return target_.next_deadline_ns(); }
    // Forwarded when T has report(std::ostream&) const (ecat::Stack has).
    void report(std::ostream& out) const override {
        if constexpr (requires(const T& t) { t.report(out); }) target_.report(out);
    }

  private:
    T& target_;
};

}  // namespace slave
