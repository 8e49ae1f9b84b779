// ecatctl slaves [slave] [-v]: one line per slave (position, station address, alias, AL state, name), as
// IgH's `ethercat slaves`; with -v everything SOEM's `slaveinfo` shows: identity, ESC type and sizes, the
// process data sizes of the default PDO assignment (SII), ports and their link state, DC support and delays,
// the SM and FMMU registers, the mailboxes, mailbox protocols and CoE/FoE/EoE details (SII General category).
// Register reads only (position addressing): nothing on the slave is changed.
#include <cstdio>
#include <iostream>
#include <string>

#include "cmd_verbs.hpp"
#include "esi/sii_reader.hpp"
#include "format.hpp"
#include "util/json.hpp"
#include "util/le.hpp"

namespace ecatctl {

namespace {

using master::Address;
using master::Error;

struct SlavesArgs {
    std::string slave;  // empty: all
    bool station = false;
    bool verbose = false;
    bool json = false;
};

std::string protocols_text(uint16_t p) {
    static const std::pair<uint16_t, const char*> kNames[] = {{0x01, "AoE"}, {0x02, "EoE"}, {0x04, "CoE"},
                                                              {0x08, "FoE"}, {0x10, "SoE"}, {0x20, "VoE"}};
    std::string s;
    for (auto [bit, name] : kNames)
        if (p & bit) s += std::string(s.empty() ? "" : " ") + name;
    return s.empty() ? "none" : s;
}

std::string coe_details_text(uint8_t d) {
    static const std::pair<uint8_t, const char*> kNames[] = {{0x01, "SDO"},
                                                             {0x02, "SDO information"},
                                                             {0x04, "PDO assign"},
                                                             {0x08, "PDO configuration"},
                                                             {0x10, "upload at startup"},
                                                             {0x20, "SDO complete access"}};
    std::string s;
    for (auto [bit, name] : kNames)
        if (d & bit) s += std::string(s.empty() ? "" : ", ") + name;
    return s.empty() ? "none" : s;
}

unsigned default_pdo_bits(const std::vector<esi::SiiPdo>& pdos) {
    unsigned n = 0;
    for (const auto& p : pdos)
        if (p.sm != 0xFF)
            for (const auto& e : p.entries)
                n += e.bit_length;
    return n;
}

int show_slave(master::Master& m, uint16_t pos, bool verbose, util::JsonWriter* json) {
    const Address a = Address::position(pos);
    uint8_t info[10] = {};
    if (Error e = m.read(a, esc::reg::kType, info); e != Error::Ok)
        return report_error(nullptr, e, "reading slave " + std::to_string(pos));
    uint8_t addr[4] = {};
    (void)m.read(a, esc::reg::kStationAddress, addr);
    auto st = m.al_status(a);
    std::string state = st ? std::string(master::al_state_name(st->state)) + (st->error ? "+ERR" : "") : "?";
    esi::SiiInfo sii;
    bool have_sii = false;
    if (auto img = m.sii_read_image(a)) {
        sii = esi::parse_sii(*img);
        have_sii = true;
    }
    const std::string name = sii.general ? sii.general->name : std::string();
    if (json) {
        // docs/ecatctl-json.md, "slaves".
        json->begin_object()
            .member("position", pos)
            .member("station", util::get16(addr))
            .member("alias", util::get16(addr + 2));
        if (st)
            json->member("state", master::al_state_name(st->state))
                .member("al_error", st->error)
                .member("al_status_code", st->code);
        json->member("name", name);
        if (have_sii)
            json->member("vendor_id", sii.vendor_id)
                .member("product_code", sii.product_code)
                .member("revision", sii.revision)
                .member("serial", sii.serial_number)
                .member("output_bits", default_pdo_bits(sii.rx_pdos))
                .member("input_bits", default_pdo_bits(sii.tx_pdos));
        json->end_object();
        return kExitOk;
    }
    if (!verbose) {
        std::printf("%-3u 0x%04x %5u:%-3u %-8s %s\n", pos, util::get16(addr), util::get16(addr + 2), pos,
                    state.c_str(), name.c_str());
        return kExitOk;
    }
    std::printf("Slave %u: %s\n", pos, name.empty() ? "(no name in the SII)" : name.c_str());
    std::printf("  Station address 0x%04x, alias %u\n", util::get16(addr), util::get16(addr + 2));
    if (st)
        std::printf("  State %s, AL status code 0x%04x (%s)\n", state.c_str(), st->code,
                    std::string(master::al_status_code_name(st->code)).c_str());
    if (have_sii) {
        std::printf("  Vendor 0x%08x, product 0x%08x, revision 0x%08x, serial 0x%08x\n", sii.vendor_id,
                    sii.product_code, sii.revision, sii.serial_number);
        const unsigned out_bits = default_pdo_bits(sii.rx_pdos), in_bits = default_pdo_bits(sii.tx_pdos);
        std::printf("  Output size: %u bits (%u bytes), input size: %u bits (%u bytes) (default PDOs, SII)\n",
                    out_bits, (out_bits + 7) / 8, in_bits, (in_bits + 7) / 8);
    }
    const uint16_t features = util::get16(info + 8);
    std::printf(
        "  ESC type 0x%02x, revision %u, build %u; %u FMMUs, %u SMs, %u KiB process RAM, features 0x%04x\n",
        info[0], info[1], util::get16(info + 2), info[4], info[5], info[6], features);
    // Ports: descriptor 0x0007 (2 bits each), DL status 0x0110 (link bits 4..7, communication bits
    // 9,11,13,15).
    uint8_t dl[2] = {};
    (void)m.read(a, esc::reg::kDlStatus, dl);
    const uint16_t dls = util::get16(dl);
    std::printf("  Ports:");
    unsigned active = 0;
    for (unsigned p = 0; p < 4; ++p) {
        static const char* const kKind[] = {"-", "not configured", "EBUS", "MII"};
        const unsigned kind = (info[7] >> (2 * p)) & 3u;
        const bool link = (dls >> (4 + p)) & 1u;
        const bool comm = (dls >> (9 + 2 * p)) & 1u;
        if (comm) ++active;
        std::printf(" %u:%s%s%s", p, kKind[kind], link ? "+link" : "", comm ? "+comm" : "");
    }
    std::printf(" (%u active)\n", active);
    // DC: features bit 2 (DC), bit 3 (64-bit system time); receive times latched by a write to 0x0900.
    if (features & 0x0004) {
        uint8_t latch[4] = {};
        (void)m.broadcast_write(esc::reg::kDcRecvTime0, latch);
        uint8_t rt[16] = {}, delay[4] = {}, offset[8] = {};
        (void)m.read(a, esc::reg::kDcRecvTime0, rt);
        (void)m.read(a, esc::reg::kDcDelay, delay);
        (void)m.read(a, esc::reg::kDcOffset, offset);
        std::printf("  DC: yes, %s system time; system time delay %u ns, offset %lld ns\n",
                    (features & 0x0008) ? "64-bit" : "32-bit", util::get32(delay),
                    static_cast<long long>(static_cast<uint64_t>(util::get32(offset)) |
                                           (static_cast<uint64_t>(util::get32(offset + 4)) << 32)));
        std::printf("  DC receive times: port 0 %u, port 1 %u, port 2 %u, port 3 %u ns\n", util::get32(rt),
                    util::get32(rt + 4), util::get32(rt + 8), util::get32(rt + 12));
    } else {
        std::printf("  DC: no\n");
    }
    for (unsigned i = 0; i < info[5] && i < 16; ++i) {
        uint8_t sm[8] = {};
        if (m.read(a, static_cast<uint16_t>(esc::reg::kSm + 8 * i), sm) != Error::Ok) break;
        const uint8_t type = i < sii.sync_managers.size() ? sii.sync_managers[i].type : 0;
        std::printf("  SM%u A:%04x L:%4u F:%08x Type:%u\n", i, util::get16(sm), util::get16(sm + 2),
                    util::get32(sm + 4), type);
    }
    for (unsigned i = 0; i < info[4] && i < 16; ++i) {
        uint8_t f[16] = {};
        if (m.read(a, static_cast<uint16_t>(esc::reg::kFmmu + 16 * i), f) != Error::Ok) break;
        std::printf("  FMMU%u Ls:%08x Ll:%4u Lsb:%u Leb:%u Ps:%04x Psb:%u Ty:%02x Act:%02x\n", i,
                    util::get32(f), util::get16(f + 4), f[6], f[7], util::get16(f + 8), f[10], f[11], f[12]);
    }
    if (have_sii) {
        const auto& mb = sii.standard_mailbox;
        const auto& bb = sii.bootstrap_mailbox;
        std::printf(
            "  Mailbox: out 0x%04x %u bytes, in 0x%04x %u bytes; bootstrap out 0x%04x %u, in 0x%04x %u\n",
            mb.out_start, mb.out_size, mb.in_start, mb.in_size, bb.out_start, bb.out_size, bb.in_start,
            bb.in_size);
        std::printf("  Mailbox protocols: %s (0x%04x)\n", protocols_text(sii.mailbox_protocols).c_str(),
                    sii.mailbox_protocols);
        if (sii.general) {
            const auto& g = *sii.general;
            std::printf("  CoE details: %s (0x%02x)\n", coe_details_text(g.coe_details).c_str(),
                        g.coe_details);
            std::printf("  FoE details: 0x%02x, EoE details: 0x%02x, SoE channels: %u, DS402 channels: %u\n",
                        g.foe_details, g.eoe_details, g.soe_channels, g.ds402_channels);
            std::printf("  Group \"%s\", order \"%s\", E-bus current %d mA\n", g.group.c_str(),
                        g.order.c_str(), g.ebus_current_ma);
        }
        std::printf("  SII: %zu bytes used, EEPROM %zu bytes, checksum %s\n", sii.image_bytes,
                    sii.eeprom_bytes(), sii.crc_ok ? "ok" : "WRONG");
    }
    return kExitOk;
}

int run_slaves(master::Master& m, const SlavesArgs& s) {
    auto n = m.count_slaves();
    if (!n) return report_error(nullptr, n.error(), "counting slaves (BRD 0x0000)");
    if (*n == 0) {
        std::fprintf(stderr, "ecatctl: no slave answered\n");
        return kExitNoSlave;
    }
    uint16_t first = 0, last = static_cast<uint16_t>(*n - 1);
    if (!s.slave.empty() && s.station) {
        // The slave whose configured station address (0x0010) is the one given.
        auto want = parse_number(s.slave, 0xFFFF);
        if (!want) {
            std::fprintf(stderr, "ecatctl: bad station address '%s'\n", s.slave.c_str());
            return kExitUsage;
        }
        for (uint16_t p = 0; p < *n; ++p) {
            auto st = m.read_reg<uint16_t>(Address::position(p), 0x0010);
            if (st && *st == *want) {
                if (!s.json) return show_slave(m, p, s.verbose, nullptr);
                util::JsonWriter w(std::cout);
                w.begin_object().key("slaves").begin_array();
                const int rc = show_slave(m, p, false, &w);
                w.end_array().end_object();
                std::cout << std::flush;
                return rc;
            }
        }
        std::fprintf(stderr, "ecatctl: no slave has station address %s\n", s.slave.c_str());
        return kExitNoSlave;
    }
    if (!s.slave.empty()) {
        auto p = parse_number(s.slave, 0xFFFF);
        if (!p) {
            std::fprintf(stderr, "ecatctl: bad slave '%s'\n", s.slave.c_str());
            return kExitUsage;
        }
        if (*p >= *n) {
            std::fprintf(stderr, "ecatctl: no slave %s (%u on the line)\n", s.slave.c_str(), *n);
            return kExitNoSlave;
        }
        first = last = static_cast<uint16_t>(*p);
    }
    int rc = kExitOk;
    if (s.json) {
        util::JsonWriter w(std::cout);
        w.begin_object().key("slaves").begin_array();
        for (uint16_t p = first; p <= last; ++p)
            if (int r = show_slave(m, p, false, &w); r != kExitOk) rc = r;
        w.end_array().end_object();
        std::cout << std::flush;
        return rc;
    }
    for (uint16_t p = first; p <= last; ++p) {
        if (int r = show_slave(m, p, s.verbose, nullptr); r != kExitOk) rc = r;
        if (s.verbose && p != last) std::printf("\n");
    }
    return rc;
}

}  // namespace

void add_slaves_command(CLI::App& app, MasterRunner run, int& rc) {
    auto s = std::make_shared<SlavesArgs>();
    auto* c = app.add_subcommand("slaves",
                                 "List the slaves (IgH `ethercat slaves`); -v: all SOEM `slaveinfo` shows");
    c->add_option("slave", s->slave, "Only the slave at this position (or station address with --station)");
    c->add_flag("-s,--station", s->station, "<slave> is a station address");
    c->add_flag("-v,--verbose", s->verbose,
                "Identity, sizes, ports, DC, SMs, FMMUs, mailbox, protocols, CoE details");
    c->add_flag("--json", s->json, "JSON on stdout: position, station, alias, state, name, identity, sizes");
    c->callback(
        [s, run = std::move(run), &rc] { rc = run([&](master::Master& m) { return run_slaves(m, *s); }); });
}

}  // namespace ecatctl
