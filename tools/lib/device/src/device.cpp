// device::Device: the soft drive's firmware composed from od, ecat, coe, foe, drive and esi.
#include "device/device.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <iomanip>
#include <iostream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include "coe/events.hpp"
#include "coe/pdo_validation.hpp"
#include "drive/errors.hpp"
#include "drive/objects.hpp"
#include "drive/state_machine.hpp"
#include "esc/wire/al.hpp"
#include "esc/wire/registers.hpp"
#include "esi/esi.hpp"
#include "esi/sii.hpp"
#include "foe/firmware.hpp"
#include "foe/image.hpp"
#include "maxpos/maxpos.hpp"
#include "od/device_config.hpp"
#include "util/le.hpp"
#include "util/lex.hpp"
#include "util/strfmt.hpp"

namespace device {

namespace {

foe::StoreConfig store_config(const DeviceOptions& options, const od::DeviceDescription& d) {
    foe::StoreConfig c;
    c.dir = firmware_dir(options);
    c.identity = foe::ImageIdentity::from(d.identity);
    c.device_name = d.identity.device_name.empty() ? "MAXPOS" : d.identity.device_name;
    return c;
}

od::DeviceDescription base_description(const DeviceOptions& options) {
    od::DeviceDescription d = options.product               ? options.product->description
                              : options.config_file.empty() ? maxpos::description()
                                                            : maxpos::load_config(options.config_file);
    if (options.serial_number) d.identity.serial_number = *options.serial_number;
    return d;
}

od::Dictionary make_dictionary(const DeviceOptions& options, const od::DeviceDescription& d) {
    return options.product ? options.product->make_dictionary(d) : maxpos::dictionary(d);
}

// The built-in MAXPOS has every part; a product the parts it declares.
bool has_foe_part(const DeviceOptions& options, const od::DeviceDescription& d) {
    return !options.product || (d.mailbox_protocols & od::mailbox_protocol::FoE) != 0;
}
bool has_coe_part(const DeviceOptions& options, const od::DeviceDescription& d) {
    return !options.product || (d.mailbox_protocols & od::mailbox_protocol::CoE) != 0;
}
bool has_drive_part(const DeviceOptions& options) {
    return !options.product || options.product->application == od::Application::Cia402Drive;
}

// Where the product keeps the drive's vendor parameters: the built-in MAXPOS's; a product from an ESI or ENI
// has only the CiA 402 objects, which the drive binds by index.
const drive::VendorObjects& vendor_objects(const DeviceOptions& options) {
    static const drive::VendorObjects none{};
    return options.product ? none : maxpos::drive_objects();
}

bool has_parameter_part(const DeviceOptions& options, const od::Dictionary& dict) {
    return !options.product || dict.find(0x1010) != nullptr || dict.find(0x1011) != nullptr;
}

// The SII image as built: the product's own EEPROM image byte for byte (a unit of a line with its serial
// number in words 0x0E/0x0F, which the checksum of words 0..6 does not cover), else built from the
// description and the dictionary.
std::vector<uint8_t> built_sii(const DeviceOptions& options, const od::DeviceDescription& d,
                               const od::Dictionary& dict) {
    if (options.product && !options.product->eeprom.empty()) {
        std::vector<uint8_t> image = options.product->eeprom;
        if (options.serial_number && image.size() >= 0x20) {
            const uint32_t serial = *options.serial_number;
            for (int i = 0; i < 4; ++i)
                image[static_cast<std::size_t>(0x1C + i)] = static_cast<uint8_t>(serial >> (8 * i));
        }
        return image;
    }
    return esi::build_sii(d, dict);
}

std::string source_name(const DeviceOptions& options) {
    if (options.product) return options.product->source;
    return options.config_file.empty() ? std::string("the built-in drive") : options.config_file.string();
}

// The description with the version of the active image of an opened store.
void apply_active_image(od::DeviceDescription& d, const foe::FirmwareStore& store) {
    if (const auto& active = store.active_image()) foe::apply_version(d.identity, active->header.version);
}

bool is_nan(double v) {
    return std::isnan(v);
}

}  // namespace

std::filesystem::path firmware_dir(const DeviceOptions& options) {
    return options.state_dir / "firmware";
}

od::DeviceDescription make_description(const DeviceOptions& options) {
    od::DeviceDescription d = base_description(options);
    std::error_code ec;
    if (has_foe_part(options, d) && !options.state_dir.empty() &&
        std::filesystem::is_directory(firmware_dir(options), ec)) {
        foe::FirmwareStore store(store_config(options, d));
        if (store.open()) apply_active_image(d, store);
    }
    return d;
}

void check_device(const DeviceOptions& options) {
    const od::DeviceDescription d = make_description(options);
    try {
        const od::Dictionary dict = make_dictionary(options, d);
        (void)built_sii(options, d, dict);
    } catch (const std::exception& e) {
        throw od::ConfigError(source_name(options), 0, e.what());
    }
}

std::vector<uint8_t> make_sii(const DeviceOptions& options) {
    const od::DeviceDescription d = make_description(options);
    const od::Dictionary dict = make_dictionary(options, d);
    std::vector<uint8_t> image = built_sii(options, d, dict);
    if (options.state_dir.empty()) return image;
    EepromWrites writes(options.state_dir);
    if (writes.load().empty()) writes.apply(image);
    return image;
}

std::string make_esi(const DeviceOptions& options) {
    const od::DeviceDescription d = make_description(options);
    const od::Dictionary dict = make_dictionary(options, d);
    // A device with its own EEPROM image (ESI Eeprom/Data) is described with that image.
    if (options.product && !options.product->eeprom.empty())
        return esi::build_esi(d, dict, options.product->eeprom);
    return esi::build_esi(d, dict);
}

// Everything a restart rebuilds, in construction order (members are destroyed in reverse).
struct Device::Parts {
    od::DeviceDescription desc;
    std::unique_ptr<foe::FirmwareUpdate> firmware;  // store in <state>/firmware + FoE server
    od::Dictionary dict;
    std::unique_ptr<od::ParameterStore> params;
    od::ParameterStore::LoadResult load;
    std::unique_ptr<ecat::Stack> stack;
    std::unique_ptr<coe::CoeServer> coe;
    std::unique_ptr<coe::DiagnosisHistory> diag;
    std::string diag_unusable;  // why a product's 0x10F3 holds no history (empty: it does, or there is none)
    std::unique_ptr<coe::EventReporter> events;
    std::unique_ptr<drive::Drive> drive;
    std::unique_ptr<IoModel> io;  // a device without application
};

Device::Device(esc::Esc& esc, DeviceOptions options)
    : esc_(esc), options_(std::move(options)), eeprom_writes_(options_.state_dir) {
    // Temporaries a save killed half-way left behind (parameters, SII words; the firmware store removes its
    // own when it opens): never valid, removed before anything else reads the state directory.
    const od::ParameterStore params(options_.state_dir);
    if (params.remove_stale_temp())
        log() << "softdrive: removed " << params.file().string() << ".tmp left by an interrupted save\n";
    if (eeprom_writes_.remove_stale_temp())
        log() << "softdrive: removed " << eeprom_writes_.file().string()
              << ".tmp left by an interrupted save\n";
    if (options_.load_sii) {
        if (const std::string error = eeprom_writes_.load(); !error.empty())
            log() << "softdrive: " << eeprom_writes_.file().string() << " not used (" << error
                  << "); serving the SII as built\n";
    }
    build();
    if (options_.load_sii && !eeprom_writes_.empty()) {
        // The SII served is not the generated one: say so, and how to go back (docs/decisions/device.md).
        event(slave::LogLevel::Warn, "the SII served carries " + std::to_string(eeprom_writes_.size()) +
                                         " word(s) a master wrote into the EEPROM, kept in " +
                                         eeprom_writes_.file().string() +
                                         "; delete that file (or start with --reset-sii) to serve the "
                                         "SII generated from the object model");
        std::vector<uint8_t> image = built_sii(options_, parts_->desc, parts_->dict);
        eeprom_writes_.apply(image);
        const od::Identity& id = parts_->desc.identity;
        for (const std::string& d :
             sii_drift(image, id.vendor_id, id.product_code, id.revision, id.serial_number))
            event(slave::LogLevel::Warn, "the SII served: " + d);
    }
    // What the product declares that is not emulated: said once. A mode its 0x6502 announces that the drive
    // core cannot serve is one of them: the drive took it out of 0x6502 (docs/decisions/device.md).
    if (options_.product && options_.announce_product) {
        std::vector<std::string> warnings = options_.product->warnings;
        if (parts_ && parts_->drive && parts_->drive->withheld_modes() != 0) {
            std::ostringstream w;
            w << "0x6502 announces modes the drive core does not serve on this dictionary (bits 0x"
              << std::hex << std::setw(8) << std::setfill('0') << parts_->drive->withheld_modes()
              << "); 0x6502 announces the others";
            warnings.push_back(w.str());
        }
        if (parts_ && !parts_->diag_unusable.empty())
            warnings.push_back(
                parts_->diag_unusable +
                " (ETG.1020 Diagnosis History): 0x10F3 serves the values the description gives, "
                "without a diagnosis history");
        for (const std::string& w : warnings) {
            if (options_.events != nullptr)
                event(slave::LogLevel::Warn, options_.product->source + ": " + w);
            else
                log() << "softecat: " << options_.product->source << ": " << w << '\n';
        }
    }
    // Registered once the device exists: a constructor that throws leaves no callback behind.
    if (options_.load_sii)
        esc_.on_eeprom_write([this](uint16_t address, uint16_t value) {
            eeprom_writes_.record(address, value);
            eeprom_dirty_ = true;
            eeprom_save_ns_ = 0;  // scheduled by the next poll()
        });
}

Device::~Device() {
    if (options_.load_sii) esc_.on_eeprom_write({});
    if (eeprom_dirty_) save_eeprom_writes();
}

void Device::save_eeprom_writes() {
    eeprom_dirty_ = false;
    eeprom_save_ns_ = 0;
    if (const std::string error = eeprom_writes_.save(); !error.empty())
        log() << "softdrive: the EEPROM content the master wrote is not kept: " << error << '\n';
}

void Device::event(slave::LogLevel level, const std::string& text) const {
    if (options_.events != nullptr) options_.events->write(level, text);
}

ecat::StackStats Device::stack_stats() const {
    ecat::StackStats total = earlier_stacks_;
    ecat::add_stats(total, parts_->stack->stats());
    return total;
}

namespace {

// The state names of the AL vocabulary (esc::al_state_name: INIT, PREOP, BOOT, SAFEOP, OP).
std::string state_text(od::AlState s) {
    return std::string(esc::al_state_name(s));
}

std::string requested_text(uint8_t requested) {
    switch (requested) {
        case 0x01:
        case 0x02:
        case 0x03:
        case 0x04:
        case 0x08:
            return std::string(esc::al_state_name(requested));
        default:
            return "unknown state " + std::to_string(requested);
    }
}

std::string al_code_text(uint16_t code) {
    return util::strprintf("0x%04X (%s)", static_cast<unsigned>(code),
                           std::string(esc::al::status_text(code)).c_str());
}

std::string hex16(uint16_t v) {
    char b[8];
    std::snprintf(b, sizeof b, "0x%04X", static_cast<unsigned>(v));
    return b;
}

}  // namespace

// ---- ecat::EventSink --------------------------------------------------------------------------------

void Device::state_changed(od::AlState from, od::AlState to) {
    event(slave::LogLevel::Info, std::string("AL state ") + state_text(from) + " -> " + state_text(to));
}

void Device::state_refused(od::AlState current, uint8_t requested, uint16_t code) {
    event(slave::LogLevel::Warn, std::string("refused AL state request ") + state_text(current) + " -> " +
                                     requested_text(requested) + ": AL status code " + al_code_text(code));
    // The mailbox runs from Pre-Op on: a refusal in Init (or Bootstrap) has no mailbox to report through.
    if (current != od::AlState::Init && current != od::AlState::Boot) io_state_error(code);
}

// A device without drive (no firmware error table of its own) reports a refused AL request as ETG.1000.6
// does for CoE devices: emergency 0xA000 (EtherCAT state machine transition error), the AL status code in
// the first two bytes of the manufacturer-specific field, the error register (CiA 301 0x1001: bit 0 generic,
// bit 4 communication) kept in 0x1001 where the dictionary has it.
void Device::io_state_error(uint16_t al_status_code) {
    if (parts_->drive || !parts_->events) return;
    constexpr uint16_t kStateMachineError = 0xA000;
    constexpr uint8_t kRegister = 0x11;  // generic + communication
    if (parts_->dict.find(0x1001, 0) != nullptr) (void)parts_->dict.set<uint8_t>(0x1001, 0, kRegister);
    const std::array<uint8_t, 5> mfr{static_cast<uint8_t>(al_status_code & 0xFF),
                                     static_cast<uint8_t>(al_status_code >> 8), 0, 0, 0};
    io_state_error_ = true;
    ++stats_.emergencies;
    parts_->events->raise(kStateMachineError, kRegister, mfr);
}

void Device::io_state_error_clear() {
    if (!io_state_error_) return;
    io_state_error_ = false;
    if (parts_->dict.find(0x1001, 0) != nullptr) (void)parts_->dict.set<uint8_t>(0x1001, 0, 0);
    ++stats_.emergencies;
    if (parts_->events) parts_->events->clear(0xA000, 0);  // the "no error" emergency (code 0x0000)
}

void Device::local_error(od::AlState state, uint16_t code) {
    event(slave::LogLevel::Warn,
          std::string("error indication in ") + state_text(state) + ": AL status code " + al_code_text(code));
}

void Device::watchdog_expired(od::AlState state) {
    event(slave::LogLevel::Warn,
          std::string("process-data watchdog expired in ") + state_text(state) + " (outputs not refreshed)");
}

void Device::foe_write(std::string_view name, uint64_t bytes, uint32_t error_code,
                       std::string_view error_text) {
    std::string line = "FoE write '" + std::string(name) + "', " + std::to_string(bytes) + " bytes: ";
    if (error_code == 0) {
        event(slave::LogLevel::Info, line + "stored");
        return;
    }
    event(slave::LogLevel::Warn,
          line + util::strprintf("failed, FoE error 0x%04X (%s)", static_cast<unsigned>(error_code),
                                 std::string(error_text).c_str()));
}

std::ostream& Device::log() const {
    return options_.log != nullptr ? *options_.log : std::cerr;
}

void Device::build() {
    std::error_code ec;
    std::filesystem::create_directories(options_.state_dir, ec);
    if (ec)
        throw std::runtime_error("cannot create the state directory '" + options_.state_dir.string() +
                                 "': " + ec.message());

    // The new device is built beside the old one and replaces it only when complete: a restart that fails
    // (e.g. the state directory became unusable) leaves the old firmware running.
    auto p = std::make_unique<Parts>();
    p->desc = base_description(options_);
    if (has_foe_part(options_, p->desc)) {
        foe::ServerConfig foe_config = foe::ServerConfig::from(p->desc);
        foe_config.faults = options_.faults.foe;
        p->firmware = std::make_unique<foe::FirmwareUpdate>(options_.state_dir, p->desc, foe_config);
        if (!p->firmware->ok())
            log() << "softdrive: firmware store " << firmware_dir(options_).string() << ": "
                  << p->firmware->error().text << " (running the built-in firmware)\n";
        p->firmware->apply_to(p->desc.identity);
    }

    p->dict = make_dictionary(options_, p->desc);
    coe::install_pdo_validators(p->dict, {}, p->desc.pdo_rules);
    if (options_.faults.identity_mismatch && p->dict.find(0x1018, 2) != nullptr)
        (void)p->dict.set<uint32_t>(0x1018, 2, p->desc.identity.product_code + 1);
    // Values set at run time (set_value), kept across restarts.
    for (const auto& [key, raw] : set_values_)
        (void)p->dict.set_raw(static_cast<uint16_t>(key >> 8), static_cast<uint8_t>(key & 0xFF), raw);
    const bool drive = has_drive_part(options_);
    if (drive && options_.commission) {
        // Only what exists is commissioned (a vendor's drive may lack the MAXPOS motor objects).
        od::Status s = od::Status::Ok;
        try {
            s = drive::commission(p->dict, vendor_objects(options_));
        } catch (const std::exception& e) {
            if (!options_.product) throw;
            log() << "softdrive: commissioning the motor parameters failed: " << e.what() << '\n';
        }
        if (s != od::Status::Ok)
            log() << "softdrive: commissioning the motor parameters failed: " << od::to_string(s) << '\n';
    }
    Parts* raw = p.get();
    if (has_parameter_part(options_, p->dict)) {
        p->params = std::make_unique<od::ParameterStore>(options_.state_dir);
        p->load = p->params->load(p->dict);
        if (p->load.found && !p->load.applied)
            log() << "softdrive: stored parameters " << p->params->file().string() << " not used ("
                  << p->load.error << "); running with the defaults\n";
        od::attach_store(
            p->dict, *p->params,
            [raw] {
                // MAXPOS firmware specification §7.2.21: restoring defaults only with the axis in "Power
                // Disable" (not switched on).
                constexpr auto sw = drive::obj::Statusword;
                const od::Entry* e = raw->dict.find(sw.index, sw.sub);
                if (e == nullptr) return od::Status::Ok;
                return (raw->dict.get<uint16_t>(sw.index, sw.sub) & drive::sw::SwitchedOn) != 0
                           ? od::Status::WrongState
                           : od::Status::Ok;
            },
            // A master's 0x1010/0x2110 "save" and 0x1011/0x2111 "load": what the store did, done or failed (a
            // failed one was answered with an SDO abort; the log says why).
            [this, raw](const od::Entry& e, bool save, const std::string& error) {
                // Appended piece by piece: "literal" + a temporary string trips GCC 12's -Wrestrict at -O3.
                std::string which = "(";
                which += hex16(e.index);
                which += ':';
                which += std::to_string(e.subindex);
                which += ' ';
                which += e.name;
                which += ')';
                if (!error.empty())
                    event(slave::LogLevel::Error,
                          std::string(save ? "stored parameters not saved "
                                           : "stored parameters not restored ") +
                              which + ": " + error +
                              " (the master got SDO abort 0x06060000, hardware error)");
                else if (save)
                    event(slave::LogLevel::Info,
                          "stored parameters saved " + which + " to " + raw->params->file().string());
                else
                    event(slave::LogLevel::Info,
                          "stored parameters restored to defaults at the next start " + which);
            });
    }

    std::vector<uint8_t> image;
    if (options_.load_sii) {
        image = built_sii(options_, p->desc, p->dict);
        eeprom_writes_.apply(image);
        // Loaded before the controller starts, as an ESC loads its EEPROM at power-on: the stack finds the
        // ESC configuration (device emulation, 0x0141) the device runs with.
        esc_.load_eeprom(image);
    }

    p->stack = std::make_unique<ecat::Stack>(esc_, p->dict, p->desc, *this, [this] { return esc_.irq(); });
    p->stack->set_faults(options_.faults.stack);
    if (has_coe_part(options_, p->desc)) {
        coe::CoeConfig coe_config;
        coe_config.faults = options_.faults.coe;
        coe_config.complete_access = (p->desc.coe_details & od::coe_details::CompleteAccess) != 0;
        p->coe = std::make_unique<coe::CoeServer>(
            p->dict, [raw] { return raw->stack->state(); }, coe_config);
        // The diagnosis history where the dictionary has its object (0x10F3, ETG.1020).
        // A product whose 0x10F3 has no room for messages (a vendor ESI that declares :00..:05 only) serves
        // the object as the values it declares, without a history: said once with the product's warnings.
        if (options_.product && p->dict.find(0x10F3) != nullptr)
            p->diag_unusable = coe::DiagnosisHistory::unusable(p->dict);
        if (!options_.product || (p->dict.find(0x10F3) != nullptr && p->diag_unusable.empty()))
            p->diag = std::make_unique<coe::DiagnosisHistory>(p->dict, &p->coe->emergency());
        p->events = std::make_unique<coe::EventReporter>(p->coe->emergency(), p->diag.get(),
                                                         [this] { return system_time_ns(); });
        p->events->set_texts(p->desc.diag_messages);  // the texts the ESI lists as DiagMessages
        p->stack->add_handler(*p->coe);
    }
    if (p->firmware) {
        p->stack->add_handler(p->firmware->server());
        p->firmware->server().set_event_sink(this);
    }
    p->stack->set_event_sink(this);
    if (drive) {
        // A vendor's CiA 402 dictionary the drive core cannot run on: said, and served as process data.
        try {
            p->drive = std::make_unique<drive::Drive>(p->dict, this, vendor_objects(options_));
            p->drive->axis().faults = options_.faults.axis;
        } catch (const std::exception& e) {
            if (!options_.product) throw;
            log() << "softecat: " << options_.product->source
                  << ": the CiA 402 drive core does not run on this dictionary (" << e.what()
                  << "); serving its process data without a drive\n";
            p->drive.reset();
        }
    }
    if (!p->drive) p->io = std::make_unique<IoModel>();

    if (parts_) ecat::add_stats(earlier_stacks_, parts_->stack->stats());
    parts_ = std::move(p);
    restart_pending_ = false;
    io_state_error_ = false;
    outputs_lost_pending_ = false;
    last_cycle_ns_ = 0;
    ++stats_.builds;
    apply_environment();
}

void Device::apply_environment() {
    if (!parts_->drive) return;
    drive::Environment& env = parts_->drive->environment();
    const EnvironmentOptions& e = options_.environment;
    env.remove_switches();
    if (!is_nan(e.negative_limit)) env.set_negative_limit(e.negative_limit);
    if (!is_nan(e.positive_limit)) env.set_positive_limit(e.positive_limit);
    if (!is_nan(e.home_from) || !is_nan(e.home_to)) {
        const double from = is_nan(e.home_from) ? e.home_to : e.home_from;
        const double to = is_nan(e.home_to) ? e.home_from : e.home_to;
        env.set_home_switch(std::min(from, to), std::max(from, to));
    }
    env.set_mechanical_stops(e.stop_lo, e.stop_hi);
    for (int pin = 1; pin <= static_cast<int>(inputs_.size()); ++pin)
        if (inputs_[static_cast<std::size_t>(pin - 1)] >= 0)
            env.set_input(pin, inputs_[static_cast<std::size_t>(pin - 1)] != 0);
}

bool Device::set_input(int pin, bool level) {
    if (pin < 1 || pin > static_cast<int>(inputs_.size()) || !parts_->drive) return false;
    inputs_[static_cast<std::size_t>(pin - 1)] = level ? 1 : 0;
    parts_->drive->environment().set_input(pin, level);
    return true;
}

void Device::set_environment(const EnvironmentOptions& environment) {
    options_.environment = environment;
    apply_environment();
}

void Device::poll(uint64_t now_ns) {
    parts_->stack->poll(now_ns);
    if (outputs_lost_pending_) react_to_outputs_lost();  // after poll(): the error indication is set by now
    // The restart runs here, after the Stack's poll() returned: the Stack is destroyed with the rest.
    if (restart_pending_) {
        restart_pending_ = false;
        try {
            build();
            const od::Identity& id = parts_->desc.identity;
            event(slave::LogLevel::Info,
                  util::strprintf(
                      "firmware restarted (Bootstrap -> Init): revision 0x%08X, software version %s",
                      static_cast<unsigned>(id.revision), id.software_version.c_str()));
        } catch (const std::exception& e) {
            log() << "softdrive: restart failed, the running firmware stays: " << e.what() << '\n';
            event(slave::LogLevel::Error, std::string("firmware restart failed: ") + e.what());
        }
        parts_->stack->poll(now_ns);
    }
    // The drive's own loop: it runs when no master cycle drives it (outside Op), as the controller of a
    // hardware drive never stops; the first run right after a build sets the statusword.
    if (parts_->drive &&
        (last_cycle_ns_ == 0 || (parts_->stack->state() != od::AlState::Op && now_ns >= free_run_due_ns())))
        run_drive(now_ns);
    if (eeprom_dirty_) {
        if (eeprom_save_ns_ == 0)
            eeprom_save_ns_ = now_ns + kEepromSaveDelayNs;
        else if (now_ns >= eeprom_save_ns_)
            save_eeprom_writes();
    }
}

void Device::prefetch(int stage) const {
    switch (stage) {
        case 0:  // this object: what poll() and quiet() read of it (reads nothing)
            __builtin_prefetch(this);
            __builtin_prefetch(&parts_);
            __builtin_prefetch(&restart_pending_);
            __builtin_prefetch(&last_cycle_ns_);
            __builtin_prefetch(&eeprom_dirty_);
            break;
        case 1: {  // reads esc_ and parts_
            __builtin_prefetch(&esc_);
            const Parts* p = parts_.get();
            if (p == nullptr) break;
            __builtin_prefetch(&p->stack);
            __builtin_prefetch(&p->drive);
            __builtin_prefetch(&p->io);
            break;
        }
        default:  // reads the Esc object and the parts
            esc_.prefetch(false);
            if (!parts_) break;
            if (parts_->stack) parts_->stack->prefetch();
            if (parts_->io) __builtin_prefetch(parts_->io.get());
            break;
    }
}

bool Device::quiet(uint64_t now_ns, bool registers_unchanged) const {
    if (restart_pending_ || outputs_lost_pending_ || (parts_->drive && last_cycle_ns_ == 0)) return false;
    if (!parts_->stack->quiet(now_ns, registers_unchanged)) return false;
    if (eeprom_dirty_ && (eeprom_save_ns_ == 0 || now_ns >= eeprom_save_ns_)) return false;
    if (!parts_->drive) return true;  // nothing runs on its own
    return parts_->stack->state() == od::AlState::Op || now_ns < free_run_due_ns();
}

uint64_t Device::next_deadline_ns() const {
    uint64_t next = parts_->stack->next_deadline_ns();
    if (eeprom_dirty_ && eeprom_save_ns_ != 0) next = std::min(next, eeprom_save_ns_);
    if (!parts_->drive || parts_->stack->state() == od::AlState::Op || last_cycle_ns_ == 0) return next;
    return std::min(next, free_run_due_ns());
}

void Device::run_drive(uint64_t now_ns) {
    int64_t dt = 0;
    if (last_cycle_ns_ != 0 && now_ns > last_cycle_ns_)
        dt = std::min<int64_t>(static_cast<int64_t>(now_ns - last_cycle_ns_), kMaxCycleStepNs);
    last_cycle_ns_ = now_ns;
    parts_->drive->cycle(static_cast<int64_t>(now_ns), dt);
    ++stats_.cycles;
}

uint64_t Device::system_time_ns() {
    uint8_t b[8] = {};
    esc_.read(esc::reg::kDcSystemTime, b);
    return util::get64(b);
}

// ---- ecat::Application ------------------------------------------------------------------------------

uint16_t Device::check_transition(od::AlState /*from*/, od::AlState /*to*/) {
    return 0;
}

void Device::on_state_change(od::AlState from, od::AlState to) {
    io_state_error_clear();  // a state change carried out: the refused request is over
    // Leaving Op by any path ends the outputs, whether or not on_outputs_lost() came first.
    if (from == od::AlState::Op && to != od::AlState::Op) {
        outputs_lost_pending_ = true;
        if (parts_->io) parts_->io->safe_outputs();  // before a plan that ends here is cleared
    }
    if (parts_->io) {
        // The mapping is fixed from Safe-Op on: the plan of the IO model is built once, here.
        const bool pd_from = from == od::AlState::SafeOp || from == od::AlState::Op;
        const bool pd_to = to == od::AlState::SafeOp || to == od::AlState::Op;
        if (pd_to && !pd_from) {
            parts_->io->build(parts_->stack->process_data(), held_);
        } else if (pd_from && !pd_to) {
            parts_->io->clear();
        }
    }
}

void Device::on_cycle(uint64_t now_ns) {
    if (parts_->drive) {
        run_drive(now_ns);
        return;
    }
    last_cycle_ns_ = now_ns;
    parts_->io->cycle();
    ++stats_.cycles;
}

void Device::on_outputs_lost() {
    outputs_lost_pending_ = true;
}

void Device::react_to_outputs_lost() {
    outputs_lost_pending_ = false;
    if (!parts_->drive) {
        if (parts_->io) parts_->io->safe_outputs();  // also a watchdog that leaves the device in Op
        return;
    }
    // A fall-back (watchdog, sync loss: the stack set the error indication) is a communication failure:
    // 0x8180 with the 0x6007 reaction in any drive state. A master that asks to leave Op is not an error; it
    // gets the reaction only while its outputs were commanding motion (operation enabled, statusword bit 2).
    const bool fall_back = parts_->stack->error();
    constexpr auto statusword = drive::obj::Statusword;
    const od::Entry* sw = parts_->dict.find(statusword.index, statusword.sub);
    const bool enabled = sw != nullptr && (parts_->dict.get<uint16_t>(statusword.index, statusword.sub) &
                                           drive::sw::OperationEnabled) != 0;
    if (fall_back || enabled) parts_->drive->connection_lost();
}

void Device::on_restart() {
    restart_pending_ = true;
}

// ---- drive::EventSink -------------------------------------------------------------------------------

void Device::raise(uint16_t error_code, uint8_t error_register, const std::array<uint8_t, 5>& mfr) {
    const drive::ErrorInfo* info = drive::find_error(error_code);
    if (options_.events != nullptr && options_.events->enabled(slave::LogLevel::Error)) {
        event(slave::LogLevel::Error, "drive fault " + hex16(error_code) + ": " +
                                          (info != nullptr ? std::string(info->name) : "unknown error"));
    }
    ++stats_.emergencies;
    ++stats_.diagnoses;
    // The error's name finds the text of a device whose texts came from an ESI (no code binding there).
    if (parts_->events)
        parts_->events->raise(error_code, error_register, mfr,
                              info != nullptr ? info->name : std::string_view());
}

void Device::clear(uint16_t error_code, uint8_t error_register) {
    if (options_.events != nullptr && options_.events->enabled(slave::LogLevel::Debug))
        event(slave::LogLevel::Debug, "drive error " + hex16(error_code) + " cleared");
    ++stats_.emergencies;
    if (parts_->events) parts_->events->clear(error_code, error_register);
}

void Device::diag(drive::Severity severity, uint16_t code, std::string_view text) {
    const slave::LogLevel level = severity == drive::Severity::Error     ? slave::LogLevel::Error
                                  : severity == drive::Severity::Warning ? slave::LogLevel::Warn
                                                                         : slave::LogLevel::Debug;
    if (options_.events != nullptr && options_.events->enabled(level)) {
        // Appended piece by piece: GCC 12's -O3 reports a false -Werror=restrict on "literal" +
        // std::string&&.
        std::string line = "drive";
        if (code != 0) line.append(" ").append(hex16(code));
        line.append(": ").append(text);
        event(level, line);
    }
    ++stats_.diagnoses;
    if (!parts_->events) return;
    parts_->events->diag(severity == drive::Severity::Error     ? coe::DiagType::Error
                         : severity == drive::Severity::Warning ? coe::DiagType::Warning
                                                                : coe::DiagType::Info,
                         code, text);
}

// ---- parts ------------------------------------------------------------------------------------------

bool Device::has_coe() const {
    return parts_->coe != nullptr;
}
bool Device::has_foe() const {
    return parts_->firmware != nullptr;
}
bool Device::has_parameters() const {
    return parts_->params != nullptr;
}
bool Device::has_drive() const {
    return parts_->drive != nullptr;
}
const IoModel* Device::io_model() const {
    return parts_->io.get();
}

const od::DeviceDescription& Device::description() const {
    return parts_->desc;
}
od::Dictionary& Device::dictionary() {
    return parts_->dict;
}
ecat::Stack& Device::stack() {
    return *parts_->stack;
}
const ecat::Stack& Device::stack() const {
    return *parts_->stack;
}
coe::CoeServer& Device::coe() {
    return *parts_->coe;
}
coe::DiagnosisHistory& Device::diagnosis() {
    return *parts_->diag;
}
foe::FoeServer& Device::foe() {
    return parts_->firmware->server();
}
foe::FirmwareStore& Device::firmware_store() {
    return parts_->firmware->store();
}
drive::Drive& Device::drive() {
    return *parts_->drive;
}
od::ParameterStore& Device::parameters() {
    return *parts_->params;
}
const od::ParameterStore::LoadResult& Device::parameter_load() const {
    return parts_->load;
}

}  // namespace device

