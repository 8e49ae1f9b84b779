// ecat-conform: runs the conformance catalogue against one slave on a Linux interface and reports, test by
// test, where the slave differs from what the standards and its ESI file promise.
#include <fnmatch.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <set>
#include <sstream>

#include "conform.hpp"
#include "esc/link.hpp"
#include "report.hpp"
#include "util/strfmt.hpp"

namespace {

using conform::Status;

std::vector<std::string> split(const std::string& s) {
    std::vector<std::string> out;
    std::stringstream ss(s);
    std::string x;
    while (std::getline(ss, x, ','))
        if (!x.empty()) out.push_back(x);
    return out;
}

bool selected(const conform::TestCase& t, const std::set<std::string>& groups, const std::string& filter) {
    if (!groups.empty() && !groups.count(t.group)) return false;
    if (!filter.empty()) {
        bool any = false;
        for (const auto& f : split(filter))
            any = any || fnmatch(f.c_str(), t.id.c_str(), 0) == 0;
        if (!any) return false;
    }
    return true;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{
        "ecat-conform: EtherCAT slave conformance tests (ETG.1000, ETG.2000, ETG.1020, ETG.5001, CiA 402)"};
    app.set_version_flag("--version", std::string("ecat-conform ") + SOFTECAT_VERSION);
    conform::Options o;
    std::string groups_arg, filter, junit, json, backend;
    bool list = false, markdown = false;
    app.add_option("--iface,-i", o.iface, "Interface the slave is on");
    app.add_option("--slave", o.slave, "Position of the slave under test on the bus (0 = first)");
    app.add_option("--esi", o.esi_path,
                   "ESI XML file: the expectation (object dictionary, PDOs, SMs, DC, ...)");
    app.add_option("--device", o.device,
                   "Device index in the ESI file (default: the one matching the SII identity)");
    app.add_option("--group", groups_arg,
                   "Only these groups (comma separated): esc,sii,esm,mbx,sdo,sdoinfo,pd,dc,foe,cia402");
    app.add_option("--filter", filter, "Only tests whose id matches this glob (comma separated globs)");
    app.add_flag("--list", list, "Print the catalogue and exit");
    app.add_flag("--markdown", markdown, "With --list: a markdown table");
    app.add_option("--junit", junit, "Write JUnit XML to FILE");
    app.add_option("--json", json, "Write the results as JSON to FILE");
    app.add_option("--timeout-scale", o.timeout_scale, "Multiply every timeout (slow slaves, busy hosts)")
        ->check(CLI::Range(0.1, 100.0));
    app.add_option("--foe-file", o.foe_file,
                   "A file name the device accepts over FoE in Bootstrap (enables the password test)");
    app.add_option("--foe-password", o.foe_password, "The FoE password of that file (default 0)");
    app.add_option("--backend", backend, "Raw-socket backend: packet or pcap");
    app.add_flag("--verbose,-v", o.verbose, "Details of passed and skipped tests too");
    CLI11_PARSE(app, argc, argv);

    const conform::Catalogue catalogue = conform::build_catalogue();
    std::set<std::string> groups;
    for (const auto& g : split(groups_arg)) {
        bool known = false;
        for (const auto& n : conform::group_names())
            known = known || n == g;
        if (!known) {
            std::fprintf(stderr, "ecat-conform: unknown group '%s'\n", g.c_str());
            return 2;
        }
        groups.insert(g);
    }
    conform::Catalogue chosen;
    for (const auto& t : catalogue)
        if (selected(t, groups, filter)) chosen.push_back(t);
    if (list) {
        conform::write_list(std::cout, chosen, markdown);
        return 0;
    }
    if (o.iface.empty()) {
        std::fprintf(stderr, "ecat-conform: --iface is required (or --list)\n");
        return 2;
    }
    if (chosen.empty()) {
        std::fprintf(stderr, "ecat-conform: no test matches the selection\n");
        return 2;
    }
    std::unique_ptr<esc::Link> link;
    try {
        link = esc::open_link(o.iface, backend);
    } catch (const esc::LinkError& e) {
        std::fprintf(stderr, "ecat-conform: %s\n", e.what());
        return 2;
    }
    master::MasterOptions mo;
    mo.timeout = std::chrono::microseconds(static_cast<long>(20'000 * o.timeout_scale));
    mo.retries = 2;
    mo.accept_own_source = true;  // esc.frame.source_mac checks the bit; the rest still runs
    mo.sii_timeout = std::chrono::milliseconds(static_cast<long>(100 * o.timeout_scale));
    mo.al_timeout = std::chrono::milliseconds(static_cast<long>(5000 * o.timeout_scale));
    master::Master m(*link, mo);
    conform::Context ctx(m, o);
    ctx.link = link.get();

    const auto t0 = std::chrono::steady_clock::now();
    std::vector<conform::TestResult> results;
    conform::RunInfo info;
    info.iface = o.iface;
    const std::string setup_error = ctx.setup();
    if (!setup_error.empty()) {
        info.device = "(none)";
        for (const auto& t : chosen) {
            conform::TestResult r;
            r.test = &t;
            r.outcome = conform::fail("cannot start: " + setup_error);
            results.push_back(r);
        }
    } else {
        if (ctx.sii)
            info.device = util::strprintf(
                "slave %u of %u, vendor 0x%08x product 0x%08x revision 0x%08x%s", o.slave, ctx.slave_count,
                ctx.sii->dword(0x08), ctx.sii->dword(0x0A), ctx.sii->dword(0x0C), ctx.esi ? "" : " (no ESI)");
        else
            info.device = util::strprintf("slave %u of %u (SII unreadable)", o.slave, ctx.slave_count);
        if (ctx.esi) info.device += ", ESI device \"" + ctx.esi->type_name + "\"";
        std::string group;
        std::string lost;  // id of the test during which the slave stopped answering, "" while it answers
        for (const auto& t : chosen) {
            conform::TestResult r;
            r.test = &t;
            const auto s0 = std::chrono::steady_clock::now();
            if (!lost.empty()) {
                // Back (restarted, replugged)? Addresses again and carry on; else fail at once.
                auto n = m.count_slaves();
                if (n && *n > o.slave && m.assign_station_addresses(*n) == master::Error::Ok) {
                    ctx.notes.push_back("the slave answered again after it was lost during " + lost);
                    lost.clear();
                    group.clear();
                } else {
                    r.outcome = conform::fail("the slave no longer answers (lost during " + lost + ")");
                    results.push_back(r);
                    continue;
                }
            }
            // Every group starts from INIT with SMs and FMMUs off, as a master's start-up does.
            if (t.group != group) {
                group = t.group;
                if (ctx.to_init() != master::Error::Ok) {
                    // Lost the slave (reset, unplugged)? Addresses again, then carry on.
                    (void)m.assign_station_addresses(ctx.slave_count);
                    (void)ctx.to_init();
                }
            }
            try {
                r.outcome = t.run(ctx);
            } catch (const std::exception& e) {
                r.outcome = conform::fail(std::string("test aborted: ") + e.what());
            }
            if (r.outcome.status == Status::Fail && t.severity == conform::Severity::Warning)
                r.outcome.status = Status::Warn;
            // A slave that stopped answering (reset, crash): say so on the test that saw it.
            if (r.outcome.status == Status::Fail && !ctx.rd<uint16_t>(esc::reg::kStationAddress)) {
                r.outcome.message += " (the slave no longer answers at its station address)";
                auto n = m.count_slaves();
                if (!n || *n <= o.slave || m.assign_station_addresses(*n) != master::Error::Ok) lost = t.id;
            }
            r.duration =
                std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - s0);
            results.push_back(r);
        }
        const std::string note = ctx.restore();
        if (!note.empty()) ctx.notes.push_back(note);
        info.notes = ctx.notes;
    }
    info.duration =
        std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - t0);
    conform::write_text(std::cout, results, info, isatty(STDOUT_FILENO) != 0, o.verbose);
    if (!junit.empty()) {
        std::ofstream f(junit);
        conform::write_junit(f, results, info);
        if (!f) std::fprintf(stderr, "ecat-conform: cannot write %s\n", junit.c_str());
    }
    if (!json.empty()) {
        std::ofstream f(json);
        conform::write_json(f, results, info);
        if (!f) std::fprintf(stderr, "ecat-conform: cannot write %s\n", json.c_str());
    }
    return conform::totals(results).failed ? 1 : 0;
}
