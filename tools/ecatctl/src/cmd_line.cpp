// The verbs that look at the whole line at once, as IgH's `ethercat` has them:
//   crc [--clear]       the error counters 0x0300-0x0313 of every slave (ESC datasheet section II)
//   states [STATE]      every slave's AL state, or every slave taken to STATE (as `state` takes one)
//   alias [SLAVE] [N]   the configured station alias: register 0x0012 and SII word 4; N writes word 4 and the
//                       SII checksum (word 7), taken by the ESC at its next power-on
//   graph               the line or tree as Graphviz dot (ports from DL status, order from the positions)
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "cmd_line.hpp"
#include "cmd_state.hpp"
#include "common.hpp"
#include "esc/wire/registers.hpp"
#include "esc/wire/sii.hpp"
#include "esi/sii_reader.hpp"
#include "format.hpp"
#include "master/bus.hpp"
#include "util/le.hpp"

namespace ecatctl {

namespace {

using master::Address;
using master::Error;

// The number of slaves, or an exit code (printed) when there are none or nothing answered.
int count_line(master::Master& m, uint16_t& n) {
    auto c = m.count_slaves();
    if (!c) return report_error(c.error(), "counting slaves (BRD 0x0000)");
    if (*c == 0) {
        std::fprintf(stderr, "ecatctl: no slave answered\n");
        return kExitNoSlave;
    }
    n = *c;
    return kExitOk;
}

// ---- crc --------------------------------------------------------------------------------------------------

constexpr uint16_t kCounters = 0x0300;  // 0x0300-0x0313
constexpr uint16_t kPortDescriptor = 0x0007;
constexpr std::size_t kCounterBytes = 0x14;

int run_crc(master::Master& m, bool clear) {
    uint16_t n = 0;
    if (int rc = count_line(m, n); rc != kExitOk) return rc;
    std::printf("Slave Port  Invalid  RX-err  Fwd-RX  Lost-link   ProcUnit  PDI\n");
    int rc = kExitOk;
    for (uint16_t p = 0; p < n; ++p) {
        const Address a = Address::position(p);
        uint8_t c[kCounterBytes] = {};
        uint8_t desc = 0;
        if (Error e = m.read(a, kCounters, c); e != Error::Ok) {
            rc = report_error(e, "reading the error counters of " + slave_label(a));
            continue;
        }
        (void)m.read(a, kPortDescriptor, std::span<uint8_t>(&desc, 1));
        bool first = true;
        for (unsigned port = 0; port < 4; ++port) {
            if (((desc >> (2 * port)) & 3u) == 0) continue;  // not implemented
            if (first)
                std::printf("%5u %4u %8u %7u %7u %10u %10u %4u\n", p, port, c[2 * port], c[2 * port + 1],
                            c[8 + port], c[0x10 + port], c[0x0C], c[0x0D]);
            else
                std::printf("%5s %4u %8u %7u %7u %10u\n", "", port, c[2 * port], c[2 * port + 1], c[8 + port],
                            c[0x10 + port]);
            first = false;
        }
        if (!clear) continue;
        // One byte per group clears the group (ESC datasheet section II): RX errors, processing unit, PDI,
        // lost link.
        const uint8_t zero[1] = {0};
        for (uint16_t reg : {uint16_t{0x0300}, uint16_t{0x030C}, uint16_t{0x030D}, uint16_t{0x0310}})
            if (Error e = m.write(a, reg, zero); e != Error::Ok) {
                rc = report_error(e, "clearing the error counters of " + slave_label(a));
                break;
            }
    }
    if (clear && rc == kExitOk) std::printf("cleared\n");
    return rc;
}

// ---- states
// -------------------------------------------------------------------------------------------------

int run_states(master::Master& m, const std::string& target) {
    if (!target.empty() && !is_state_word(target))
        return usage_error("unknown state '" + target + "' (INIT, PREOP, BOOT, SAFEOP, OP)");
    uint16_t n = 0;
    if (int rc = count_line(m, n); rc != kExitOk) return rc;
    int rc = kExitOk;
    for (uint16_t p = 0; p < n; ++p) {
        const Address a = Address::position(p);
        if (!target.empty())
            if (int r = go_to_state(m, a, target); r != kExitOk) rc = r;
        auto st = m.al_status(a);
        if (!st) {
            rc = report_error(st.error(), "reading the AL status of " + slave_label(a));
            continue;
        }
        std::printf("%-3u %s%s", p, std::string(master::al_state_name(st->state)).c_str(),
                    st->error ? " +ERR" : "");
        if (st->error || st->code)
            std::printf(" 0x%04x %s", st->code, std::string(master::al_status_code_name(st->code)).c_str());
        std::printf("\n");
    }
    if (state_word(target) == "OP")
        std::fprintf(
            stderr,
            "ecatctl: nothing exchanges process data now: with their SM watchdog on, the slaves leave "
            "OP by themselves (AL status code 0x001B); `ecatctl pd --all` keeps a line in OP\n");
    return rc;
}

// ---- alias
// --------------------------------------------------------------------------------------------------

struct AliasArgs {
    std::string slave;
    std::string value;
    bool station = false;
};

int show_alias(master::Master& m, Address a, uint16_t position) {
    auto reg = m.read_reg<uint16_t>(a, esc::reg::kStationAlias);
    if (!reg) return report_error(reg.error(), "reading the station alias (0x0012) of " + slave_label(a));
    auto word = m.sii_read_word(a, esc::sii::word::StationAlias);
    if (!word) return report_error(word.error(), "reading SII word 4 of " + slave_label(a));
    std::printf("%-3u alias %u (0x%04x)", position, *reg, *reg);
    if (*word != *reg) std::printf(", SII word 4: %u (0x%04x), taken at the next power-on", *word, *word);
    std::printf("\n");
    return kExitOk;
}

int run_alias(master::Master& m, const AliasArgs& args) {
    std::optional<uint64_t> value;
    if (!args.value.empty()) {
        value = parse_number(args.value, 0xFFFF);
        if (!value) return usage_error("bad alias '" + args.value + "' (0..65535)");
    }
    if (args.slave.empty()) {
        if (value) return usage_error("writing an alias needs the slave");
        uint16_t n = 0;
        if (int rc = count_line(m, n); rc != kExitOk) return rc;
        int rc = kExitOk;
        for (uint16_t p = 0; p < n; ++p)
            if (int r = show_alias(m, Address::position(p), p); r != kExitOk) rc = r;
        return rc;
    }
    auto a = parse_slave_address(args.slave, args.station);
    if (!a) return usage_error("bad slave '" + args.slave + "'");
    if (int rc = check_slave_present(m, *a); rc != kExitOk) return rc;
    if (!value) return show_alias(m, *a, a->value);
    // Word 4 and the checksum over words 0-6 (word 7), as the ESC checks it at reload.
    uint8_t head[16] = {};
    if (Error e = m.sii_read(*a, 0, head); e != Error::Ok)
        return report_error(e, "reading the SII configuration area of " + slave_label(*a));
    util::put16(head + 2 * esc::sii::word::StationAlias, static_cast<uint16_t>(*value));
    const uint16_t crc = esc::sii::crc8(head, 14);
    if (Error e = m.sii_write_word(*a, esc::sii::word::StationAlias, static_cast<uint16_t>(*value));
        e != Error::Ok)
        return report_error(e, "writing SII word 4 of " + slave_label(*a));
    if (Error e =
            m.sii_write_word(*a, esc::sii::word::Checksum, static_cast<uint16_t>((head[15] << 8) | crc));
        e != Error::Ok)
        return report_error(e, "writing the SII checksum (word 7) of " + slave_label(*a));
    std::printf("alias %u written to SII word 4 (checksum 0x%02x); the slave takes it at its next power-on\n",
                static_cast<unsigned>(*value), crc);
    return kExitOk;
}

// ---- graph
// --------------------------------------------------------------------------------------------------

std::string dot_escape(const std::string& s) {
    std::string o;
    for (char c : s) {
        if (c == '"' || c == '\\') o += '\\';
        if (static_cast<unsigned char>(c) >= 0x20) o += c;
    }
    return o;
}

int run_graph(master::Master& m) {
    master::BusOptions o;
    auto scanned = master::scan_bus(m, o);
    if (!scanned) return report_error(scanned.error(), "scanning the line");
    std::vector<master::SlaveInfo>& slaves = *scanned;
    if (slaves.empty()) {
        std::fprintf(stderr, "ecatctl: no slave answered\n");
        return kExitNoSlave;
    }
    // Entry ports from DC receive times where the slaves have DC; the tree from the open ports either way.
    if (master::measure_dc(m, slaves) != Error::Ok && master::compute_dc_topology(slaves) != Error::Ok) {
        std::fprintf(stderr, "ecatctl: the open ports of the slaves do not describe a tree in their order\n");
        return kExitProtocol;
    }
    std::printf("digraph ethercat {\n  rankdir=LR;\n  node [shape=box];\n  master [label=\"master\"];\n");
    for (const auto& s : slaves) {
        std::string name;
        if (auto img = m.sii_read_image(Address::position(s.position))) {
            const esi::SiiInfo sii = esi::parse_sii(*img);
            if (sii.general) name = sii.general->name;
        }
        std::printf("  s%u [label=\"%u: %s\\n0x%04x %s\"];\n", s.position, s.position,
                    dot_escape(name.empty() ? std::string("(no name)") : name).c_str(), s.station,
                    std::string(master::al_state_name(s.al.state)).c_str());
    }
    for (const auto& s : slaves) {
        if (s.parent < 0)
            std::printf("  master -> s%u [headlabel=\"%d\"];\n", s.position, s.entry_port);
        else
            std::printf("  s%d -> s%u [taillabel=\"%d\", headlabel=\"%d\"];\n", s.parent, s.position,
                        s.parent_port, s.entry_port);
    }
    std::printf("}\n");
    return kExitOk;
}

}  // namespace

void add_line_commands(CLI::App& app, MasterRunner run, int& rc) {
    auto clear = std::make_shared<bool>(false);
    auto* crc = app.add_subcommand("crc", "The error counters (0x0300-0x0313) of every slave, per port");
    crc->add_flag("--clear", *clear, "Clear them afterwards");
    crc->callback([clear, run, &rc] { rc = run([&](master::Master& m) { return run_crc(m, *clear); }); });

    auto target = std::make_shared<std::string>();
    auto* states = app.add_subcommand(
        "states", "Every slave's AL state, or every slave taken to STATE with the set-up it needs");
    states->add_option("state", *target, "INIT|PREOP|BOOT|SAFEOP|OP (omit to show the states)");
    states->callback(
        [target, run, &rc] { rc = run([&](master::Master& m) { return run_states(m, *target); }); });

    auto alias = std::make_shared<AliasArgs>();
    auto* al = app.add_subcommand(
        "alias",
        "The configured station alias (0x0012, SII word 4) of every slave or one; a value writes it");
    al->add_option("slave", alias->slave, "Slave position (or station address with --station)");
    al->add_option("value", alias->value, "New alias (0..65535), written to SII word 4 with the checksum");
    al->add_flag("-s,--station", alias->station, "<slave> is a station address");
    al->callback([alias, run, &rc] { rc = run([&](master::Master& m) { return run_alias(m, *alias); }); });

    auto* graph = app.add_subcommand("graph", "The line or tree as Graphviz dot (dot -Tsvg)");
    graph->callback([run, &rc] { rc = run([&](master::Master& m) { return run_graph(m); }); });
}

}  // namespace ecatctl
