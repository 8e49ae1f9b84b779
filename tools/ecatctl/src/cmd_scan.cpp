// `ecatctl scan`: count the slaves, assign station addresses, list identity, AL state, DC propagation delay
// and device name of every slave on the line.
#include <CLI/CLI.hpp>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "commands.hpp"
#include "common.hpp"
#include "esi/sii_reader.hpp"
#include "format.hpp"
#include "master/bus.hpp"
#include "master/coe.hpp"
#include "master/foe.hpp"
#include "master/mailbox.hpp"
#include "master/master.hpp"
#include "master/session.hpp"
#include "util/json.hpp"
#include "util/le.hpp"
#include "util/strfmt.hpp"

namespace ecatctl {

namespace {

using master::Address;
using master::Error;

int scan(master::Master& m, bool dc, bool json) {
    auto bus = master::scan_bus(m);
    if (!bus) return fail(bus.error(), "scanning the line (BRD 0x0000, station addresses, SII)");
    std::vector<master::SlaveInfo>& slaves = *bus;
    if (slaves.empty()) {
        std::cerr << "ecatctl: no slave answered\n";
        return kExitNoSlave;
    }
    int rc = kExitOk;
    // Propagation delays from the reference clock (the first DC slave), measured as a master's DC set-up
    // does (BWR 0x0900, the port receive times), without writing offsets or delays.
    bool dc_ok = false;
    if (dc && master::reference_clock(slaves) >= 0) {
        const Error e = master::measure_dc(m, slaves);
        if (e == Error::Ok) {
            dc_ok = true;
        } else {
            std::cerr << "ecatctl: measuring DC delays: " << master::to_string(e) << "\n";
            rc = exit_code(e);
        }
    }
    // The device name from the SII General category (through the STRINGS category).
    auto name_of = [&](const master::SlaveInfo& s) {
        if (auto img = m.sii_read_image(Address::station(s.station))) {
            const esi::SiiInfo info = esi::parse_sii(*img);
            if (info.general) return info.general->name;
        }
        return std::string();
    };
    if (json) {
        // docs/ecatctl-json.md, "scan".
        util::JsonWriter w(std::cout);
        w.begin_object().key("slaves").begin_array();
        for (const master::SlaveInfo& s : slaves) {
            w.begin_object().member("position", s.position).member("station", s.station);
            if (s.error != Error::Ok) {
                w.member("read_error", master::to_string(s.error)).end_object();
                rc = exit_code(s.error);
                continue;
            }
            w.member("state", master::al_state_name(s.al.state))
                .member("al_error", s.al.error)
                .member("al_status_code", s.al.code)
                .member("vendor_id", s.vendor_id)
                .member("product_code", s.product_code)
                .member("revision", s.revision)
                .member("serial", s.serial)
                .key("delay_ns");
            if (dc_ok && s.has_dc)
                w.value(s.delay_ns);
            else
                w.null();
            w.member("name", name_of(s)).end_object();
        }
        w.end_array().end_object();
        std::cout << std::flush;
        return rc;
    }
    std::printf("%zu slave%s\n", slaves.size(), slaves.size() == 1 ? "" : "s");
    std::printf("%-4s %-7s %-10s %-10s %-10s %-10s %-10s %-9s %s\n", "pos", "station", "state", "vendor",
                "product", "revision", "serial", "delay/ns", "name");
    for (const master::SlaveInfo& s : slaves) {
        if (s.error != Error::Ok) {
            std::printf("%-4u 0x%04x  %s\n", s.position, s.station,
                        std::string(master::to_string(s.error)).c_str());
            rc = exit_code(s.error);
            continue;
        }
        std::string state = std::string(master::al_state_name(s.al.state));
        if (s.al.error) {
            state += util::strprintf("+ERR(0x%04x)", s.al.code);
        }
        std::string delay = "-";
        if (dc_ok && s.has_dc) delay = std::to_string(s.delay_ns);
        const std::string name = name_of(s);
        std::string line = util::strprintf("%-4u 0x%04x  %-10s 0x%08x 0x%08x 0x%08x 0x%08x %-9s %s",
                                           s.position, s.station, state.c_str(), s.vendor_id, s.product_code,
                                           s.revision, s.serial, delay.c_str(), name.c_str());
        line.erase(line.find_last_not_of(' ') + 1);  // no trailing blanks when there is no name
        std::printf("%s\n", line.c_str());
    }
    return rc;
}

}  // namespace

void add_scan_command(CLI::App& app, MasterRunner run, int& rc) {
    auto* scan_cmd =
        app.add_subcommand("scan",
                           "Count the slaves, assign station addresses 0x1001.., list identity, AL "
                           "state and DC propagation delay");
    auto no_dc = std::make_shared<bool>(false);
    auto json = std::make_shared<bool>(false);
    scan_cmd->add_flag("--no-dc", *no_dc, "Do not measure DC propagation delays (no BWR to 0x0900)");
    scan_cmd->add_flag("--json", *json, "JSON on stdout (docs/ecatctl-json.md)");
    scan_cmd->callback([run, no_dc, json, &rc] {
        rc = run([no_dc, json](master::Master& m) { return scan(m, !*no_dc, *json); });
    });
}

}  // namespace ecatctl
