// Group mbx, emergencies: the emergency of a device that is not a drive (a drive's emergencies are those of
// its faults, cia402.fault.*, behind --allow-fault). Provoked safely: an AL request the state machine must
// refuse (PREOP -> OP, ETG.1000.6: invalid state change 0x0011); nothing is written to outputs or flash.
#include "master/diag.hpp"
#include "testkit.hpp"

namespace conform {

namespace {

using master::Error;
constexpr const char* kEmcy =
    "ETG.1000.6 CoE emergency (mailbox length 10, CoE service 1, error code, error register, 5 bytes); CiA "
    "301 error register 0x1001 (bit 0 generic at any error, class bits by error code); ETG.1020 diagnosis "
    "history 0x10F3 (emergencies stored as diag code 0xE800)";

// The CiA 301 error register bit that an error code's class sets (-1 when the class has none).
int class_bit(uint16_t code) {
    switch (code >> 12) {
        case 0x2:
            return 1;  // current
        case 0x3:
            return 2;  // voltage
        case 0x4:
            return 3;  // temperature
        case 0x8:
            return (code >> 8) == 0x81 || (code >> 8) == 0x82 ? 4 : -1;  // communication, protocol error
        default:
            return -1;
    }
}

// The device is a CiA 402 drive (ESI profile, else 0x1000): its emergencies are tested as a drive's.
bool is_drive(Context& ctx) {
    if (ctx.esi && ctx.esi->profile_no) return *ctx.esi->profile_no == 402;
    auto t = ctx.upload_uint(0x1000, 0);
    return t && (*t & 0xFFFF) == 402;
}

// Every message a check of one emergency finds wrong, "" if none.
std::string emergency_defects(std::span<const uint8_t> m, std::optional<uint64_t> reg1001) {
    std::string bad;
    auto add = [&](const std::string& s) { bad += (bad.empty() ? "" : "; ") + s; };
    if (get16(m.data()) != 10) add("mailbox length " + dec(get16(m.data())) + ", not 10");
    const uint16_t coe = get16(&m[6]);
    if (coe & 0x01FF) add("CoE number field " + hex(coe & 0x01FF) + ", not 0");
    if (coe & 0x0E00) add("CoE reserved bits 9-11 set (" + hex(coe, 4) + ")");
    const uint16_t code = get16(&m[8]);
    const uint8_t er = m[10];
    if (code == 0) add("error code 0x0000 (no error) for an error");
    if (!(er & 0x01)) add("error register " + hex(er, 2) + " without bit 0 (generic error)");
    if (const int b = class_bit(code); b >= 0 && !(er & (1u << b)))
        add("error register " + hex(er, 2) + " without bit " + dec(b) + " of the class of " + hex(code));
    if (reg1001 && (*reg1001 & 0xFF) != er)
        add("error register " + hex(er, 2) + " but 0x1001 reads " + hex(*reg1001 & 0xFF, 2));
    return bad;
}

// ETG.1020 diagnosis history: a device with 0x10F3 stores its emergencies there too, as messages with the
// emergency-derived diag code (0xE800 in the low word, the error code above). "" when the history holds a
// message with `code`, else what was found; nullopt when the device has no 0x10F3.
std::optional<std::string> history_defect(Context& ctx, uint16_t code) {
    auto newest = ctx.upload_uint(0x10F3, 2);
    if (!newest) return std::nullopt;
    // A 0x10F3 whose subindices end before :06 (ETG.1020: the messages start there) has no room for one: a
    // vendor's ESI may declare the header only (Weidmueller's UR20); nothing to look for.
    if (auto top = ctx.upload_uint(0x10F3, 0); top && *top < 6) return std::nullopt;
    master::DiagHeader h;
    if (auto v = ctx.upload_uint(0x10F3, 1)) h.max_messages = static_cast<uint8_t>(*v);
    h.newest = static_cast<uint8_t>(*newest);
    if (auto v = ctx.upload_uint(0x10F3, 3)) h.acknowledged = static_cast<uint8_t>(*v);
    if (h.newest == 0) return std::string("no message at all (0x10F3:02 = 0)");
    std::string seen;
    for (uint8_t sub : master::diag_message_order(h, true, false)) {
        auto b = ctx.upload(0x10F3, sub);
        if (!b) return "0x10F3:" + hex(sub, 2) + " upload: " + ctx.sdo_error(b.error());
        auto e = master::decode_diag_message(*b, sub);
        if (!e) continue;
        if (e->from_emergency() && e->emergency_code() == code) return std::string();
        seen += hex(e->code, 8) + " ";
    }
    return "diag codes " + (seen.empty() ? std::string("none") : seen);
}

Outcome refused_request_emergency(Context& ctx) {
    CONFORM_NEED(ctx.need_coe());
    CONFORM_NEED(ctx.need_state_machine());
    if (Error e = ctx.to_init(); e != Error::Ok) return fail("cannot reach INIT", err(e));
    CONFORM_PREOP(ctx);
    if (is_drive(ctx))
        return skip("a CiA 402 drive: its emergencies are those of its faults (cia402.fault.*)");
    std::vector<uint8_t> raw;
    for (int i = 0; i < 16 && ctx.mbx_read_raw(raw, ctx.ms(30)) == Error::Ok; ++i) {
    }  // what earlier tests left in SM1
    const master::AlStatus st = ctx.request_raw(8, ctx.ms(2000));
    std::vector<std::vector<uint8_t>> emcy;
    for (int i = 0; i < 8 && ctx.mbx_read_raw(raw, ctx.ms(300)) == Error::Ok; ++i)
        if (raw.size() >= 16 && (raw[5] & 0x0F) == 3 && (raw[7] >> 4) == 1) emcy.push_back(raw);
    (void)ctx.ack_error();
    ctx.mbx_resync();
    std::optional<uint64_t> reg1001;
    if (auto r = ctx.upload_uint(0x1001, 0)) reg1001 = *r;
    std::optional<std::string> history;
    if (!emcy.empty()) history = history_defect(ctx, get16(&emcy.front()[8]));
    (void)ctx.to_init();
    const std::string state = state_text(static_cast<uint8_t>(st.state | (st.error ? 0x10 : 0)));
    if (st.state != 2 || !st.error)
        return skip("PREOP -> OP was not refused (" + state + "): see esm.invalid.*");
    if (emcy.empty()) return skip("no emergency for the refused request (an emergency is optional there)");
    // The first emergency is the one of the refusal; a later one may already be the "no error" of the
    // acknowledge.
    const auto& m = emcy.front();
    const std::string got = bytes_hex(std::span<const uint8_t>(m).subspan(0, 16));
    // 0x1001 is read after the acknowledge: it is compared only while no later emergency says it changed.
    if (const std::string bad = emergency_defects(m, emcy.size() == 1 ? reg1001 : std::nullopt); !bad.empty())
        return fail("emergency of the refused PREOP -> OP: " + bad, got);
    if (history && !history->empty())
        return fail("emergency " + hex(get16(&m[8])) +
                        " not in the diagnosis history 0x10F3 (ETG.1020: diag code " +
                        hex((static_cast<uint32_t>(get16(&m[8])) << 16) | 0xE800, 8) + ")",
                    *history, "a message with that code");
    return pass("emergency " + hex(get16(&m[8])) + " register " + hex(m[10], 2), got);
}

// ETG.1020 diagnosis history 0x10F3 header against its messages: newest message (:02) 0 or within
// 6..5+max (:01); the message it names is there and no stored message has a later time stamp.
Outcome history_header(Context& ctx) {
    CONFORM_NEED(ctx.need_coe());
    CONFORM_PREOP(ctx);
    auto newest = ctx.upload_uint(0x10F3, 2);
    if (!newest) return skip("no diagnosis history 0x10F3");
    master::DiagHeader h;
    auto max = ctx.upload_uint(0x10F3, 1);
    if (!max) return fail("0x10F3:01 (maximum messages) upload: " + ctx.sdo_error(max.error()));
    h.max_messages = static_cast<uint8_t>(*max);
    h.newest = static_cast<uint8_t>(*newest);
    if (auto v = ctx.upload_uint(0x10F3, 3)) h.acknowledged = static_cast<uint8_t>(*v);
    // The other header fields, each against the structure: the messages are subindices 6..:00, so :01 names
    // no more than those; :05 defines bits 0-5 (emergency, three suppress bits, acknowledge mode, overflow),
    // the rest is reserved; :04 (new messages available) is TRUE only with a message not yet read.
    if (auto top = ctx.upload_uint(0x10F3, 0); top && static_cast<int>(*max) > static_cast<int>(*top) - 5)
        return fail("0x10F3:01 (maximum messages) more than the message subindices 6..:00", dec(*max),
                    "<= " + dec(static_cast<int>(*top) - 5) + " (:00 = " + dec(*top) + ")");
    auto flags = ctx.upload_uint(0x10F3, 5);
    if (flags && (*flags & 0xFFC0))
        return fail("0x10F3:05 (flags): reserved bits 6-15 set", hex(*flags, 4), "bits 0-5 only");
    auto available = [&ctx]() -> std::optional<uint64_t> {
        auto v = ctx.upload_uint(0x10F3, 4);
        return v ? std::optional<uint64_t>(*v & 1) : std::nullopt;
    };
    if (h.newest == 0) {
        if (auto a = available(); a && *a)
            return fail("0x10F3:04 (new messages available) TRUE without any message (:02 = 0)", "1", "0");
        return pass("no message", "0x10F3:02 = 0");
    }
    if (h.newest < 6 || h.newest > 5 + h.max_messages)
        return fail("0x10F3:02 (newest message) outside the message subindices", dec(h.newest),
                    "0 or 6.." + dec(5 + h.max_messages));
    auto b = ctx.upload(0x10F3, h.newest);
    std::optional<master::DiagEntry> top;
    if (b) top = master::decode_diag_message(*b, h.newest);
    if (!top)
        return fail("0x10F3:02 names subindex " + dec(h.newest) + ", which holds no message",
                    b ? bytes_hex(*b, 16) : ctx.sdo_error(b.error()), "a diagnosis message");
    // The newest message was just read: in overwrite mode (:05 bit 4 clear) nothing is left unread, unless
    // a message came meanwhile (:02 moved).
    if (flags && !(*flags & 0x0010)) {
        auto a = available();
        auto again = ctx.upload_uint(0x10F3, 2);
        if (a && *a && again && *again == h.newest)
            return fail("0x10F3:04 (new messages available) still TRUE after the newest message (:" +
                            dec(h.newest) + ") was read, overwrite mode",
                        "1", "0");
    }
    unsigned n = 0;
    for (uint8_t sub : master::diag_message_order(h, true, false)) {
        if (sub == h.newest) continue;
        if (n >= 64) break;  // enough to judge; a long ring costs one upload per message
        auto m = ctx.upload(0x10F3, sub);
        if (!m) continue;
        auto e = master::decode_diag_message(*m, sub);
        if (!e) continue;
        ++n;
        if (e->timestamp_ns > top->timestamp_ns)
            return fail("0x10F3:02 names subindex " + dec(h.newest) + ", but subindex " + dec(sub) +
                            " holds a later message",
                        dec(static_cast<long long>(e->timestamp_ns)) + " ns",
                        "<= " + dec(static_cast<long long>(top->timestamp_ns)) + " ns");
    }
    return pass("newest " + dec(h.newest), dec(n + 1) + " messages");
}

}  // namespace

void add_emcy_tests(Catalogue& c) {
    Adder add{c, "mbx"};
    add("emcy.refused_request",
        "A refused AL request (PREOP -> OP) of a device that is not a drive: its emergency, if it sends "
        "one, is 10 bytes of CoE service 1 with a non-zero error code, the generic and class bits in its "
        "error register, which equals 0x1001, and is stored in 0x10F3 where the device has it",
        kEmcy, refused_request_emergency, "CoE, a state machine (no device emulation), not a CiA 402 drive");
    add("diag.history_header",
        "Diagnosis history 0x10F3: newest message (:02) 0 or a message subindex, holding the latest "
        "message; maximum messages (:01) within 6..:00, flags (:05) without reserved bits, new messages "
        "available (:04) FALSE once the newest is read (overwrite mode)",
        "ETG.1020 diagnosis history 0x10F3 (subindex 1 maximum messages, 2 newest message, 4 new messages "
        "available, 5 flags, 6.. messages)",
        history_header, "CoE and 0x10F3");
}

}  // namespace conform