// ---- values at run time -----------------------------------------------------------------------------

namespace device {
namespace {

// The bytes of an entry's value from text: an integer in the entry's range (decimal, 0x hex, negative for
// signed types), a real number for REAL types, true/false/on/off for BOOL. false if it does not fit.
bool encode(const od::Entry& e, std::string_view text, std::vector<uint8_t>& raw) {
    const std::size_t bytes = e.byte_size();
    if (bytes == 0 || bytes > 8 || od::is_string(e.type)) return false;
    raw.assign(bytes, 0);
    if (od::is_real(e.type)) {
        // Finite and within the type's range: a REAL takes at most FLT_MAX (1e300 is refused, not stored as
        // infinity); a value below the smallest subnormal rounds to zero, as any conversion rounds.
        const double max = bytes == 4 ? static_cast<double>(std::numeric_limits<float>::max())
                                      : std::numeric_limits<double>::max();
        double v = 0;
        if (util::parse_number(text, v, -max, max) != util::NumberError::None) return false;
        if (bytes == 4) {
            const auto f = static_cast<float>(v);
            std::memcpy(raw.data(), &f, 4);
        } else if (bytes == 8) {
            std::memcpy(raw.data(), &v, 8);
        } else {
            return false;
        }
        return true;
    }
    uint64_t bits = 0;
    const unsigned width = std::min<unsigned>(e.bit_length, 64);
    if (text == "true" || text == "on") {
        bits = 1;
    } else if (text == "false" || text == "off") {
        bits = 0;
    } else if (od::is_signed(e.type)) {
        const int64_t lo = width >= 64 ? INT64_MIN : -(int64_t{1} << (width - 1));
        const int64_t hi = width >= 64 ? INT64_MAX : (int64_t{1} << (width - 1)) - 1;
        int64_t v = 0;
        if (util::parse_number(text, v, lo, hi) != util::NumberError::None) return false;
        bits = static_cast<uint64_t>(v);
    } else {
        const uint64_t hi = width >= 64 ? UINT64_MAX : (uint64_t{1} << width) - 1;
        uint64_t v = 0;
        if (util::parse_number(text, v, uint64_t{0}, hi) != util::NumberError::None) return false;
        bits = v;
    }
    for (std::size_t i = 0; i < bytes; ++i)
        raw[i] = static_cast<uint8_t>(bits >> (8 * i));
    return true;
}

}  // namespace

std::string Device::set_value(uint16_t index, uint8_t sub, std::string_view text) {
    od::Dictionary& d = parts_->dict;
    const od::Entry* e = d.find(index, sub);
    const std::string where = util::strprintf("0x%04X:%02X", static_cast<unsigned>(index), sub);
    if (e == nullptr) return "no entry " + where;
    if (!e->tx_mappable()) return where + " is not a process-data input (not TxPDO-mappable)";
    std::vector<uint8_t> raw;
    if (!encode(*e, text, raw))  // printf, not "literal" + std::string&& (GCC 12 -O3 -Wrestrict, bug 105651)
        return util::strprintf("'%.*s' is no value of %s (%.*s, %u bits)", static_cast<int>(text.size()),
                               text.data(), where.c_str(), static_cast<int>(od::to_string(e->type).size()),
                               od::to_string(e->type).data(), static_cast<unsigned>(e->bit_length));
    if (const od::Status st = d.set_raw(index, sub, raw); st != od::Status::Ok)
        return where + ": " + std::string(od::to_string(st));
    const uint32_t key = io_key(index, sub);
    set_values_[key] = std::move(raw);
    held_.insert(key);
    if (parts_->io) parts_->io->hold(index, sub);
    return {};
}

std::string Device::value_text(uint16_t index, uint8_t sub) const {
    const od::Dictionary& d = parts_->dict;
    const od::Entry* e = d.find(index, sub);
    if (e == nullptr) return {};
    const auto raw = d.raw(index, sub);
    if (od::is_string(e->type) || raw.size() > 8) {
        std::string s = "\"";
        for (const uint8_t c : raw) {
            if (c == 0 && e->type == od::DataType::VisibleString) break;
            if (c >= 0x20 && c < 0x7F && c != '"' && c != '\\')
                s += static_cast<char>(c);
            else
                s += util::strprintf("\\x%02X", static_cast<unsigned>(c));
        }
        return s + "\"";
    }
    uint64_t v = 0;
    for (std::size_t i = 0; i < raw.size(); ++i)
        v |= static_cast<uint64_t>(raw[i]) << (8 * i);
    if (od::is_real(e->type)) {
        double x = 0;
        if (raw.size() == 4) {
            float f = 0;
            std::memcpy(&f, raw.data(), 4);
            x = f;
        } else if (raw.size() == 8) {
            std::memcpy(&x, raw.data(), 8);
        }
        // As many digits as the type needs to read back the same value: 9 for a REAL, 17 for an LREAL.
        return util::strprintf("%.*g", raw.size() == 4 ? 9 : 17, x);
    }
    const unsigned width = std::min<unsigned>(e->bit_length, 64);
    if (width < 64) v &= (uint64_t{1} << width) - 1;
    if (od::is_signed(e->type) && width > 0 && width < 64 && (v >> (width - 1)) != 0)
        v |= ~uint64_t{0} << width;
    return od::is_signed(e->type) ? std::to_string(static_cast<int64_t>(v)) : std::to_string(v);
}

}  // namespace device
