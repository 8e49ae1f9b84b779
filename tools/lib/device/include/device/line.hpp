#pragma once
// A segment of soft drives in one process (ecat-slave --slaves N / --topology FILE): an esc::Segment of
// ESCs, each with its Device (the composed firmware) on its own state directory, and the faults a real line
// has, on demand. The runtime (slave::Runtime in segment mode) walks frames through segment() and runs
// this as its firmware: poll() runs every powered device, next_deadline_ns() is the earliest of them.
//
// Power: off takes the device off the line (Segment::set_power(false)) and destroys its Device and ESC;
// what it stored on disk stays (parameters, firmware images and SII words are written atomically). On
// builds a fresh ESC (EEPROM image rebuilt as at start) and a fresh Device on the same state directory:
// the device comes back in Init, as after switching a drive on.
//
// Control lines (apply(); the --control socket): see docs/segment.md.
//   slave <index|name> <command>     a device command (device/control.hpp) for that device
//   link <index|name> <port> up|down a cable plugged / pulled
//   drop <hop> <fraction>            frames lost on hop k (the cable into device k; 0 = from the master)
//   corrupt <hop> <fraction>         frames given a bad FCS there
//   delay <hop> <ns>                 a longer cable, and the reply held back as long
//   power <index|name> off|on|cycle
//   clear                            all hop faults off
//   segment                          one line per device and per hop
//   anything else                    a device command for device 0
#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "device/control.hpp"
#include "device/device.hpp"
#include "esc/clock.hpp"
#include "esc/esc.hpp"
#include "esc/segment.hpp"
#include "slave/log.hpp"
#include "slave/slave.hpp"
#include "slave/topology.hpp"

namespace device {

struct LineOptions {
    // Devices, wiring, timing (state_dir of every device resolved by the caller; config empty: base's).
    slave::Topology topology;
    DeviceOptions base;  // everything else of each device (environment, faults, commission)
    // The product of each device, by topology index (a device from an ESI or an ENI slave); missing or null:
    // base.product (the built-in drive unless base says otherwise).
    std::vector<std::shared_ptr<const od::Product>> products;
    esc::EscConfig esc;  // base ESC configuration (RAM, faults); ports, drift and offset per device
    std::filesystem::path control_path;             // the --control socket; empty: none
    gid_t control_group = ControlSocket::kNoGroup;  // --control-group: who else may use it
    slave::Log* log = nullptr;  // segment events (faults, power); each device logs as "NAME: ..."
};

struct LineStats {
    uint64_t link_changes = 0;           // cables pulled or plugged through link
    uint64_t fault_changes = 0;          // drop/corrupt/delay/clear commands
    std::vector<uint64_t> power_cycles;  // per device: times it was switched on again after an off
    uint64_t polls = 0;                  // devices' firmware polled (Device::poll) by poll()
};

class Line final : public slave::SegmentFirmware {
  public:
    // Builds every ESC and Device and wires the segment. send: the external port's link (empty: none);
    // it goes to topology.external_device/port, or port 1 of the last device.
    // Throws od::ConfigError / std::runtime_error as Device does, std::invalid_argument for bad wiring.
    Line(const esc::Clock& clock, LineOptions options, slave::ExternalSend send = {});
    ~Line() override;

    // ---- slave::Firmware ------------------------------------------------------------------------
    void poll(uint64_t now_ns) override;
    uint64_t next_deadline_ns() const override;
    int control_fd() const override { return control_ ? control_->fd() : -1; }
    void on_control(uint64_t now_ns) override;
    // Device 0's figures as a single drive reports them (ecat.*, device.*), then segment.* lines, then every
    // device's ecat.* and device.* lines prefixed segment.device<k>.
    void report(std::ostream& out) const override;
    esc::Segment& segment() override { return segment_; }

    // ---- the devices -----------------------------------------------------------------------------
    std::size_t size() const { return units_.size(); }
    // Index of a device by name or index ("drive3", "2"); -1 if none.
    int find(std::string_view name_or_index) const;
    const std::string& name(int device) const;
    bool powered(int device) const;
    // The device's firmware; null while it is powered off.
    Device* device(int index);
    esc::Esc& esc(int index);

    // ---- faults ----------------------------------------------------------------------------------
    void power(int device, bool on);
    // Applies one control line; the answer ("ok ...", "error: ...", several lines for `segment`).
    std::string apply(std::string_view line);
    const LineStats& stats() const { return stats_; }

  private:
    struct Unit;
    void build_unit(Unit& unit);
    void event(slave::LogLevel level, const std::string& text) const;
    std::string segment_text() const;

    const esc::Clock& clock_;
    LineOptions options_;
    std::vector<std::unique_ptr<Unit>> units_;  // before segment_: the ESCs outlive the Segment
    esc::Segment segment_;
    std::unique_ptr<ControlSocket> control_;
    LineStats stats_;
    // Per device, as the last poll() found it: its next deadline, and when it must be asked (kQuiet: only
    // when woken or due; kEveryPass: not quiet after its poll; kOnActivity: quiet but for an interrupt
    // line it cannot use, so it reads the registers themselves: asked when its ESC's registers changed,
    // seen_ holding EscSignals::activity as of its last poll). Not known after a control command, a power
    // change or a caller's access to a device (deadline_known_ false: next_deadline_ns() asks every
    // device, the next poll() too).
    enum Ask : uint8_t { kQuiet = 0, kEveryPass = 1, kOnActivity = 2 };
    std::vector<uint64_t> due_;
    std::vector<uint8_t> ask_;
    std::vector<uint32_t> seen_;
    bool deadline_known_ = false;
};

}  // namespace device
