// ecatctl: a small EtherCAT master on the command line, in the spirit of IgH's `ethercat` tool.
//   ecatctl [--iface NAME] [--backend pcap|packet] [--timeout MS] [--retries N] <verb> ...
// Verbs: scan | reg read | reg write | sii read | sii write | sii decode | state | upload | download | sdos |
// pd
#include <CLI/CLI.hpp>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "cmd_diag.hpp"
#include "cmd_firmware.hpp"
#include "cmd_state.hpp"
#include "cmd_verbs.hpp"
#include "common.hpp"
#include "esc/link.hpp"
#include "format.hpp"
#include "master/coe.hpp"
#include "master/foe.hpp"
#include "master/mailbox.hpp"
#include "master/master.hpp"
#include "master/session.hpp"
#ifdef ECATCTL_HAVE_ESI
#include "esi/sii.hpp"
#endif

namespace {

using namespace ecatctl;
using master::Address;
using master::Error;

struct Globals {
    std::string iface = "ecat1";
    std::string backend;
    unsigned timeout_ms = 100;
    unsigned retries = 2;
};

// The AL status of the last refused state request, for fail() to report.
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

int usage(const std::string& what) {
    std::cerr << "ecatctl: " << what << "\n";
    return kExitUsage;
}

// Opens the link and runs fn with a master on it; maps link errors to exit codes.
template <typename Fn>
int with_master(const Globals& g, Fn fn) {
    std::unique_ptr<esc::Link> link;
    try {
        link = esc::open_link(g.iface, g.backend);
    } catch (const esc::LinkError& e) {
        std::cerr << "ecatctl: " << e.what() << "\n";
        switch (e.kind()) {
            case esc::LinkError::Kind::NoSuchInterface:
            case esc::LinkError::Kind::InterfaceDown:
                return kExitNoInterface;
            case esc::LinkError::Kind::PermissionDenied:
                std::cerr << "ecatctl: raw sockets need root or CAP_NET_RAW (try sudo)\n";
                return kExitNoPrivileges;
            case esc::LinkError::Kind::BadArgument:
                return kExitUsage;
            case esc::LinkError::Kind::System:
                return kExitFailure;
        }
        return kExitFailure;
    }
    master::MasterOptions o;
    o.timeout = std::chrono::milliseconds(g.timeout_ms);
    o.retries = g.retries;
    master::Master m(*link, o);
    return fn(m);
}

std::optional<Address> parse_slave(const std::string& text, bool station) {
    auto v = parse_number(text, 0xFFFF);
    if (!v) return std::nullopt;
    return station ? Address::station(static_cast<uint16_t>(*v))
                   : Address::position(static_cast<uint16_t>(*v));
}

// The slave a command names; a bad one is reported as a usage error (exit kExitUsage) and gives nullopt.
std::optional<Address> named_slave(const std::string& text, bool station) {
    auto a = parse_slave(text, station);
    if (!a) usage("bad slave '" + text + "'");
    return a;
}

std::string slave_text(Address a) {
    char b[32];
    std::snprintf(b, sizeof b, a.mode == Address::Mode::Station ? "station 0x%04x" : "slave %u", a.value);
    return b;
}

// ---- scan ----------------------------------------------------------------------------------------

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
        auto u32 = [&](int k) {
            return static_cast<unsigned>(id[4 * k] | (id[4 * k + 1] << 8) | (id[4 * k + 2] << 16) |
                                         (static_cast<unsigned>(id[4 * k + 3]) << 24));
        };
        std::string name;
#ifdef ECATCTL_HAVE_ESI
        // The device name from the SII General category (through the STRINGS category).
        if (auto img = m.sii_read_image(a)) {
            const esi::SiiInfo info = esi::parse_sii(*img);
            if (info.general) name = info.general->name;
        }
#endif
        std::printf("%-4u 0x%04x  %-10s 0x%08x 0x%08x 0x%08x 0x%08x %s\n", i, station, state.c_str(), u32(0),
                    u32(1), u32(2), u32(3), name.c_str());
    }
    return rc;
}

// ---- reg -----------------------------------------------------------------------------------------

struct RegArgs {
    std::string slave;
    std::string address;
    std::string length;
    std::vector<std::string> values;
    std::string type;
    bool station = false;
};

