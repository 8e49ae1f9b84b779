// Helpers the commands of main.cpp share: failures and usage errors, naming the slave, the mailbox.
#include <CLI/CLI.hpp>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "common.hpp"
#include "format.hpp"
#include "master/coe.hpp"
#include "master/foe.hpp"
#include "master/mailbox.hpp"
#include "master/master.hpp"
#include "master/session.hpp"
#include "util/input_file.hpp"
#include "util/strfmt.hpp"

namespace ecatctl {

using master::Address;
using master::Error;

master::AlStatus g_refusal;

int fail(Error e, const std::string& what) {
    if (e == Error::AlRefused) {
        std::fprintf(stderr, "ecatctl: %s: refused, stays in %s, AL status code 0x%04x (%s)\n", what.c_str(),
                     std::string(master::al_state_name(g_refusal.state)).c_str(), g_refusal.code,
                     std::string(master::al_status_code_name(g_refusal.code)).c_str());
        return kExitProtocol;
    }
    return report_error(e, what);
}

std::string state_failure(const master::AlStatus* st, const std::string& wanted) {
    if (st == nullptr || st->state == 0)
        return "no AL status at the end (is the slave still there?), not " + wanted;
    std::string text =
        "ended in " + std::string(master::al_state_name(st->state)) + (st->error ? "+ERR" : "");
    if (!st->error) return text + ", not " + wanted;
    std::ostringstream code;
    code << std::hex << std::setw(4) << std::setfill('0') << st->code;
    return text + ", not " + wanted + ", AL status code 0x" + code.str() + " (" +
           std::string(master::al_status_code_name(st->code)) + ")";
}

// The slave a command names; a bad one is reported as a usage error (exit kExitUsage) and gives nullopt.
std::optional<Address> named_slave(const std::string& text, bool station) {
    auto a = parse_slave_address(text, station);
    if (!a) usage_error("bad slave '" + text + "'");
    return a;
}

std::optional<std::vector<uint8_t>> read_file(const std::string& path, std::size_t max_bytes,
                                              std::string_view what) {
    try {
        return util::read_input_bytes(path, max_bytes, what);
    } catch (const util::InputFileError& e) {
        std::fprintf(stderr, "ecatctl: %s\n", e.what());
        return std::nullopt;
    }
}

// A slave in INIT gets its mailbox SMs from its SII and is taken to PREOP; one already in PREOP or above
// keeps the SMs it has. A slave in PREOP whose mailbox SMs are gone (cleared by another tool, or a master
// that stopped half-way) is set up again through INIT, as IgH's master does; above PREOP that would stop its
// process data, so it is only said.
Error open_mailbox(master::Master& m, master::Mailbox& mbx, Address a) {
    auto st = m.al_status(a);
    if (!st) return st.error();
    const auto from_init = [&] {
        if (Error e = mbx.configure_from_sii(); e != Error::Ok) return e;
        master::AlStatus final;
        const Error e = m.request_state(a, master::AlState::PreOp, &final);
        if (e == Error::AlRefused) g_refusal = final;  // fail() reports it, in one message
        return e;
    };
    if (st->state == static_cast<uint8_t>(master::AlState::Init)) return from_init();
    const Error e = mbx.adopt_current();
    if (e != Error::MailboxNotConfigured) return e;
    const auto declared = m.sii_has_mailbox(a);  // a coupler or an IO terminal has none: nothing to set up
    if (!declared) return declared.error();
    if (!*declared) return Error::NoMailbox;
    if (st->state != static_cast<uint8_t>(master::AlState::PreOp)) {
        std::fprintf(stderr,
                     "ecatctl: %s is in %s without its mailbox SyncManagers; `ecatctl state %u init` and "
                     "again sets them up\n",
                     slave_label(a).c_str(), std::string(master::al_state_name(st->state)).c_str(), a.value);
        return e;
    }
    std::fprintf(stderr,
                 "ecatctl: %s is in PREOP without its mailbox SyncManagers: set up again through INIT\n",
                 slave_label(a).c_str());
    master::AlStatus final;
    if (Error back = m.request_state(a, master::AlState::Init, &final); back != Error::Ok) {
        if (back == Error::AlRefused) g_refusal = final;
        return back;
    }
    return from_init();
}

int sdo_failed(const master::SdoClient& sdo, Error e, const std::string& what) {
    return report_sdo_failure(sdo, e, what, fail);
}

}  // namespace ecatctl
