// Group sdo: CoE SDO transfers (expedited, normal, segmented, complete access), the standard abort codes,
// the object dictionary against the ESI, identity against the SII, PDO assignment/mapping rules.
#include <functional>
#include <thread>

#include "report.hpp"
#include "sdo_util.hpp"

namespace conform {

namespace {

using master::Error;
constexpr const char* kSdo = "ETG.1000.6 CoE SDO services";
constexpr const char* kAbort = "ETG.1000.6 CoE SDO abort codes";
constexpr const char* kCa = "ETG.1000.6 CoE SDO complete access";
constexpr const char* kOd = "ETG.2000 Dictionary/Objects; ETG.1000.6 CoE object dictionary";

// A writable entry of 1, 2 or 4 bytes (no command objects), from the ESI.
const EntryRef* pick_rw(Context& ctx, std::vector<EntryRef>& store, unsigned bits_min, unsigned bits_max,
                        bool need_limits = false, bool high = true) {
    if (!ctx.esi) return nullptr;
    store = esi_entries(*ctx.esi);
    for (const auto& r : store) {
        if (command_object(*ctx.esi, r.obj->index) || !writable_in_preop(*r.e) || r.e->access != "rw")
            continue;
        if (r.e->bit_size < bits_min || r.e->bit_size > bits_max || r.e->bit_size % 8) continue;
        if (r.e->type.rfind("STRING", 0) == 0) continue;
        if (need_limits) {
            const unsigned bits = r.e->bit_size;
            const bool is_signed = r.e->type == "SINT" || r.e->type == "INT" || r.e->type == "DINT";
            const int64_t tmax = is_signed ? (int64_t{1} << (bits - 1)) - 1
                                           : (bits >= 63 ? INT64_MAX : (int64_t{1} << bits) - 1);
            const int64_t tmin = is_signed ? -(int64_t{1} << (bits - 1)) : 0;
            if (high && !(r.e->max && *r.e->max < tmax)) continue;
            if (!high && !(r.e->min && *r.e->min > tmin)) continue;
        }
        return &r;
    }
    return nullptr;
}

Outcome identity(Context& ctx, uint8_t sub, std::size_t word) {
    CONFORM_NEED(ctx.need_coe());
    CONFORM_PREOP(ctx);
    auto v = ctx.upload_uint(0x1018, sub);
    if (!v) return fail("0x1018:" + dec(sub) + " upload: " + ctx.sdo_error(v.error()));
    return expect_eq("0x1018:" + dec(sub) + " against SII word " + hex(word, 2), hex(*v, 8),
                     hex(ctx.sii->dword(word), 8));
}

// Largest object (complete access) or entry that does not fit one mailbox answer: a segmented upload.
struct Big {
    uint16_t index = 0;
    uint8_t sub = 0;
    bool ca = false;
    std::size_t bytes = 0;
};
std::optional<Big> big_object(Context& ctx) {
    if (!ctx.esi || !ctx.mbx) return std::nullopt;
    const std::size_t room = ctx.mbx->max_in_payload() > 10 ? ctx.mbx->max_in_payload() - 10 : 0;
    // A STRING by its default text, not its capacity: the text is what uploads (od.size).
    for (const auto& [i, o] : ctx.esi->objects)
        for (const auto& e : o.entries) {
            const std::size_t bytes = visible_string(e) ? default_text_bytes(e) : e.bit_size / 8u;
            if (bytes > room && e.access != "wo") return Big{i, e.subindex, false, bytes};
        }
    if (ctx.need_complete_access().empty())
        for (const auto& [i, o] : ctx.esi->objects)
            if (o.object_code != 7 && o.bit_size / 8u > room) return Big{i, 0, true, o.bit_size / 8u};
    return std::nullopt;
}

Outcome expedited_sizes(Context& ctx) {
    CONFORM_NEED(ctx.need_coe());
    CONFORM_PREOP(ctx);
    std::vector<std::tuple<uint16_t, uint8_t, unsigned>> cands;
    if (ctx.esi) {
        for (const auto& r : esi_entries(*ctx.esi))
            if (r.e->access != "wo" && (r.e->bit_size == 8 || r.e->bit_size == 16 || r.e->bit_size == 32) &&
                r.e->type.rfind("STRING", 0) != 0 && cands.size() < 40)
                cands.emplace_back(r.obj->index, r.e->subindex, r.e->bit_size / 8);
    } else {
        cands = {{0x1001, 0, 1}, {0x1018, 0, 1}, {0x1000, 0, 4}};
    }
    for (auto [i, s, n] : cands) {
        SdoAnswer a = sdo_raw(ctx, sdo_req(0x40, i, s));
        end_open_sdo(ctx);  // a server may answer in the normal form with segments to follow: not wanted
        if (a.error != Error::Ok) return fail(hex(i) + ":" + dec(s) + " upload", a.describe());
        if (a.is_abort()) continue;  // access rules are other tests' business
        const uint8_t c = a.cmd();
        if ((c & 0xE0) != 0x40)
            return fail(hex(i) + ":" + dec(s) + ": not an upload response", hex(c, 2), "0x4f/0x4b/0x43");
        // The server chooses the form (CiA 301 SDO upload initiate; ETG.1000.6): expedited with the size
        // indicated (judged), expedited without (s = 0: no size to judge), or normal with the size field.
        unsigned got = 0;
        if ((c & 0x03) == 0x03)
            got = 4u - ((c >> 2) & 3u);
        else if ((c & 0x03) == 0x02)
            continue;
        else if ((c & 0x03) == 0x01 && a.p.size() >= 10)
            got = get32(&a.p[6]);
        else
            return fail(hex(i) + ":" + dec(s) + ": upload response without its size", hex(c, 2),
                        "0x4f/0x4b/0x43, 0x42 or 0x41 with the size");
        if (got != n)
            return fail(hex(i) + ":" + dec(s) + ": size in the upload response", dec(got) + " bytes",
                        dec(n) + " bytes");
    }
    return pass(dec(static_cast<long long>(cands.size())) + " entries");
}

// A writable entry of the ESI downloaded with its own value, in one of the four ways; every field of each
// response checked (expect_response).
enum class Download { Expedited, Normal, Segmented, WrongToggle };
Outcome download_own_value(Context& ctx, Download how) {
    CONFORM_NEED(ctx.need_coe());
    CONFORM_NEED(ctx.need_esi());
    CONFORM_PREOP(ctx);
    const bool segmented = how == Download::Segmented || how == Download::WrongToggle;
    std::vector<EntryRef> st;
    const EntryRef* r = pick_rw(ctx, st, segmented ? 16 : 8, 32);
    if (!r)
        return skip(segmented ? "no writable 2..4-byte entry in the ESI"
                              : "no writable 1..4-byte entry in the ESI");
    const uint16_t index = r->obj->index;
    const uint8_t sub = r->e->subindex;
    const std::string name = hex(index) + ":" + dec(sub);
    auto v = ctx.upload(index, sub);
    if (!v) return fail("upload: " + ctx.sdo_error(v.error()));
    const auto size = static_cast<uint32_t>(v->size());
    if (how == Download::Expedited) {
        uint32_t value = 0;
        for (std::size_t i = 0; i < v->size() && i < 4; ++i)
            value |= static_cast<uint32_t>((*v)[i]) << (8 * i);
        return expect_response(
            sdo_raw(ctx, sdo_req(static_cast<uint8_t>(0x23 | ((4 - size) << 2)), index, sub, value)), 3,
            index, sub, false, name);
    }
    auto req = sdo_req(0x21, index, sub, size);
    if (how == Download::Normal) req.insert(req.end(), v->begin(), v->end());
    SdoAnswer a = sdo_raw(ctx, req);
    Outcome o = expect_response(a, 3, index, sub, false, name + (segmented ? " initiate" : ""));
    // Everything in one last segment, toggle 0 (or 1, wrong, on the first segment).
    std::vector<uint8_t> seg(10, 0);
    seg[1] = 0x20;
    seg[2] = static_cast<uint8_t>((how == Download::WrongToggle ? 0x10 : 0) | 0x01 | ((7 - size) << 1));
    std::copy(v->begin(), v->end(), seg.begin() + 3);
    if (!segmented || o.status != Status::Pass) {
        // An initiate taken (download response, wrong only in a field) leaves the transfer open in the
        // slave: its last segment (right toggle) closes it, so the failure stays in this test.
        if (segmented && a.error == Error::Ok && a.mailbox_type == 3 && (a.cmd() & 0xE0) == 0x60) {
            seg[2] = static_cast<uint8_t>(seg[2] & ~0x10);
            (void)sdo_raw(ctx, seg);
        }
        return o;
    }
    SdoAnswer s = sdo_raw(ctx, seg);
    if (how == Download::WrongToggle) {
        if (!s.is_abort()) return fail("wrong toggle taken", s.describe(), "abort 0x05030000");
        return expect_eq("abort code", hex(s.abort_code(), 8), hex(0x05030000, 8));
    }
    if (s.is_abort() || s.cmd() != 0x20 || s.p.size() != 10)
        return fail("segment response", s.describe(), "0x20 (toggle 0), mailbox length 10");
    return pass(name);
}

// The first RxPDO of the ESI a master may remap (PdoConfig announced; not Fixed, with entries) in `p`, the
// slave in PREOP; else the skip (or failure to reach PREOP) that says why not.
Outcome remappable_rxpdo(Context& ctx, const EsiPdo*& p) {
    CONFORM_NEED(ctx.need_esi());
    if (!ctx.esi->coe.pdo_config) return skip("the ESI does not announce PdoConfig");
    CONFORM_PREOP(ctx);
    for (const auto& x : ctx.esi->rxpdos)
        if (!x.fixed && !x.entries.empty()) {
            p = &x;
            return pass();
        }
    return skip("no configurable RxPDO");
}

// An entry of the first configurable RxPDO written while its subindex 0 is not 0: another valid entry
// (subindex 2's) into subindex 1, a real change of an active mapping; a write taken is undone. The answer in
// `a`; an outcome other than a pass where the test cannot run.
Outcome entry_written_while_active(Context& ctx, const EsiPdo*& p, SdoAnswer& a) {
    if (Outcome o = remappable_rxpdo(ctx, p); o.status != Status::Pass) return o;
    auto v = ctx.upload_uint(p->index, 1);
    auto v2 = ctx.upload_uint(p->index, 2);
    if (!v || !v2)
        return fail(hex(p->index) + ":01/:02 upload: " + ctx.sdo_error(!v ? v.error() : v2.error()));
    a = sdo_raw(ctx, sdo_req(0x23, p->index, 1, static_cast<uint32_t>(*v2)));
    if (!a.is_abort()) (void)ctx.download_uint(p->index, 1, *v, 4);
    return pass();
}

// A mapping object's entries (subindex 1..:00) as read, for putting them back.
master::Result<std::vector<uint64_t>> read_mapping(Context& ctx, uint16_t index) {
    auto n = ctx.upload_uint(index, 0);
    if (!n) return n.error();
    std::vector<uint64_t> entries;
    for (uint8_t sub = 1; sub <= *n; ++sub) {
        auto v = ctx.upload_uint(index, sub);
        if (!v) return v.error();
        entries.push_back(*v);
    }
    return entries;
}

// Writes a mapping as a master does (ETG.1000.6 PDO mapping): subindex 0 to 0, the entries, the count.
Error write_mapping(Context& ctx, uint16_t index, const std::vector<uint64_t>& entries,
                    uint8_t entry_bytes = 4) {
    Error e = ctx.download_uint(index, 0, 0, 1);
    for (std::size_t k = 0; k < entries.size() && e == Error::Ok; ++k)
        e = ctx.download_uint(index, static_cast<uint8_t>(k + 1), entries[k], entry_bytes);
    return e == Error::Ok ? ctx.download_uint(index, 0, entries.size(), 1) : e;
}

// A mapping or assignment the slave must refuse, written as a master does: subindex 0 to 0, `value` into
// subindex 1 (`bytes` long), subindex 0 to 1. The refusal may come at the entry, at subindex 0 or, at the
// latest, as a refused PREOP -> SAFEOP; judge(abort, subindex) judges an abort.
Outcome refused_pdo_write(Context& ctx, uint16_t index, uint32_t value, uint8_t bytes,
                          const std::string& what,
                          const std::function<Outcome(const SdoAnswer&, uint8_t)>& judge) {
    if (ctx.download_uint(index, 0, 0, 1) != Error::Ok) return fail(hex(index) + ":00 = 0 refused");
    if (SdoAnswer a = sdo_raw(ctx, sdo_req(bytes == 2 ? 0x2B : 0x23, index, 1, value)); a.is_abort())
        return judge(a, 1);
    if (SdoAnswer b = sdo_raw(ctx, sdo_req(0x2F, index, 0, 1)); b.is_abort()) return judge(b, 0);
    // Taken by both writes: a device may check at PREOP -> SAFEOP instead; it must refuse there.
    const Error e = ctx.to_safeop();
    (void)ctx.to_preop();
    if (e == Error::Ok)
        return fail(what + ": taken, and SAFEOP reached with it", "acknowledged",
                    "an abort, or a refused PREOP -> SAFEOP");
    return pass(what + ": refused at PREOP -> SAFEOP", err(e));
}

// An ESI that announces PdoAssign but declares the SM's assignment object read-only (Beckhoff's EKM1101:
// 0x1C12 "ro", its one RxPDO fixed): the assignment cannot be written whatever PdoAssign says, and
// od.read_only judges that a write is refused. "" when the ESI lets the assignment be written.
std::string need_assign_writable(const Context& ctx, uint16_t index) {
    if (!ctx.esi) return {};
    const EsiObject* o = ctx.esi->object(index);
    if (!o) return {};
    for (uint8_t sub : {uint8_t{0}, uint8_t{1}})
        if (const EsiEntry* e = o->entry(sub); e && e->access == "ro")
            return "the ESI declares " + hex(index) + ":" + hex(sub, 2) +
                   " read-only (od.read_only checks that a write is refused)";
    return {};
}

}  // namespace

void add_sdo_tests(Catalogue& c) {
    Adder add{c, "sdo"};
    add(
        "upload.expedited", "Upload of 0x1000: the 4 bytes, expedited (0x43, 0x42) or normal (0x41)", kSdo,
        {&Context::need_coe},
        [](Context& ctx) {
            SdoAnswer a = sdo_raw(ctx, sdo_req(0x40, 0x1000, 0));
            if (Outcome o = expect_response(a, 2, 0x1000, 0, false, "0x1000"); o.status != Status::Pass)
                return o;
            // Expedited with or without the size indicated (0x43, 0x42), or normal with size 4 (0x41): the
            // server's choice (CiA 301 SDO upload initiate; ETG.1000.6).
            const bool normal4 = a.cmd() == 0x41 && a.p.size() == 14 && get32(&a.p[6]) == 4;
            if (a.cmd() != 0x43 && a.cmd() != 0x42 && !normal4)
                return fail("upload response command", hex(a.cmd(), 2), "0x43, 0x42, or 0x41 with 4 bytes");
            if (normal4) return pass("0x1000", hex(get32(&a.p[10]), 8));
            return pass("0x1000", hex(get32(&a.p[6]), 8));
        },
        "CoE");
    add("upload.expedited_size", "Expedited upload responses give the entry's size (1, 2, 4 bytes)", kSdo,
        expedited_sizes, "CoE");
    add(
        "upload.response_fields",
        "Upload responses of 0x1000, 0x1008, 0x1018:00-04, 0x1C00, 0x1C12, 0x1C13 entries: every field as "
        "the request (index, subindex, specifier, service, length)",
        kSdo, {&Context::need_coe},
        [](Context& ctx) {
            const std::pair<uint16_t, uint8_t> probes[] = {
                {0x1000, 0}, {0x1008, 0}, {0x1018, 0}, {0x1018, 1}, {0x1018, 2}, {0x1018, 3}, {0x1018, 4},
                {0x1C00, 0}, {0x1C00, 1}, {0x1C00, 2}, {0x1C12, 0}, {0x1C13, 0}, {0x1C12, 1}, {0x1C13, 1}};
            unsigned n = 0;
            for (auto [i, s] : probes) {
                SdoAnswer a = sdo_raw(ctx, sdo_req(0x40, i, s));
                end_open_sdo(ctx);  // 0x1008 may come in segments: only the initiate response is judged
                if (a.is_abort()) continue;  // not every device has every one of them
                Outcome o = expect_response(a, 2, i, s, false, "upload " + hex(i) + ":" + dec(s));
                if (o.status != Status::Pass) return o;
                ++n;
            }
            if (n == 0) return fail("none of the probed entries could be uploaded");
            return pass(dec(n) + " responses");
        },
        "CoE");
    add(
        "upload.normal", "Normal upload of an object of 5..mailbox bytes: size indicated, data complete",
        kSdo, {&Context::need_coe},
        [](Context& ctx) {
            uint16_t idx = 0x1008;
            uint8_t sub = 0;
            std::size_t want = 0;
            bool text = false;
            bool free_text = false;  // a STRING without a default text: its length is the device's
            if (ctx.esi) {
                idx = 0;
                const auto long_readable = [&](const EntryRef& r) {
                    return r.e->access != "wo" && r.e->bit_size > 32 &&
                           r.e->bit_size / 8u + 10 <= ctx.mbx->max_in_payload();
                };
                // A diagnosis message (0x10F3:06 and up, ETG.1020) is as long as the message it holds, empty
                // slots 0 bytes, whatever the ESI's array size: never the entry judged.
                const auto diag_message = [](const EntryRef& r) {
                    return r.obj->index == 0x10F3 && r.e->subindex >= 6;
                };
                // A STRING only with a default text of 5 bytes or more: its text may be shorter than its
                // capacity, and one of up to 4 bytes comes expedited. Else a STRING without such a default:
                // the device's text decides the form.
                for (const bool any_text : {false, true}) {
                    for (const auto& r : esi_entries(*ctx.esi))
                        if (long_readable(r) && !diag_message(r) &&
                            (any_text ? visible_string(*r.e)
                                      : !visible_string(*r.e) || default_text_bytes(*r.e) > 4)) {
                            idx = r.obj->index, sub = r.e->subindex, want = r.e->bit_size / 8u;
                            text = visible_string(*r.e);
                            free_text = any_text;
                            break;
                        }
                    if (idx) break;
                }
                if (!idx) return skip("no readable object of 5 bytes or more in the ESI");
            }
            SdoAnswer a = sdo_raw(ctx, sdo_req(0x40, idx, sub));
            if (a.is_abort() && !ctx.esi) return skip("0x1008 not present");
            if (a.error != Error::Ok || a.mailbox_type != 3) return fail("no SDO answer", a.describe());
            if (free_text && (a.cmd() & 0xE2) == 0x42)  // a text of up to 4 bytes comes expedited (CiA 301)
                return skip(hex(idx) + ":" + dec(sub) + " holds a text of 4 bytes or less: expedited");
            if (a.cmd() != 0x41)
                return fail(hex(idx) + ":" + dec(sub) + " normal upload response command", a.describe(),
                            "0x41");
            const uint32_t size = get32(&a.p[6]);
            if (a.p.size() - 10 != size)
                return fail("data length against the size field",
                            dec(static_cast<long long>(a.p.size() - 10)), dec(size));
            if (want && (text ? size > want : size != want))
                return fail("size against the ESI", dec(size),
                            (text ? "at most " : "") + dec(static_cast<long long>(want)));
            return pass(hex(idx) + ":" + dec(sub), dec(size) + " bytes");
        },
        "CoE");
    add(
        "upload.segmented",
        "Segmented upload of an object larger than the mailbox: complete, toggles alternate", kSdo,
        {&Context::need_coe, &Context::need_esi},
        [](Context& ctx) {
            auto b = big_object(ctx);
            if (!b) return skip("no object larger than the mailbox in the ESI");
            auto r = ctx.upload(b->index, b->sub, b->ca);
            if (!r)
                return fail(hex(b->index) + (b->ca ? " (complete access)" : "") +
                            " upload: " + ctx.sdo_error(r.error()));
            return pass(hex(b->index), dec(static_cast<long long>(r->size())) + " bytes");
        },
        "ESI with an object larger than the mailbox");
    add(
        "upload.toggle_error", "Upload segment request with the wrong toggle bit: abort 0x05030000", kAbort,
        {&Context::need_coe, &Context::need_esi},
        [](Context& ctx) {
            auto b = big_object(ctx);
            if (!b) return skip("no object larger than the mailbox in the ESI");
            SdoAnswer a =
                sdo_raw(ctx, sdo_req(static_cast<uint8_t>(0x40 | (b->ca ? 0x10 : 0)), b->index, b->sub));
            if (a.error != Error::Ok || (a.cmd() & 0xEF) != 0x41)
                return fail("initiate upload", a.describe(), "0x41 (segmented)");
            std::vector<uint8_t> seg = sdo_req(0x70, 0, 0);  // upload segment, toggle 1: the first must be 0
            for (int i = 3; i < 10; ++i)
                seg[static_cast<std::size_t>(i)] = 0;
            SdoAnswer s = sdo_raw(ctx, seg);
            if (!s.is_abort()) return fail("wrong toggle not aborted", s.describe(), "abort 0x05030000");
            return expect_eq("abort code", hex(s.abort_code(), 8), hex(0x05030000, 8));
        },
        "ESI with an object larger than the mailbox");
    add(
        "upload.toggle_sequence",
        "Segmented upload responses alternate the toggle bit from 0; bit 0 (last segment) only in the last",
        kSdo, {&Context::need_coe, &Context::need_esi},
        [](Context& ctx) {
            auto b = big_object(ctx);
            if (!b) return skip("no object larger than the mailbox in the ESI");
            SdoAnswer a =
                sdo_raw(ctx, sdo_req(static_cast<uint8_t>(0x40 | (b->ca ? 0x10 : 0)), b->index, b->sub));
            if (a.error != Error::Ok || (a.cmd() & 0xEF) != 0x41)
                return fail("initiate upload", a.describe(), "0x41 (segmented)");
            std::size_t done = a.p.size() - 10;
            const std::size_t size = get32(&a.p[6]);
            uint8_t t = 0;
            // Every segment response is a new mailbox message (ETG.1000.4 mailbox counter): a counter equal
            // to the reply before it is a repeat to a master, which drops it.
            uint8_t counter = ctx.mbx ? ctx.mbx->last_rx_counter() : 0;
            for (int n = 0; done < size && n < 64; ++n, t ^= 1) {
                std::vector<uint8_t> seg(10, 0);
                seg[1] = 0x20;
                seg[2] = static_cast<uint8_t>(0x60 | (t << 4));
                SdoAnswer s = sdo_raw(ctx, seg);
                if (s.error != Error::Ok || s.mailbox_type != 3 || s.is_abort())
                    return fail("segment " + dec(n), s.describe());
                if (ctx.mbx) {
                    const uint8_t now = ctx.mbx->last_rx_counter();
                    if (now == 0 || now == counter)
                        return fail("segment " + dec(n) + ": mailbox counter of the reply before it, or 0",
                                    dec(now), "1..7, not " + dec(counter));
                    counter = now;
                }
                if (((s.cmd() >> 4) & 1) != t)
                    return fail("toggle of segment " + dec(n), dec((s.cmd() >> 4) & 1), dec(t));
                const std::size_t len = s.p.size() == 10 ? 7u - ((s.cmd() >> 1) & 7u) : s.p.size() - 3;
                done += len;
                // Bit 0 of a segment (ETG.1000.6 upload segment response, c): set in the segment that
                // completes the size indicated, clear in every one before it.
                if (((s.cmd() & 1) != 0) != (done >= size))
                    return fail("segment " + dec(n) + ": last-segment bit 0 against the bytes still due",
                                hex(s.cmd(), 2) + " after " + dec(static_cast<long long>(done)) + " of " +
                                    dec(static_cast<long long>(size)) + " bytes",
                                done >= size ? "bit 0 set (no more segments)" : "bit 0 clear");
                if (s.cmd() & 1) break;
            }
            if (done != size)
                return fail("bytes received", dec(static_cast<long long>(done)),
                            dec(static_cast<long long>(size)));
            return pass("segments", dec(static_cast<long long>(size)) + " bytes");
        },
        "ESI with an object larger than the mailbox");
    // A writable entry downloaded with its own value, in each of the four ways (download_own_value).
    const struct {
        const char* id;
        const char* title;
        const char* clause;
        Download how;
    } downloads[] = {
        {"download.expedited", "Expedited download of a writable entry (its own value): response 0x60", kSdo,
         Download::Expedited},
        {"download.normal", "Normal (size-indicated) download of a writable entry: response 0x60", kSdo,
         Download::Normal},
        {"download.segmented", "Segmented download (initiate, then a last segment): value taken", kSdo,
         Download::Segmented},
        {"download.toggle_error", "Download segment with the wrong toggle bit: abort 0x05030000", kAbort,
         Download::WrongToggle},
    };
    for (const auto& d : downloads)
        add(
            d.id, d.title, d.clause, [how = d.how](Context& ctx) { return download_own_value(ctx, how); },
            "ESI given");
    add(
        "abort.missing_object", "Upload of a missing object: abort 0x06020000", kAbort, {&Context::need_coe},
        [](Context& ctx) {
            const uint16_t i = missing_index(ctx);
            return expect_abort(sdo_raw(ctx, sdo_req(0x40, i, 0)), i, 0, {0x06020000}, "upload " + hex(i));
        },
        "CoE");
    add(
        "abort.missing_object_download", "Download to a missing object: abort 0x06020000", kAbort,
        {&Context::need_coe},
        [](Context& ctx) {
            const uint16_t i = missing_index(ctx);
            return expect_abort(sdo_raw(ctx, sdo_req(0x2F, i, 0, 1)), i, 0, {0x06020000},
                                "download " + hex(i));
        },
        "CoE");
    add(
        "abort.missing_subindex", "Upload of a missing subindex of 0x1018: abort 0x06090011", kAbort,
        {&Context::need_coe},
        [](Context& ctx) {
            auto n = ctx.upload_uint(0x1018, 0);
            if (!n) return fail("0x1018:00 upload: " + ctx.sdo_error(n.error()));
            const uint8_t s = static_cast<uint8_t>(*n + 1);
            return expect_abort(sdo_raw(ctx, sdo_req(0x40, 0x1018, s)), 0x1018, s, {0x06090011},
                                "0x1018:" + dec(s));
        },
        "CoE");
    add(
        "abort.missing_subindex_var",
        "Upload of subindex 1 of a VAR object (0x1000 device type): abort 0x06090011, not the value", kAbort,
        {&Context::need_coe},
        [](Context& ctx) {
            // A VAR has subindex 0 only (ETG.1000.6 / CiA 301 object code VAR): a server that ignores the
            // subindex of a VAR answers every subindex with the value.
            return expect_abort(sdo_raw(ctx, sdo_req(0x40, 0x1000, 1)), 0x1000, 1, {0x06090011}, "0x1000:1");
        },
        "CoE");
    add(
        "abort.write_read_only",
        "Download to the read-only 0x1018:01: abort 0x06010002 (or the general 0x06010000 of its family)",
        kAbort, {&Context::need_coe},
        [](Context& ctx) {
            auto v = ctx.upload_uint(0x1018, 1);
            if (!v) return fail("0x1018:01 upload: " + ctx.sdo_error(v.error()));
            return expect_abort(sdo_raw(ctx, sdo_req(0x23, 0x1018, 1, static_cast<uint32_t>(*v))), 0x1018, 1,
                                {0x06010002, 0x06010000}, "write 0x1018:01");
        },
        "CoE");
    add(
        "abort.command_byte_download",
        "Abort of a failed download: command byte 0x80, index and subindex echoed", kAbort,
        {&Context::need_coe},
        [](Context& ctx) {
            SdoAnswer a = sdo_raw(ctx, sdo_req(0x23, 0x1018, 1, 0));
            if (a.error != Error::Ok || a.mailbox_type != 3 || a.p.size() < 10)
                return fail("no answer", a.describe());
            if (a.cmd() != 0x80) return fail("command byte of the refusal", hex(a.cmd(), 2), "0x80");
            if (get16(&a.p[3]) != 0x1018 || a.p[5] != 1)
                return fail("index/subindex", bytes_hex(std::span<const uint8_t>(a.p).subspan(3, 3)),
                            "18 10 01");
            return pass("abort", a.describe());
        },
        "CoE");
    add(
        "abort.command_byte_upload", "Abort of a failed upload: command byte 0x80, index and subindex echoed",
        kAbort, {&Context::need_coe},
        [](Context& ctx) {
            const uint16_t i = missing_index(ctx);
            SdoAnswer a = sdo_raw(ctx, sdo_req(0x40, i, 3));
            if (a.error != Error::Ok || a.mailbox_type != 3 || a.p.size() < 10)
                return fail("no answer", a.describe());
            if (a.cmd() != 0x80) return fail("command byte", hex(a.cmd(), 2), "0x80");
            if (get16(&a.p[3]) != i || a.p[5] != 3)
                return fail("index/subindex not echoed",
                            bytes_hex(std::span<const uint8_t>(a.p).subspan(3, 3)));
            return pass("abort", a.describe());
        },
        "CoE");
    add(
        "abort.unknown_command", "Request with client command specifier 7: abort 0x05040001", kAbort,
        {&Context::need_coe},
        [](Context& ctx) {
            return expect_abort(sdo_raw(ctx, sdo_req(0xE0, 0x1000, 0)), 0x1000, 0, {0x05040001},
                                "command 0xe0");
        },
        "CoE");
    add(
        "abort.length_too_long",
        "Download of more bytes than the entry holds: abort 0x06070012 (or 0x06070010)", kAbort,
        {&Context::need_coe, &Context::need_esi},
        [](Context& ctx) {
            std::vector<EntryRef> st;
            const EntryRef* r = pick_rw(ctx, st, 8, 16);
            if (!r) return skip("no writable 1..2-byte entry in the ESI");
            return expect_abort(sdo_raw(ctx, sdo_req(0x23, r->obj->index, r->e->subindex, 0)), r->obj->index,
                                r->e->subindex, {0x06070012, 0x06070010},
                                "4 bytes to " + dec(r->e->bit_size) + " bits");
        },
        "ESI given");
    add(
        "abort.length_too_short",
        "Download of fewer bytes than the entry holds: abort 0x06070013 (or 0x06070010)", kAbort,
        {&Context::need_coe, &Context::need_esi},
        [](Context& ctx) {
            std::vector<EntryRef> st;
            const EntryRef* r = pick_rw(ctx, st, 32, 32);
            if (!r) return skip("no writable 4-byte entry in the ESI");
            return expect_abort(sdo_raw(ctx, sdo_req(0x2F, r->obj->index, r->e->subindex, 0)), r->obj->index,
                                r->e->subindex, {0x06070013, 0x06070010}, "1 byte to 32 bits");
        },
        "ESI given");
    for (bool high : {true, false}) {
        add(
            high ? "abort.value_too_high" : "abort.value_too_low",
            std::string("Download above the ESI's ") + (high ? "MaxValue: abort 0x06090031 (or 0x06090030)"
                                                             : "MinValue: abort 0x06090032 (or 0x06090030)"),
            kAbort,
            [high](Context& ctx) {
                CONFORM_NEED(ctx.need_coe());
                CONFORM_NEED(ctx.need_esi());
                CONFORM_PREOP(ctx);
                std::vector<EntryRef> st;
                const EntryRef* r = pick_rw(ctx, st, 8, 32, true, high);
                if (!r)
                    return skip(std::string("no writable entry with a ") +
                                (high ? "MaxValue below" : "MinValue above") + " its type's range");
                const int64_t v = high ? *r->e->max + 1 : *r->e->min - 1;
                const unsigned n = r->e->bit_size / 8u;
                SdoAnswer a = sdo_raw(ctx, sdo_req(static_cast<uint8_t>(0x23 | ((4 - n) << 2)), r->obj->index,
                                                   r->e->subindex, static_cast<uint32_t>(v)));
                return expect_abort(a, r->obj->index, r->e->subindex,
                                    {high ? 0x06090031u : 0x06090032u, 0x06090030u},
                                    hex(r->obj->index) + ":" + dec(r->e->subindex) + " = " + dec(v));
            },
            "ESI with limits");
    }
    add(
        "abort.mapping_in_safeop", "PDO assignment 0x1C12 written in SAFEOP: refused with an abort",
        "ETG.1000.6 CoE PDO assignment (changed in PREOP only)",
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_coe());
            if (Error e = ctx.to_safeop(); e != Error::Ok) return fail("cannot reach SAFEOP: " + err(e));
            if (!ctx.has_process_data())
                return skip("no process data (no PDO assigned to a process-data SM)");
            auto v = ctx.upload_uint(0x1C12, 0);
            if (!v) return fail("0x1C12:00 upload: " + ctx.sdo_error(v.error()));
            SdoAnswer a = sdo_raw(ctx, sdo_req(0x2F, 0x1C12, 0, static_cast<uint32_t>(*v)));
            return expect_abort(a, 0x1C12, 0, {0x08000022, 0x06010002, 0x08000020}, "0x1C12:00 in SAFEOP");
        },
        "CoE");
    add(
        "abort.mapping_object_in_safeop",
        "PDO mapping object (first RxPDO) written in SAFEOP: refused with an abort",
        "ETG.1000.6 CoE PDO mapping (changed in PREOP only)",
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_coe());
            if (Error e = ctx.to_safeop(); e != Error::Ok) return fail("cannot reach SAFEOP: " + err(e));
            const std::vector<uint16_t> rx = ctx.pds->layout().pdos(true);
            const std::vector<uint16_t> pdos = rx.empty() ? ctx.pds->layout().pdos(false) : rx;
            if (pdos.empty()) return skip("no PDO assigned");
            auto v = ctx.upload_uint(pdos[0], 0);
            if (!v) return fail(hex(pdos[0]) + ":00 upload: " + ctx.sdo_error(v.error()));
            SdoAnswer a = sdo_raw(ctx, sdo_req(0x2F, pdos[0], 0, static_cast<uint32_t>(*v)));
            return expect_abort(a, pdos[0], 0, {0x08000022, 0x06010002, 0x08000020},
                                hex(pdos[0]) + ":00 in SAFEOP");
        },
        "CoE");
    add(
        "abort.mapping_sub0_nonzero", "Mapping entry written while subindex 0 is not 0: abort 0x06010003",
        "ETG.1000.6 CoE PDO mapping (subindex 0 set to 0 before entries change)",
        [](Context& ctx) {
            const EsiPdo* p = nullptr;
            SdoAnswer a;
            if (Outcome o = entry_written_while_active(ctx, p, a); o.status != Status::Pass) return o;
            return expect_abort(a, p->index, 1, {0x06010003}, hex(p->index) + ":01");
        },
        "ESI announces PdoConfig", Severity::Warning);
    add(
        "abort.mapping_sub0_nonzero_code",
        "Mapping entry written while subindex 0 is not 0, where refused: with 0x06010003 or the general "
        "0x06010000 of its family, not a code of another situation",
        "ETG.1000.6 SDO abort codes (0x06010003: subindex cannot be written, SI0 must be 0 for write access)",
        [](Context& ctx) {
            const EsiPdo* p = nullptr;
            SdoAnswer a;
            if (Outcome o = entry_written_while_active(ctx, p, a); o.status != Status::Pass) return o;
            // Taking the write is a warning of its own; a refusal must name this situation.
            if (!a.is_abort()) return skip("taken (see sdo.abort.mapping_sub0_nonzero, a warning)");
            return expect_abort(a, p->index, 1, {0x06010003, 0x06010000}, hex(p->index) + ":01");
        },
        "ESI announces PdoConfig");
    for (auto [sub, word, name] : {std::tuple<uint8_t, std::size_t, const char*>{1, 0x08, "vendor"},
                                   {2, 0x0A, "product"},
                                   {3, 0x0C, "revision"},
                                   {4, 0x0E, "serial"}}) {
        add(
            std::string("identity.") + name,
            std::string("0x1018:0") + dec(sub) + " (" + name + ") equals the SII",
            "ETG.1000.6 identity object 0x1018; SII words 0x08-0x0F",
            [s = sub, w = word](Context& ctx) { return identity(ctx, s, w); },
            "CoE");  // clang 14: no binding capture
    }
    add(
        "device_type_vs_esi", "0x1000 device type equals the ESI's default", kOd,
        {&Context::need_coe, &Context::need_esi},
        [](Context& ctx) {
            const EsiObject* o = ctx.esi->object(0x1000);
            if (!o || o->entries.empty() || o->entries[0].default_data.size() < 4)
                return skip("no 0x1000 default in the ESI");
            auto v = ctx.upload(0x1000, 0);
            if (!v) return fail("upload: " + ctx.sdo_error(v.error()));
            return expect_eq("0x1000", bytes_hex(*v), bytes_hex(o->entries[0].default_data));
        },
        "ESI given");
    add(
        "device_name_vs_esi",
        "0x1008 manufacturer device name equals the ESI's DefaultString (read-only object)",
        "ETG.1000.6 0x1008 manufacturer device name; ETG.2000 Dictionary/Objects/Object/Info/DefaultString",
        {&Context::need_coe, &Context::need_esi},
        [](Context& ctx) {
            const EsiObject* o = ctx.esi->object(0x1008);
            const EsiEntry* e = o ? o->entry(0) : nullptr;
            if (!e || e->default_data.empty() || !e->default_is_string)
                return skip("no 0x1008 DefaultString in the ESI");
            if (e->access != "ro") return skip("0x1008 writable in the ESI (" + e->access + ")");
            auto v = ctx.upload(0x1008, 0);
            if (!v) return fail("upload: " + ctx.sdo_error(v.error()));
            // A device may pad the string to its declared size with NULs or blanks (VISIBLE_STRING): compared
            // without.
            auto text = [](std::vector<uint8_t> b) {
                while (!b.empty() && (b.back() == 0 || b.back() == ' '))
                    b.pop_back();
                return std::string(b.begin(), b.end());
            };
            return expect_eq("0x1008", printable(text(*v)), printable(text(e->default_data)));
        },
        "ESI given");
    add(
        "sm_types", "0x1C00 SM communication types equal the SII SyncM types, subindex 0 counts them",
        "ETG.1000.6 0x1C00 sync manager communication type", {&Context::need_coe},
        [](Context& ctx) {
            const SiiCategory* sm = ctx.sii->find(41);
            if (!sm) return skip("no SII SyncM category");
            auto n = ctx.upload_uint(0x1C00, 0);
            if (!n) return fail("0x1C00:00 upload: " + ctx.sdo_error(n.error()));
            std::string got, want;
            auto d = ctx.sii->data(*sm);
            // Subindex 0 counts the SMs the device uses (ETG.1000.6 0x1C00): every SM of the SII up to the
            // last one with a type; a count short of them hides the SMs after it from a master.
            std::size_t used = 0;
            for (std::size_t i = 0; i + 8 <= d.size(); i += 8)
                if (d[i + 7] != 0) used = i / 8 + 1;
            if (*n < used)
                return fail("0x1C00:00 number of SMs against the SII SyncM category",
                            dec(static_cast<long long>(*n)), "at least " + dec(static_cast<long long>(used)));
            for (std::size_t i = 0; i + 8 <= d.size() && i / 8 < *n; i += 8) {
                auto t = ctx.upload_uint(0x1C00, static_cast<uint8_t>(i / 8 + 1));
                got += (t ? dec(static_cast<long long>(*t)) : "?") + " ";
                want += dec(d[i + 7]) + " ";
            }
            return expect_eq("types", got, want);
        },
        "CoE");
    add(
        "od.present", "Every object of the ESI answers an upload of subindex 0 (or of its only entry)", kOd,
        {&Context::need_coe, &Context::need_esi},
        [](Context& ctx) {
            std::string missing;
            for (const auto& [i, o] : ctx.esi->objects) {
                if (!o.entries.empty() && o.entries[0].access == "wo") continue;
                SdoAnswer a = sdo_raw(ctx, sdo_req(0x40, i, 0));
                end_open_sdo(ctx);  // a long entry (a VAR's text) answers with a transfer: not wanted here
                if (a.error != Error::Ok) return fail(hex(i) + ": " + a.describe());
                if (a.is_abort() && (a.abort_code() == 0x06020000 || a.abort_code() == 0x06090011))
                    missing += hex(i) + " ";
            }
            if (!missing.empty()) return fail("objects of the ESI missing in the slave", missing, "none");
            return pass(dec(static_cast<long long>(ctx.esi->objects.size())) + " objects");
        },
        "ESI given");
    add(
        "store.wrong_signature",
        "0x1010/0x1011 :01 written without the signature (\"save\"/\"load\"): refused with an abort "
        "(0x08000020 or another 0x080000xx), nothing stored or restored",
        "CiA 301 / ETG.1000.6 store parameters 0x1010, restore default parameters 0x1011: the signature "
        "0x65766173 \"save\" / 0x64616F6C \"load\"; another value is refused (abort 0x08000020)",
        {&Context::need_coe},
        [](Context& ctx) {
            std::string seen;
            for (uint16_t i : {uint16_t{0x1010}, uint16_t{0x1011}}) {
                auto caps = ctx.upload_uint(i, 1);
                if (!caps) continue;  // the object (optional) is not there
                // One letter off the signature: a value a device must not take for the command. A device that
                // refuses it changes nothing; one that acknowledges it has not checked the signature.
                const uint32_t wrong = i == 0x1010 ? 0x65766174u : 0x64616F6Du;
                SdoAnswer a = sdo_raw(ctx, sdo_req(0x23, i, 1, wrong));
                if (a.error != Error::Ok) return fail(hex(i) + ":01: " + a.describe());
                if (!a.is_abort())
                    return fail(hex(i) + ":01 = " + hex(wrong, 8) + " (not the signature) acknowledged",
                                a.describe(), "an abort (0x08000020)");
                if ((a.abort_code() & 0xFFFFFF00u) != 0x08000000u)
                    return fail(hex(i) + ":01 with a wrong signature: abort code", hex(a.abort_code(), 8),
                                "0x08000020 (data cannot be stored), or another 0x080000xx");
                seen += hex(i) + " " + hex(a.abort_code(), 8) + " ";
            }
            if (seen.empty()) return skip("no 0x1010/0x1011");
            return pass("refused", seen);
        },
        "CoE, 0x1010 or 0x1011");
    add(
        "od.subindex0_highest",
        "Subindex 0 of every ESI object with entries names a subindex that exists (its highest, or the count "
        "of an array's entries)",
        "ETG.1000.6 / CiA 301 object dictionary: subindex 0 of a RECORD is the highest subindex supported, "
        "of "
        "an ARRAY the number of entries",
        {&Context::need_coe, &Context::need_esi},
        [](Context& ctx) {
            unsigned n = 0;
            for (const auto& [i, o] : ctx.esi->objects) {
                if (o.entries.size() < 2 || o.entries[0].subindex != 0 || o.entries[0].access == "wo")
                    continue;
                auto top = ctx.upload(i, 0);
                if (!top || top->size() != 1 || (*top)[0] == 0) continue;  // od.size / od.present judge those
                const uint8_t k = (*top)[0];
                SdoAnswer a = sdo_raw(ctx, sdo_req(0x40, i, k));
                end_open_sdo(ctx);  // the highest entry may be long: its transfer is not wanted here
                if (a.error != Error::Ok) return fail(hex(i) + ":" + dec(k) + ": " + a.describe());
                ++n;
                if (a.is_abort() && a.abort_code() == 0x06090011)
                    return fail(hex(i) + ":00 = " + dec(k) + ", but subindex " + dec(k) + " does not exist",
                                "abort 0x06090011", "subindex " + dec(k) + " uploads");
            }
            return pass(dec(n) + " objects");
        },
        "ESI given");
    add(
        "od.size", "Every readable entry of the ESI uploads with its declared size", kOd,
        {&Context::need_coe, &Context::need_esi},
        [](Context& ctx) {
            unsigned n = 0;
            for (const auto& r : esi_entries(*ctx.esi)) {
                if (r.e->access == "wo" || r.e->bit_size % 8 || r.e->bit_size == 0) continue;
                if (r.obj->index == 0x10F3 && r.e->subindex > 5)
                    continue;  // ETG.1020: diagnosis messages vary in length
                auto v = ctx.upload(r.obj->index, r.e->subindex);
                if (!v) {
                    if (v.error() == Error::SdoAbort)
                        continue;  // access is od.present's and the abort tests' business
                    return fail(hex(r.obj->index) + ":" + dec(r.e->subindex) + ": " +
                                ctx.sdo_error(v.error()));
                }
                ++n;
                // A VISIBLE_STRING uploads its text, which may be shorter than the capacity STRING(n)
                // declares (ETG.1000.6 SDO upload: the data size is the object's current size; a text is not
                // padded); longer is an error.
                if (visible_string(*r.e) ? v->size() > r.e->bit_size / 8u : v->size() != r.e->bit_size / 8u)
                    return fail(
                        hex(r.obj->index) + ":" + dec(r.e->subindex) + " (" + r.e->type + ") size",
                        dec(static_cast<long long>(v->size())) + " bytes",
                        (visible_string(*r.e) ? "at most " : "") + dec(r.e->bit_size / 8u) + " bytes");
            }
            return pass(dec(n) + " entries");
        },
        "ESI given");
    add(
        "od.read_only",
        "Every read-only entry of the ESI refuses a download with 0x06010002 (or the general 0x06010000)",
        kOd, {&Context::need_coe, &Context::need_esi},
        [](Context& ctx) {
            unsigned n = 0;
            for (const auto& r : esi_entries(*ctx.esi)) {
                if (r.e->access != "ro" || r.e->subindex == 0 || r.e->bit_size > 32 || r.e->bit_size % 8 ||
                    r.e->bit_size == 0)
                    continue;
                auto v = ctx.upload_uint(r.obj->index, r.e->subindex);
                if (!v) continue;
                const unsigned b = r.e->bit_size / 8u;
                SdoAnswer a = sdo_raw(ctx, sdo_req(static_cast<uint8_t>(0x23 | ((4 - b) << 2)), r.obj->index,
                                                   r.e->subindex, static_cast<uint32_t>(*v)));
                // 0x06010000 (unsupported access to an object) is the general code of the 0x0601000x family
                // (ETG.1000.6 SDO abort codes), as 0x06070010 is of the length codes.
                Outcome o = expect_abort(a, r.obj->index, r.e->subindex, {0x06010002, 0x06010000},
                                         hex(r.obj->index) + ":" + dec(r.e->subindex));
                if (o.status != Status::Pass) return o;
                if (++n >= 40) break;
            }
            return pass(dec(n) + " entries");
        },
        "ESI given");
    add(
        "od.writable_in_op",
        "Device-profile entries the ESI declares writable in OP (not mapped) take a download in OP: their "
        "own "
        "value written back is acknowledged",
        "ETG.1000.6 SDO download; ETG.2000 object access per state (Access rw, WriteRestrictions); "
        "ETG.1000.6 "
        "abort 0x08000022 only where the state forbids the access",
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_coe());
            CONFORM_NEED(ctx.need_esi());
            CONFORM_NEED(ctx.need_pd_layout());
            // Entries 0x6000-0x6FFF writable in OP by the ESI (rw without restrictions, or restrictions that
            // name OP), of 1, 2 or 4 bytes, that no ESI PDO maps (a mapped entry is written by the process
            // data) and that are no command or device-state object: the value read is written back unchanged.
            auto in_op = [](const EsiEntry& e) {
                if (e.access != "rw") return false;
                if (e.write_restrictions.empty()) return true;
                std::size_t at = 0;
                const std::string& w = e.write_restrictions;
                while (at <= w.size()) {
                    const std::size_t end = std::min(w.find('_', at), w.size());
                    if (w.compare(at, end - at, "OP") == 0) return true;
                    at = end + 1;
                }
                return false;
            };
            auto mapped = [&](uint16_t i, uint8_t s) {
                for (const auto* list : {&ctx.esi->rxpdos, &ctx.esi->txpdos})
                    for (const EsiPdo& p : *list)
                        for (const auto& pe : p.entries)
                            if (pe.index == i && pe.subindex == s) return true;
                return false;
            };
            std::vector<const EsiEntry*> pick;
            std::vector<uint16_t> pick_index;
            for (const auto& r : esi_entries(*ctx.esi)) {
                const uint16_t i = r.obj->index;
                if (i < 0x6000 || i > 0x6FFF || !in_op(*r.e) ||
                    (r.e->bit_size != 8 && r.e->bit_size != 16 && r.e->bit_size != 32))
                    continue;
                if (command_object(*ctx.esi, i) || device_state_object(i) || mapped(i, r.e->subindex))
                    continue;
                pick.push_back(r.e);
                pick_index.push_back(i);
                if (pick.size() >= 8) break;
            }
            if (pick.empty()) return skip("no unmapped device-profile entry writable in OP in the ESI");
            if (Error e = ctx.to_op(); e != Error::Ok) return fail("cannot reach OP: " + err(e));
            std::string done;
            for (std::size_t k = 0; k < pick.size(); ++k) {
                const uint16_t i = pick_index[k];
                const uint8_t s = pick[k]->subindex;
                (void)ctx.cycle(2);
                auto v = ctx.upload_uint(i, s);
                (void)ctx.cycle(2);
                if (!v) continue;  // unreadable: the od tests' matter
                Error e = ctx.download_uint(i, s, *v, pick[k]->bit_size / 8u);
                (void)ctx.cycle(2);
                if (e != Error::Ok) {
                    (void)ctx.to_init();
                    return fail(hex(i) + ":" + dec(s) +
                                    " (writable in OP by the ESI) written in OP with its own "
                                    "value",
                                ctx.sdo_error(e), "acknowledged");
                }
                done += hex(i) + ":" + dec(s) + " ";
            }
            (void)ctx.to_init();
            if (done.empty()) return skip("none of the entries uploads");
            return pass("acknowledged in OP", done);
        },
        "ESI given");
    add(
        "od.defaults",
        "Read-only, unmapped entries hold the ESI's default value (device-state objects aside)", kOd,
        {&Context::need_coe, &Context::need_esi},
        [](Context& ctx) {
            unsigned n = 0;
            for (const auto& r : esi_entries(*ctx.esi)) {
                if (r.e->access != "ro" || !r.e->pdo_mapping.empty() || r.e->default_data.empty()) continue;
                if (r.obj->index == 0x1018 && r.e->subindex == 4) continue;  // serial number: per device
                if (device_state_object(r.obj->index)) continue;
                if (r.e->type.rfind("STRING", 0) == 0) continue;
                auto v = ctx.upload(r.obj->index, r.e->subindex);
                if (!v) continue;
                ++n;
                if (*v != r.e->default_data)
                    return fail(hex(r.obj->index) + ":" + dec(r.e->subindex) + " value", bytes_hex(*v),
                                bytes_hex(r.e->default_data));
            }
            return pass(dec(n) + " entries");
        },
        "ESI given", Severity::Warning);
    add(
        "od.limits", "Entries with ESI limits hold a value within MinValue..MaxValue", kOd,
        {&Context::need_coe, &Context::need_esi},
        [](Context& ctx) {
            unsigned n = 0;
            for (const auto& r : esi_entries(*ctx.esi)) {
                if (!r.e->min || !r.e->max || r.e->bit_size > 32 || r.e->bit_size % 8 || !r.e->bit_size)
                    continue;
                auto v = ctx.upload_uint(r.obj->index, r.e->subindex);
                if (!v) continue;
                int64_t x = static_cast<int64_t>(*v);
                const bool is_signed = r.e->type == "SINT" || r.e->type == "INT" || r.e->type == "DINT";
                if (is_signed) x = static_cast<int64_t>(*v << (64 - r.e->bit_size)) >> (64 - r.e->bit_size);
                ++n;
                if (x < *r.e->min || x > *r.e->max)
                    return fail(hex(r.obj->index) + ":" + dec(r.e->subindex) + " out of its limits", dec(x),
                                dec(*r.e->min) + ".." + dec(*r.e->max));
            }
            return pass(dec(n) + " entries");
        },
        "ESI given", Severity::Warning);
    // The padding byte after subindex 0 is checked on the identity and on both PDO assignments: a device
    // may build them differently (the assignment objects are often generated from the PDO configuration).
    for (const auto& [id, index] : {std::pair<const char*, uint16_t>{"ca.upload_padding", 0x1018},
                                    {"ca.upload_padding_1c12", 0x1C12},
                                    {"ca.upload_padding_1c13", 0x1C13}}) {
        add(
            id,
            "Complete access upload of " + hex(index) +
                " from subindex 0: subindex 0 padded to 16 bits (padding value free), then the entries",
            kCa,
            [index = index](Context& ctx) {
                CONFORM_NEED(ctx.need_complete_access());
                CONFORM_PREOP(ctx);
                auto n = ctx.upload_uint(index, 0);
                if (!n) {
                    if (index != 0x1018 && n.error() == Error::SdoAbort)
                        return skip(hex(index) + " not present");
                    return fail(hex(index) + ":00: " + ctx.sdo_error(n.error()));
                }
                std::vector<uint8_t> want = {static_cast<uint8_t>(*n), 0};
                for (uint8_t s = 1; s <= *n; ++s) {
                    auto v = ctx.upload(index, s);
                    if (!v) return fail(hex(index) + ":" + dec(s) + ": " + ctx.sdo_error(v.error()));
                    want.insert(want.end(), v->begin(), v->end());
                }
                auto ca = ctx.upload(index, 0, true);
                if (!ca) return fail("complete access upload: " + ctx.sdo_error(ca.error()));
                if (ca->size() >= 2) want[1] = (*ca)[1];  // the padding byte's value is not defined
                return expect_eq(hex(index) + " complete", bytes_hex(*ca, 64), bytes_hex(want, 64));
            },
            "complete access announced");
    }
    add(
        "ca.response_fields",
        "Complete access upload of 0x1018 from subindex 0: response with the complete-access bit, index "
        "and subindex echoed, size as the data",
        kCa, {&Context::need_complete_access},
        [](Context& ctx) {
            SdoAnswer a = sdo_raw(ctx, sdo_req(0x50, 0x1018, 0));
            Outcome o = expect_response(a, 2, 0x1018, 0, true, "complete access upload of 0x1018");
            end_open_sdo(ctx);
            return o;
        },
        "complete access announced");
    add(
        "ca.upload_from_sub1",
        "Complete access upload of 0x1018 from subindex 1: the entries without subindex 0", kCa,
        {&Context::need_complete_access},
        [](Context& ctx) {
            auto n = ctx.upload_uint(0x1018, 0);
            if (!n) return fail("0x1018:00: " + ctx.sdo_error(n.error()));
            std::vector<uint8_t> want;
            for (uint8_t s = 1; s <= *n; ++s) {
                auto v = ctx.upload(0x1018, s);
                if (!v) return fail("0x1018:" + dec(s) + ": " + ctx.sdo_error(v.error()));
                want.insert(want.end(), v->begin(), v->end());
            }
            auto ca = ctx.upload(0x1018, 1, true);
            if (!ca) return fail("complete access upload: " + ctx.sdo_error(ca.error()));
            return expect_eq("0x1018 from :01", bytes_hex(*ca, 64), bytes_hex(want, 64));
        },
        "complete access announced");
    add(
        "ca.download_assign", "Complete access download of 0x1C12 with its own value in PREOP", kCa,
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_complete_access());
            CONFORM_NEED(ctx.need_esi());
            if (!ctx.esi->coe.pdo_assign) return skip("the ESI does not announce PdoAssign");
            CONFORM_NEED(need_assign_writable(ctx, 0x1C12));
            CONFORM_PREOP(ctx);
            auto ca = ctx.upload(0x1C12, 0, true);
            if (!ca) return fail("complete access upload: " + ctx.sdo_error(ca.error()));
            // Sent raw (a normal download of the object's own image), so that the response's fields are
            // judged as those of an upload are: the complete-access bit, index and subindex, reserved bits
            // and bytes.
            std::vector<uint8_t> req = sdo_req(0x31, 0x1C12, 0, static_cast<uint32_t>(ca->size()));
            req.insert(req.end(), ca->begin(), ca->end());
            SdoAnswer a = sdo_raw(ctx, req);
            if (a.is_abort())
                return fail("complete access download: abort " + hex(a.abort_code(), 8), a.describe());
            if (Outcome o = expect_response(a, 3, 0x1C12, 0, true, "complete access download of 0x1C12");
                o.status != Status::Pass) {
                end_open_sdo(ctx);
                return o;
            }
            auto again = ctx.upload(0x1C12, 0, true);
            if (!again) return fail("upload after: " + ctx.sdo_error(again.error()));
            return expect_eq("0x1C12", bytes_hex(*again), bytes_hex(*ca));
        },
        "complete access and PdoAssign announced");
    add(
        "ca.not_announced", "Complete access refused when not announced (0x06010004, or a general code)", kCa,
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_coe());
            if (ctx.need_complete_access().empty()) return skip("complete access is announced");
            CONFORM_PREOP(ctx);
            // 0x06010004 names the case; a server that has no complete access at all may as well answer with
            // the general "unsupported access to an object" (0x06010000) or take the bit for a command
            // specifier it does not know (0x05040001). Each refuses, which is what the ESI promises.
            return expect_abort(sdo_raw(ctx, sdo_req(0x50, 0x1018, 0)), 0x1018, 0,
                                {0x06010004, 0x06010000, 0x05040001}, "complete access");
        },
        "complete access not announced");
    add(
        "pdo.assign_change", "PDO assignment changed in PREOP to another ESI PDO reads back; restored",
        "ETG.1000.6 CoE PDO assignment 0x1C12",
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_esi());
            if (!ctx.esi->coe.pdo_assign) return skip("the ESI does not announce PdoAssign");
            CONFORM_NEED(need_assign_writable(ctx, 0x1C12));
            CONFORM_PREOP(ctx);
            // Only the subindices the assignment has are read: an empty one (no outputs) may have
            // subindex 0 alone (ETG.1000.6 PDO assignment: subindices 1..n exist up to the maximum).
            auto n = ctx.upload_uint(0x1C12, 0);
            if (!n) return fail("0x1C12:00 upload: " + ctx.sdo_error(n.error()));
            if (*n != 1)
                return skip("needs one assigned RxPDO (0x1C12:00 = " + dec(static_cast<long long>(*n)) + ")");
            auto first = ctx.upload_uint(0x1C12, 1);
            if (!first) return fail("0x1C12:01 upload: " + ctx.sdo_error(first.error()));
            uint16_t other = 0;
            for (const auto& p : ctx.esi->rxpdos)
                if (p.index != *first) {
                    other = p.index;
                    break;
                }
            if (!other || *n != 1) return skip("needs one assigned RxPDO and another one in the ESI");
            Error e1 = ctx.download_uint(0x1C12, 0, 0, 1);
            Error e2 = ctx.download_uint(0x1C12, 1, other, 2);
            Error e3 = ctx.download_uint(0x1C12, 0, 1, 1);
            auto got = ctx.upload_uint(0x1C12, 1);
            (void)ctx.download_uint(0x1C12, 0, 0, 1);
            (void)ctx.download_uint(0x1C12, 1, *first, 2);
            (void)ctx.download_uint(0x1C12, 0, *n, 1);
            if (e1 != Error::Ok || e2 != Error::Ok || e3 != Error::Ok)
                return fail("assignment refused: " + ctx.sdo_error(e1 != Error::Ok   ? e1
                                                                   : e2 != Error::Ok ? e2
                                                                                     : e3));
            return expect_eq("0x1C12:01", got ? hex(*got) : "?", hex(other));
        },
        "ESI announces PdoAssign");
    add(
        "pdo.mapping_rewrite", "PDO mapping rewritten in PREOP (subindex 0 to 0, entries, count) reads back",
        "ETG.1000.6 CoE PDO mapping",
        [](Context& ctx) {
            const EsiPdo* p = nullptr;
            if (Outcome o = remappable_rxpdo(ctx, p); o.status != Status::Pass) return o;
            auto entries = read_mapping(ctx, p->index);
            if (!entries) return fail("upload: " + ctx.sdo_error(entries.error()));
            if (Error e = write_mapping(ctx, p->index, *entries); e != Error::Ok)
                return fail("mapping write: " + ctx.sdo_error(e));
            auto again = ctx.upload_uint(p->index, 0);
            return expect_eq(hex(p->index) + ":00", again ? dec(static_cast<long long>(*again)) : "?",
                             dec(static_cast<long long>(entries->size())));
        },
        "ESI announces PdoConfig");
    add(
        "pdo.mapping_not_mappable",
        "An object the ESI does not declare RxPDO-mappable written into a mapping: refused with 0x06040041 "
        "(cannot be mapped; 0x06040043 as the general code), at the entry or at subindex 0, or at the "
        "latest by PREOP -> SAFEOP; restored",
        "ETG.1000.6 CoE PDO mapping; SDO abort code 0x06040041",
        [](Context& ctx) {
            const EsiPdo* p = nullptr;
            if (Outcome o = remappable_rxpdo(ctx, p); o.status != Status::Pass) return o;
            // 0x1018:01 (vendor id) where the ESI leaves it unmappable, else the first such entry of 8..32
            // bits.
            uint16_t obj = 0;
            const EsiEntry* bad = nullptr;
            for (const auto& [index, o] : ctx.esi->objects)
                for (const auto& e : o.entries)
                    if (e.subindex > 0 && e.pdo_mapping.find_first_of("Rr") == std::string::npos &&
                        e.access != "wo" && (e.bit_size == 8 || e.bit_size == 16 || e.bit_size == 32) &&
                        (!bad || (index == 0x1018 && e.subindex == 1))) {
                        obj = index;
                        bad = &e;
                    }
            if (!bad) return skip("no unmappable entry in the ESI dictionary");
            const uint32_t value =
                static_cast<uint32_t>(obj) << 16 | static_cast<uint32_t>(bad->subindex) << 8 | bad->bit_size;
            auto entries = read_mapping(ctx, p->index);
            if (!entries) return fail("upload: " + ctx.sdo_error(entries.error()));
            const std::string what = hex(obj) + ":" + dec(bad->subindex) + " into " + hex(p->index);
            const Outcome o = refused_pdo_write(
                ctx, p->index, value, 4, what, [&p, &what](const SdoAnswer& a, uint8_t sub) {
                    return expect_abort(a, p->index, sub, {0x06040041, 0x06040043},
                                        what + (sub ? "" : ", at subindex 0"));
                });
            (void)write_mapping(ctx, p->index, *entries);
            return o;
        },
        "ESI announces PdoConfig");
    add(
        "pdo.assign_unknown_pdo",
        "A PDO index that does not exist (not in the ESI, no object) assigned to 0x1C12: refused with an "
        "abort, at the entry or at subindex 0, or at the latest by PREOP -> SAFEOP; restored",
        "ETG.1000.6 CoE PDO assignment 0x1C12 (only existing PDOs of the SM's direction)",
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_esi());
            if (!ctx.esi->coe.pdo_assign) return skip("the ESI does not announce PdoAssign");
            CONFORM_NEED(need_assign_writable(ctx, 0x1C12));
            CONFORM_PREOP(ctx);
            uint16_t none = 0;
            for (uint16_t i = 0x17FF; i >= 0x1600 && !none; --i) {
                bool listed = ctx.esi->object(i) != nullptr;
                for (const auto& x : ctx.esi->rxpdos)
                    listed = listed || x.index == i;
                if (!listed) none = i;
            }
            if (!none) return skip("every RxPDO index is used");
            auto before = read_mapping(ctx, 0x1C12);  // the assignment, read as a mapping (:00, :01..)
            if (!before) return fail("0x1C12 upload: " + ctx.sdo_error(before.error()));
            const std::string what = hex(none) + " (no such PDO) into 0x1C12:01";
            const Outcome o =
                refused_pdo_write(ctx, 0x1C12, none, 2, what, [&what](const SdoAnswer& a, uint8_t sub) {
                    return pass(what + (sub ? ": refused" : ": refused at subindex 0"), a.describe());
                });
            (void)write_mapping(ctx, 0x1C12, *before, 2);
            return o;
        },
        "ESI announces PdoAssign");
    add(
        "pdo.mapping_too_long",
        "PDO mapping filled to its last subindex with its largest entry: taken, or refused with a code of "
        "the situation (0x06040042 PDO length exceeded and kin), never 'cannot be mapped' for a mappable "
        "object",
        "ETG.1000.6 CoE PDO mapping; SDO abort codes 0x06040041/0x06040042/0x06040043",
        [](Context& ctx) {
            const EsiPdo* p = nullptr;
            if (Outcome o = remappable_rxpdo(ctx, p); o.status != Status::Pass) return o;
            const EsiObject* o = ctx.esi->object(p->index);
            if (!o || o->entries.size() < 2)
                return skip(hex(p->index) + " has no entries in the ESI dictionary");
            const uint8_t last = o->entries.back().subindex;
            const EsiPdoEntry* big = nullptr;
            for (const auto& e : p->entries)
                if (e.index && (!big || e.bit_len > big->bit_len)) big = &e;
            if (!big) return skip("no mapped object in " + hex(p->index));
            auto entries = read_mapping(ctx, p->index);
            if (!entries) return fail("upload: " + ctx.sdo_error(entries.error()));
            const uint64_t value = (static_cast<uint64_t>(big->index) << 16) |
                                   (static_cast<uint64_t>(big->subindex) << 8) | big->bit_len;
            const Error e = write_mapping(ctx, p->index, std::vector<uint64_t>(last, value));
            const uint32_t code = e == Error::SdoAbort ? ctx.sdo->last_abort() : 0;
            const Error r = write_mapping(ctx, p->index, *entries);  // put the mapping back
            const std::string what = dec(last) + " x " + hex(value, 8) + " in " + hex(p->index);
            if (r != Error::Ok) return fail("mapping not restored: " + ctx.sdo_error(r));
            if (e == Error::Ok) return pass(what + ": taken");
            if (e != Error::SdoAbort) return fail(what + ": " + ctx.sdo_error(e));
            for (uint32_t ok : {0x06040042u, 0x06040043u, 0x06090030u, 0x06090031u, 0x06090011u, 0x08000000u})
                if (code == ok) return pass(what + ": refused", hex(code, 8));
            return fail(what + ": refused with the code of another situation", hex(code, 8),
                        "0x06040042 (or 0x06040043, 0x0609003x, 0x06090011, 0x08000000)");
        },
        "ESI announces PdoConfig");
}

}  // namespace conform
