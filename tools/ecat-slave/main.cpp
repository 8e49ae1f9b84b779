// ecat-slave: parses the command line (and the configuration file) and hands over to
// slave::run_slave() with the soft drive (tools/lib/device) as firmware.
#include <grp.h>
#include <CLI/CLI.hpp>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <string_view>
#include <vector>

#include "config_check.hpp"
#include "device/faults.hpp"
#include "device/firmware.hpp"
#include "device/line.hpp"
#include "eni_line.hpp"
#include "esc/link.hpp"
#include "esi/device/product.hpp"
#include "esi/eni/eni_reader.hpp"
#include "esi/model.hpp"
#include "od/device_config.hpp"
#include "send_control.hpp"
#include "slave/log.hpp"
#include "slave/slave.hpp"
#include "slave/topology.hpp"
#include "util/dir_lock.hpp"
#include "util/lex.hpp"

namespace {

// Config file sections that belong to the device description (maxpos::load_config), not to the program.
bool device_section(const std::string& item) {
    for (const char* s : {"identity.", "mailbox.", "bootstrap_mailbox.", "eeprom."})
        if (item.rfind(s, 0) == 0) return true;
    return false;
}

// Writes the bytes to path, or to standard output for "-"; on failure, why (strerror) in error.
bool write_output(const std::string& path, std::string_view bytes, std::string& error) {
    errno = 0;
    FILE* f = path == "-" ? stdout : std::fopen(path.c_str(), "wb");
    bool ok =
        f != nullptr && std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size() && std::fflush(f) == 0;
    int err = errno;
    if (f != nullptr && f != stdout && std::fclose(f) != 0 && ok) ok = false, err = errno;
    if (!ok) error = std::strerror(err ? err : EIO);
    return ok;
}

}  // namespace

