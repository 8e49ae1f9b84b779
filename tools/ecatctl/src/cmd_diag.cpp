// ecatctl diag [slave] [--oldest-first] [--new] [--ack]: the diagnosis history 0x10F3 (ETG.1020) read over
// CoE SDO and printed as text: the header subindices, the flags, then one line per message with its time
// stamp (DC system time), type, diag code, text and parameters. A message's text id (ETG.1020) is named
// from the device's ESI DiagMessages (ETG.2000) with --esi FILE, else from the built-in drive's texts
// (drive/wire/diag_texts.hpp); emergency-derived codes from the drive's error table
// (drive/wire/error_codes.hpp). Both od-free: ecatctl does not link the drive.
#include "cmd_diag.hpp"

#include "commands.hpp"

#include <cstdio>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "drive/wire/diag_texts.hpp"
#include "drive/wire/error_codes.hpp"
#include "esi/esi_reader.hpp"
#include "format.hpp"
#include "master/coe.hpp"
#include "master/diag.hpp"
#include "master/mailbox.hpp"
#include "util/json.hpp"
#include "util/le.hpp"
#include "util/strfmt.hpp"

namespace ecatctl {

namespace {

using master::Error;

struct DiagArgs {
    std::string slave = "0";
    bool station = false;
    bool oldest_first = false;
    bool only_new = false;
    bool ack = false;
    bool json = false;
    std::string esi_path;  // --esi: the device's ESI, for its texts
};

// The ESI given with --esi, read before the master opens the link (a bad file: exit 2, nothing sent).
struct EsiTexts {
    esi::EsiFile file;
    std::map<uint16_t, std::string> texts;  // of the device picked for the slave
};

std::string_view drive_error_name(uint16_t code) {
    if (const drive::ErrorInfo* e = drive::find_error_code(code)) return e->name;
    return {};
}

// The built-in drive's diagnosis texts by id (what its ESI lists as DiagMessages).
std::string_view drive_text(uint16_t id) {
    return drive::diag_text_of(id);
}

// The device of the file that the slave is (0x1018:02 product code, :03 revision; esi::find_device), else the
// file's only device; nullptr if none fits.
const esi::EsiDevice* pick_device(const esi::EsiFile& f, master::SdoClient& sdo) {
    if (f.devices.size() == 1) return &f.devices.front();
    auto read32 = [&](uint8_t sub) -> std::optional<uint32_t> {
        uint8_t buf[4];
        auto n = sdo.upload(0x1018, sub, buf);
        if (!n || *n != 4) return std::nullopt;
        return util::get32(buf);
    };
    const auto product = read32(2);
    if (!product) return nullptr;
    return esi::find_device(f, *product, read32(3)).device;
}

int report(const master::SdoClient& sdo, Error e, const char* what) {
    if (e == Error::SdoAbort) {
        std::fprintf(stderr, "ecatctl: %s: SDO abort 0x%08x (%s)\n", what, sdo.last_abort(),
                     std::string(master::sdo_abort_text(sdo.last_abort())).c_str());
        return kExitProtocol;
    }
    if (e == Error::MailboxError) {
        std::fprintf(stderr, "ecatctl: %s: mailbox error 0x%04x\n", what, sdo.last_mailbox_error());
        return kExitProtocol;
    }
    std::fprintf(stderr, "ecatctl: %s: %s\n", what, std::string(master::to_string(e)).c_str());
    return e == Error::Timeout || e == Error::MailboxTimeout ? kExitNoSlave : kExitProtocol;
}

int run_diag(master::Master& m, const DiagArgs& d, EsiTexts* esi) {
    auto v = parse_number(d.slave, 0xFFFF);
    if (!v) {
        std::fprintf(stderr, "ecatctl: bad slave '%s'\n", d.slave.c_str());
        return kExitUsage;
    }
    const auto a = d.station ? master::Address::station(static_cast<uint16_t>(*v))
                             : master::Address::position(static_cast<uint16_t>(*v));
    master::Mailbox mbx(m, a);
    if (Error e = open_mailbox(m, mbx, a); e != Error::Ok) {
        std::fprintf(stderr, "ecatctl: opening the mailbox: %s\n", std::string(master::to_string(e)).c_str());
        return e == Error::Timeout ? kExitNoSlave : kExitProtocol;
    }
    master::SdoClient sdo(mbx);
    master::TextIdLookup texts = drive_text;
    if (esi != nullptr) {
        const esi::EsiDevice* dev = pick_device(esi->file, sdo);
        if (dev == nullptr) {
            std::fprintf(stderr, "ecatctl: %s: no device of the file is the slave (0x1018:02/:03)\n",
                         d.esi_path.c_str());
            return kExitUsage;
        }
        for (const esi::EsiDiagMessage& t : dev->diag_messages)
            esi->texts.emplace(t.text_id, t.text);
        texts = [esi](uint16_t id) -> std::string_view {
            auto it = esi->texts.find(id);
            return it != esi->texts.end() ? std::string_view(it->second) : std::string_view();
        };
    }
    uint8_t buf[8];
    auto read_uint = [&](uint8_t sub, uint16_t& out) -> Error {
        auto n = sdo.upload(master::kDiagIndex, sub, buf);
        if (!n) return n.error();
        if (*n < 1 || *n > 2) return Error::MailboxProtocol;
        out = static_cast<uint16_t>(buf[0] | (*n == 2 ? buf[1] << 8 : 0));
        return Error::Ok;
    };
    master::DiagHeader h;
    uint16_t val = 0;
    static const char* const kWhat[] = {"",
                                        "reading 0x10F3:01",
                                        "reading 0x10F3:02",
                                        "reading 0x10F3:03",
                                        "reading 0x10F3:04",
                                        "reading 0x10F3:05"};
    for (uint8_t sub = 1; sub <= 5; ++sub) {
        if (Error e = read_uint(sub, val); e != Error::Ok) return report(sdo, e, kWhat[sub]);
        switch (sub) {
            case 1:
                h.max_messages = static_cast<uint8_t>(val);
                break;
            case 2:
                h.newest = static_cast<uint8_t>(val);
                break;
            case 3:
                h.acknowledged = static_cast<uint8_t>(val);
                break;
            case 4:
                h.new_available = val != 0;
                break;
            default:
                h.flags = val;
        }
    }
    // JSON (docs/ecatctl-json.md, "diag") is written once everything is read: no half document on stdout.
    std::ostringstream json_text;
    util::JsonWriter w(json_text);
    if (d.json) {
        w.begin_object()
            .member("max_messages", h.max_messages)
            .member("newest", h.newest)
            .member("acknowledged", h.acknowledged)
            .member("new_messages", h.new_available)
            .member("flags", h.flags)
            .key("messages")
            .begin_array();
    } else {
        std::printf("diagnosis history 0x10F3: %u messages at most, newest :%02u, acknowledged :%02u, %s\n",
                    h.max_messages, h.newest, h.acknowledged,
                    h.new_available ? "new messages" : "no new messages");
        std::printf("flags 0x%04x: %s\n", h.flags, master::format_diag_flags(h.flags).c_str());
    }

    const auto order = master::diag_message_order(h, !d.oldest_first, d.only_new);
    std::vector<uint8_t> msg(512);
    unsigned shown = 0;
    for (uint8_t sub : order) {
        auto n = sdo.upload(master::kDiagIndex, sub, msg);
        if (!n) {
            return report(sdo, n.error(), util::strprintf("reading 0x10F3:%02x", sub).c_str());
        }
        auto e = master::decode_diag_message(std::span<const uint8_t>(msg.data(), *n), sub);
        if (!e) continue;  // an empty slot of a ring not yet full
        ++shown;
        if (!d.json) {
            std::printf("%s\n", master::format_diag_line(*e, drive_error_name, texts).c_str());
            continue;
        }
        w.begin_object()
            .member("subindex", e->subindex)
            .member("type", master::diag_type_name(e->type))
            .member("code", e->code)
            .member("text_id", e->text_id)
            .member("timestamp_ns", e->timestamp_ns)
            .member("local_time", e->local_time)
            .member("text", master::diag_text(*e, drive_error_name, texts))
            .key("parameters")
            .begin_array();
        for (const auto& p : e->params)
            w.value(master::format_diag_param(p));
        w.end_array().member("truncated", e->truncated).end_object();
    }
    if (d.json) w.end_array();
    if (shown == 0 && !d.json) std::printf("%s\n", d.only_new ? "no new messages" : "no messages");

    if (d.ack && h.newest != 0) {
        const uint8_t newest = h.newest;
        if (Error e = sdo.download(master::kDiagIndex, 3, std::span<const uint8_t>(&newest, 1));
            e != Error::Ok)
            return report(sdo, e, "acknowledging (0x10F3:03)");
        if (d.json)
            w.member("acknowledged_now", newest);
        else
            std::printf(
                "acknowledged up to :%02u%s\n", newest,
                (h.flags & master::kDiagFlagAcknowledgeMode) ? "" : " (the slave is in overwrite mode)");
    }
    if (d.json) {
        w.end_object();
        std::cout << json_text.str() << std::flush;
    }
    return kExitOk;
}

}  // namespace

void add_diag_command(CLI::App& app, MasterRunner run, int& rc) {
    auto args = std::make_shared<DiagArgs>();
    auto* c = app.add_subcommand("diag", "Print the diagnosis history (0x10F3) read through CoE SDO");
    c->add_option("slave", args->slave, "Slave position (or station address with --station)")
        ->capture_default_str();
    c->add_flag("-s,--station", args->station, "<slave> is a station address");
    c->add_flag("--oldest-first", args->oldest_first, "Oldest message first (default: newest first)");
    c->add_flag("--new", args->only_new, "Only messages newer than the acknowledged one");
    c->add_flag("--ack", args->ack, "Acknowledge up to the newest message afterwards (write 0x10F3:03)");
    c->add_flag("--json", args->json, "JSON on stdout (docs/ecatctl-json.md)");
    c->add_option("--esi", args->esi_path,
                  "The slave's ESI file: name text ids by its DiagMessages (default: the built-in drive's "
                  "texts); a file of several devices is matched by the slave's 0x1018 identity");
    c->callback([args, run = std::move(run), &rc] {
        std::shared_ptr<EsiTexts> esi;
        if (!args->esi_path.empty()) {
            try {
                esi = std::make_shared<EsiTexts>();
                esi->file = esi::read_esi_file(args->esi_path);
            } catch (const std::exception& e) {
                std::fprintf(stderr, "ecatctl: %s\n", e.what());
                rc = kExitUsage;
                return;
            }
        }
        rc = run([&](master::Master& m) { return run_diag(m, *args, esi.get()); });
    });
}

}  // namespace ecatctl
