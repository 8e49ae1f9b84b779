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
#include "util/le.hpp"
#include "util/strfmt.hpp"

namespace ecatctl {

namespace {

using master::Address;
using master::Error;

int scan(master::Master& m, bool dc) {
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
    std::printf("%zu slave%s\n", slaves.size(), slaves.size() == 1 ? "" : "s");
    std::printf("%-4s %-7s %-10s %-10s %-10s %-10s %-10s %-9s %s\n", "pos", "station", "state", "vendor",
                "product", "revision", "serial", "delay/ns", "name");
    for (const master::SlaveInfo& s : slaves) {
        const Address a = Address::station(s.station);
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
        std::string name;
        // The device name from the SII General category (through the STRINGS category).
        if (auto img = m.sii_read_image(a)) {
            const esi::SiiInfo info = esi::parse_sii(*img);
            if (info.general) name = info.general->name;
        }
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
    scan_cmd->add_flag("--no-dc", *no_dc, "Do not measure DC propagation delays (no BWR to 0x0900)");
    scan_cmd->callback(
        [run, no_dc, &rc] { rc = run([no_dc](master::Master& m) { return scan(m, !*no_dc); }); });
}

}  // namespace ecatctl
