// Group sdoinfo: the SDO information service: every list type, object and entry descriptions against the
// ESI, error replies.
#include <set>

#include "sdo_util.hpp"

namespace conform {

namespace {

using master::Error;
constexpr const char* kInfo = "ETG.1000.6 CoE SDO information service";

struct InfoCache {
    std::map<uint16_t, master::ObjectDescription> objects;
    std::map<std::pair<uint16_t, uint8_t>, master::EntryDescription> entries;
    std::string error;
};

// Object and entry descriptions of every ESI object, fetched once per run.
InfoCache& descriptions(Context& ctx) {
    auto& slot = ctx.cache["sdoinfo"];
    if (slot) return *static_cast<InfoCache*>(slot.get());
    auto c = std::make_shared<InfoCache>();
    for (const auto& [i, o] : ctx.esi->objects) {
        auto d = ctx.sdo->object_description(i);
        if (!d) {
            c->error = "object description " + hex(i) + ": " + ctx.sdo_error(d.error());
            break;
        }
        c->objects[i] = *d;
        for (const auto& e : o.entries) {
            auto x = ctx.sdo->entry_description(i, e.subindex, 0x70);
            if (!x) {
                c->error =
                    "entry description " + hex(i) + ":" + dec(e.subindex) + ": " + ctx.sdo_error(x.error());
                break;
            }
            c->entries[{i, e.subindex}] = *x;
        }
        if (!c->error.empty()) break;
    }
    slot = c;
    return *c;
}

#define CONFORM_INFO(ctx)                \
    CONFORM_NEED((ctx).need_sdo_info()); \
    CONFORM_NEED((ctx).need_esi());      \
    CONFORM_PREOP(ctx);                  \
    InfoCache& info = descriptions(ctx); \
    if (!info.error.empty()) return fail(info.error)

std::string list_text(const std::set<uint16_t>& s) {
    std::string r;
    for (auto i : s)
        r += hex(i) + " ";
    return r.empty() ? "(none)" : r;
}

// Objects the ESI declares outside its <Dictionary>, which a device built from it has although the dictionary
// does not list them (ETG.2000: the Dictionary element need not be complete): the PDOs of its RxPdo/TxPdo
// elements and the objects their entries map (type 1: all; type 2: RxPDO entries; type 3: TxPDO entries),
// and for type 1 the objects ETG.1000.6 requires of every CoE device whose values the ESI gives elsewhere
// (0x1000 device type, 0x1008-0x100A names and versions, 0x1018 identity from Type) and the SM communication
// type and PDO assignment objects 0x1C00 and 0x1C10+n of its Sm elements.
std::set<uint16_t> implied_objects(const EsiDevice& d, uint16_t type) {
    std::set<uint16_t> r;
    for (const auto* pdos : {&d.rxpdos, &d.txpdos}) {
        const bool rx = pdos == &d.rxpdos;
        if ((type == 2 && !rx) || (type == 3 && rx)) continue;
        for (const auto& p : *pdos) {
            if (type == 1) r.insert(p.index);
            for (const auto& e : p.entries)
                if (e.index != 0) r.insert(e.index);
        }
    }
    if (type == 1) {
        r.insert({0x1000, 0x1008, 0x1009, 0x100A, 0x1018});
        if (!d.sms.empty()) r.insert(0x1C00);
        for (std::size_t n = 0; n < d.sms.size() && n < 32; ++n)
            r.insert(static_cast<uint16_t>(0x1C10 + n));
    }
    return r;
}

Outcome list_vs_esi(Context& ctx, uint16_t type, const std::function<bool(const EsiObject&)>& in_list) {
    CONFORM_NEED(ctx.need_sdo_info());
    CONFORM_NEED(ctx.need_esi());
    CONFORM_PREOP(ctx);
    auto l = ctx.sdo->od_list(type);
    if (!l) return fail("list type " + dec(type) + ": " + ctx.sdo_error(l.error()));
    std::set<uint16_t> got(l->begin(), l->end()), want;
    for (const auto& [i, o] : ctx.esi->objects)
        if (in_list(o)) want.insert(i);
    if (type == 1) want.insert(ctx.module_mapping_objects.begin(), ctx.module_mapping_objects.end());
    // Lists 1-3 may also name what the ESI declares outside its dictionary (implied_objects); lists 4 and 5
    // (backup, settings) only what the dictionary flags.
    const std::set<uint16_t> implied = type <= 3 ? implied_objects(*ctx.esi, type) : std::set<uint16_t>{};
    std::set<uint16_t> missing, extra;
    for (auto i : want)
        if (!got.count(i)) missing.insert(i);
    for (auto i : got)
        if (!want.count(i) && !implied.count(i)) extra.insert(i);
    if (missing.empty() && extra.empty()) return pass(dec(static_cast<long long>(got.size())) + " objects");
    return fail("list differs from the ESI", "missing " + list_text(missing) + "; extra " + list_text(extra),
                "none missing, none extra");
}

bool any_entry(const EsiObject& o, const std::function<bool(const EsiEntry&)>& f) {
    for (const auto& e : o.entries)
        if (f(e)) return true;
    return false;
}

// Each object of the ESI against its object description: the first failure `check` returns, else a pass.
Outcome objects_vs_esi(Context& ctx,
                       const std::function<std::optional<Outcome>(uint16_t, const EsiObject&,
                                                                  const master::ObjectDescription&)>& check) {
    CONFORM_INFO(ctx);
    for (const auto& [i, o] : ctx.esi->objects)
        if (auto r = check(i, o, info.objects[i])) return *r;
    return pass();
}

// Each entry of the ESI against its entry description: the first failure `check` returns, else a pass.
Outcome entries_vs_esi(
    Context& ctx,
    const std::function<std::optional<Outcome>(const EntryRef&, const master::EntryDescription&)>& check) {
    CONFORM_INFO(ctx);
    for (const auto& r : esi_entries(*ctx.esi))
        if (auto o = check(r, info.entries[{r.obj->index, r.e->subindex}])) return *o;
    return pass();
}

// The answer to a description request for something missing: an error reply with `code`. `described` is
// the failure when the slave describes it.
template <class D>
Outcome expect_error_reply(Context& ctx, const master::Result<D>& d, const std::string& described,
                           uint32_t code) {
    if (d) return fail(described, d->name, "error " + hex(code, 8));
    if (d.error() != Error::SdoAbort) return fail("no error reply: " + ctx.sdo_error(d.error()));
    return expect_eq("error code", hex(ctx.sdo->last_abort(), 8), hex(code, 8));
}

// Access bits of an entry description: 0-2 read in PREOP/SAFEOP/OP, 3-5 write in PREOP/SAFEOP/OP.
uint16_t expected_access(const EsiEntry& e) {
    uint16_t a = 0;
    if (e.access == "ro" || e.access == "rw") a |= 0x07;
    if (e.access == "rw" || e.access == "wo") {
        const auto& w = e.write_restrictions;
        if (w.empty()) {
            a |= 0x38;
        } else {
            if (w.find("PreOP") != std::string::npos) a |= 0x08;
            if (w.find("SafeOP") != std::string::npos) a |= 0x10;
            if (w == "OP" || (w.size() > 3 && w.compare(w.size() - 3, 3, "_OP") == 0)) a |= 0x20;
        }
    }
    return a;
}

SdoAnswer info_raw(Context& ctx, uint8_t opcode, std::vector<uint8_t> body) {
    std::vector<uint8_t> r = {0x00, 0x80, opcode, 0, 0, 0};
    r.insert(r.end(), body.begin(), body.end());
    return sdo_raw(ctx, r);
}

}  // namespace

void add_sdoinfo_tests(Catalogue& c) {
    Adder add{c, "sdoinfo"};
    const std::string a = "SDO information and ESI";
    add(
        "list.all", "Object list 'all objects' (type 1) equals the ESI's objects", kInfo,
        [](Context& ctx) { return list_vs_esi(ctx, 1, [](const EsiObject&) { return true; }); }, a);
    // The lists of type 2..5 hold the objects with an entry of a kind (ETG.1000.6 SDO information list
    // types).
    const struct {
        const char* id;
        uint16_t type;
        const char* title;
        bool (*in)(const EsiEntry&);
        Severity sev;
    } lists[] = {
        {"list.rxpdo", 2, "Object list 'RxPDO-mappable' (type 2) equals the ESI's objects with PdoMapping R",
         [](const EsiEntry& e) { return e.pdo_mapping.find('R') != std::string::npos; }, Severity::Error},
        {"list.txpdo", 3, "Object list 'TxPDO-mappable' (type 3) equals the ESI's objects with PdoMapping T",
         [](const EsiEntry& e) { return e.pdo_mapping.find('T') != std::string::npos; }, Severity::Error},
        {"list.backup", 4, "Object list 'backup' (type 4) equals the ESI's objects with Backup entries",
         [](const EsiEntry& e) { return e.backup; }, Severity::Warning},
        {"list.settings", 5, "Object list 'settings' (type 5) equals the ESI's objects with Setting entries",
         [](const EsiEntry& e) { return e.setting; }, Severity::Warning},
    };
    for (const auto& l : lists)
        add(
            l.id, l.title, kInfo,
            [type = l.type, in = l.in](Context& ctx) {
                return list_vs_esi(ctx, type, [in](const EsiObject& o) { return any_entry(o, in); });
            },
            a, l.sev);
    add(
        "list.lengths", "List type 0 gives the lengths of lists 1..5", kInfo, {&Context::need_sdo_info},
        [](Context& ctx) {
            auto l = ctx.sdo->od_list(0);
            if (!l) return fail("list type 0: " + ctx.sdo_error(l.error()));
            std::string got, want;
            for (uint16_t t = 1; t <= 5; ++t) {
                auto x = ctx.sdo->od_list(t);
                if (!x) return fail("list type " + dec(t) + ": " + ctx.sdo_error(x.error()));
                want += dec(static_cast<long long>(x->size())) + " ";
                got += (t - 1u < l->size() ? dec((*l)[t - 1u]) : std::string("-")) + " ";
            }
            return expect_eq("lengths of lists 1..5", got, want);
        },
        "SDO information");
    add(
        "list.fragments", "A list longer than the mailbox comes in fragments counting down to 0", kInfo,
        {&Context::need_sdo_info},
        [](Context& ctx) {
            SdoAnswer r = info_raw(ctx, 0x01, {0x01, 0x00});
            if (r.error != Error::Ok || r.p.size() < 6) return fail("no answer", r.describe());
            int n = 0;
            uint16_t left = get16(&r.p[4]);
            // Every fragment is a new mailbox message with the next counter (ETG.1000.4), not the transfer's.
            uint8_t counter = ctx.mbx->last_rx_counter();
            while (r.p[2] & 0x80) {
                master::MailboxMessage msg;
                if (Error e = ctx.mbx->receive(msg, ctx.ms(500)); e != Error::Ok)
                    return fail("fragment " + dec(n + 1) + ": " + err(e));
                if (msg.payload.size() < 6)
                    return fail("fragment too short", dec(static_cast<long long>(msg.payload.size())));
                if (msg.counter == 0 || msg.counter == counter)
                    return fail(
                        "fragment " + dec(n + 1) + ": mailbox counter of the fragment before it, or 0",
                        dec(msg.counter), "1..7, not " + dec(counter));
                counter = msg.counter;
                r.p.assign(msg.payload.begin(), msg.payload.end());
                const uint16_t now = get16(&r.p[4]);
                if (now + 1 != left) return fail("fragments left", dec(now), dec(left - 1));
                left = now;
                ++n;
            }
            if (left != 0) return fail("last fragment: fragments left", dec(left), "0");
            if (n == 0) return skip("the list fits one mailbox");
            return pass(dec(n + 1) + " fragments");
        },
        "SDO information");
    add(
        "od.object_code", "Object descriptions: object code (VAR/ARRAY/RECORD) as the ESI", kInfo,
        [](Context& ctx) {
            CONFORM_INFO(ctx);
            for (const auto& [i, o] : ctx.esi->objects) {
                const uint8_t got = info.objects[i].object_code;
                if (got == o.object_code) continue;
                // An ARRAY with gaps in its subindices can only be written as a record-like DataType in an
                // ESI: accepted when all entries after subindex 0 have one type.
                bool one_type = o.entries.size() > 1;
                for (std::size_t k = 1; k < o.entries.size(); ++k)
                    one_type = one_type && o.entries[k].type == o.entries[1].type;
                if (got == 8 && o.object_code == 9 && one_type) continue;
                return fail(hex(i) + " object code", dec(got), dec(o.object_code));
            }
            return pass(dec(static_cast<long long>(info.objects.size())) + " objects");
        },
        a);
    // Each object description against the ESI, one field a test.
    const struct {
        const char* id;
        const char* title;
        std::optional<Outcome> (*check)(uint16_t, const EsiObject&, const master::ObjectDescription&);
        Severity sev;
    } object_fields[] = {
        {"od.max_subindex", "Object descriptions: maximum subindex as the ESI",
         [](uint16_t i, const EsiObject& o, const master::ObjectDescription& d) -> std::optional<Outcome> {
             if (d.max_subindex != o.max_subindex())
                 return fail(hex(i) + " max subindex", dec(d.max_subindex), dec(o.max_subindex()));
             return std::nullopt;
         },
         Severity::Error},
        {"od.data_type", "Object descriptions of VAR and ARRAY objects: data type as the ESI",
         [](uint16_t i, const EsiObject& o, const master::ObjectDescription& d) -> std::optional<Outcome> {
             std::string t = o.object_code == 7
                                 ? o.type
                                 : (o.object_code == 8 && o.entries.size() > 1 ? o.entries.back().type : "");
             const uint16_t want = esi_coe_type(t);
             if (want && d.data_type != want)
                 return fail(hex(i) + " data type", hex(d.data_type), hex(want) + " (" + t + ")");
             return std::nullopt;
         },
         Severity::Error},
        {"od.name", "Object descriptions: name as the ESI",
         [](uint16_t i, const EsiObject& o, const master::ObjectDescription& d) -> std::optional<Outcome> {
             if (d.name != o.name) return fail(hex(i) + " name", d.name, o.name);
             return std::nullopt;
         },
         Severity::Warning},
    };
    for (const auto& f : object_fields)
        add(
            f.id, f.title, kInfo, [check = f.check](Context& ctx) { return objects_vs_esi(ctx, check); }, a,
            f.sev);
    // Each entry description against the ESI, one field a test.
    const struct {
        const char* id;
        const char* title;
        std::optional<Outcome> (*check)(const EntryRef&, const master::EntryDescription&);
    } entry_fields[] = {
        {"entry.data_type", "Entry descriptions: data type as the ESI",
         [](const EntryRef& r, const master::EntryDescription& d) -> std::optional<Outcome> {
             const uint16_t want = esi_coe_type(r.e->type);
             // An unsigned type given fewer bits than its size (an enum on USINT with BitSize 3, Beckhoff's
             // DTxxxxENyy) may be described as the BITn of its size.
             const bool short_unsigned = (want == 0x0005 || want == 0x0006) && r.e->bit_size > 0 &&
                                         r.e->bit_size < 8 && d.data_type == 0x002F + r.e->bit_size;
             if (want && d.data_type != want && !short_unsigned)
                 return fail(hex(r.obj->index) + ":" + dec(r.e->subindex) + " data type", hex(d.data_type),
                             hex(want) + " (" + r.e->type + ")");
             return std::nullopt;
         }},
        {"entry.value_info",
         "Entry descriptions: the value info of the response names only elements the request asked for",
         [](const EntryRef& r, const master::EntryDescription& d) -> std::optional<Outcome> {
             // ETG.1000.6 Get Entry Description: the response's value info says which of the elements asked
             // for (unit type 0x08, default 0x10, minimum 0x20, maximum 0x40) follow; a device may leave some
             // out, never add one (a master would take its bytes for the name). Asked: 0x70 (descriptions()).
             if (d.value_info & ~0x70)
                 return fail(hex(r.obj->index) + ":" + dec(r.e->subindex) + " value info of the response",
                             hex(d.value_info, 2), "bits of 0x70 (the request's) only");
             return std::nullopt;
         }},
        {"entry.bit_length", "Entry descriptions: bit length as the ESI",
         [](const EntryRef& r, const master::EntryDescription& d) -> std::optional<Outcome> {
             const unsigned want = declared_bits(*r.e);
             if (d.bit_length != want)
                 return fail(
                     hex(r.obj->index) + ":" + dec(r.e->subindex) + " bit length", dec(d.bit_length),
                     dec(want) + (want != r.e->bit_size ? " (the ESI declares " + r.e->type + ", BitSize " +
                                                              dec(r.e->bit_size) + ", with a default of " +
                                                              dec(want / 8) + " characters)"
                                                        : ""));
             return std::nullopt;
         }},
        {"entry.access", "Entry descriptions: read/write access per state as the ESI's Access",
         [](const EntryRef& r, const master::EntryDescription& d) -> std::optional<Outcome> {
             const uint16_t want = expected_access(*r.e);
             if ((d.access & 0x3F) != want)
                 return fail(hex(r.obj->index) + ":" + dec(r.e->subindex) + " access bits (" + r.e->access +
                                 (r.e->write_restrictions.empty() ? "" : ", " + r.e->write_restrictions) +
                                 ")",
                             hex(d.access & 0x3F, 2), hex(want, 2));
             return std::nullopt;
         }},
        {"entry.pdo_mapping", "Entry descriptions: RxPDO/TxPDO mappable bits as the ESI's PdoMapping",
         [](const EntryRef& r, const master::EntryDescription& d) -> std::optional<Outcome> {
             const uint16_t declared =
                 static_cast<uint16_t>((r.e->pdo_mapping.find('R') != std::string::npos ? 0x40 : 0) |
                                       (r.e->pdo_mapping.find('T') != std::string::npos ? 0x80 : 0));
             // An entry an ESI PDO maps is mappable in that direction although the dictionary leaves its
             // PdoMapping out (the ESI contradicts itself; the device maps it, so it must say so).
             const uint16_t want = declared | r.mapped;
             if ((d.access & 0xC0) != want)
                 return fail(hex(r.obj->index) + ":" + dec(r.e->subindex) + " mapping bits",
                             hex(d.access & 0xC0, 2),
                             hex(want, 2) + (want != declared ? " (the ESI's PdoMapping " + hex(declared, 2) +
                                                                    " and the PDOs that map it)"
                                                              : ""));
             return std::nullopt;
         }},
    };
    for (const auto& f : entry_fields)
        add(
            f.id, f.title, kInfo, [check = f.check](Context& ctx) { return entries_vs_esi(ctx, check); }, a);
    add(
        "entry.name", "Entry descriptions: name as the ESI", kInfo,
        [](Context& ctx) {
            CONFORM_INFO(ctx);
            for (const auto& [i, o] : ctx.esi->objects) {
                if (o.object_code == 7) continue;  // a VAR's entry is named after the object
                for (const auto& e : o.entries) {
                    if (o.object_code == 8 && e.subindex > 0)
                        continue;  // array elements share one name in the ESI
                    const auto& d = info.entries[{i, e.subindex}];
                    if (d.name != e.name)
                        return fail(hex(i) + ":" + dec(e.subindex) + " name", d.name, e.name);
                }
            }
            return pass();
        },
        a, Severity::Warning);
    add(
        "names.visible",
        "Object and entry description names: visible characters only (no terminator, no control character), "
        "not the ESI's name cut short",
        "ETG.1000.6 SDO information object/entry description: the name (VISIBLE_STRING) is the rest of the "
        "message",
        [](Context& ctx) {
            CONFORM_INFO(ctx);
            // A name whose length comes from the mailbox length: a C terminator or padding sent with it, or a
            // length that runs past the name, shows as NUL or control characters a master puts on screen.
            auto control = [](const std::string& n) {
                return std::any_of(n.begin(), n.end(), [](char ch) {
                    const auto u = static_cast<unsigned char>(ch);
                    return u < 0x20 || u == 0x7F;
                });
            };
            auto shown = [](const std::string& n) {
                return bytes_hex(
                    std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(n.data()), n.size()), 48);
            };
            for (const auto& [i, d] : info.objects)
                if (control(d.name))
                    return fail(hex(i) + " object name holds a control character", shown(d.name),
                                "visible characters");
            for (const auto& [k, d] : info.entries)
                if (control(d.name))
                    return fail(hex(k.first) + ":" + dec(k.second) + " entry name holds a control character",
                                shown(d.name), "visible characters");
            // The other side of the same length: a name one to three characters short of the ESI's, which it
            // begins, cut inside a word (an off-by-one that drops the last character, a terminator counted
            // off), is the ESI's name cut, not another name (a shorter name ending at a word, or any other
            // name, is sdoinfo.od.name's and sdoinfo.entry.name's, warnings).
            auto cut = [](const std::string& got, const std::string& esi) {
                return !got.empty() && got.size() < esi.size() && esi.size() - got.size() <= 3 &&
                       esi.compare(0, got.size(), got) == 0 && got.back() != ' ' && esi[got.size()] != ' ';
            };
            for (const auto& [i, o] : ctx.esi->objects) {
                const auto at = info.objects.find(i);
                if (at != info.objects.end() && cut(at->second.name, o.name))
                    return fail(hex(i) + " object name cut short of the ESI's", at->second.name, o.name);
                if (o.object_code == 7) continue;  // a VAR's entry is named after the object
                for (const auto& e : o.entries) {
                    if (o.object_code == 8 && e.subindex > 0) continue;  // array elements share one name
                    const auto en = info.entries.find({i, e.subindex});
                    if (en != info.entries.end() && cut(en->second.name, e.name))
                        return fail(hex(i) + ":" + dec(e.subindex) + " entry name cut short of the ESI's",
                                    en->second.name, e.name);
                }
            }
            return pass(dec(static_cast<long long>(info.objects.size() + info.entries.size())) + " names");
        },
        a);
    add(
        "entry.default",
        "Entry descriptions: default value (value info 0x10) as the ESI's DefaultData (device-state objects "
        "aside)",
        kInfo,
        [](Context& ctx) {
            CONFORM_INFO(ctx);
            unsigned n = 0;
            for (const auto& r : esi_entries(*ctx.esi)) {
                const auto& d = info.entries[{r.obj->index, r.e->subindex}];
                if (!(d.value_info & 0x10) || r.e->default_data.empty() ||
                    r.e->type.rfind("STRING", 0) == 0 || device_state_object(r.obj->index))
                    continue;
                const std::size_t off = (d.value_info & 0x08) ? 4 : 0;
                const std::size_t len = (d.bit_length + 7u) / 8u;
                if (d.values.size() < off + len) continue;
                std::vector<uint8_t> v(d.values.begin() + static_cast<std::ptrdiff_t>(off),
                                       d.values.begin() + static_cast<std::ptrdiff_t>(off + len));
                ++n;
                if (v != r.e->default_data)
                    return fail(hex(r.obj->index) + ":" + dec(r.e->subindex) + " default", bytes_hex(v),
                                bytes_hex(r.e->default_data));
            }
            if (!n) return skip("no entry description carries a default value");
            return pass(dec(n) + " entries");
        },
        a, Severity::Warning);
    add(
        "entry.limits",
        "Entry descriptions: minimum/maximum (value info 0x20/0x40) as the ESI's MinValue/MaxValue", kInfo,
        [](Context& ctx) {
            CONFORM_INFO(ctx);
            unsigned n = 0;
            for (const auto& r : esi_entries(*ctx.esi)) {
                const auto& d = info.entries[{r.obj->index, r.e->subindex}];
                if ((d.value_info & 0x60) != 0x60 || !r.e->min || !r.e->max || d.bit_length > 32 ||
                    d.bit_length % 8)
                    continue;
                const std::size_t len = d.bit_length / 8u;
                std::size_t off = ((d.value_info & 0x08) ? 4 : 0) + ((d.value_info & 0x10) ? len : 0);
                if (d.values.size() < off + 2 * len) continue;
                auto val = [&](std::size_t o) {
                    uint64_t v = 0;
                    for (std::size_t k = 0; k < len; ++k)
                        v |= static_cast<uint64_t>(d.values[o + k]) << (8 * k);
                    const bool is_signed = r.e->type == "SINT" || r.e->type == "INT" || r.e->type == "DINT";
                    if (is_signed) return static_cast<int64_t>(v << (64 - 8 * len)) >> (64 - 8 * len);
                    return static_cast<int64_t>(v);
                };
                ++n;
                if (val(off) != *r.e->min || val(off + len) != *r.e->max)
                    return fail(hex(r.obj->index) + ":" + dec(r.e->subindex) + " limits",
                                dec(val(off)) + ".." + dec(val(off + len)),
                                dec(*r.e->min) + ".." + dec(*r.e->max));
            }
            if (!n) return skip("no entry description carries limits");
            return pass(dec(n) + " entries");
        },
        a, Severity::Warning);
    add(
        "entry.value_range",
        "Entry descriptions: the slave's own minimum not above its maximum, its default between them",
        "ETG.1000.6 SDO information entry description value info: default, minimum and maximum value of the "
        "entry (one range, whatever the ESI says)",
        [](Context& ctx) {
            CONFORM_INFO(ctx);
            // Judged against the description itself, not the ESI (entry.limits compares with the ESI as a
            // warning): a maximum below the minimum, or a default outside them, is a range no value fits.
            unsigned n = 0;
            for (const auto& [k, d] : info.entries) {
                const bool is_signed = d.data_type >= 0x0002 && d.data_type <= 0x0004;
                const bool is_unsigned = d.data_type >= 0x0005 && d.data_type <= 0x0007;
                if ((d.value_info & 0x60) != 0x60 || !(is_signed || is_unsigned) || d.bit_length > 32 ||
                    d.bit_length % 8 || d.bit_length == 0)
                    continue;
                const std::size_t len = d.bit_length / 8u;
                const std::size_t def = (d.value_info & 0x08) ? 4 : 0;
                const std::size_t lo = def + ((d.value_info & 0x10) ? len : 0);
                if (d.values.size() < lo + 2 * len) continue;
                auto val = [&](std::size_t o) {
                    uint64_t v = 0;
                    for (std::size_t b = 0; b < len; ++b)
                        v |= static_cast<uint64_t>(d.values[o + b]) << (8 * b);
                    if (is_signed) return static_cast<int64_t>(v << (64 - 8 * len)) >> (64 - 8 * len);
                    return static_cast<int64_t>(v);
                };
                ++n;
                const std::string at = hex(k.first) + ":" + dec(k.second);
                if (val(lo) > val(lo + len))
                    return fail(at + ": maximum below minimum", dec(val(lo)) + ".." + dec(val(lo + len)),
                                "minimum <= maximum");
                if ((d.value_info & 0x10) && (val(def) < val(lo) || val(def) > val(lo + len)))
                    return fail(at + ": default outside minimum..maximum", dec(val(def)),
                                dec(val(lo)) + ".." + dec(val(lo + len)));
            }
            if (!n) return skip("no entry description carries minimum and maximum");
            return pass(dec(n) + " entries");
        },
        a);
    add(
        "error.missing_object", "Object description of a missing object: error reply 0x06020000", kInfo,
        {&Context::need_sdo_info},
        [](Context& ctx) {
            const uint16_t i = missing_index(ctx);
            return expect_error_reply(ctx, ctx.sdo->object_description(i),
                                      "described a missing object " + hex(i), 0x06020000);
        },
        "SDO information");
    add(
        "error.missing_subindex", "Entry description of a missing subindex of 0x1018: error reply 0x06090011",
        kInfo, {&Context::need_sdo_info},
        [](Context& ctx) {
            auto n = ctx.upload_uint(0x1018, 0);
            if (!n) return fail("0x1018:00: " + ctx.sdo_error(n.error()));
            return expect_error_reply(ctx, ctx.sdo->entry_description(0x1018, static_cast<uint8_t>(*n + 1)),
                                      "described a missing subindex", 0x06090011);
        },
        "SDO information");
    add(
        "error.format", "SDO information error reply: opcode 7, complete, 4-byte abort code (length 10)",
        kInfo, {&Context::need_sdo_info},
        [](Context& ctx) {
            const uint16_t i = missing_index(ctx);
            SdoAnswer r = info_raw(ctx, 0x03, {static_cast<uint8_t>(i), static_cast<uint8_t>(i >> 8)});
            if (r.error != Error::Ok || r.mailbox_type != 3) return fail("no answer", r.describe());
            if ((r.p[2] & 0x7F) != 0x07) return fail("opcode", hex(r.p[2] & 0x7F, 2), "0x07");
            if (r.p[2] & 0x80) return fail("incomplete bit set on an error reply", hex(r.p[2], 2), "0x07");
            return expect_eq("CoE length of the error reply", dec(static_cast<long long>(r.p.size())), "10");
        },
        "SDO information");
    add(
        "entry.sub0_type", "Entry description of subindex 0 of ARRAY/RECORD objects: UNSIGNED8, 8 bits",
        kInfo,
        [](Context& ctx) {
            CONFORM_INFO(ctx);
            for (const auto& [i, o] : ctx.esi->objects) {
                if (o.object_code == 7) continue;
                const auto& d = info.entries[{i, 0}];
                if (d.data_type != 0x0005 || d.bit_length != 8)
                    return fail(hex(i) + ":0", hex(d.data_type) + "/" + dec(d.bit_length), "0x0005/8");
            }
            return pass();
        },
        a);
}

}  // namespace conform
