// `ecatctl upload|download`: one object through CoE SDO (INIT slaves are taken to PREOP).
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

#include "cmd_verbs.hpp"
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

struct SdoArgs {
    std::string slave;
    std::string index;
    std::string sub;
    std::vector<std::string> values;
    std::string type;
    bool station = false;
    bool complete = false;
    bool json = false;
};

// The CoE basic data type of a --type.
uint16_t coe_type_of(ValueType t) {
    switch (t) {
        case ValueType::U8:
            return dtype::Unsigned8;
        case ValueType::U16:
            return dtype::Unsigned16;
        case ValueType::U32:
            return dtype::Unsigned32;
        case ValueType::U64:
            return dtype::Unsigned64;
        case ValueType::I8:
            return dtype::Integer8;
        case ValueType::I16:
            return dtype::Integer16;
        case ValueType::I32:
            return dtype::Integer32;
        case ValueType::I64:
            return dtype::Integer64;
        case ValueType::F32:
            return dtype::Real32;
        case ValueType::F64:
            return dtype::Real64;
    }
    return 0;
}

int sdo_transfer(master::Master& m, const SdoArgs& s, bool upload) {
    auto a = named_slave(s.slave, s.station);
    if (!a) return kExitUsage;
    auto index = parse_number(s.index, 0xFFFF);
    if (!index) return usage_error("bad index '" + s.index + "'");
    auto sub = parse_number(s.sub, 0xFF);
    if (!sub) return usage_error("bad subindex '" + s.sub + "'");
    bool text = s.type == "string";
    std::optional<ValueType> type;
    if (!s.type.empty() && !text && !(type = parse_type(s.type)))
        return usage_error("bad type '" + s.type + "'");
    if (!upload && s.values.empty()) return usage_error("nothing to download");
    // Without --type the values are bytes, unless SDO information names the entry's type (as upload does).
    auto encode = [&](std::vector<uint8_t>& data, std::string& why) {
        for (const std::string& v : s.values) {
            if (text) {
                if (!data.empty()) data.push_back(' ');
                data.insert(data.end(), v.begin(), v.end());
            } else if (type) {
                auto b = encode_value(*type, v);
                if (!b) return why = "value '" + v + "' does not fit its type", false;
                data.insert(data.end(), b->begin(), b->end());
            } else {
                auto b = parse_number(v, 0xFF);
                if (!b) return why = "bad byte '" + v + "' (0..0xff; use --type for wider values)", false;
                data.push_back(static_cast<uint8_t>(*b));
            }
        }
        return true;
    };
    std::vector<uint8_t> data;
    std::string why;
    // With --type, the values are checked before anything is sent.
    if (!upload && (type || text) && !encode(data, why)) return usage_error(why);
    master::Mailbox mbx(m, *a);
    if (Error e = open_mailbox(m, mbx, *a); e != Error::Ok)
        return fail(e, "opening the mailbox of " + slave_label(*a));
    master::SdoClient sdo(mbx);
    if (!upload && !type && !text) {
        if (!s.complete)
            if (auto d =
                    sdo.entry_description(static_cast<uint16_t>(*index), static_cast<uint8_t>(*sub), 0)) {
                text = d->data_type == 0x0009;
                type = value_type_of(d->data_type);
            }
        if (!encode(data, why)) return usage_error(why);
    }
    const std::string what = util::strprintf("%s 0x%04x:%02x", upload ? "upload of" : "download to",
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
    if (s.json) {
        // docs/ecatctl-json.md, "upload".
        util::JsonWriter w(std::cout);
        std::string hex;
        for (uint8_t b : out)
            hex += util::strprintf(hex.empty() ? "%02x" : " %02x", b);
        w.begin_object()
            .member("index", *index)
            .member("subindex", *sub)
            .member("complete_access", s.complete)
            .member("size", out.size())
            .member("bytes", hex);
        if (text) {
            w.key("value").value(std::string(out.begin(), out.end()));
        } else if (type) {
            const std::size_t size = type_size(*type);
            w.key("values").begin_array();
            for (std::size_t i = 0; i + size <= out.size(); i += size) {
                const auto part = std::span<const uint8_t>(out).subspan(i, size);
                write_typed_json(w, coe_type_of(*type), static_cast<uint16_t>(size * 8), part);
            }
            w.end_array();
        } else {
            write_described_upload_json(w, sdo, static_cast<uint16_t>(*index), static_cast<uint8_t>(*sub),
                                        s.complete, out);
        }
        w.end_object();
        std::cout << std::flush;
        return kExitOk;
    }
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

}  // namespace

void add_sdo_commands(CLI::App& app, MasterRunner run, int& rc) {
    auto so = std::make_shared<SdoArgs>();
    auto* up =
        app.add_subcommand("upload", "Read an object through CoE SDO (INIT slaves are taken to PREOP)");
    up->add_option("slave", so->slave, "Slave position (or station address with --station)")->required();
    up->add_option("index", so->index, "Object index")->required();
    up->add_option("subindex", so->sub, "Subindex")->required();
    up->add_option("--type", so->type,
                   "u8|u16|u32|u64|i8|i16|i32|i64|real32|real64|string (default: from SDO information)");
    up->add_flag("-s,--station", so->station, "<slave> is a station address");
    up->add_flag("-c,--complete", so->complete, "Complete access (whole object from the subindex, 0 or 1)");
    up->add_flag("--json", so->json, "JSON on stdout: bytes and the value(s) by type (docs/ecatctl-json.md)");
    up->callback([so, run, &rc] { rc = run([&](master::Master& m) { return sdo_transfer(m, *so, true); }); });
    auto* down =
        app.add_subcommand("download", "Write an object through CoE SDO (INIT slaves are taken to PREOP)");
    down->add_option("slave", so->slave, "Slave position (or station address with --station)")->required();
    down->add_option("index", so->index, "Object index")->required();
    down->add_option("subindex", so->sub, "Subindex")->required();
    down->add_option("values", so->values, "Bytes, values of --type, or text with --type string")->required();
    down->add_option("--type", so->type, "u8|u16|u32|u64|i8|i16|i32|i64|real32|real64|string");
    down->add_flag("-s,--station", so->station, "<slave> is a station address");
    down->add_flag("-c,--complete", so->complete, "Complete access");
    down->callback(
        [so, run, &rc] { rc = run([&](master::Master& m) { return sdo_transfer(m, *so, false); }); });
}

}  // namespace ecatctl
