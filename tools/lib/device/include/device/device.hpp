#pragma once
// A soft device's firmware, composed: everything that runs behind the ESC's PDI of a product (od::Product:
// the built-in MAXPOS, or a device read from a vendor's ESI). For the MAXPOS (DeviceOptions::product null):
//
//   description  maxpos::load_config (or the default), revision/0x100A from the active FoE image
//   dictionary   the product's (maxpos::dictionary) + PDO validators + parameter store (0x1010/0x1011)
//   SII          esi::build_sii of the same description and dictionary, loaded into the ESC
//   ecat::Stack  over the ESC's PDI, esc.irq() as interrupt line, with this as its Application
//   CoE          coe::CoeServer (SDO, SDO info, emergencies) + coe::DiagnosisHistory (0x10F3)
//   FoE          foe::FoeServer over a two-slot foe::FirmwareStore in the state dir
//   drive        drive::Drive on the dictionary, with this as its EventSink
//
// For a product, only the parts it needs: its own dictionary builder (with 0x1018 from its description),
// its EEPROM image byte for byte when it has one (esi::build_sii otherwise), the CoE server only with CoE
// declared, the FoE server and firmware store only with FoE declared, the parameter store only if
// 0x1010/0x1011 exist, the drive only for od::Application::Cia402Drive. A product without application
// gets the IO model (device/io_model.hpp) for its process data. Its warnings are said once at start.
//
// A Bootstrap -> Init restart rebuilds all of it from the then active firmware image, after the Stack's
// poll() returned. The Device runs in the runtime's thread; nothing here is thread-safe.
#include <array>
#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "coe/diagnosis.hpp"
#include "coe/sdo_server.hpp"
#include "device/eeprom_writes.hpp"
#include "device/io_model.hpp"
#include "drive/drive.hpp"
#include "drive/event_sink.hpp"
#include "ecat/application.hpp"
#include "ecat/event_sink.hpp"
#include "ecat/stack.hpp"
#include "esc/esc.hpp"
#include "foe/server.hpp"
#include "foe/store.hpp"
#include "od/device.hpp"
#include "od/dictionary.hpp"
#include "od/product.hpp"
#include "od/store.hpp"
#include "slave/log.hpp"

namespace device {

// The simulated machine around the motor (drive::Environment), positions in raw encoder increments.
// NaN: not fitted.
struct EnvironmentOptions {
    static constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
    double negative_limit = kNone;  // negative limit switch (DigIN1) active at and below
    double positive_limit = kNone;  // positive limit switch (DigIN2) active at and above
    double home_from = kNone;       // home switch (DigIN3) active on [home_from, home_to]
    double home_to = kNone;
    double stop_lo = kNone;  // mechanical stops
    double stop_hi = kNone;
};

// Deliberate deviations of the firmware's layers, a testing aid (device/faults.hpp); none by default.
struct DeviceFaults {
    ecat::StackFaults stack;
    coe::CoeFaults coe;
    foe::FoeFaults foe;
    drive::AxisFaults axis;
    bool identity_mismatch = false;  // 0x1018:02 = the SII's product code + 1
};

struct DeviceOptions {
    // The product this device is (an ESI's device, ...); null: the built-in MAXPOS, from config_file.
    std::shared_ptr<const od::Product> product;
    // Say the product's warnings at start (a line of units of one product says them once, for its first).
    bool announce_product = true;
    std::filesystem::path config_file;  // MAXPOS configuration (maxpos::load_config); empty: defaults
    std::filesystem::path state_dir = "/var/lib/softecat";  // parameters.bin, firmware/
    EnvironmentOptions environment;
    bool load_sii = true;         // false: the ESC serves a user's image (--eeprom), leave it alone
    bool commission = true;       // drive::commission() before the stored parameters are applied
    std::ostream* log = nullptr;  // warnings (bad parameter file, ...); null: std::cerr
    // One line per event (state changes, refused requests, FoE writes, restarts, 0x1010 saves, watchdog,
    // drive faults); null: events are not logged.
    slave::Log* events = nullptr;
    DeviceFaults faults;  // testing aid (ecat-slave --fault); none by default
    // Serial number of this unit (0x1018:04 and the SII's serial word), instead of the configuration's: the
    // drives of one segment (ecat-slave --slaves N) are numbered 1..N. Unset: the configuration's.
    std::optional<uint32_t> serial_number;
};

// Where the firmware slots live inside the state directory.
std::filesystem::path firmware_dir(const DeviceOptions& options);

// The description the device runs with: the configuration file (or od's default, SyncManagers placed),
// with revision and software version of the active firmware image in the state directory, if there is
// one (the state directory is only read if it exists; an empty state_dir: the built-in firmware, as a
// fresh state directory starts with). Throws od::ConfigError on a bad configuration.
od::DeviceDescription make_description(const DeviceOptions& options);
// Everything the device builds from its configuration before it serves (description, dictionary, SII
// image), so that a value one of them refuses is found before any network set-up. Throws od::ConfigError
// (naming the configuration file, and the line where the parser knows it).
void check_device(const DeviceOptions& options);
// The SII image and the ESI text of that description and its dictionary (what --write-sii/--write-esi
// write and what the ESC serves: the SII with the words a master wrote into the EEPROM on top; an empty
// state_dir: of the built-in firmware, no EEPROM writes).
std::vector<uint8_t> make_sii(const DeviceOptions& options);
std::string make_esi(const DeviceOptions& options);

struct DeviceStats {
    uint64_t builds = 0;       // 1 + restarts from Bootstrap
    uint64_t cycles = 0;       // drive cycles run
    uint64_t emergencies = 0;  // raise() + clear() calls from the drive
    uint64_t diagnoses = 0;    // messages offered to the diagnosis history
};

class Device final : public ecat::Application, public drive::EventSink, public ecat::EventSink {
  public:
    // Builds the whole device; loads the SII into esc unless options.load_sii is false.
    // Throws od::ConfigError on a bad configuration file and std::runtime_error if the state directory
    // cannot be used.
    Device(esc::Esc& esc, DeviceOptions options);
    ~Device() override;
    Device(const Device&) = delete;
    Device& operator=(const Device&) = delete;

