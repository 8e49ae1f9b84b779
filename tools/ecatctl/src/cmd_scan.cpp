// `ecatctl scan`: count the slaves, assign station addresses, list identity, AL state and device name.
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
#include "master/coe.hpp"
#include "master/foe.hpp"
#include "master/mailbox.hpp"
#include "master/master.hpp"
#include "master/session.hpp"
#include "util/le.hpp"

namespace ecatctl {

namespace {

using master::Address;
using master::Error;

int scan(master::Master& m) {
    auto n = m.count_slaves();
    if (!n) return fail(n.error(), "counting slaves (BRD 0x0000)");
    if (*n == 0) {
        std::cerr << "ecatctl: no slave answered\n";
        return kExitNoSlave;
    }
    if (Error e = m.assign_station_addresses(*n); e != Error::Ok)
        return fail(e, "assigning station addresses");
    std::printf("%u slave%s\n", *n, *n == 1 ? "" : "s");
    std::printf("%-4s %-7s %-10s %-10s %-10s %-10s %-10s %s\n", "pos", "station", "state", "vendor",
                "product", "revision", "serial", "name");
    int rc = kExitOk;
    for (uint16_t i = 0; i < *n; ++i) {
        const uint16_t station = static_cast<uint16_t>(0x1001 + i);
        const Address a = Address::station(station);
        std::string state = "?";
        if (auto st = m.al_status(a)) {
            state = std::string(master::al_state_name(st->state));
            if (st->error) {
                char b[32];
                std::snprintf(b, sizeof b, "+ERR(0x%04x)", st->code);
                state += b;
            }
        } else {
            rc = exit_code(st.error());
        }
        uint8_t id[16];
        const Error e = m.sii_read(a, master::sii::VendorId, id);
        if (e != Error::Ok) {
            std::printf("%-4u 0x%04x  %-10s SII: %s\n", i, station, state.c_str(),
                        std::string(master::to_string(e)).c_str());
            rc = exit_code(e);
            continue;
        }
        auto u32 = [&](int k) { return static_cast<unsigned>(util::get32(&id[4 * k])); };
        std::string name;
        // The device name from the SII General category (through the STRINGS category).
        if (auto img = m.sii_read_image(a)) {
            const esi::SiiInfo info = esi::parse_sii(*img);
            if (info.general) name = info.general->name;
        }
        std::printf("%-4u 0x%04x  %-10s 0x%08x 0x%08x 0x%08x 0x%08x %s\n", i, station, state.c_str(), u32(0),
                    u32(1), u32(2), u32(3), name.c_str());
    }
    return rc;
}

}  // namespace

void add_scan_command(CLI::App& app, MasterRunner run, int& rc) {
    auto* scan_cmd = app.add_subcommand(
        "scan", "Count the slaves, assign station addresses 0x1001.., list identity and AL state");
    scan_cmd->callback([run, &rc] { rc = run([](master::Master& m) { return scan(m); }); });
}

}  // namespace ecatctl
