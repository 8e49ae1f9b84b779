// `ecatctl foe read|write`: file access over EtherCAT (writes go through BOOT).
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

#include "cmd_firmware.hpp"  // ProgressBar
#include "commands.hpp"
#include "common.hpp"
#include "format.hpp"
#include "master/coe.hpp"
#include "master/foe.hpp"
#include "master/mailbox.hpp"
#include "master/master.hpp"
#include "master/session.hpp"

namespace ecatctl {

namespace {

using master::Address;
using master::Error;

struct FoeArgs {
    std::string slave = "0";
    bool station = false;
    std::string name;
    std::string file;
    std::string output;
    std::string password = "0";
    bool stay = false;
    bool progress = false;
};

int foe_failed(const master::FoeClient& foe, Error e, const std::string& what) {
    if (e == Error::FoeError) {
        std::fprintf(stderr, "ecatctl: %s: FoE error 0x%04x%s%s\n", what.c_str(), foe.last_error(),
                     foe.last_error_text().empty() ? "" : ": ", foe.last_error_text().c_str());
        return kExitProtocol;
    }
    return fail(e, what);
}

int foe_transfer(master::Master& m, const FoeArgs& f, bool read) {
    auto a = named_slave(f.slave, f.station);
    if (!a) return kExitUsage;
    auto password = parse_number(f.password, 0xFFFFFFFF);
    if (!password) return usage_error("bad password '" + f.password + "'");
    std::vector<uint8_t> data;
    std::string name = f.name;
    if (!read) {
        auto d = read_file(f.file, kMaxFileBytes, "file to write");
        if (!d) return kExitUsage;
        data = std::move(*d);
        // The device takes firmware under its device name (0x1008, the SII General name) or the firmware
        // file name built from it; the local file's name means nothing to it.
        if (name.empty()) {
            auto device = sii_device_name(m, *a);
            if (!device)
                return usage_error(
                    foe_names_hint(slave_label(*a) + " has no device name in its SII: give --name"));
            name = *device;
        }
    }
    if (name.empty()) return usage_error("give the file name on the slave");
    master::Mailbox mbx(m, *a);
    auto st = m.al_status(*a);
    if (!st) return fail(st.error(), "reading the AL status of " + slave_label(*a));
    const auto boot = static_cast<uint8_t>(master::AlState::Boot);
    bool entered_boot = false;
    if (st->state == boot) {
        if (Error e = mbx.adopt_current(); e != Error::Ok) return fail(e, "opening the bootstrap mailbox");
    } else if (!read) {
        // Firmware goes in through Bootstrap: INIT, the bootstrap mailbox from the SII, BOOT. INIT is not
        // requested again from a slave in INIT: with device emulation off AL control is a mailbox the slave
        // must read before it takes the next write, and "INIT reached" would not wait for that read, so the
        // BOOT request right after could be dropped by the ESC.
        if (st->state != static_cast<uint8_t>(master::AlState::Init)) {
            if (Error e = m.request_state(*a, master::AlState::Init); e != Error::Ok)
                return fail(e, "going to INIT");
        }
        if (Error e = mbx.configure_from_sii(true); e != Error::Ok)
            return fail(e, "setting up the bootstrap mailbox");
        master::AlStatus final;
        if (Error e = m.request_state(*a, master::AlState::Boot, &final); e != Error::Ok) {
            if (e == Error::AlRefused) g_refusal = final;
            return fail(e, "going to BOOT");
        }
        entered_boot = true;
    } else if (Error e = open_mailbox(m, mbx, *a); e != Error::Ok) {
        return fail(e, "opening the mailbox of " + slave_label(*a));
    }
    master::FoeClient foe(mbx);
    int rc = kExitOk;
    if (read) {
        auto file = foe.read(name, static_cast<uint32_t>(*password));
        if (!file) return foe_failed(foe, file.error(), "reading '" + name + "'");
        if (f.output.empty()) {
            std::fputs(hex_dump(0, *file).c_str(), stdout);
        } else if (f.output == "-") {  // the file itself on standard output
            std::fwrite(file->data(), 1, file->size(), stdout);
        } else {
            std::ofstream o(f.output, std::ios::binary | std::ios::trunc);
            o.write(reinterpret_cast<const char*>(file->data()), static_cast<std::streamsize>(file->size()));
            if (!o) {
                std::cerr << "ecatctl: cannot write " << f.output << ": " << std::strerror(errno) << "\n";
                return kExitFailure;
            }
            std::cerr << "ecatctl: " << file->size() << " bytes written to " << f.output << "\n";
        }
    } else {
        ProgressBar bar("writing '" + name + "'", f.progress);
        foe.set_progress(bar.callback());
        const Error e = foe.write(name, data, static_cast<uint32_t>(*password));
        bar.finish();
        if (e == Error::FoeError && foe.last_error() == 0x8001) {  // not found: say which names it takes
            std::cerr << "ecatctl: "
                      << foe_names_hint("writing '" + name + "': FoE error 0x8001 (" + foe.last_error_text() +
                                        ")")
                      << "\n";
            rc = kExitProtocol;
        } else if (e != Error::Ok)
            rc = foe_failed(foe, e, "writing '" + name + "'");
        else
            std::cerr << "ecatctl: " << data.size() << " bytes written to '" << name << "'\n";
    }
    if (entered_boot && !f.stay) {
        // Leaving Bootstrap restarts the device with the new firmware (B -> I).
        if (Error e = m.request_state(*a, master::AlState::Init); e != Error::Ok && rc == kExitOk)
            rc = fail(e, "leaving BOOT");
    }
    return rc;
}

}  // namespace

void add_foe_command(CLI::App& app, MasterRunner run, int& rc) {
    auto fa = std::make_shared<FoeArgs>();
    auto* foe = app.add_subcommand("foe", "File access over EtherCAT")->require_subcommand(1);
    auto* foe_rd = foe->add_subcommand("read", "Read a file from the slave (hex dump, or -o FILE)");
    foe_rd->add_option("name", fa->name, "File name on the slave")->required();
    foe_rd->add_option("-o,--output", fa->output, "Write the file here ('-': standard output)");
    foe_rd->add_option("-p,--position", fa->slave, "Slave position (or station address with --station)")
        ->capture_default_str();
    foe_rd->add_flag("-s,--station", fa->station, "--position is a station address");
    foe_rd->add_option("--password", fa->password, "FoE password")->capture_default_str();
    foe_rd->callback(
        [fa, run, &rc] { rc = run([&](master::Master& m) { return foe_transfer(m, *fa, true); }); });
    auto* foe_wr = foe->add_subcommand("write", "Write a file (firmware) through BOOT, then back to INIT");
    foe_wr->add_option("file", fa->file, "Local file")->required()->check(CLI::ExistingFile);
    foe_wr->add_option("-n,--name", fa->name,
                       "File name on the slave (default: the device name from its SII)");
    foe_wr->add_option("-p,--position", fa->slave, "Slave position (or station address with --station)")
        ->capture_default_str();
    foe_wr->add_flag("-s,--station", fa->station, "--position is a station address");
    foe_wr->add_option("--password", fa->password, "FoE password")->capture_default_str();
    foe_wr->add_flag("--stay", fa->stay, "Stay in BOOT afterwards");
    foe_wr->add_flag("--progress", fa->progress, "Show progress also when stderr is not a terminal");
    foe_wr->callback(
        [fa, run, &rc] { rc = run([&](master::Master& m) { return foe_transfer(m, *fa, false); }); });
}

}  // namespace ecatctl
