#pragma once
// Raw CoE SDO requests for the sdo, sdoinfo, pd and cia402 groups: the answer as the slave sent it.
#include "testkit.hpp"

namespace conform {

struct SdoAnswer {
    master::Error error = master::Error::Ok;
    uint8_t mailbox_type = 0;
    std::vector<uint8_t> p;  // CoE payload (CoE header first)
    bool is_abort() const {
        return error == master::Error::Ok && mailbox_type == 3 && p.size() >= 10 && p[2] == 0x80;
    }
    uint32_t abort_code() const { return is_abort() ? get32(&p[6]) : 0; }
    uint8_t cmd() const { return p.size() >= 3 ? p[2] : 0; }
    std::string describe() const {
        if (error != master::Error::Ok) return std::string(master::to_string(error));
        if (mailbox_type == 0)
            return "mailbox error " + (p.size() >= 4 ? hex(get16(&p[2])) : std::string("?"));
        if (is_abort())
            return "abort " + hex(abort_code(), 8) + " (" +
                   std::string(master::sdo_abort_text(abort_code())) + ")";
        return "command " + hex(cmd(), 2) + " " + bytes_hex(p, 14);
    }
};

// Whether the exchange leaves a segmented transfer open in the slave (ETG.1000.6 SDO services): a download
// initiated with fewer bytes than its size, an upload answered with fewer bytes than its size, a segment
// without the last-segment bit. An abort or an answer that is not an SDO one ends nothing the test knows of.
inline void track_sdo_transfer(Context& ctx, const std::vector<uint8_t>& req, const SdoAnswer& a) {
    if (req.size() < 3 || (req[1] >> 4) != 2) return;
    if (req[2] == 0x80 || a.is_abort()) {
        ctx.sdo_open.reset();
        return;
    }
    if (a.error != master::Error::Ok || a.mailbox_type != 3 || a.p.size() < 3) return;
    const uint8_t ccs = req[2] >> 5;
    bool open = false;
    if (ccs == 1) {  // initiate download: open unless expedited or all the indicated bytes came with it
        open = !(req[2] & 0x02) && (req[2] & 0x01) && req.size() >= 10 && get32(&req[6]) > req.size() - 10;
        if (open && req.size() >= 6) ctx.sdo_open = Context::OpenSdo{get16(&req[3]), req[5], false, false};
    } else if (ccs == 2) {  // initiate upload: open when the response indicates more than it carries
        open = (a.cmd() >> 5) == 2 && !(a.cmd() & 0x02) && (a.cmd() & 0x01) && a.p.size() >= 10 &&
               get32(&a.p[6]) > a.p.size() - 10;
        if (open && req.size() >= 6) ctx.sdo_open = Context::OpenSdo{get16(&req[3]), req[5], true, false};
    } else if (ccs == 0 || ccs == 3) {  // a segment: open until the last one, the next with the other toggle
        open = ccs == 0 ? !(req[2] & 0x01) : !(a.cmd() & 0x01);
        if (ctx.sdo_open) ctx.sdo_open->toggle = !(req[2] & 0x10);
    }
    if (!open) ctx.sdo_open.reset();
}

inline SdoAnswer sdo_raw(Context& ctx, std::vector<uint8_t> coe) {
    SdoAnswer a;
    a.error = ctx.coe_request(coe, a.p, a.mailbox_type);
    track_sdo_transfer(ctx, coe, a);
    return a;
}

// CoE header (service 2, SDO request), command, index, subindex, 4 data bytes.
inline std::vector<uint8_t> sdo_req(uint8_t cmd, uint16_t index, uint8_t sub, uint32_t data = 0) {
    std::vector<uint8_t> r = {
        0x00, 0x20, cmd, static_cast<uint8_t>(index), static_cast<uint8_t>(index >> 8), sub, 0, 0, 0, 0};
    put32(&r[6], data);
    return r;
}

inline std::string abort_set(std::initializer_list<uint32_t> codes) {
    std::string s;
    for (auto c : codes)
        s += (s.empty() ? "abort " : " or ") + hex(c, 8);
    return s;
}

// Fails unless the answer is an abort with one of the codes, command byte 0x80, index/subindex echoed.
inline Outcome expect_abort(const SdoAnswer& a, uint16_t index, uint8_t sub,
                            std::initializer_list<uint32_t> codes, const std::string& what) {
    const std::string want = abort_set(codes);
    if (!a.is_abort()) return fail(what + ": not aborted", a.describe(), want);
    if (get16(&a.p[3]) != index || a.p[5] != sub)
        return fail(what + ": abort names another object", hex(get16(&a.p[3])) + ":" + dec(a.p[5]),
                    hex(index) + ":" + dec(sub));
    for (auto c : codes)
        if (c == a.abort_code()) return pass(what, a.describe());
    return fail(what + ": abort code", a.describe(), want);
}

// Every field the standard defines in an SDO upload (scs 2) or download (scs 3) response: mailbox type CoE,
// CoE service 3 (SDO response) with the reserved bits 9-11 clear, the command specifier, the complete-access
// bit set only for a complete access (and in an upload response to one), index and subindex echoed, the
// reserved bytes of a download response 0, and the mailbox length of the response
// type: 10 for an expedited upload or a download response, 10 + the data for a normal upload (the data
// may continue in segments: then not more than the size indicated).
inline Outcome expect_response(const SdoAnswer& a, uint8_t scs, uint16_t index, uint8_t sub, bool ca,
                               const std::string& what) {
    const std::string want = scs == 2 ? "upload response 0x4x" : "download response 0x60";
    if (a.error != master::Error::Ok || a.mailbox_type != 3 || a.p.size() < 10 || a.is_abort())
        return fail(what + ": no SDO response", a.describe(), want);
    const std::string head =
        bytes_hex(std::span<const uint8_t>(a.p).subspan(0, std::min<std::size_t>(a.p.size(), 10)));
    if ((a.p[1] >> 4) != 3) return fail(what + ": CoE service", dec(a.p[1] >> 4), "3 (SDO response)");
    if (a.p[1] & 0x0E) return fail(what + ": CoE header reserved bits 9-11 set", head, "clear");
    const uint8_t c = a.cmd();
    if ((c >> 5) != scs) return fail(what + ": command specifier", hex(c, 2), want);
    if ((c & 0x10) && !ca)
        return fail(what + ": complete-access bit set for a single entry", hex(c, 2), want);
    // The upload response to a complete access says so (ETG.1000.6 SDO upload CA response, command 0x51):
    // a master parses the data as the whole object only when the bit is set.
    if (ca && !(c & 0x10))
        return fail(what + ": complete-access bit clear in the response to a complete access", hex(c, 2),
                    scs == 2 ? "0x5x" : "0x70");
    if (get16(&a.p[3]) != index || a.p[5] != sub)
        return fail(what + ": index/subindex not echoed", hex(get16(&a.p[3])) + ":" + dec(a.p[5]),
                    hex(index) + ":" + dec(sub));
    if (scs == 3) {
        if ((c & 0x1F) != (ca ? (c & 0x10) : 0))
            return fail(what + ": download response bits 0-3 reserved", hex(c, 2), "0x60");
        if (a.p.size() != 10)
            return fail(what + ": mailbox length of a download response", dec(a.p.size()), "10");
        // ETG.1000.6 SDO download response: the 4 bytes after the subindex are reserved (0).
        if (get32(&a.p[6]) != 0)
            return fail(what + ": download response bytes 4-7 reserved", bytes_hex(a.p, 10), "00 00 00 00");
        return pass(what, hex(c, 2));
    }
    if (c & 0x02) {
        if (a.p.size() != 10)
            return fail(what + ": mailbox length of an expedited upload response", dec(a.p.size()), "10");
        return pass(what, head);
    }
    if (!(c & 0x01)) return fail(what + ": normal upload response without size indicated", hex(c, 2), "0x41");
    const uint32_t size = get32(&a.p[6]);
    if (a.p.size() - 10 > size)
        return fail(what + ": more data than the size indicated", dec(a.p.size() - 10) + " bytes",
                    "<= " + dec(size));
    return pass(what, head);
}

// ESI entries that are readable (not wo) with their object.
struct EntryRef {
    const EsiObject* obj;
    const EsiEntry* e;
    // 0x40 / 0x80 (the access bits of an entry description) when an RxPdo / TxPdo element of the ESI maps
    // the entry: a PDO that maps it makes it mappable, whatever the dictionary's PdoMapping says.
    uint16_t mapped = 0;
};
inline std::vector<EntryRef> esi_entries(const EsiDevice& d) {
    std::vector<EntryRef> v;
    for (const auto& [i, o] : d.objects)
        for (const auto& e : o.entries) {
            EntryRef r{&o, &e};
            for (const auto* pdos : {&d.rxpdos, &d.txpdos})
                for (const auto& p : *pdos)
                    for (const auto& pe : p.entries)
                        if (pe.index == i && pe.subindex == e.subindex) r.mapped |= p.rx ? 0x40 : 0x80;
            v.push_back(r);
        }
    return v;
}
// An object whose value the standard makes the device's own state, not a configuration an ESI can give: it is
// not compared with the ESI's DefaultData (a device's value, and the default it describes, may differ from
// it). ETG.1000.6 / CiA 301 0x1001 error register; ETG.1020 0x10F3 diagnosis history and 0x10F8 timestamp;
// ETG.1020 0x1C32/0x1C33 SM synchronisation (measured times and counters); ETG.5001.1 0xF040 detected
// address list and 0xF050 detected module ident list (the modules plugged in) and the diagnosis area
// 0xA000-0xAFFF. The serial number 0x1018:04 is per device (a caller's own rule).
inline bool device_state_object(uint16_t index) {
    return index == 0x1001 || index == 0x10F3 || index == 0x10F8 || index == 0x1C32 || index == 0x1C33 ||
           index == 0xF040 || index == 0xF050 || (index >= 0xA000 && index <= 0xAFFF);
}
// A VISIBLE_STRING entry (ESI type STRING(n)): its BitSize is the capacity, the text may be shorter.
inline bool visible_string(const EsiEntry& e) {
    return esi_coe_type(e.type) == 0x0009;
}
// The capacity in bits a device declares for an entry: the ESI's BitSize, but at least the length of a
// STRING's default text (a device holds its default; SOES' ESIs declare 0x1009 "STRING(0)", BitSize 0, with
// the text "1.0").
inline std::size_t default_text_bytes(const EsiEntry& e) {
    if (!visible_string(e) || !e.default_is_string) return 0;
    std::size_t n = e.default_data.size();
    while (n > 0 && e.default_data[n - 1] == 0)
        --n;
    return n;
}
inline unsigned declared_bits(const EsiEntry& e) {
    return std::max<unsigned>(e.bit_size, static_cast<unsigned>(8 * default_text_bytes(e)));
}

// An index of the manufacturer range the ESI has no object at (from 0x5FFE down; 0x5FFE without an ESI).
inline uint16_t missing_index(Context& ctx) {
    for (uint16_t i = 0x5FFE; i > 0x2000; --i)
        if (!ctx.esi || !ctx.esi->object(i)) return i;
    return 0x5FFE;
}
inline bool command_object(const EsiDevice& esi, uint16_t index) {
    // Store/restore parameters (signature commands), diagnosis history, PDO mapping/assignment: writing
    // them has effects beyond the value; tests of plain entries leave them out. A PDO's mapping object is
    // wherever the ESI's RxPdo/TxPdo names it, not only in the standard ranges.
    auto names_pdo = [&](const std::vector<EsiPdo>& pdos) {
        for (const EsiPdo& p : pdos)
            if (p.index == index) return true;
        return false;
    };
    return index == 0x1010 || index == 0x1011 || index == 0x10F3 || (index >= 0x1600 && index <= 0x1BFF) ||
           (index >= 0x1C10 && index <= 0x1C2F) || index == 0x6040 || names_pdo(esi.rxpdos) ||
           names_pdo(esi.txpdos);
}
inline bool writable_in_preop(const EsiEntry& e) {
    return (e.access == "rw" || e.access == "wo") &&
           (e.write_restrictions.empty() || e.write_restrictions.find("PreOP") != std::string::npos);
}

// A segmented transfer left open (track_sdo_transfer) is ended, after a test or by a test that only wanted
// the first answer, so that the slave's next transfers do not meet this one (a master starts no transfer
// while another is in progress, ETG.1000.6 SDO; an emulator was seen to stop serving): an upload by
// requesting its segments to the last (any server takes that), a download by an Abort SDO Transfer request
// (ETG.1000.6: either side may abort; unconfirmed, code 0x08000000 general error; a made-up last segment
// would write the entry). SM1 is emptied after.
inline void end_open_sdo(Context& ctx) {
    if (!ctx.sdo_open || !ctx.mbx) return;
    const Context::OpenSdo o = *ctx.sdo_open;
    if (o.upload) {
        for (int i = 0; i < 64 && ctx.sdo_open; ++i) {
            std::vector<uint8_t> seg(10, 0);
            seg[1] = 0x20;
            seg[2] = static_cast<uint8_t>(0x60 | (ctx.sdo_open->toggle ? 0x10 : 0));
            if (sdo_raw(ctx, seg).error != master::Error::Ok) break;
        }
    } else {
        std::vector<uint8_t> r = {0x00, 0x20, 0x80, 0, 0, o.sub, 0, 0, 0, 0};
        put16(&r[3], o.index);
        put32(&r[6], 0x08000000);
        (void)ctx.mbx->send(master::MailboxType::CoE, r);
    }
    ctx.sdo_open.reset();
    ctx.mbx_resync();
}

}  // namespace conform