int main(int argc, char** argv) {
    slave::SlaveOptions options;
    device::DeviceOptions device;
    std::string state_dir = device.state_dir.string();
    std::string write_sii, write_esi, control;
    std::vector<std::string> send_lines;
    std::vector<double> home, stops;
    std::vector<std::string> faults;
    CLI::App app{"Soft EtherCAT slave: a CiA 402 servo drive on a Linux network interface", "ecat-slave"};
    app.set_version_flag("--version", std::string("ecat-slave ") + SOFTECAT_VERSION);
    app.set_config("--config", "",
                   "Device configuration file: the [identity], [mailbox], [bootstrap_mailbox] and [eeprom] "
                   "sections describe the device, keys before the first section (or in [default]) are "
                   "options of this program (e.g. state-dir = /tmp/drive)");
    app.allow_config_extras(CLI::config_extras_mode::capture);
    app.add_option("--iface", options.iface,
                   "Network interface to serve; without it a veth pair is created and its other end printed");
    app.add_option("--veth-name", options.veth_name,
                   "Slave end of the veth pair to create (the master end is "
                   "the name with its number incremented, ecat0 -> ecat1)")
        ->capture_default_str();
    app.add_option("--veth-peer", options.veth_peer, "Master end of the veth pair (default: derived)");
    app.add_option("--backend", options.backend,
                   std::string("Link backend (default: ") + esc::default_link_backend() + ")")
        ->check(CLI::IsMember({"pcap", "packet"}));
    app.add_option("--capture", options.capture_file, "Record every frame in and out to this .pcap file");
    app.add_option("--eeprom", options.eeprom_file,
                   "Serve this binary SII EEPROM image instead of the one built from the device model")
        ->check(CLI::ExistingFile);
    app.add_option("--state-dir", state_dir,
                   "Directory for stored parameters and firmware images (created if missing)")
        ->capture_default_str();
    app.add_option("--write-sii", write_sii,
                   "Write the device's SII EEPROM image to FILE ('-': standard output) and exit: of the "
                   "built-in firmware, or with --state-dir of the firmware active there (and the EEPROM "
                   "words a master wrote)")
        ->type_name("FILE");
    app.add_option("--write-esi", write_esi,
                   "Write the device's ESI (EtherCATInfo XML) to FILE ('-': standard output) and exit: of "
                   "the built-in firmware, or with --state-dir of the firmware active there")
        ->type_name("FILE");
    app.add_option("--control", control,
                   "Create a UNIX datagram socket here that changes the simulated machine at run time "
                   "(lines like 'input 4 on', 'sto off', 'limit-pos 50000', 'status'; "
                   "e.g. ecat-slave --control PATH --send 'input 4 on')")
        ->type_name("PATH");
    app.add_option(
           "--send", send_lines,
           "With --control PATH: send this command line to the ecat-slave running with that control socket, "
           "print its answer and exit (0: ok, 1: error or no answer, 2: no such socket); repeatable")
        ->type_name("LINE")
        ->needs("--control");
    std::string control_group;
    app.add_option("--control-group", control_group,
                   "Let the members of this group use the --control socket too (mode 0660; default: 0600, "
                   "the owner and root only)")
        ->type_name("GROUP");
    auto* env = app.add_option_group("Simulated machine", "Positions in raw encoder increments");
    env->add_option("--limit-neg", device.environment.negative_limit,
                    "Negative limit switch (DigIN1), active at and below this position");
    env->add_option("--limit-pos", device.environment.positive_limit,
                    "Positive limit switch (DigIN2), active at and above this position");
    env->add_option("--home", home, "Home switch (DigIN3), active from FROM to TO")->expected(2);
    env->add_option("--stops", stops, "Mechanical stops LO HI")->expected(2);
    app.add_option("--ram-kib", options.ram_kib, "Process RAM size in KiB")
        ->check(CLI::Range(1, 60))
        ->capture_default_str();
    app.add_option("--rt-priority", options.rt_priority,
                   "Run with SCHED_FIFO at this priority (1-99) and lock all memory")
        ->check(CLI::Range(1, 99));
    app.add_option("--cpu", options.cpu, "Pin the slave to this CPU")->check(CLI::NonNegativeNumber);
    auto* spin =
        app.add_option("--spin-us", options.spin_us,
                       "Wake N us before each timed event (SYNC0, application cycle, watchdog) and "
                       "busy-wait to it: takes the timer latency out of the cycle, for up to N us of CPU "
                       "per event")
            ->check(CLI::Range(1, 100000));
    app.add_flag("--busy-poll", options.busy_poll,
                 "Never sleep: poll the network and the clock in a loop (one CPU fully busy; use with --cpu)")
        ->excludes(spin);
    app.add_option(
           "--fault", faults,
           "Testing aid for conformance tools: break one behaviour on purpose, as a faulty slave would "
           "(repeatable or a comma-separated list; '--fault list' prints them all)")
        ->type_name("NAME");
    app.add_flag("--verbose,-v", options.verbose,
                 "Print statistics at exit (of the whole run, across restarts)");
    bool quiet = false, reset_sii = false;
    std::string log_level = "info";
    auto* quiet_flag = app.add_flag("--quiet,-q", quiet, "Log errors only (same as --log-level error)");
    app.add_option("--log-level", log_level,
                   "Events logged on stderr, one line each: error, warn, info (default: state changes, FoE "
                   "writes, restarts, parameter saves) or debug (also the drive's own state changes)")
        ->check(CLI::IsMember({"error", "warn", "warning", "info", "debug"}))
        ->excludes(quiet_flag);
    app.add_flag(
        "--reset-sii", reset_sii,
        "Forget the SII words a master wrote into the EEPROM (kept in the state directory) and serve "
        "the SII generated from the object model");
    app.add_option("--stats-file", options.stats_file,
                   "Write the statistics as 'name value' lines to this file at exit");
    int slaves = 1;
    std::string topology_file;
    auto* slaves_opt =
        app.add_option(
               "--slaves", slaves,
               "Serve N drives in a line (device k's port 1 to device k+1's port 0), serial numbers 1..N, "
               "state directories <state-dir>/drive<k> when N > 1")
            ->check(CLI::Range(1, static_cast<int>(slave::kMaxDevices)));
    app.add_option(
           "--topology", topology_file,
           "Serve the devices of this topology file (docs/segment.md): names, config files, where each "
           "is plugged in, clocks and cables")
        ->check(CLI::ExistingFile)
        ->excludes(slaves_opt)
        ->type_name("FILE");
    // A device from its vendor's ESI (issue 21): the product esi::load_product makes of it.
    std::string esi_file, device_spec;
    auto* esi_opt =
        app.add_option("--esi", esi_file,
                       "Serve the device this ESI file (EtherCATInfo XML) describes instead of the "
                       "MAXPOS: identity, SII, SMs, dictionary, PDOs, mailbox protocols from the file")
            ->type_name("FILE");
    app.add_option(
           "--device", device_spec,
           "The device of a --esi file with several: 0xPRODUCT:0xREVISION, 0xPRODUCT, or its Type name; "
           "a modular device's modules after '@', one per slot (Type or ModuleIdent, '-' empty): "
           "EXM9000@EXM-DI8,-,EXM-AI2")
        ->needs(esi_opt)
        ->type_name("SPEC");
    std::string eni_file;
    app.add_option(
           "--eni", eni_file,
           "Serve the line this ENI (ETG.2100 EtherCAT Network Information, as TwinCAT or EC-Engineer "
           "export it) describes, in its order and wiring; each slave from the ENI's data "
           "(docs/eni.md)")
        ->excludes(slaves_opt)
        ->excludes(esi_opt)
        ->type_name("FILE");
    std::string esi_dir;
    app.add_option(
           "--esi-dir", esi_dir,
           "With --eni: serve each slave whose vendor id, product code and revision a device of an ESI "
           "file in this folder (*.xml) has from that ESI, the others from the ENI's data")
        ->type_name("DIR");
    app.add_option("--out-iface", options.out_iface,
                   "Port 1 of the last device (or the topology's 'external' port) leads to this interface: "
                   "the line continues there; no carrier closes the port")
        ->type_name("OUT");
    // The configuration file is checked first: CLI11 would name neither the file nor the line.
    if (auto config = ecat_slave::config_file_argument(argc, argv)) {
        if (const std::string problem = ecat_slave::check_config_file(app, *config); !problem.empty()) {
            std::cerr << "ecat-slave: " << problem << '\n';
            return slave::kExitUsage;
        }
    }
    try {
        app.parse(argc, argv);
        for (const std::string& extra : app.remaining())
            if (!device_section(extra))
                throw CLI::ConfigError("unknown option '" + extra + "' in the configuration file");
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        std::cerr << "ecat-slave: " << e.what() << " (ecat-slave --help)\n";  // one line
        return slave::kExitUsage;
    }
    if (!send_lines.empty()) return ecat_slave::send_control(control, send_lines, std::cout, std::cerr);
    device::FaultSet fault_set;
    for (const std::string& item : faults) {
        if (item == "list") {
            device::print_faults(std::cout);
            return slave::kExitOk;
        }
        if (const auto unknown = device::add_faults(item, fault_set)) {
            std::cerr << "ecat-slave: --fault: unknown fault '" << *unknown
                      << "' ('ecat-slave --fault list' prints the known ones)\n";
            return slave::kExitUsage;
        }
    }
    device::apply_faults(fault_set, options.esc_faults, device.faults);
    if (fault_set.any()) {
        std::cerr << "ecat-slave: running with deliberate faults (testing aid):";
        for (const auto& f : device::fault_catalogue())
            if (fault_set.test(static_cast<std::size_t>(f.fault))) std::cerr << ' ' << f.name;
        std::cerr << '\n';
    }
    if (home.size() == 2) device.environment.home_from = home[0], device.environment.home_to = home[1];
    if (stops.size() == 2) device.environment.stop_lo = stops[0], device.environment.stop_hi = stops[1];
    if (auto* config = app.get_config_ptr(); config != nullptr && config->count() > 0)
        device.config_file = config->as<std::string>();
    if (!esi_file.empty()) {
        // A bad file or spec is a usage error naming the file (and line) before anything else is set up.
        if (!device.config_file.empty()) {
            std::cerr << "ecat-slave: --esi serves the device of its file: not with a MAXPOS --config\n";
            return slave::kExitUsage;
        }
        try {
            device.product = std::make_shared<const od::Product>(esi::load_product(esi_file, device_spec));
        } catch (const std::exception& e) {
            std::cerr << "ecat-slave: " << e.what() << '\n';
            return slave::kExitUsage;
        }
        // The ESC has the ports the ESI's Physics declares (ETG.2000; ESC register 0x0007).
        options.port_descriptor = esi::physics_port_descriptor(device.product->description.physics);
    }
    device.state_dir = state_dir;
    slave::Log log(std::cerr, quiet ? slave::LogLevel::Error : *slave::parse_log_level(log_level),
                   slave::stderr_is_terminal());
    device.events = &log;
    if (reset_sii) {
        const std::filesystem::path writes = device.state_dir / device::EepromWrites::kFileName;
        std::error_code ec;
        if (std::filesystem::remove(writes, ec))
            log.info("removed " + writes.string() + ": serving the SII generated from the object model");
        else if (ec)
            log.warn("cannot remove " + writes.string() + ": " + ec.message());
    }
    gid_t control_gid = device::ControlSocket::kNoGroup;
    if (!control_group.empty()) {
        const group* g = ::getgrnam(control_group.c_str());
        gid_t number = 0;
        if (g != nullptr)
            control_gid = g->gr_gid;
        else if (util::parse_number(control_group, number) == util::NumberError::None)
            control_gid = number;
        else {
            std::cerr << "ecat-slave: --control-group: no group '" << control_group << "'\n";
            return slave::kExitUsage;
        }
        if (control.empty()) {
            std::cerr << "ecat-slave: --control-group needs --control\n";
            return slave::kExitUsage;
        }
    }
    if (!control.empty()) {
        const std::filesystem::path parent = std::filesystem::absolute(control).parent_path();
        std::error_code ec;
        if (!std::filesystem::is_directory(parent, ec)) {
            std::cerr << "ecat-slave: --control: directory " << parent.string() << " does not exist\n";
            return slave::kExitUsage;
        }
    }

    try {
        if (!write_sii.empty() || !write_esi.empty()) {
            // Deterministic: the files describe the built-in firmware (what a fresh state directory starts
            // with) unless a state directory is named, whatever an FoE update left in the default one.
            device::DeviceOptions described = device;
            if (app.get_option("--state-dir")->count() == 0) described.state_dir.clear();
            const od::Identity id = device::make_description(described).identity;
            std::string why;
            const std::vector<uint8_t> sii =
                write_sii.empty() ? std::vector<uint8_t>{} : device::make_sii(described);
            if (!write_sii.empty() &&
                !write_output(write_sii, {reinterpret_cast<const char*>(sii.data()), sii.size()}, why)) {
                std::cerr << "ecat-slave: cannot write " << write_sii << ": " << why << '\n';
                return slave::kExitFailure;
            }
            if (!write_esi.empty() && !write_output(write_esi, device::make_esi(described), why)) {
                std::cerr << "ecat-slave: cannot write " << write_esi << ": " << why << '\n';
                return slave::kExitFailure;
            }
            std::ostringstream revision;
            revision << "0x" << std::hex << std::uppercase << std::setw(8) << std::setfill('0')
                     << id.revision;
            std::cerr << "ecat-slave: "
                      << (described.product ? described.product->source
                          : described.state_dir.empty()
                              ? "the built-in firmware"
                              : "the firmware active in " + described.state_dir.string())
                      << (id.software_version.empty() ? "" : ", software version " + id.software_version)
                      << ", revision " << revision.str() << '\n';
            return slave::kExitOk;
        }
        device::check_device(device);  // a bad configuration is a usage error, before any setup
    } catch (const od::ConfigError& e) {
        std::cerr << "ecat-slave: " << e.what() << '\n';
        return slave::kExitUsage;
    } catch (const std::exception& e) {
        std::cerr << "ecat-slave: " << e.what() << '\n';
        return slave::kExitFailure;
    }
    if (!options.eeprom_file.empty()) {
        try {  // a bad --eeprom is a usage error (exit 2), found before any network set-up
            (void)slave::load_eeprom_file(options);
        } catch (const std::exception& e) {
            std::cerr << "ecat-slave: --eeprom: " << e.what() << '\n';
            return slave::kExitUsage;
        }
    }
    const bool segment_mode =
        slaves > 1 || !topology_file.empty() || !eni_file.empty() || !options.out_iface.empty();
    if (slaves_opt->count() > 0 && !segment_mode) device.serial_number = 1;  // --slaves 1: serial number 1
    // Each state directory is the one device's that runs on it: locked until exit (a second process, or a
    // second device of a topology on the same directory, is a usage error before any network set-up).
    std::vector<std::unique_ptr<util::DirLock>> state_locks;
    auto lock_state = [&state_locks](const std::filesystem::path& dir) {
        try {
            state_locks.push_back(std::make_unique<util::DirLock>(dir));
            return true;
        } catch (const util::DirLockError& e) {
            std::cerr << "ecat-slave: " << e.what() << '\n';
            return false;
        }
    };
    if (!segment_mode) {
        if (!lock_state(device.state_dir)) return slave::kExitUsage;
        options.eeprom_loader = device::eeprom_loader(device);
        options.firmware_factory = device::firmware_factory(device, control, control_gid);
        return slave::run_slave(options, std::cout, std::cerr);
    }
    if (!options.eeprom_file.empty()) {
        std::cerr << "ecat-slave: --eeprom serves one image: not with --slaves, --topology or --out-iface\n";
        return slave::kExitUsage;
    }
    device::LineOptions line;
    std::map<std::pair<std::string, std::string>, std::shared_ptr<const od::Product>> esi_products;
    if (!eni_file.empty() && !topology_file.empty()) {
        std::cerr << "ecat-slave: --eni and --topology both describe the line: give one\n";
        return slave::kExitUsage;
    }
    try {
        if (!esi_dir.empty() && eni_file.empty()) {
            std::cerr << "ecat-slave: --esi-dir goes with --eni (a topology names each ESI with esi=)\n";
            return slave::kExitUsage;
        }
        if (!eni_file.empty()) {
            ecat_slave::EsiIndex index;
            if (!esi_dir.empty()) {
                index = ecat_slave::index_esi_dir(esi_dir);
                for (const std::string& skipped : index.skipped)
                    log.info("--esi-dir: left out: " + skipped);
            }
            ecat_slave::EniLine eni = ecat_slave::eni_line(eni_file, esi_dir.empty() ? nullptr : &index);
            line.topology = std::move(eni.topology);
            line.products = std::move(eni.products);
            for (const std::string& r : eni.report)
                std::cerr << "ecat-slave: " << r << '\n';
        } else if (topology_file.empty()) {
            line.topology = slave::line_topology(slaves);
            if (device.product) {
                // --esi with --slaves N / --out-iface: each unit has the ports of the ESI's Physics; the line
                // runs through port 1 of each (and of the last, to --out-iface).
                const uint8_t ports = options.port_descriptor;
                if ((ports & 0x0C) == 0 && (slaves > 1 || !options.out_iface.empty())) {
                    std::cerr << "ecat-slave: " << esi_file << ": the device has no port 1 (its Physics '"
                              << device.product->description.physics << "'): "
                              << (slaves > 1 ? "no line of --slaves " + std::to_string(slaves)
                                             : std::string("nothing leads to --out-iface"))
                              << '\n';
                    return slave::kExitUsage;
                }
                for (slave::TopologyDevice& d : line.topology.devices)
                    d.descriptor = ports;
            }
        } else {
            // A device given by esi= has the ports its ESI's Physics declares: its product is made once
            // here and served below.
            line.topology =
                slave::load_topology(topology_file, [&esi_products](const slave::TopologyDevice& d) {
                    auto& p = esi_products[{d.esi, d.device_spec}];
                    if (!p) p = std::make_shared<const od::Product>(esi::load_product(d.esi, d.device_spec));
                    return esi::physics_port_descriptor(p->description.physics);
                });
        }
    } catch (const slave::TopologyError& e) {
        std::cerr << "ecat-slave: " << e.what() << '\n';
        return slave::kExitUsage;
    } catch (const esi::eni::EniError& e) {
        std::cerr << "ecat-slave: " << e.what() << '\n';
        return slave::kExitUsage;
    } catch (const std::runtime_error& e) {  // an ESI of --esi-dir that matches but cannot be served
        std::cerr << "ecat-slave: " << e.what() << '\n';
        return slave::kExitUsage;
    }
    // Devices of a topology file from an ESI (esi=FILE [device=SPEC]).
    line.products.resize(line.topology.devices.size());
    for (std::size_t k = 0; k < line.topology.devices.size(); ++k) {
        const slave::TopologyDevice& d = line.topology.devices[k];
        if (d.esi.empty()) continue;
        try {
            auto& p = esi_products[{d.esi, d.device_spec}];
            if (!p) p = std::make_shared<const od::Product>(esi::load_product(d.esi, d.device_spec));
            line.products[k] = p;
        } catch (const std::exception& e) {
            std::cerr << "ecat-slave: " << line.topology.where(d.line) << "device " << d.name << ": "
                      << e.what() << '\n';
            return slave::kExitUsage;
        }
        log.info("device " + d.name + ": served from " + line.products[k]->source);
    }
    if (topology_file.empty() && slaves == 1) {
        line.topology.devices[0].state_dir = device.state_dir.string();
        // One drive with --out-iface only: the serial number of its configuration, as without --out-iface.
        if (slaves_opt->count() == 0) line.topology.devices[0].serial = 0;
    }
    for (std::size_t k = 0; k < line.topology.devices.size(); ++k) {
        slave::TopologyDevice& d = line.topology.devices[k];
        if (d.state_dir.empty()) d.state_dir = (device.state_dir / d.name).string();
        // Each device's configuration is loaded now: a bad one is a usage error naming the topology line.
        device::DeviceOptions o = device;
        if (!d.config.empty()) o.config_file = d.config;
        if (k < line.products.size() && line.products[k]) o.product = line.products[k];
        o.state_dir = d.state_dir;
        try {
            device::check_device(o);
        } catch (const std::exception& e) {
            std::cerr << "ecat-slave: " << (d.line > 0 ? line.topology.where(d.line) : std::string())
                      << "device " << d.name << ": " << e.what() << '\n';
            return slave::kExitUsage;
        }
        try {
            state_locks.push_back(std::make_unique<util::DirLock>(d.state_dir));
        } catch (const util::DirLockError& e) {
            std::cerr << "ecat-slave: " << (d.line > 0 ? line.topology.where(d.line) : std::string())
                      << "device " << d.name << ": " << e.what() << '\n';
            return slave::kExitUsage;
        }
        if (reset_sii) {
            const std::filesystem::path writes =
                std::filesystem::path(d.state_dir) / device::EepromWrites::kFileName;
            std::error_code ec;
            if (std::filesystem::remove(writes, ec)) log.info("removed " + writes.string());
        }
    }
    line.base = device;
    line.esc.process_ram_kib = options.ram_kib;
    line.esc.faults = options.esc_faults;
    line.control_path = control;
    line.control_group = control_gid;
    line.log = &log;
    options.log = &log;
    options.segment_factory = [&line](const esc::Clock& clock, const slave::SlaveOptions&,
                                      slave::ExternalSend send) -> std::unique_ptr<slave::SegmentFirmware> {
        return std::make_unique<device::Line>(clock, line, std::move(send));
    };
    return slave::run_slave(options, std::cout, std::cerr);
}