int reg_read(master::Master& m, const RegArgs& r) {
    auto a = named_slave(r.slave, r.station);
    if (!a) return kExitUsage;
    auto addr = parse_number(r.address, 0xFFFF);
    if (!addr) return usage("bad register address '" + r.address + "'");
    std::optional<ValueType> type;
    if (!r.type.empty() && !(type = parse_type(r.type))) return usage("bad type '" + r.type + "'");
    std::size_t len = type ? type_size(*type) : 0;
    if (!r.length.empty()) {
        auto l = parse_number(r.length, master::kMaxDatagramData);
        if (!l || *l == 0)
            return usage("bad length '" + r.length + "' (1.." + std::to_string(master::kMaxDatagramData) +
                         ")");
        len = *l;
    }
    if (len == 0) return usage("give a length or --type");
    if (type && len % type_size(*type) != 0) return usage("length is not a multiple of the type size");
    if (*addr + len > 0x10000) return usage("register range runs past 0xffff");
    std::vector<uint8_t> data(len);
    if (Error e = m.read(*a, static_cast<uint16_t>(*addr), data); e != Error::Ok)
        return fail(e, "reading " + slave_text(*a));
    if (type) {
        const std::size_t n = type_size(*type);
        for (std::size_t i = 0; i < len; i += n)
            std::printf("%s\n", format_value(*type, std::span<const uint8_t>(data).subspan(i, n)).c_str());
    } else {
        std::fputs(hex_dump(static_cast<uint32_t>(*addr), data).c_str(), stdout);
    }
    return kExitOk;
}

int reg_write(master::Master& m, const RegArgs& r) {
    auto a = named_slave(r.slave, r.station);
    if (!a) return kExitUsage;
    auto addr = parse_number(r.address, 0xFFFF);
    if (!addr) return usage("bad register address '" + r.address + "'");
    std::optional<ValueType> type;
    if (!r.type.empty() && !(type = parse_type(r.type))) return usage("bad type '" + r.type + "'");
    std::vector<uint8_t> data;
    for (const std::string& v : r.values) {
        if (type) {
            auto b = encode_value(*type, v);
            if (!b) return usage("value '" + v + "' does not fit " + r.type);
            data.insert(data.end(), b->begin(), b->end());
        } else {
            auto b = parse_number(v, 0xFF);
            if (!b) return usage("bad byte '" + v + "' (0..0xff; use --type for wider values)");
            data.push_back(static_cast<uint8_t>(*b));
        }
    }
    if (data.empty() || data.size() > master::kMaxDatagramData) return usage("nothing to write, or too much");
    if (*addr + data.size() > 0x10000) return usage("register range runs past 0xffff");
    if (Error e = m.write(*a, static_cast<uint16_t>(*addr), data); e != Error::Ok)
        return fail(e, "writing " + slave_text(*a));
    return kExitOk;
}

// ---- sii -----------------------------------------------------------------------------------------

struct SiiArgs {
    std::string slave = "0";
    bool station = false;
    std::string output;
    std::string input;
    bool all = false;
    bool force = false;
};

int sii_read(master::Master& m, const SiiArgs& s) {
    auto a = named_slave(s.slave, s.station);
    if (!a) return kExitUsage;
    auto img = m.sii_read_image(*a, s.all);
    if (!img) return fail(img.error(), "reading the SII of " + slave_text(*a));
    if (s.output.empty()) {
        std::fputs(hex_dump(0, *img).c_str(), stdout);
        return kExitOk;
    }
    if (s.output == "-") {
        std::fwrite(img->data(), 1, img->size(), stdout);
        return kExitOk;
    }
    std::ofstream f(s.output, std::ios::binary | std::ios::trunc);
    f.write(reinterpret_cast<const char*>(img->data()), static_cast<std::streamsize>(img->size()));
    if (!f) {
        std::cerr << "ecatctl: cannot write " << s.output << ": " << std::strerror(errno) << "\n";
        return kExitFailure;
    }
    std::cerr << "ecatctl: " << img->size() << " bytes written to " << s.output << "\n";
    return kExitOk;
}

