// `ecatctl pd --all`: every slave on the line to OP in one process-data session (one LRW per cycle over all
// slaves' SM2/SM3, expected working counter = the sum of their shares), with optional DC (delays and offsets
// measured over the line, SYNC0 on every slave with one start time).
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "common.hpp"
#include "format.hpp"
#include "master/bus.hpp"
#include "master/coe.hpp"
#include "master/mailbox.hpp"
#include "master/master.hpp"
#include "master/session.hpp"
#include "util/json.hpp"

namespace ecatctl {

using master::Address;
using master::Error;

int process_data_all(master::Master& m, const PdAllArgs& p) {
    auto bus = master::scan_bus(m, {.first_station = 0x1001, .identity = false});
    if (!bus) return fail(bus.error(), "scanning the line");
    if (bus->empty()) {
        std::cerr << "ecatctl: no slave answered\n";
        return kExitNoSlave;
    }
    const std::size_t n = bus->size();
    std::vector<Address> addresses;
    for (const master::SlaveInfo& s : *bus)
        addresses.push_back(Address::station(s.station));
    // Slaves without mailbox (SII words 0x18-0x1B all zero: couplers, digital IO terminals) get their layout
    // from the SII alone and no SDO client.
    std::vector<bool> mailbox(n, true);
    for (std::size_t k = 0; k < n; ++k) {
        const auto declared = m.sii_has_mailbox(addresses[k]);
        if (!declared) return fail(declared.error(), "reading the SII of " + slave_label(addresses[k]));
        mailbox[k] = *declared;
    }
    master::SdoClients sdos;
    const Error opened = sdos.open(m, addresses, [&](master::Mailbox& mbx, Address a) {
        const std::size_t k = a.value - 0x1001u;
        const master::SlaveInfo& s = (*bus)[k];
        // Configuration happens in PREOP.
        if (s.al.state != static_cast<uint8_t>(master::AlState::Init) &&
            (s.al.state != static_cast<uint8_t>(master::AlState::PreOp) || s.al.error)) {
            if (Error e = m.request_state(a, master::AlState::PreOp); e != Error::Ok) return e;
        }
        if (!mailbox[k])
            return s.al.state == static_cast<uint8_t>(master::AlState::Init)
                       ? m.request_state(a, master::AlState::PreOp)
                       : Error::Ok;
        return open_mailbox(m, mbx, a);
    });
    if (opened != Error::Ok)
        return fail(opened, "opening the mailbox of " + slave_label(addresses[sdos.failed()]));
    std::vector<master::SdoClient*> clients(sdos.clients().begin(), sdos.clients().end());
    for (std::size_t k = 0; k < n; ++k)
        if (!mailbox[k]) clients[k] = nullptr;
    master::ProcessDataSession pd(m, addresses, clients);
    if (Error e = pd.discover(); e != Error::Ok) return fail(e, "reading the process-data layouts");
    for (std::size_t k = 0; k < n; ++k)
        if (!mailbox[k])
            if (Error e = pd.discover_sii(k); e != Error::Ok)
                return fail(e, "reading the process-data layout of " + slave_label(addresses[k]));
    master::DcConfig dc;
    dc.enable = p.dc;
    dc.cycle_ns = p.cycle_us * 1000u;
    // Every slave's SYNC0 gets its start time before the first one is due.
    dc.start_delay = std::max(dc.start_delay, std::chrono::milliseconds(10 + 2 * static_cast<int64_t>(n)));
    if (Error e = pd.configure(dc); e != Error::Ok) return fail(e, "configuring process data");
    if (!p.json)
        std::printf("%zu slave%s, outputs %zu bytes, inputs %zu bytes, expected wkc %u\n", n,
                    n == 1 ? "" : "s", pd.outputs().size(), pd.inputs().size(), pd.expected_wkc());
    const auto period = std::chrono::microseconds(p.cycle_us);
    std::vector<uint8_t> out_bytes = p.outputs;
    auto fill = [&] {
        for (std::size_t k = 0; k < pd.size(); ++k) {
            auto o = pd.outputs(k);
            std::copy_n(out_bytes.begin(), std::min(out_bytes.size(), o.size()), o.begin());
        }
    };
    if (int rc = pd_to_state(pd, p.op, period, fill); rc != kExitOk) return rc;
    const master::CycleStats before = pd.stats();
    pd_run(pd, p.steps, p.count, period, out_bytes, fill);
    const auto& s = pd.stats();
    // Per slave: its state now and its share of the working counter; a slave that is gone or not in the
    // state is what a working-counter error means.
    std::vector<master::AlStatus> states(n);
    const Error read = pd.read_states(states);
    const uint8_t want = static_cast<uint8_t>(p.op ? master::AlState::Op : master::AlState::SafeOp);
    bool all_there = read == Error::Ok;
    if (p.json) {
        // docs/ecatctl-json.md, "pd --all".
        const uint64_t cycles = s.cycles - before.cycles;
        util::JsonWriter w(std::cout);
        w.begin_object()
            .member("cycles", cycles)
            .member("lost", s.lost - before.lost)
            .member("wkc_errors", s.wkc_errors - before.wkc_errors)
            .member("expected_wkc", pd.expected_wkc());
        if (p.dc) w.member("reference_time_ns", pd.reference_time());
        w.key("slaves").begin_array();
        for (std::size_t k = 0; k < n; ++k) {
            const master::AlStatus& st = states[k];
            if (st.state != want || st.error) all_there = false;
            w.begin_object().member("position", k).member("station", addresses[k].value).key("state");
            if (st.state)
                w.value(master::al_state_name(st.state));
            else
                w.null();  // gone
            w.member("al_error", st.error)
                .member("al_status_code", st.code)
                .member("expected_wkc", pd.expected_wkc(k))
                .member("output_bytes", pd.outputs(k).size())
                .member("input_bytes", pd.inputs(k).size());
            if (p.dc && k < pd.dc_slaves().size()) w.member("delay_ns", pd.dc_slaves()[k].delay_ns);
            w.end_object();
        }
        w.end_array().end_object();
        std::cout << std::flush;
    } else {
        std::printf("%-4s %-7s %-10s %-4s %-7s %-7s", "pos", "station", "state", "wkc", "out", "in");
        std::printf(p.dc ? " %s\n" : "\n", "delay/ns");
        for (std::size_t k = 0; k < n; ++k) {
            const master::AlStatus& st = states[k];
            std::string state = st.state ? std::string(master::al_state_name(st.state)) : "gone";
            if (st.error) state += "+ERR";
            if (st.state != want || st.error) all_there = false;
            std::printf("%-4zu 0x%04x  %-10s %-4u %-7zu %-7zu", k, addresses[k].value, state.c_str(),
                        pd.expected_wkc(k), pd.outputs(k).size(), pd.inputs(k).size());
            if (p.dc && k < pd.dc_slaves().size())
                std::printf(" %lld\n", static_cast<long long>(pd.dc_slaves()[k].delay_ns));
            else
                std::printf("\n");
        }
        print_pd_cycles(pd, before);
        if (p.dc)
            std::printf("reference system time %llu ns\n",
                        static_cast<unsigned long long>(pd.reference_time()));
    }
    if (!p.keep) {
        std::vector<uint16_t> stations;
        for (const Address& a : addresses)
            stations.push_back(a.value);
        (void)m.request_state_all(master::AlState::PreOp, stations);
    }
    // A run that ends with a slave outside the state asked for, or with an AL error, failed: say which.
    if (read != Error::Ok)
        std::cerr << "ecatctl: reading the AL states at the end: " << to_string(read) << '\n';
    unsigned off = 0;
    for (const master::AlStatus& st : states)
        off += st.state != want || st.error;
    if (read == Error::Ok && off != 0) {
        std::cerr << "ecatctl: " << off << " of " << n << (n == 1 ? " slave" : " slaves") << " not in "
                  << (p.op ? "OP" : "SAFEOP") << " at the end:";
        for (std::size_t k = 0; k < n; ++k)
            if (states[k].state != want || states[k].error)
                std::cerr << "\n  " << slave_label(addresses[k]) << ": "
                          << state_failure(&states[k], p.op ? "OP" : "SAFEOP");
        std::cerr << '\n';
    }
    const bool clean = s.lost == before.lost && s.wkc_errors == before.wkc_errors && all_there;
    return clean ? kExitOk : kExitProtocol;
}

}  // namespace ecatctl
