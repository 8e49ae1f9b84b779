// `ecatctl sdos`: the object dictionary through the SDO information service.
#include <CLI/CLI.hpp>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
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

namespace ecatctl {

namespace {

using master::Address;
using master::Error;

struct SdosArgs {
    std::string slave = "0";
    bool station = false;
    bool quiet = false;
    bool json = false;
};

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

int sdos(master::Master& m, const std::string& slave, bool station, bool quiet, bool json) {
    auto a = named_slave(slave, station);
    if (!a) return kExitUsage;
    master::Mailbox mbx(m, *a);
    if (Error e = open_mailbox(m, mbx, *a); e != Error::Ok)
        return fail(e, "opening the mailbox of " + slave_label(*a));
    master::SdoClient sdo(mbx);
    auto list = sdo.od_list(1);
    if (!list) return sdo_failed(sdo, list.error(), "reading the object list");
    if (json) {
        // docs/ecatctl-json.md, "sdos". The whole dictionary is read before anything is written: a failure
        // half-way leaves no half document on stdout.
        std::ostringstream o;
        util::JsonWriter w(o);
        w.begin_object().key("objects").begin_array();
        for (uint16_t index : *list) {
            auto od = sdo.object_description(index);
            if (!od) return sdo_failed(sdo, od.error(), "describing object " + std::to_string(index));
            w.begin_object()
                .member("index", index)
                .member("object_code", od->object_code)
                .member("max_subindex", od->max_subindex)
                .member("name", od->name);
            if (!quiet) {
                std::vector<EntryView> entries;
                const uint8_t last = od->object_code == 7 ? 0 : od->max_subindex;
                if (Error e = describe_entries(sdo, index, last, entries); e != Error::Ok)
                    return sdo_failed(sdo, e, "describing an entry");
                w.key("entries").begin_array();
                for (const auto& e : entries)
                    w.begin_object()
                        .member("subindex", e.subindex)
                        .member("name", e.name)
                        .member("data_type", e.data_type)
                        .member("type", esi_type_name(e.data_type))
                        .member("bit_length", e.bit_length)
                        .member("access", e.access)
                        .end_object();
                w.end_array();
            }
            w.end_object();
        }
        w.end_array().end_object();
        std::cout << o.str() << std::flush;
        return kExitOk;
    }
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

}  // namespace

void add_sdos_command(CLI::App& app, MasterRunner run, int& rc) {
    auto sd = std::make_shared<SdosArgs>();
    auto* c = app.add_subcommand("sdos", "List the object dictionary through the SDO information service");
    c->add_option("slave", sd->slave, "Slave position (or station address with --station)")
        ->capture_default_str();
    c->add_flag("-s,--station", sd->station, "<slave> is a station address");
    c->add_flag("-q,--quiet", sd->quiet, "Objects only, no entries");
    c->add_flag("--json", sd->json, "JSON on stdout (docs/ecatctl-json.md)");
    c->callback([sd, run, &rc] {
        rc = run([&](master::Master& m) { return sdos(m, sd->slave, sd->station, sd->quiet, sd->json); });
    });
}

}  // namespace ecatctl