    // Outside Op, the drive runs on its own every kFreeRunNs when no master cycle ran it (the controller of
    // a hardware drive never stops: a fault reaction ramps down after the master is gone). Its cycles fall
    // on the grid of multiples of kFreeRunNs of the clock, so the drives of a line run theirs in the same
    // wake-up of the runtime instead of one wake-up each.
    static constexpr uint64_t kFreeRunNs = 10'000'000;
    // Longest time one drive cycle simulates: after a longer pause the machine does not catch up.
    static constexpr int64_t kMaxCycleStepNs = 100'000'000;

    // Firmware entry points (slave::Firmware through an adapter).
    void poll(uint64_t now_ns);
    // Asks the memory system for the state a poll reads first, without waiting for it and without changing
    // anything, in stages that a caller polling many devices runs over all of them in turn, each needing
    // what the one before brought into the cache: 0 this object, 1 the parts it holds and the Esc object,
    // 2 the stack's units, the IO model and the ESC's own state (device::Line::poll). The state of devices
    // last touched a cycle ago is mostly evicted on a shared host; asked for together, their cache misses
    // overlap instead of adding up, one device after the other.
    void prefetch(int stage) const;
    // True if poll(now_ns) would do nothing: the stack is quiet, no restart or reaction pending, no
    // free-running drive cycle or EEPROM save due. A line polls only the devices that are not.
    // registers_unchanged: no frame and no timer event changed the ESC's registers since the last poll
    // (ecat::Cycle::quiet()).
    bool quiet(uint64_t now_ns, bool registers_unchanged = false) const;
    uint64_t next_deadline_ns() const;

    // Which parts this device has (see the header comment); the accessors below of a part it has not
    // must not be called.
    bool has_coe() const;
    bool has_foe() const;
    bool has_parameters() const;
    bool has_drive() const;
    // The process data of a device without application (null for a drive).
    const IoModel* io_model() const;
    // Sets the value of entry index:sub from its text (an integer, hex 0x.., a real number for REAL
    // types, true/false); an input of a device without application is held at it (io_model.hpp). Returns
    // "" or why not (no such entry, not a process-data input (TxPDO-mappable), bad value). Kept across
    // restarts.
    std::string set_value(uint16_t index, uint8_t sub, std::string_view text);
    // The value of an entry as text ("" if there is no such entry).
    std::string value_text(uint16_t index, uint8_t sub) const;

