// ecatctl: a small EtherCAT master on the command line, in the spirit of IgH's `ethercat` tool.
//   ecatctl [--iface NAME] [--backend pcap|packet] [--timeout MS] [--retries N] <verb> ...
// main.cpp only wires the command line; each command is in its own file (commands.hpp lists them).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "cmd_diag.hpp"
#include "cmd_firmware.hpp"
#include "cmd_line.hpp"
#include "cmd_state.hpp"
#include "cmd_verbs.hpp"
#include "commands.hpp"
#include "common.hpp"
#include "esc/link.hpp"
#include "format.hpp"
#include "master/master.hpp"

namespace {

using namespace ecatctl;

struct Globals {
    std::string iface = "ecat1";
    std::string backend;
    unsigned timeout_ms = 100;
    unsigned retries = 2;
};

// Opens the link and runs fn with a master on it; maps link errors to exit codes.
template <typename Fn>
int with_master(const Globals& g, Fn fn) {
    std::unique_ptr<esc::Link> link;
    try {
        link = esc::open_link(g.iface, g.backend);
    } catch (const esc::LinkError& e) {
        std::cerr << "ecatctl: " << e.what() << "\n";
        switch (e.kind()) {
            case esc::LinkError::Kind::NoSuchInterface:
            case esc::LinkError::Kind::InterfaceDown:
                return kExitNoInterface;
            case esc::LinkError::Kind::PermissionDenied:
                std::cerr << "ecatctl: raw sockets need root or CAP_NET_RAW (try sudo)\n";
                return kExitNoPrivileges;
            case esc::LinkError::Kind::BadArgument:
                return kExitUsage;
            case esc::LinkError::Kind::System:
                return kExitFailure;
        }
        return kExitFailure;
    }
    master::MasterOptions o;
    o.timeout = std::chrono::milliseconds(g.timeout_ms);
    o.retries = g.retries;
    master::Master m(*link, o);
    return fn(m);
}

}  // namespace

int main(int argc, char** argv) {
    Globals g;
    CLI::App app{
        "A small EtherCAT master for the command line.\n"
        "Exit codes: 0 ok, 1 failure, 2 usage, 3 interface missing or down, 4 no privileges,\n"
        "5 no slave answered, 6 unexpected answer (working counter, SII, AL state)",
        "ecatctl"};
    app.require_subcommand(1);
    app.set_version_flag("--version", "ecatctl " ECATCTL_VERSION);
    app.add_option("-i,--iface", g.iface, "Network interface (the master end of the slave's veth pair)")
        ->envname("ECATCTL_IFACE")
        ->capture_default_str();
    app.add_option("-b,--backend", g.backend, "Link backend: pcap or packet (default: the link library's)")
        ->check(CLI::IsMember({"pcap", "packet"}));
    app.add_option("-t,--timeout", g.timeout_ms, "Reply timeout per frame in milliseconds")
        ->check(CLI::Range(1u, 60000u))
        ->capture_default_str();
    app.add_option("--retries", g.retries, "Extra attempts after a lost frame")
        ->check(CLI::Range(0u, 100u))
        ->capture_default_str();

    int rc = kExitOk;
    add_scan_command(
        app, [&](const auto& fn) { return with_master(g, fn); }, rc);

    add_reg_command(
        app, [&](const auto& fn) { return with_master(g, fn); }, rc);

    add_sii_command(
        app, [&](const auto& fn) { return with_master(g, fn); }, rc);

    add_state_command(
        app, [&](const auto& fn) { return with_master(g, fn); }, rc);

    add_sdo_commands(
        app, [&](const auto& fn) { return with_master(g, fn); }, rc);

    add_pd_command(
        app, [&](const auto& fn) { return with_master(g, fn); }, rc);

    add_sdos_command(
        app, [&](const auto& fn) { return with_master(g, fn); }, rc);

    add_foe_command(
        app, [&](const auto& fn) { return with_master(g, fn); }, rc);

    add_diag_command(
        app, [&](const auto& fn) { return with_master(g, fn); }, rc);

    add_firmware_update(
        app, [&](const auto& fn) { return with_master(g, fn); }, rc);

    add_slaves_command(
        app, [&](const auto& fn) { return with_master(g, fn); }, rc);
    add_pdos_command(
        app, [&](const auto& fn) { return with_master(g, fn); }, rc);
    add_cstruct_command(
        app, [&](const auto& fn) { return with_master(g, fn); }, rc);
    add_xml_command(
        app, [&](const auto& fn) { return with_master(g, fn); }, rc);
    add_line_commands(
        app, [&](const auto& fn) { return with_master(g, fn); }, rc);

    // `-p N` names the slave in every verb, also in those that take it as their first argument.
    std::vector<std::string> args = position_option_as_argument(argc, argv);
    std::vector<char*> argp;
    for (std::string& a : args)
        argp.push_back(a.data());
    argc = static_cast<int>(argp.size());
    argp.push_back(nullptr);
    argv = argp.data();
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        return report_usage_error(app, e, argc, argv);  // one line, exit 2
    }
    return rc;
}
