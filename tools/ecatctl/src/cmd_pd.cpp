// `ecatctl pd`: bring a slave to OP and exchange process data cyclically (LRW), with optional DC.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <iterator>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "cmd_verbs.hpp"
#include "coe_view.hpp"
#include "commands.hpp"
#include "common.hpp"
#include "format.hpp"
#include "master/coe.hpp"
#include "master/foe.hpp"
#include "master/mailbox.hpp"
#include "master/master.hpp"
#include "master/session.hpp"
#include "util/json.hpp"
#include "util/strfmt.hpp"

namespace ecatctl {

namespace {

using master::Address;
using master::Error;

struct PdArgs {
    std::string slave = "0";
    unsigned cycle_us = 1000;
    uint64_t count = 1000;
    bool dc = false;
    std::string state = "OP";
    std::vector<std::string> outputs;
    std::vector<std::string> steps;
    bool keep = false;
    bool station = false;  // slave is a station address (as scan assigns them)
    bool all = false;      // every slave on the line in one session (cmd_pd_all.cpp)
    bool json = false;     // the outcome as JSON on stdout (docs/ecatctl-json.md, "pd")
};

// "CYCLES:B0,B1,..." -> cycles and the output bytes sent (from the first byte) during them.
struct Step {
    uint64_t cycles = 0;
    std::vector<uint8_t> bytes;
};
std::optional<Step> parse_step(const std::string& text) {
    const auto colon = text.find(':');
    if (colon == std::string::npos) return std::nullopt;
    auto n = parse_number(text.substr(0, colon), 10'000'000);
    if (!n) return std::nullopt;
    Step st;
    st.cycles = *n;
    std::string rest = text.substr(colon + 1);
    std::size_t pos = 0;
    while (pos <= rest.size()) {
        const auto comma = rest.find(',', pos);
        const std::string item =
            rest.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos);
        if (item.empty()) return std::nullopt;
        const bool hex_digits = item.find_first_not_of("0123456789abcdefABCDEF") == std::string::npos;
        auto b = parse_number(hex_digits && item.size() <= 2 ? "0x" + item : item, 0xFF);
        if (!b) return std::nullopt;
        st.bytes.push_back(static_cast<uint8_t>(*b));
        if (comma == std::string::npos) break;
        pos = comma + 1;
    }
    return st;
}

}  // namespace

int pd_to_state(master::ProcessDataSession& pd, bool op, std::chrono::microseconds period,
                const std::function<void()>& fill) {
    master::AlStatus final;
    auto go = [&](master::AlState s, const char* name) {
        const Error e = pd.request_state(s, period, &final, fill);
        if (e == Error::AlRefused) {
            std::fprintf(stderr, "ecatctl: %s refused: AL status code 0x%04x (%s)\n", name, final.code,
                         std::string(master::al_status_code_name(final.code)).c_str());
            return kExitProtocol;
        }
        return e == Error::Ok ? kExitOk : fail(e, std::string("requesting ") + name);
    };
    if (int rc = go(master::AlState::SafeOp, "SAFEOP"); rc != kExitOk) return rc;
    return op ? go(master::AlState::Op, "OP") : kExitOk;
}

void pd_run(master::ProcessDataSession& pd, const std::vector<PdStep>& steps, uint64_t count,
            std::chrono::microseconds period, std::vector<uint8_t>& out_bytes,
            const std::function<void()>& fill) {
    const std::vector<uint8_t> final_outputs = out_bytes;
    for (const auto& [cycles, bytes] : steps) {
        out_bytes = bytes;
        pd.run(cycles, period, fill);
    }
    if (!final_outputs.empty() || steps.empty())
        out_bytes = final_outputs;  // else the last step's bytes stay
    pd.run(count, period, fill);
}