    // The machine at run time: a digital input pin 1..6 (not wired to a switch). Kept across restarts.
    // Returns false for a pin outside 1..6 or on a device without drive.
    bool set_input(int pin, bool level);
    // Replaces the switches / stops; kept across restarts.
    void set_environment(const EnvironmentOptions& environment);
    const EnvironmentOptions& environment() const { return options_.environment; }

    // ---- ecat::Application --------------------------------------------------------------------------
    uint16_t check_transition(od::AlState from, od::AlState to) override;
    void on_state_change(od::AlState from, od::AlState to) override;
    void on_cycle(uint64_t now_ns) override;
    void on_outputs_lost() override;
    void on_restart() override;

    // ---- drive::EventSink ---------------------------------------------------------------------------
    void raise(uint16_t error_code, uint8_t error_register, const std::array<uint8_t, 5>& mfr) override;
    void clear(uint16_t error_code, uint8_t error_register) override;
    void diag(drive::Severity severity, uint16_t code, std::string_view text) override;

    // ---- ecat::EventSink (ecat/ and foe/ report here; lines go to options().events) -----------------------
    void state_changed(od::AlState from, od::AlState to) override;
    void state_refused(od::AlState current, uint8_t requested, uint16_t al_status_code) override;
    void local_error(od::AlState state, uint16_t al_status_code) override;
    void watchdog_expired(od::AlState state) override;
    void foe_write(std::string_view name, uint64_t bytes, uint32_t error_code,
                   std::string_view error_text) override;

    // The stack's statistics over the whole run: every firmware instance since the device was created.
    ecat::StackStats stack_stats() const;

    // ---- the parts (valid until the next restart) ---------------------------------------------------
    const DeviceOptions& options() const { return options_; }
    const od::DeviceDescription& description() const;
    od::Dictionary& dictionary();
    ecat::Stack& stack();
    const ecat::Stack& stack() const;
    coe::CoeServer& coe();
    coe::DiagnosisHistory& diagnosis();
    foe::FoeServer& foe();
    foe::FirmwareStore& firmware_store();
    drive::Drive& drive();
    od::ParameterStore& parameters();
    // What loading the parameter file at the last build did.
    const od::ParameterStore::LoadResult& parameter_load() const;
    const DeviceStats& stats() const { return stats_; }
    // The DC system time (0x0910) as the PDI reads it.
    uint64_t system_time_ns();
    // Words a master wrote into the EEPROM (kept in the state directory; see eeprom_writes.hpp).
    const EepromWrites& eeprom_writes() const { return eeprom_writes_; }
    // Time after the last EEPROM write at which the written words are saved (one file write for a burst).
    static constexpr uint64_t kEepromSaveDelayNs = 200'000'000;

  private:
    struct Parts;
    void build();
    void apply_environment();
    void run_drive(uint64_t now_ns);
    void save_eeprom_writes();
    void react_to_outputs_lost();
    std::ostream& log() const;
    void event(slave::LogLevel level, const std::string& text) const;

    esc::Esc& esc_;
    DeviceOptions options_;
    std::unique_ptr<Parts> parts_;
    std::array<int8_t, 6> inputs_{-1, -1, -1, -1, -1, -1};  // user-set pin levels, -1: untouched
    std::map<uint32_t, std::vector<uint8_t>> set_values_;   // set_value(): io_key -> raw value
    std::set<uint32_t> held_;                               // keys of set_values_
    bool restart_pending_ = false;
    bool outputs_lost_pending_ = false;  // outputs ended in this poll(); reacted to when it returns
    // A device without drive: its state machine error (a refused AL request) reported as an emergency
    // (io_state_error) until the next state change clears it.
    bool io_state_error_ = false;
    void io_state_error(uint16_t al_status_code);
    void io_state_error_clear();
    uint64_t free_run_due_ns() const { return (last_cycle_ns_ / kFreeRunNs + 1) * kFreeRunNs; }
    uint64_t last_cycle_ns_ = 0;  // last drive cycle (master's or our own); 0: none since the build
    DeviceStats stats_;
    ecat::StackStats earlier_stacks_;  // statistics of the Stacks that restarts replaced
    EepromWrites eeprom_writes_;
    bool eeprom_dirty_ = false;
    uint64_t eeprom_save_ns_ = 0;  // when the written words are saved; 0: not yet scheduled
};

}  // namespace device
