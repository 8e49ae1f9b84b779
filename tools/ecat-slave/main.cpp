// ecat-slave: parses the command line and hands over to softslave::run_slave().
#include <CLI/CLI.hpp>
#include <iostream>

#include "esc/link.hpp"
#include "softslave/slave.hpp"

int main(int argc, char** argv) {
    softslave::SlaveOptions options;
    CLI::App app{"Soft EtherCAT slave: a CiA 402 servo drive on a Linux network interface", "ecat-slave"};
    app.set_version_flag("--version", std::string("ecat-slave ") + SOFTECAT_VERSION);
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
    app.add_option("--eeprom", options.eeprom_file, "Binary SII EEPROM image to serve")
        ->check(CLI::ExistingFile);
    app.add_option("--ram-kib", options.ram_kib, "Process RAM size in KiB")
        ->check(CLI::Range(1, 60))
        ->capture_default_str();
    app.add_option("--rt-priority", options.rt_priority,
                   "Run with SCHED_FIFO at this priority (1-99) and lock all memory")
        ->check(CLI::Range(1, 99));
    app.add_option("--cpu", options.cpu, "Pin the slave to this CPU")->check(CLI::NonNegativeNumber);
    app.add_flag("--verbose,-v", options.verbose, "Print statistics at exit");
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        app.exit(e);
        return softslave::kExitUsage;
    }
    return softslave::run_slave(options, std::cout, std::cerr);
}