void print_pd_cycles(const master::ProcessDataSession& pd, const master::CycleStats& before) {
    const auto& s = pd.stats();
    const uint64_t cycles = s.cycles - before.cycles;
    const uint64_t ok = cycles - (s.lost - before.lost);
    const double avg =
        ok ? static_cast<double>((s.rtt_sum - before.rtt_sum).count()) / 1000.0 / static_cast<double>(ok) : 0;
    std::printf(
        "cycles %llu, lost %llu, wkc errors %llu (expected wkc %u), rtt min %.1f us, avg %.1f us, max %.1f "
        "us\n",
        static_cast<unsigned long long>(cycles), static_cast<unsigned long long>(s.lost - before.lost),
        static_cast<unsigned long long>(s.wkc_errors - before.wkc_errors), pd.expected_wkc(),
        static_cast<double>(s.rtt_min.count()) / 1000.0, avg,
        static_cast<double>(s.rtt_max.count()) / 1000.0);
}

namespace {

// docs/ecatctl-json.md, "pd": how the run ended, its counters, and the last images by PDO entry.
void write_pd_json(master::ProcessDataSession& pd, const master::CycleStats& before,
                   const master::AlStatus* now, bool dc, const std::vector<SyncView>& pdo_config) {
    const auto& s = pd.stats();
    const uint64_t cycles = s.cycles - before.cycles;
    const uint64_t ok = cycles - (s.lost - before.lost);
    util::JsonWriter w(std::cout);
    w.begin_object();
    if (now)
        w.member("state", master::al_state_name(now->state))
            .member("al_error", now->error)
            .member("al_status_code", now->code);
    else
        w.key("state").null();
    w.member("cycles", cycles)
        .member("lost", s.lost - before.lost)
        .member("wkc_errors", s.wkc_errors - before.wkc_errors)
        .member("expected_wkc", pd.expected_wkc())
        .member("rtt_min_ns", ok ? s.rtt_min.count() : 0)
        .member("rtt_avg_ns", ok ? (s.rtt_sum - before.rtt_sum).count() / static_cast<int64_t>(ok) : 0)
        .member("rtt_max_ns", ok ? s.rtt_max.count() : 0);
    if (dc) w.member("reference_time_ns", pd.reference_time());
    for (const bool output : {true, false}) {
        const std::span<const uint8_t> image = output ? pd.outputs() : pd.inputs();
        std::string hex;
        for (uint8_t b : image)
            hex += util::strprintf(hex.empty() ? "%02x" : " %02x", b);
        w.member(output ? "outputs_bytes" : "inputs_bytes", hex);
        w.key(output ? "outputs" : "inputs").begin_array();
        std::size_t bit = 0;
        for (const auto& sv : pdo_config) {
            if (sv.output != output) continue;
            for (const auto& pdo : sv.pdos)
                for (const auto& e : pdo.entries) {
                    if (e.index != 0) {
                        w.begin_object()
                            .member("pdo", pdo.index)
                            .member("index", e.index)
                            .member("subindex", e.subindex)
                            .member("name", e.name)
                            .member("type", esi_type_name(e.data_type))
                            .member("bit_length", e.bit_length)
                            .key("value");
                        write_typed_json(w, e.data_type, e.bit_length,
                                         extract_bits(image, bit, e.bit_length));
                        w.end_object();
                    }
                    bit += e.bit_length;
                }
            bit =
                (bit + 7) / 8 * 8;  // the next SM's data starts on a byte of the image (the session's layout)
        }
        w.end_array();
    }
    w.end_object();
    std::cout << std::flush;
}

int process_data(master::Master& m, const PdArgs& p) {
    auto pos = parse_number(p.slave, 0xFFFF);
    if (!pos && !p.all) return usage_error("bad slave '" + p.slave + "'");
    std::string t = p.state;
    for (auto& c : t)
        c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    if (t != "OP" && t != "SAFEOP") return usage_error("--state must be SAFEOP or OP");
    for (const std::string& text : p.steps)
        if (!parse_step(text))
            return usage_error("bad --step '" + text + "' (CYCLES:BYTE,BYTE,... e.g. 50:06,00)");
    std::vector<uint8_t> out_bytes;
    for (const std::string& v : p.outputs) {
        auto b = parse_number(v, 0xFF);
        if (!b) return usage_error("bad output byte '" + v + "'");
        out_bytes.push_back(static_cast<uint8_t>(*b));
    }
    if (p.all) {
        PdAllArgs all;
        all.cycle_us = p.cycle_us;
        all.count = p.count;
        all.dc = p.dc;
        all.op = t == "OP";
        all.outputs = out_bytes;
        for (const std::string& text : p.steps) {
            auto step = parse_step(text);  // validated above
            all.steps.emplace_back(step->cycles, step->bytes);
        }
        all.keep = p.keep;
        all.json = p.json;
        return process_data_all(m, all);
    }
    // Station addresses as scan gives them; DC's FRMW addresses the reference clock by station.
    auto n = m.count_slaves();
    if (!n) return fail(n.error(), "counting slaves (BRD 0x0000)");
    if (!p.station && *pos >= *n)
        return check_slave_present(m, Address::position(static_cast<uint16_t>(*pos)));
    if (Error e = m.assign_station_addresses(*n); e != Error::Ok)
        return fail(e, "assigning station addresses");
    const Address a = Address::station(static_cast<uint16_t>(p.station ? *pos : 0x1001 + *pos));
    if (p.station)
        if (int rc = check_slave_present(m, a); rc != kExitOk) return rc;
    // Configuration happens in PREOP.
    auto st = m.al_status(a);
    if (!st) return fail(st.error(), "reading the AL status");
    const auto init = static_cast<uint8_t>(master::AlState::Init);
    const auto preop = static_cast<uint8_t>(master::AlState::PreOp);
    if (st->state != init && (st->state != preop || st->error)) {
        if (Error e = m.request_state(a, master::AlState::PreOp); e != Error::Ok)
            return fail(e, "going to PREOP");
    }
    // A slave without mailbox (SII words 0x18-0x1B all zero: a coupler, a digital IO terminal) has its
    // layout in the SII alone (the PDOs its SyncM/TxPDO/RxPDO categories assign) and no SDO.
    const auto declared = m.sii_has_mailbox(a);
    if (!declared) return fail(declared.error(), "reading the SII");
    const bool has_mailbox = *declared;
    master::Mailbox mbx(m, a);
    master::SdoClient sdo(mbx);
    std::unique_ptr<master::ProcessDataSession> session;
    std::vector<SyncView> pdo_config;  // names and types of the entries, for the decoded images at the end
    if (has_mailbox) {
        if (Error e = open_mailbox(m, mbx, a); e != Error::Ok) return fail(e, "opening the mailbox");
        session = std::make_unique<master::ProcessDataSession>(m, a, sdo);
        if (Error e = session->discover(); e != Error::Ok)
            return sdo_failed(sdo, e, "reading the process-data layout");
        if (Error e = read_pdo_config(sdo, pdo_config); e != Error::Ok) pdo_config.clear();
    } else {
        if (st->state == init)
            if (Error e = m.request_state(a, master::AlState::PreOp); e != Error::Ok)
                return fail(e, "going to PREOP");
        session = std::make_unique<master::ProcessDataSession>(m, std::span<const Address>(&a, 1));
        if (Error e = session->discover_sii(0); e != Error::Ok)
            return fail(e, "reading the process-data layout");
    }
    master::ProcessDataSession& pd = *session;
    const auto& l = pd.layout();
    if (!p.json) {
        // The first SM of each direction and the direction's bytes; a device with several SMs of a direction
        // (SM2 and SM4 for outputs, ...) gets each of them listed on a second line.
        const master::ProcessDataSm none{};
        const master::ProcessDataSm* o = l.first(true);
        const master::ProcessDataSm* i = l.first(false);
        if (!o) o = &none;
        if (!i) i = &none;
        std::printf("outputs: SM%u 0x%04x, %u bytes; inputs: SM%u 0x%04x, %u bytes\n", o->index, o->start,
                    l.output_bytes(), i->index, i->start, l.input_bytes());
        if (l.sms_with_data() > (l.output_bytes() ? 1u : 0u) + (l.input_bytes() ? 1u : 0u)) {
            std::printf("process-data SMs:");
            for (const master::ProcessDataSm& sm : l.sms)
                if (sm.length)
                    std::printf(" SM%u 0x%04x %u bytes %s;", sm.index, sm.start, sm.length,
                                sm.outputs ? "outputs" : "inputs");
            std::printf("\n");
        }
    }
    master::DcConfig dc;
    dc.enable = p.dc;
    dc.cycle_ns = p.cycle_us * 1000u;
    if (Error e = pd.configure(dc); e != Error::Ok) return sdo_failed(sdo, e, "configuring process data");
    const auto period = std::chrono::microseconds(p.cycle_us);
    auto fill = [&] {
        auto o = pd.outputs();
        std::copy_n(out_bytes.begin(), std::min(out_bytes.size(), o.size()), o.begin());
    };
    if (int rc = pd_to_state(pd, t == "OP", period, fill); rc != kExitOk) return rc;
    const master::CycleStats before = pd.stats();
    std::vector<PdStep> steps;
    for (const std::string& text : p.steps) {
        auto step = parse_step(text);  // validated before anything was sent
        steps.emplace_back(step->cycles, step->bytes);
    }
    pd_run(pd, steps, p.count, period, out_bytes, fill);
    const auto& s = pd.stats();
    auto now = m.al_status(a);
    if (p.json) {
        write_pd_json(pd, before, now ? &*now : nullptr, p.dc, pdo_config);
    } else {
        std::printf("state: %s%s\n", now ? std::string(master::al_state_name(now->state)).c_str() : "?",
                    now && now->error ? " +ERR" : "");
        print_pd_cycles(pd, before);
        if (p.dc)
            std::printf("reference system time %llu ns\n",
                        static_cast<unsigned long long>(pd.reference_time()));
        std::printf("inputs:\n%s", hex_dump(0, pd.inputs()).c_str());
        print_pd_entries(pdo_config, pd.outputs(), pd.inputs());
    }
    if (!p.keep) (void)m.request_state(a, master::AlState::PreOp);
    // A run that ends outside the state asked for, or with an AL error, failed, whatever the counters say.
    const auto want = static_cast<uint8_t>(t == "OP" ? master::AlState::Op : master::AlState::SafeOp);
    const bool in_state = now && now->state == want && !now->error;
    if (!in_state) std::cerr << "ecatctl: " << state_failure(now ? &*now : nullptr, t) << '\n';
    const bool clean = s.lost == before.lost && s.wkc_errors == before.wkc_errors && in_state;
    return clean ? kExitOk : kExitProtocol;
}

}  // namespace