std::optional<std::vector<uint8_t>> read_file(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    if (!f) return std::nullopt;
    return std::vector<uint8_t>(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

int sii_write(master::Master& m, const SiiArgs& s) {
    auto a = named_slave(s.slave, s.station);
    if (!a) return kExitUsage;
    auto img = read_file(s.input);
    if (!img) return usage("cannot read " + s.input);
    if (img->size() < 16 || img->size() % 2 != 0 || img->size() > 65536)
        return usage(s.input + ": an SII image is an even number of bytes, 16 to 65536");
    const uint16_t w7 = static_cast<uint16_t>((*img)[14] | ((*img)[15] << 8));
    const uint8_t crc = sii_crc(std::span<const uint8_t>(img->data(), 14));
    if (w7 != 0x88A4 && (w7 & 0xFF) != crc && !s.force) {
        char b[96];
        std::snprintf(b, sizeof b, "%s: checksum word 7 is 0x%04x, CRC of words 0-6 is 0x%02x (use --force)",
                      s.input.c_str(), w7, crc);
        return usage(b);
    }
    const std::size_t words = img->size() / 2;
    for (std::size_t w = 0; w < words; ++w) {
        const uint16_t v = static_cast<uint16_t>((*img)[2 * w] | ((*img)[2 * w + 1] << 8));
        if (Error e = m.sii_write_word(*a, static_cast<uint32_t>(w), v); e != Error::Ok)
            return fail(e, "writing SII word " + std::to_string(w) + " of " + slave_text(*a));
    }
    std::cerr << "ecatctl: " << words << " words written\n";
    return kExitOk;
}

// ---- CoE SDO -------------------------------------------------------------------------------------

struct SdoArgs {
    std::string slave;
    std::string index;
    std::string sub;
    std::vector<std::string> values;
    std::string type;
    bool station = false;
    bool complete = false;
};

// A slave in INIT gets its mailbox SMs from its SII and is taken to PREOP; one already in PREOP or above
// keeps the SMs it has.
Error open_mailbox(master::Master& m, master::Mailbox& mbx, Address a) {
    auto st = m.al_status(a);
    if (!st) return st.error();
    if (st->state == static_cast<uint8_t>(master::AlState::Init)) {
        if (Error e = mbx.configure_from_sii(); e != Error::Ok) return e;
        master::AlStatus final;
        const Error e = m.request_state(a, master::AlState::PreOp, &final);
        if (e == Error::AlRefused) g_refusal = final;  // fail() reports it, in one message
        return e;
    }
    return mbx.adopt_current();
}

int sdo_failed(const master::SdoClient& sdo, Error e, const std::string& what) {
    return report_sdo_failure(sdo, e, what, fail);
}

int sdo_transfer(master::Master& m, const SdoArgs& s, bool upload) {
    auto a = named_slave(s.slave, s.station);
    if (!a) return kExitUsage;
    auto index = parse_number(s.index, 0xFFFF);
    if (!index) return usage("bad index '" + s.index + "'");
    auto sub = parse_number(s.sub, 0xFF);
    if (!sub) return usage("bad subindex '" + s.sub + "'");
    const bool text = s.type == "string";
    std::optional<ValueType> type;
    if (!s.type.empty() && !text && !(type = parse_type(s.type))) return usage("bad type '" + s.type + "'");
    std::vector<uint8_t> data;
    if (!upload) {
        for (const std::string& v : s.values) {
            if (text) {
                if (!data.empty()) data.push_back(' ');
                data.insert(data.end(), v.begin(), v.end());
            } else if (type) {
                auto b = encode_value(*type, v);
                if (!b) return usage("value '" + v + "' does not fit " + s.type);
                data.insert(data.end(), b->begin(), b->end());
            } else {
                auto b = parse_number(v, 0xFF);
                if (!b) return usage("bad byte '" + v + "' (0..0xff; use --type for wider values)");
                data.push_back(static_cast<uint8_t>(*b));
            }
        }
        if (data.empty()) return usage("nothing to download");
    }
    master::Mailbox mbx(m, *a);
    if (Error e = open_mailbox(m, mbx, *a); e != Error::Ok)
        return fail(e, "opening the mailbox of " + slave_text(*a));
    master::SdoClient sdo(mbx);
    char what[64];
    std::snprintf(what, sizeof what, "%s 0x%04x:%02x", upload ? "upload of" : "download to",
                  static_cast<unsigned>(*index), static_cast<unsigned>(*sub));
    if (!upload) {
        const Error e =
            sdo.download(static_cast<uint16_t>(*index), static_cast<uint8_t>(*sub), data, s.complete);
        return e == Error::Ok ? kExitOk : sdo_failed(sdo, e, what);
    }
    std::vector<uint8_t> out(65536);
    auto n = sdo.upload(static_cast<uint16_t>(*index), static_cast<uint8_t>(*sub), out, s.complete);
    if (!n) return sdo_failed(sdo, n.error(), what);
    out.resize(*n);
    if (text) {
        std::fwrite(out.data(), 1, out.size(), stdout);
        std::fputc('\n', stdout);
    } else if (type) {
        const std::size_t size = type_size(*type);
        if (out.size() % size != 0) {
            std::fputs(hex_dump(0, out).c_str(), stdout);
            std::fprintf(stderr, "ecatctl: %zu bytes do not make whole %s values\n", out.size(),
                         s.type.c_str());
            return kExitProtocol;
        }
        for (std::size_t i = 0; i < out.size(); i += size)
            std::printf("%s\n", format_value(*type, std::span<const uint8_t>(out).subspan(i, size)).c_str());
    } else if (print_described_upload(sdo, static_cast<uint16_t>(*index), static_cast<uint8_t>(*sub),
                                      s.complete, out)) {
    } else if (out.size() == 1 || out.size() == 2 || out.size() == 4 || out.size() == 8) {
        const ValueType t = out.size() == 1   ? ValueType::U8
                            : out.size() == 2 ? ValueType::U16
                            : out.size() == 4 ? ValueType::U32
                                              : ValueType::U64;
        std::printf("%s\n", format_value(t, out).c_str());
    } else {
        std::fputs(hex_dump(0, out).c_str(), stdout);
    }
    return kExitOk;
}

// ---- process data --------------------------------------------------------------------------------

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

int process_data(master::Master& m, const PdArgs& p) {
    auto pos = parse_number(p.slave, 0xFFFF);
    if (!pos) return usage("bad slave '" + p.slave + "'");
    std::string t = p.state;
    for (auto& c : t)
        c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    if (t != "OP" && t != "SAFEOP") return usage("--state must be SAFEOP or OP");
    for (const std::string& text : p.steps)
        if (!parse_step(text)) return usage("bad --step '" + text + "' (CYCLES:BYTE,BYTE,... e.g. 50:06,00)");
    std::vector<uint8_t> out_bytes;
    for (const std::string& v : p.outputs) {
        auto b = parse_number(v, 0xFF);
        if (!b) return usage("bad output byte '" + v + "'");
        out_bytes.push_back(static_cast<uint8_t>(*b));
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
    master::Mailbox mbx(m, a);
    if (Error e = open_mailbox(m, mbx, a); e != Error::Ok) return fail(e, "opening the mailbox");
    master::SdoClient sdo(mbx);
    master::ProcessDataSession pd(m, a, sdo);
    if (Error e = pd.discover(); e != Error::Ok) return sdo_failed(sdo, e, "reading the process-data layout");
    std::vector<SyncView> pdo_config;  // names and types of the entries, for the decoded images at the end
    if (Error e = read_pdo_config(sdo, pdo_config); e != Error::Ok) pdo_config.clear();
    const auto& l = pd.layout();
    std::printf("outputs: SM2 0x%04x, %u bytes; inputs: SM3 0x%04x, %u bytes\n", l.sm2_start, l.sm2_length,
                l.sm3_start, l.sm3_length);
    master::DcConfig dc;
    dc.enable = p.dc;
    dc.cycle_ns = p.cycle_us * 1000u;
    if (Error e = pd.configure(dc); e != Error::Ok) return sdo_failed(sdo, e, "configuring process data");
    const auto period = std::chrono::microseconds(p.cycle_us);
    auto fill = [&] {
        auto o = pd.outputs();
        std::copy_n(out_bytes.begin(), std::min(out_bytes.size(), o.size()), o.begin());
    };
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
    if (t == "OP")
        if (int rc = go(master::AlState::Op, "OP"); rc != kExitOk) return rc;
    const master::CycleStats before = pd.stats();
    const std::vector<uint8_t> final_outputs = out_bytes;
    for (const std::string& text : p.steps) {
        auto step = parse_step(text);  // validated before anything was sent
        out_bytes = step->bytes;
        pd.run(step->cycles, period, fill);
    }
    if (!p.outputs.empty() || p.steps.empty()) out_bytes = final_outputs;  // else the last step's bytes stay
    pd.run(p.count, period, fill);
    const auto& s = pd.stats();
    const uint64_t cycles = s.cycles - before.cycles;
    const uint64_t ok = cycles - (s.lost - before.lost);
    const double avg =
        ok ? static_cast<double>((s.rtt_sum - before.rtt_sum).count()) / 1000.0 / static_cast<double>(ok) : 0;
    auto now = m.al_status(a);
    std::printf("state: %s%s\n", now ? std::string(master::al_state_name(now->state)).c_str() : "?",
                now && now->error ? " +ERR" : "");
    std::printf(
        "cycles %llu, lost %llu, wkc errors %llu (expected wkc %u), rtt min %.1f us, avg %.1f us, max %.1f "
        "us\n",
        static_cast<unsigned long long>(cycles), static_cast<unsigned long long>(s.lost - before.lost),
        static_cast<unsigned long long>(s.wkc_errors - before.wkc_errors), pd.expected_wkc(),
        static_cast<double>(s.rtt_min.count()) / 1000.0, avg,
        static_cast<double>(s.rtt_max.count()) / 1000.0);
    if (p.dc)
        std::printf("reference system time %llu ns\n", static_cast<unsigned long long>(pd.reference_time()));
    std::printf("inputs:\n%s", hex_dump(0, pd.inputs()).c_str());
    print_pd_entries(pdo_config, pd.outputs(), pd.inputs());
    if (!p.keep) (void)m.request_state(a, master::AlState::PreOp);
    const bool clean = s.lost == before.lost && s.wkc_errors == before.wkc_errors && now && !now->error;
    return clean ? kExitOk : kExitProtocol;
}

// ---- SDO information -----------------------------------------------------------------------------

const char* type_name(uint16_t t) {
    switch (t) {
        case 0x0001:
            return "bool";
        case 0x0002:
            return "int8";
        case 0x0003:
            return "int16";
        case 0x0004:
            return "int32";
        case 0x0005:
            return "uint8";
        case 0x0006:
            return "uint16";
        case 0x0007:
            return "uint32";
        case 0x0008:
            return "float";
        case 0x0009:
            return "string";
        case 0x000A:
            return "octet_string";
        case 0x000B:
            return "unicode_string";
        case 0x0011:
            return "double";
        case 0x0015:
            return "int64";
        case 0x001B:
            return "uint64";
        default:
            return nullptr;
    }
}

int sdos(master::Master& m, const std::string& slave, bool station, bool quiet) {
    auto a = named_slave(slave, station);
    if (!a) return kExitUsage;
    master::Mailbox mbx(m, *a);
    if (Error e = open_mailbox(m, mbx, *a); e != Error::Ok)
        return fail(e, "opening the mailbox of " + slave_text(*a));
    master::SdoClient sdo(mbx);
    auto list = sdo.od_list(1);
    if (!list) return sdo_failed(sdo, list.error(), "reading the object list");
    for (uint16_t index : *list) {
        auto od = sdo.object_description(index);
        if (!od) return sdo_failed(sdo, od.error(), "describing object " + std::to_string(index));
        std::printf("SDO 0x%04x, \"%s\"\n", index, od->name.c_str());
        if (quiet) continue;
        const unsigned last = od->object_code == 7 ? 0 : od->max_subindex;
        for (unsigned sub = 0; sub <= last; ++sub) {
            auto e = sdo.entry_description(index, static_cast<uint8_t>(sub), 0);
            if (!e) {
                if (e.error() == Error::SdoAbort) continue;  // a gap in the subindices
                return sdo_failed(sdo, e.error(), "describing an entry");
            }
            char acc[7];
            for (int st = 0; st < 3; ++st) {
                acc[2 * st] = (e->access & (1u << st)) ? 'r' : '-';
                acc[2 * st + 1] = (e->access & (8u << st)) ? 'w' : '-';
            }
            acc[6] = 0;
            const char* tn = type_name(e->data_type);
            char tb[16];
            if (!tn) {
                std::snprintf(tb, sizeof tb, "type 0x%04x", e->data_type);
                tn = tb;
            }
            std::printf("  0x%04x:%02x, %s, %s, %u bit, \"%s\"\n", index, sub, acc, tn, e->bit_length,
                        e->name.c_str());
        }
    }
    return kExitOk;
}

// ---- FoE -----------------------------------------------------------------------------------------

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
    if (!password) return usage("bad password '" + f.password + "'");
    std::vector<uint8_t> data;
    std::string name = f.name;
    if (!read) {
        auto d = read_file(f.file);
        if (!d) return usage("cannot read " + f.file);
        data = std::move(*d);
        // The device takes firmware under its device name (0x1008, the SII General name) or the firmware
        // file name built from it; the local file's name means nothing to it.
        if (name.empty()) {
            auto device = sii_device_name(m, *a);
            if (!device)
                return usage(foe_names_hint(slave_text(*a) + " has no device name in its SII: give --name"));
            name = *device;
        }
    }
    if (name.empty()) return usage("give the file name on the slave");
    master::Mailbox mbx(m, *a);
    auto st = m.al_status(*a);
    if (!st) return fail(st.error(), "reading the AL status of " + slave_text(*a));
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
        return fail(e, "opening the mailbox of " + slave_text(*a));
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

int main(int argc, char** argv) {
    Globals g;
    CLI::App app{
        "A small EtherCAT master for the command line.\n"
        "Exit codes: 0 ok, 1 failure, 2 usage, 3 interface missing or down, 4 no privileges,\n"
        "5 no slave answered, 6 unexpected answer (working counter, SII, AL state)",
        "ecatctl"};
    app.require_subcommand(1);
    app.set_version_flag("--version", "ecatctl " ECATCTL_VERSION);
    app.add_option("-i,--iface", g.iface, "Network interface (the master end of the slave's veth pair)")
        ->envname("ECATCTL_IFACE")
        ->capture_default_str();
    app.add_option("-b,--backend", g.backend, "Link backend: pcap or packet (default: the link library's)")
        ->check(CLI::IsMember({"pcap", "packet"}));
    app.add_option("-t,--timeout", g.timeout_ms, "Reply timeout per frame in milliseconds")
        ->check(CLI::Range(1u, 60000u))
        ->capture_default_str();
    app.add_option("--retries", g.retries, "Extra attempts after a lost frame")
        ->check(CLI::Range(0u, 100u))
        ->capture_default_str();

    int rc = kExitOk;
    auto* scan_cmd = app.add_subcommand(
        "scan", "Count the slaves, assign station addresses 0x1001.., list identity and AL state");
    scan_cmd->callback([&] { rc = with_master(g, [](master::Master& m) { return scan(m); }); });

    RegArgs r;
    auto* reg = app.add_subcommand("reg", "Read or write ESC registers and memory")->require_subcommand(1);
    auto* reg_rd = reg->add_subcommand("read", "Read <len> bytes (hex dump) or values of --type");
    reg_rd->add_option("slave", r.slave, "Slave position (or station address with --station)")->required();
    reg_rd->add_option("address", r.address, "Register address")->required();
    reg_rd->add_option("length", r.length, "Bytes to read (default: the size of --type)");
    reg_rd->add_option("--type", r.type, "u8|u16|u32|u64|i8|i16|i32|i64");
    reg_rd->add_flag("-s,--station", r.station, "<slave> is a configured station address (FPRD)");
    reg_rd->callback([&] { rc = with_master(g, [&](master::Master& m) { return reg_read(m, r); }); });
    auto* reg_wr = reg->add_subcommand("write", "Write bytes (or values of --type)");
    reg_wr->add_option("slave", r.slave, "Slave position (or station address with --station)")->required();
    reg_wr->add_option("address", r.address, "Register address")->required();
    reg_wr->add_option("values", r.values, "Bytes, or values of --type")->required();
    reg_wr->add_option("--type", r.type, "u8|u16|u32|u64|i8|i16|i32|i64");
    reg_wr->add_flag("-s,--station", r.station, "<slave> is a configured station address (FPWR)");
    reg_wr->callback([&] { rc = with_master(g, [&](master::Master& m) { return reg_write(m, r); }); });

    SiiArgs s;
    auto* sii = app.add_subcommand("sii", "SII EEPROM")->require_subcommand(1);
    auto* sii_rd = sii->add_subcommand("read", "Read the image (header and categories up to the end marker)");
    sii_rd->add_option("-p,--position", s.slave, "Slave position (or station address with --station)")
        ->capture_default_str();
    sii_rd->add_flag("-s,--station", s.station, "--position is a station address");
    sii_rd->add_option("-o,--output", s.output,
                       "Write the raw image to this file ('-': stdout); default: hex dump");
    sii_rd->add_flag("-a,--all", s.all,
                     "Read the whole EEPROM size from word 0x3E, not only up to the end marker");
    sii_rd->callback([&] { rc = with_master(g, [&](master::Master& m) { return sii_read(m, s); }); });
    auto* sii_wr = sii->add_subcommand("write", "Write an image file word by word");
    sii_wr->add_option("file", s.input, "Binary image")->required()->check(CLI::ExistingFile);
    sii_wr->add_option("-p,--position", s.slave, "Slave position (or station address with --station)")
        ->capture_default_str();
    sii_wr->add_flag("-s,--station", s.station, "--position is a station address");
    sii_wr->add_flag("-f,--force", s.force, "Write even if the checksum in word 7 is wrong");
    sii_wr->callback([&] { rc = with_master(g, [&](master::Master& m) { return sii_write(m, s); }); });
#ifdef ECATCTL_HAVE_ESI
    auto* sii_dec =
        sii->add_subcommand("decode", "Print the content of an image file, or of the slave's SII");
    sii_dec->add_option("file", s.input, "Binary image (default: read it from the slave)");
    sii_dec->add_option("-p,--position", s.slave, "Slave position (or station address with --station)")
        ->capture_default_str();
    sii_dec->add_flag("-s,--station", s.station, "--position is a station address");
    sii_dec->callback([&] {
        if (!s.input.empty()) {
            auto img = read_file(s.input);
            if (!img) {
                rc = usage("cannot read " + s.input);
                return;
            }
            std::fputs(esi::decode_sii(*img).c_str(), stdout);
            rc = sii_problems(s.input, *img) ? kExitUsage : kExitOk;  // an empty or corrupt file
            return;
        }
        rc = with_master(g, [&](master::Master& m) {
            auto a = named_slave(s.slave, s.station);
            if (!a) return kExitUsage;
            auto img = m.sii_read_image(*a);
            if (!img) return fail(img.error(), "reading the SII of " + slave_text(*a));
            std::fputs(esi::decode_sii(*img).c_str(), stdout);
            return sii_problems("the SII of " + slave_text(*a), *img) ? kExitProtocol : kExitOk;
        });
    });
#endif

    add_state_command(
        app, [&](const auto& fn) { return with_master(g, fn); }, rc);

    SdoArgs so;
    auto* up =
        app.add_subcommand("upload", "Read an object through CoE SDO (INIT slaves are taken to PREOP)");
    up->add_option("slave", so.slave, "Slave position (or station address with --station)")->required();
    up->add_option("index", so.index, "Object index")->required();
    up->add_option("subindex", so.sub, "Subindex")->required();
    up->add_option("--type", so.type,
                   "u8|u16|u32|u64|i8|i16|i32|i64|real32|real64|string (default: from SDO information)");
    up->add_flag("-s,--station", so.station, "<slave> is a station address");
    up->add_flag("-c,--complete", so.complete, "Complete access (whole object from the subindex, 0 or 1)");
    up->callback([&] { rc = with_master(g, [&](master::Master& m) { return sdo_transfer(m, so, true); }); });
    auto* down =
        app.add_subcommand("download", "Write an object through CoE SDO (INIT slaves are taken to PREOP)");
    down->add_option("slave", so.slave, "Slave position (or station address with --station)")->required();
    down->add_option("index", so.index, "Object index")->required();
    down->add_option("subindex", so.sub, "Subindex")->required();
    down->add_option("values", so.values, "Bytes, values of --type, or text with --type string")->required();
    down->add_option("--type", so.type, "u8|u16|u32|u64|i8|i16|i32|i64|real32|real64|string");
    down->add_flag("-s,--station", so.station, "<slave> is a station address");
    down->add_flag("-c,--complete", so.complete, "Complete access");
    down->callback(
        [&] { rc = with_master(g, [&](master::Master& m) { return sdo_transfer(m, so, false); }); });

    PdArgs pa;
    auto* pdc = app.add_subcommand(
        "pd", "Bring a slave to OP and exchange process data cyclically (LRW), with optional DC");
    pdc->add_option("slave", pa.slave, "Slave position (or station address with --station)")
        ->capture_default_str();
    pdc->add_flag("-s,--station", pa.station, "<slave> is a station address (scan assigns 0x1001..)");
    pdc->add_option("--cycle-us", pa.cycle_us, "Cycle time in microseconds")
        ->check(CLI::Range(50u, 1000000u))
        ->capture_default_str();
    pdc->add_option("-n,--count", pa.count, "Cycles to run once the state is reached")->capture_default_str();
    pdc->add_flag("--dc", pa.dc, "Distributed clocks: SYNC0 at the cycle time, sync mode DC SYNC0");
    pdc->add_option("--state", pa.state, "SAFEOP or OP")->capture_default_str();
    pdc->add_option("--outputs", pa.outputs, "Output bytes sent every cycle (from the first byte)");
    pdc->add_option("--step", pa.steps,
                    "CYCLES:BYTES before the --count cycles, in order; bytes in hex, comma-separated "
                    "(e.g. --step 50:06,00 --step 50:0f,00)");
    pdc->add_flag("--keep", pa.keep, "Leave the slave in the state reached (default: back to PREOP)");
    pdc->callback([&] { rc = with_master(g, [&](master::Master& m) { return process_data(m, pa); }); });

    std::string sd_slave = "0";
    bool sd_station = false, sd_quiet = false;
    auto* sd = app.add_subcommand("sdos", "List the object dictionary through the SDO information service");
    sd->add_option("slave", sd_slave, "Slave position (or station address with --station)")
        ->capture_default_str();
    sd->add_flag("-s,--station", sd_station, "<slave> is a station address");
    sd->add_flag("-q,--quiet", sd_quiet, "Objects only, no entries");
    sd->callback([&] {
        rc = with_master(g, [&](master::Master& m) { return sdos(m, sd_slave, sd_station, sd_quiet); });
    });

    FoeArgs fa;
    auto* foe = app.add_subcommand("foe", "File access over EtherCAT")->require_subcommand(1);
    auto* foe_rd = foe->add_subcommand("read", "Read a file from the slave (hex dump, or -o FILE)");
    foe_rd->add_option("name", fa.name, "File name on the slave")->required();
    foe_rd->add_option("-o,--output", fa.output, "Write the file here ('-': standard output)");
    foe_rd->add_option("-p,--position", fa.slave, "Slave position (or station address with --station)")
        ->capture_default_str();
    foe_rd->add_flag("-s,--station", fa.station, "--position is a station address");
    foe_rd->add_option("--password", fa.password, "FoE password")->capture_default_str();
    foe_rd->callback(
        [&] { rc = with_master(g, [&](master::Master& m) { return foe_transfer(m, fa, true); }); });
    auto* foe_wr = foe->add_subcommand("write", "Write a file (firmware) through BOOT, then back to INIT");
    foe_wr->add_option("file", fa.file, "Local file")->required()->check(CLI::ExistingFile);
    foe_wr->add_option("-n,--name", fa.name,
                       "File name on the slave (default: the device name from its SII)");
    foe_wr->add_option("-p,--position", fa.slave, "Slave position (or station address with --station)")
        ->capture_default_str();
    foe_wr->add_flag("-s,--station", fa.station, "--position is a station address");
    foe_wr->add_option("--password", fa.password, "FoE password")->capture_default_str();
    foe_wr->add_flag("--stay", fa.stay, "Stay in BOOT afterwards");
    foe_wr->add_flag("--progress", fa.progress, "Show progress also when stderr is not a terminal");
    foe_wr->callback(
        [&] { rc = with_master(g, [&](master::Master& m) { return foe_transfer(m, fa, false); }); });

    add_diag_command(
        app, [&](const auto& fn) { return with_master(g, fn); }, rc);

    add_firmware_update(
        app, [&](const auto& fn) { return with_master(g, fn); }, rc);

#ifdef ECATCTL_HAVE_ESI
    add_slaves_command(
        app, [&](const auto& fn) { return with_master(g, fn); }, rc);
    add_pdos_command(
        app, [&](const auto& fn) { return with_master(g, fn); }, rc);
    add_cstruct_command(
        app, [&](const auto& fn) { return with_master(g, fn); }, rc);
    add_xml_command(
        app, [&](const auto& fn) { return with_master(g, fn); }, rc);
#endif

    // `-p N` names the slave in every verb, also in those that take it as their first argument.
    std::vector<std::string> args = position_option_as_argument(argc, argv);
    std::vector<char*> argp;
    for (std::string& a : args)
        argp.push_back(a.data());
    argc = static_cast<int>(argp.size());
    argp.push_back(nullptr);
    argv = argp.data();
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        return report_usage_error(app, e, argc, argv);  // one line, exit 2
    }
    return rc;
}
