// ecatctl state <slave> [INIT|PREOP|BOOT|SAFEOP|OP] [--station] [--identify]: shows the AL state, or takes
// the slave to a state the way IgH's `ethercat states` does, i.e. with the set-up each state needs, stepping
// through the states in between (ETG.1000.6 state machine: I -> P -> S -> O, I -> B, B -> I only):
// - PREOP: the mailbox SyncManagers SM0/SM1 from the SII standard mailbox (words 0x18-0x1C);
// - BOOT: INIT first, then SM0/SM1 from the SII bootstrap mailbox (words 0x14-0x17);
// - SAFEOP/OP: PREOP first, then the process-data SMs and FMMUs exactly as `ecatctl pd` sets them up (the
//   master library's ProcessDataSession: layout from the SII and the PDO assignment over CoE, sync mode,
//   SM2/SM3, FMMU0/1), cycling the process data while the state is requested.
// Without a master exchanging process data afterwards, a slave with the SM watchdog on leaves OP by itself
// (AL status code 0x001B); `ecatctl pd` keeps a slave in OP.
#include "cmd_state.hpp"

#include <cctype>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>

#include "common.hpp"
#include "format.hpp"
#include "master/coe.hpp"
#include "master/mailbox.hpp"
#include "master/session.hpp"

namespace ecatctl {

namespace {

using master::Address;
using master::AlState;
using master::Error;

struct StateArgs {
    std::string slave;
    std::string target;
    bool station = false;
    bool identify = false;
};

std::string name_of(uint8_t state) {
    return std::string(master::al_state_name(state));
}

// A refusal, with the state the slave stays in and the AL status code.
int refused(Address a, const char* step, const master::AlStatus& st) {
    std::fprintf(stderr, "ecatctl: %s refused %s: stays in %s, AL status code 0x%04x (%s)\n",
                 slave_label(a).c_str(), step, name_of(st.state).c_str(), st.code,
                 std::string(master::al_status_code_name(st.code)).c_str());
    return kExitProtocol;
}

// One plain AL control request (no set-up needed for it).
int go(master::Master& m, Address a, AlState s, const char* name) {
    master::AlStatus st;
    const Error e = m.request_state(a, s, &st);
    if (e == Error::AlRefused) return refused(a, name, st);
    if (e != Error::Ok) return report_error(e, std::string("requesting ") + name + " from " + slave_label(a));
    return kExitOk;
}

// INIT -> PREOP with SM0/SM1 from the SII (standard mailbox); from BOOT through INIT; from SAFEOP/OP down.
int to_preop(master::Master& m, Address a, uint8_t current) {
    const auto init = static_cast<uint8_t>(AlState::Init);
    if (current == static_cast<uint8_t>(AlState::Boot)) {
        if (int rc = go(m, a, AlState::Init, "INIT"); rc != kExitOk) return rc;
        current = init;
    }
    if (current == init) {
        // A slave without mailbox (a coupler, a digital IO terminal) goes to PREOP as it is.
        master::Mailbox mbx(m, a);
        if (Error e = mbx.configure_from_sii(); e != Error::Ok && e != Error::NoMailbox)
            return report_error(e, "setting up the mailbox (SM0/SM1) from the SII of " + slave_label(a));
    }
    return go(m, a, AlState::PreOp, "PREOP");
}

// PREOP -> SAFEOP (-> OP): process-data SMs and FMMUs as `pd` sets them up, cycling during the requests.
int to_safeop_op(master::Master& m, Address a, bool op) {
    const auto declared = m.sii_has_mailbox(a);
    if (!declared) return report_error(declared.error(), "reading the SII of " + slave_label(a));
    master::Mailbox mbx(m, a);
    master::SdoClient sdo(mbx);
    std::unique_ptr<master::ProcessDataSession> session;
    if (*declared) {
        if (Error e = mbx.adopt_current(); e != Error::Ok) return report_error(e, "opening the mailbox");
        session = std::make_unique<master::ProcessDataSession>(m, a, sdo);
        if (Error e = session->discover(); e != Error::Ok)
            return report_sdo_failure(sdo, e, "reading the process-data layout", report_error);
    } else {  // no mailbox: the layout the SII's SyncM/TxPDO/RxPDO categories assign, as `pd` takes it
        session = std::make_unique<master::ProcessDataSession>(m, std::span<const Address>(&a, 1));
        if (Error e = session->discover_sii(0); e != Error::Ok)
            return report_error(e, "reading the process-data layout of " + slave_label(a));
    }
    master::ProcessDataSession& pd = *session;
    if (pd.layout().output_bytes() + pd.layout().input_bytes() == 0) {  // no process data (a coupler)
        if (int rc = go(m, a, AlState::SafeOp, "SAFEOP"); rc != kExitOk || !op) return rc;
        return go(m, a, AlState::Op, "OP");
    }
    if (Error e = pd.configure(); e != Error::Ok)
        return report_sdo_failure(sdo, e, "configuring process data", report_error);
    const auto period = std::chrono::microseconds(1000);
    master::AlStatus st;
    for (AlState s : {AlState::SafeOp, AlState::Op}) {
        const char* name = s == AlState::SafeOp ? "SAFEOP" : "OP";
        const Error e = pd.request_state(s, period, &st);
        if (e == Error::AlRefused) return refused(a, name, st);
        if (e != Error::Ok)
            return report_error(e, std::string("requesting ") + name + " from " + slave_label(a));
        if (!op) break;
    }
    return kExitOk;
}

}  // namespace

std::string state_word(const std::string& text) {
    std::string t = text;
    for (auto& c : t)
        c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    return t;
}

bool is_state_word(const std::string& text) {
    const std::string t = state_word(text);
    return t == "INIT" || t == "PREOP" || t == "BOOT" || t == "SAFEOP" || t == "OP";
}

int go_to_state(master::Master& m, master::Address a, const std::string& target) {
    auto st = m.al_status(a);
    if (!st) return report_error(st.error(), "reading the AL status of " + slave_label(a));
    const std::string t = state_word(target);
    const uint8_t now = st->state;
    const auto boot = static_cast<uint8_t>(AlState::Boot);
    int rc = kExitOk;
    if (t == "INIT") {
        rc = go(m, a, AlState::Init, "INIT");
    } else if (t == "PREOP") {
        rc = to_preop(m, a, now);
    } else if (t == "BOOT") {
        if (now != boot || st->error) {
            // INIT is not requested again from a slave in INIT (request_state writes nothing then).
            rc = go(m, a, AlState::Init, "INIT");
            if (rc == kExitOk) {
                master::Mailbox mbx(m, a);
                if (Error e = mbx.configure_from_sii(true); e != Error::Ok)
                    rc = report_error(
                        e, "setting up the bootstrap mailbox (SM0/SM1) from the SII of " + slave_label(a));
                else
                    rc = go(m, a, AlState::Boot, "BOOT");
            }
        }
    } else if (t == "SAFEOP" || t == "OP") {
        const auto wanted = static_cast<uint8_t>(t == "OP" ? AlState::Op : AlState::SafeOp);
        if (now != wanted || st->error) {
            // The process data is set up in PREOP: a slave above it steps down to PREOP first.
            rc = to_preop(m, a, now);
            if (rc == kExitOk) rc = to_safeop_op(m, a, t == "OP");
        }
    } else {
        return usage_error("unknown state '" + target + "' (INIT, PREOP, BOOT, SAFEOP, OP)");
    }
    return rc;
}

namespace {

int run_state(master::Master& m, const StateArgs& args) {
    auto a = parse_slave_address(args.slave, args.station);
    if (!a) return usage_error("bad slave '" + args.slave + "'");
    if (int rc = check_slave_present(m, *a); rc != kExitOk) return rc;
    if (args.identify) {
        auto id = m.identify(*a);
        if (!id) return report_error(id.error(), "device identification of " + slave_label(*a));
        std::printf("identification value 0x%04x (%u)\n", *id, *id);
        return kExitOk;
    }
    auto st = m.al_status(*a);
    if (!st) return report_error(st.error(), "reading the AL status of " + slave_label(*a));
    if (args.target.empty()) {
        std::printf("%s%s", name_of(st->state).c_str(), st->error ? " +ERR" : "");
        if (st->error || st->code)
            std::printf(" 0x%04x %s", st->code, std::string(master::al_status_code_name(st->code)).c_str());
        std::printf("\n");
        return kExitOk;
    }
    if (int rc = go_to_state(m, *a, args.target); rc != kExitOk) return rc;
    auto final = m.al_status(*a);
    if (!final) return report_error(final.error(), "reading the AL status of " + slave_label(*a));
    std::printf("%s\n", name_of(final->state).c_str());
    if (final->state == static_cast<uint8_t>(AlState::Op))
        std::fprintf(
            stderr,
            "ecatctl: nothing exchanges process data now: with its SM watchdog on, the slave leaves OP "
            "by itself (AL status code 0x001B); `ecatctl pd` keeps it in OP\n");
    return kExitOk;
}

}  // namespace

void add_state_command(CLI::App& app, MasterRunner run, int& rc) {
    auto args = std::make_shared<StateArgs>();
    auto* c =
        app.add_subcommand("state",
                           "Show the AL state, or go to one with the set-up it needs (mailbox SMs from the "
                           "SII, process data), stepping through the states between; errors acknowledged");
    c->add_option("slave", args->slave, "Slave position (or station address with --station)")->required();
    c->add_option("state", args->target, "INIT|PREOP|BOOT|SAFEOP|OP (omit to show the current state)");
    c->add_flag("-s,--station", args->station, "<slave> is a station address");
    c->add_flag("--identify", args->identify, "Device identification: AL control bit 5, value from 0x0134");
    c->callback([args, run = std::move(run), &rc] {
        rc = run([&](master::Master& m) { return run_state(m, *args); });
    });
}

}  // namespace ecatctl