void add_pd_command(CLI::App& app, MasterRunner run, int& rc) {
    auto pa = std::make_shared<PdArgs>();
    auto* pdc = app.add_subcommand(
        "pd", "Bring a slave to OP and exchange process data cyclically (LRW), with optional DC");
    pdc->add_option("slave", pa->slave, "Slave position (or station address with --station)")
        ->capture_default_str();
    pdc->add_flag("-s,--station", pa->station, "<slave> is a station address (scan assigns 0x1001..)");
    pdc->add_flag("-a,--all", pa->all,
                  "Every slave on the line in one session: one LRW per cycle, the working counter checked "
                  "against the sum of the slaves' shares, the state of each slave listed (<slave> ignored)");
    pdc->add_option("--cycle-us", pa->cycle_us, "Cycle time in microseconds")
        ->check(CLI::Range(50u, 1000000u))
        ->capture_default_str();
    pdc->add_option("-n,--count", pa->count, "Cycles to run once the state is reached")
        ->capture_default_str();
    pdc->add_flag("--dc", pa->dc, "Distributed clocks: SYNC0 at the cycle time, sync mode DC SYNC0");
    pdc->add_option("--state", pa->state, "SAFEOP or OP")->capture_default_str();
    pdc->add_option("--outputs", pa->outputs, "Output bytes sent every cycle (from the first byte)");
    pdc->add_option("--step", pa->steps,
                    "CYCLES:BYTES before the --count cycles, in order; bytes in hex, comma-separated "
                    "(e.g. --step 50:06,00 --step 50:0f,00)");
    pdc->add_flag("--keep", pa->keep, "Leave the slave in the state reached (default: back to PREOP)");
    pdc->add_flag(
        "--json", pa->json,
        "The outcome as JSON on stdout: state, counters, images by PDO entry (docs/ecatctl-json.md)");
    pdc->callback([pa, run, &rc] { rc = run([&](master::Master& m) { return process_data(m, *pa); }); });
}

}  // namespace ecatctl
