// `ecatctl reg read|write`: ESC registers and memory.
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

struct RegArgs {
    std::string slave;
    std::string address;
    std::string length;
    std::vector<std::string> values;
    std::string type;
    bool station = false;
};

// The slave, the register address and the --type of a reg command.
struct RegTarget {
    master::Address slave;
    uint64_t address = 0;
    std::optional<ValueType> type;
};

// Fills t from r: kExitOk, or the exit code of the usage error it reported.
int reg_target(const RegArgs& r, RegTarget& t) {
    auto a = named_slave(r.slave, r.station);
    if (!a) return kExitUsage;
    auto addr = parse_number(r.address, 0xFFFF);
    if (!addr) return usage_error("bad register address '" + r.address + "'");
    if (!r.type.empty() && !(t.type = parse_type(r.type))) return usage_error("bad type '" + r.type + "'");
    t.slave = *a;
    t.address = *addr;
    return kExitOk;
}

int reg_read(master::Master& m, const RegArgs& r) {
    RegTarget t;
    if (int rc = reg_target(r, t); rc != kExitOk) return rc;
    std::size_t len = t.type ? type_size(*t.type) : 0;
    if (!r.length.empty()) {
        auto l = parse_number(r.length, master::kMaxDatagramData);
        if (!l || *l == 0)
            return usage_error("bad length '" + r.length + "' (1.." +
                               std::to_string(master::kMaxDatagramData) + ")");
        len = *l;
    }
    if (len == 0) return usage_error("give a length or --type");
    if (t.type && len % type_size(*t.type) != 0)
        return usage_error("length is not a multiple of the type size");
    if (t.address + len > 0x10000) return usage_error("register range runs past 0xffff");
    std::vector<uint8_t> data(len);
    if (Error e = m.read(t.slave, static_cast<uint16_t>(t.address), data); e != Error::Ok)
        return fail(e, "reading " + slave_label(t.slave));
    if (t.type) {
        const std::size_t n = type_size(*t.type);
        for (std::size_t i = 0; i < len; i += n)
            std::printf("%s\n", format_value(*t.type, std::span<const uint8_t>(data).subspan(i, n)).c_str());
    } else {
        std::fputs(hex_dump(static_cast<uint32_t>(t.address), data).c_str(), stdout);
    }
    return kExitOk;
}

int reg_write(master::Master& m, const RegArgs& r) {
    RegTarget t;
    if (int rc = reg_target(r, t); rc != kExitOk) return rc;
    std::vector<uint8_t> data;
    for (const std::string& v : r.values) {
        if (t.type) {
            auto b = encode_value(*t.type, v);
            if (!b) return usage_error("value '" + v + "' does not fit " + r.type);
            data.insert(data.end(), b->begin(), b->end());
        } else {
            auto b = parse_number(v, 0xFF);
            if (!b) return usage_error("bad byte '" + v + "' (0..0xff; use --type for wider values)");
            data.push_back(static_cast<uint8_t>(*b));
        }
    }
    if (data.empty() || data.size() > master::kMaxDatagramData)
        return usage_error("nothing to write, or too much");
    if (t.address + data.size() > 0x10000) return usage_error("register range runs past 0xffff");
    if (Error e = m.write(t.slave, static_cast<uint16_t>(t.address), data); e != Error::Ok)
        return fail(e, "writing " + slave_label(t.slave));
    return kExitOk;
}

}  // namespace

void add_reg_command(CLI::App& app, MasterRunner run, int& rc) {
    auto r = std::make_shared<RegArgs>();
    auto* reg = app.add_subcommand("reg", "Read or write ESC registers and memory")->require_subcommand(1);
    auto* reg_rd = reg->add_subcommand("read", "Read <len> bytes (hex dump) or values of --type");
    reg_rd->add_option("slave", r->slave, "Slave position (or station address with --station)")->required();
    reg_rd->add_option("address", r->address, "Register address")->required();
    reg_rd->add_option("length", r->length, "Bytes to read (default: the size of --type)");
    reg_rd->add_option("--type", r->type, "u8|u16|u32|u64|i8|i16|i32|i64");
    reg_rd->add_flag("-s,--station", r->station, "<slave> is a configured station address (FPRD)");
    reg_rd->callback([r, run, &rc] { rc = run([&](master::Master& m) { return reg_read(m, *r); }); });
    auto* reg_wr = reg->add_subcommand("write", "Write bytes (or values of --type)");
    reg_wr->add_option("slave", r->slave, "Slave position (or station address with --station)")->required();
    reg_wr->add_option("address", r->address, "Register address")->required();
    reg_wr->add_option("values", r->values, "Bytes, or values of --type")->required();
    reg_wr->add_option("--type", r->type, "u8|u16|u32|u64|i8|i16|i32|i64");
    reg_wr->add_flag("-s,--station", r->station, "<slave> is a configured station address (FPWR)");
    reg_wr->callback([r, run, &rc] { rc = run([&](master::Master& m) { return reg_write(m, *r); }); });
}

}  // namespace ecatctl
