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

inline SdoAnswer sdo_raw(Context& ctx, std::vector<uint8_t> coe) {
    SdoAnswer a;
    a.error = ctx.coe_request(coe, a.p, a.mailbox_type);
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

// ESI entries that are readable (not wo) with their object.
struct EntryRef {
    const EsiObject* obj;
    const EsiEntry* e;
};
inline std::vector<EntryRef> esi_entries(const EsiDevice& d) {
    std::vector<EntryRef> v;
    for (const auto& [i, o] : d.objects)
        for (const auto& e : o.entries)
            v.push_back({&o, &e});
    return v;
}
inline bool command_object(uint16_t index) {
    // Store/restore parameters (signature commands), diagnosis history, PDO mapping/assignment: writing
    // them has effects beyond the value; tests of plain entries leave them out.
    return index == 0x1010 || index == 0x1011 || index == 0x10F3 || (index >= 0x1600 && index <= 0x1BFF) ||
           index == 0x1C12 || index == 0x1C13 || index == 0x6040;
}
inline bool writable_in_preop(const EsiEntry& e) {
    return (e.access == "rw" || e.access == "wo") &&
           (e.write_restrictions.empty() || e.write_restrictions.find("PreOP") != std::string::npos);
}

}  // namespace conform
