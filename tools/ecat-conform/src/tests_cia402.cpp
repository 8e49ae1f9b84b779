// Group cia402: the drive profile (IEC 61800-7-201 / CiA 402): device control transitions through
// controlword/statusword in process data, quick stop as 0x605A says, fault and fault reset, the modes of
// 0x6502 accepted by 0x6060 and shown by 0x6061. The axis is held: in CSP the target follows the actual
// position every cycle, so enabling the drive does not move it.
#include <optional>
#include <set>
#include <thread>

#include "master/diag.hpp"
#include "pdo_map.hpp"

namespace conform {

namespace {

using master::Error;
constexpr const char* kDev = "IEC 61800-7-201 (CiA 402) device control state machine";
constexpr const char* kModes = "IEC 61800-7-201 (CiA 402) modes of operation 0x6060/0x6061/0x6502";

struct DsState {
    const char* name;
    uint16_t mask, value;
};
constexpr DsState kSod{"switch on disabled", 0x4F, 0x40};
constexpr DsState kRtso{"ready to switch on", 0x6F, 0x21};
constexpr DsState kSo{"switched on", 0x6F, 0x23};
constexpr DsState kOe{"operation enabled", 0x6F, 0x27};
constexpr DsState kQsa{"quick stop active", 0x6F, 0x07};
constexpr DsState kFault{"fault", 0x4F, 0x08};

std::string sw_text(uint16_t sw) {
    for (const DsState* s : {&kSod, &kRtso, &kSo, &kOe, &kQsa, &kFault})
        if ((sw & s->mask) == s->value) return hex(sw) + " (" + s->name + ")";
    return hex(sw);
}

std::string need_402_profile(Context& ctx) {
    if (auto r = ctx.need_402(); !r.empty()) return r;
    if (ctx.esi && ctx.esi->profile_no) return {};
    if (ctx.to_preop() != Error::Ok) return "cannot reach PREOP";
    auto v = ctx.upload_uint(0x1000, 0);
    if (!v || (*v & 0xFFFF) != 402) return "device type 0x1000 is not profile 402";
    return {};
}

struct Drive {
    explicit Drive(Context& c) : ctx(c) {}
    Context& ctx;
    PdoMap map;
    const MappedEntry *cw = nullptr, *sw = nullptr, *target = nullptr, *actual = nullptr, *mode = nullptr;

    void hold() {
        if (target && actual) image_set(ctx.pds->outputs(), *target, image_get(ctx.pds->inputs(), *actual));
    }
    uint16_t status() const { return static_cast<uint16_t>(image_get(ctx.pds->inputs(), *sw)); }

    // "" when the drive is in OP with controlword/statusword exchanged, else why not.
    std::string start() {
        if (Error e = ctx.to_safeop(); e != Error::Ok) return "cannot reach SAFEOP: " + err(e);
        if (Error e = read_map(ctx, map); e != Error::Ok) return "mapping: " + ctx.sdo_error(e);
        cw = map.find_out(0x6040);
        sw = map.find_in(0x6041);
        if (!cw || !sw) return "controlword 0x6040 / statusword 0x6041 not in the process data";
        target = map.find_out(0x607A);
        actual = map.find_in(0x6064);
        mode = map.find_out(0x6060);
        prefill_outputs(ctx, map);
        image_set(ctx.pds->outputs(), *cw, 0);
        // Cyclic synchronous position when supported and the target can follow the actual position.
        auto modes = ctx.upload_uint(0x6502, 0);
        if (modes && (*modes & 0x80) && target && actual) {
            if (mode)
                image_set(ctx.pds->outputs(), *mode, 8);
            else
                (void)ctx.download_uint(0x6060, 0, 8, 1);
        }
        (void)ctx.cycle(3);
        hold();
        master::AlStatus st;
        if (Error e = ctx.enter_op(st, [this] { hold(); }); e != Error::Ok)
            return "cannot reach OP: " + err(e) + " (" + al_code_text(st.code) + ")";
        run(10);
        return {};
    }
    void run(unsigned n) {
        for (unsigned i = 0; i < n; ++i) {
            hold();
            (void)ctx.pds->cycle();
            std::this_thread::sleep_for(std::chrono::microseconds(1000));
        }
    }
    // Sends a controlword until the statusword shows `want` (or the time is up); true when reached.
    bool command(uint16_t c, const DsState& want, int ms = 500) {
        image_set(ctx.pds->outputs(), *cw, c);
        const auto deadline = std::chrono::steady_clock::now() + ctx.ms(ms);
        while (std::chrono::steady_clock::now() < deadline) {
            run(1);
            if ((status() & want.mask) == want.value) return true;
        }
        return false;
    }
    // From wherever the drive is to switch on disabled (fault reset if needed), then along 2, 3, 4.
    bool to(const DsState& want) {
        // A fault may also come late, from the previous test's communication loss (the drive's fault
        // reaction runs on after the state machine was taken down): the reset once more if the drive shows
        // Fault after the first try.
        for (int attempt = 0;; ++attempt) {
            if ((status() & kFault.mask) == kFault.value) {
                (void)command(0x0000, kFault, 20);
                (void)command(0x0080, kSod);
            }
            if (command(0x0000, kSod)) break;
            if (attempt == 1 || (status() & kFault.mask) != kFault.value) return false;
        }
        if (&want == &kSod) return true;
        if (!command(0x0006, kRtso)) return false;
        if (&want == &kRtso) return true;
        if (!command(0x0007, kSo)) return false;
        if (&want == &kSo) return true;
        return command(0x000F, kOe);
    }
    void finish() {
        (void)command(0x0000, kSod, 200);
        (void)ctx.to_init();
    }
};

// The master leaves OP while the drive is enabled: a communication loss (0x6007). True when the statusword
// then shows fault.
bool provoke_fault(Context& ctx, Drive& d) {
    (void)ctx.request_raw(4, ctx.ms(1000));
    (void)ctx.ack_error();
    d.run(20);
    for (int i = 0; i < 50; ++i) {
        d.run(2);
        if ((d.status() & kFault.mask) == kFault.value) return true;
    }
    return false;
}

// The emergency of a drive fault: 8 bytes after the CoE header, its error register as 0x1001 with bit 0
// (generic error) set, its error code as 0x603F (when the drive has it).
// The drive started, enabled and faulted by a communication loss; an outcome when that cannot be done.
// counter_before: the mailbox counter of an SDO reply read just before the fault is provoked (0: none).
std::optional<Outcome> faulted_drive(Context& ctx, Drive& d, uint8_t* counter_before = nullptr) {
    if (!ctx.opt.allow_fault) return skip("provokes a drive fault: needs --allow-fault");
    if (auto r = need_402_profile(ctx); !r.empty()) return skip(r);
    if (auto e = d.start(); !e.empty())
        return e.find("not in the process data") != std::string::npos ? skip(e) : fail(e);
    ctx.mbx_resync();
    if (!d.to(kOe)) {
        std::string s = sw_text(d.status());
        d.finish();
        return fail("cannot reach operation enabled", s, kOe.name);
    }
    if (counter_before) {
        *counter_before = 0;
        if (ctx.upload(0x6041, 0) && ctx.mbx) *counter_before = ctx.mbx->last_rx_counter();
    }
    if (!provoke_fault(ctx, d)) {
        const std::string s = sw_text(d.status());
        d.finish();
        return skip("the communication loss did not fault the drive (statusword " + s + ")");
    }
    return std::nullopt;
}

// The emergencies (CoE service 1) that come in SM1 within 200 ms (scaled), read out while the drive's
// process data keeps cycling (its watchdog fed); the mailbox client restarts after.
std::vector<std::vector<uint8_t>> drain_emergencies(Context& ctx, Drive& d) {
    std::vector<std::vector<uint8_t>> emcy;
    std::vector<uint8_t> raw;
    const auto until = std::chrono::steady_clock::now() + ctx.ms(200);
    while (std::chrono::steady_clock::now() < until) {
        d.run(1);
        if (ctx.mbx_read_raw(raw, std::chrono::milliseconds(1)) == Error::Ok && (raw[5] & 0x0F) == 3 &&
            raw.size() >= 16 && (raw[7] >> 4) == 1)
            emcy.push_back(raw);
    }
    ctx.mbx_resync();
    return emcy;
}

Outcome fault_emergency(Context& ctx, bool generic_bit) {
    Drive d(ctx);
    uint8_t before = 0;
    if (auto o = faulted_drive(ctx, d, &before)) return *o;
    // The emergencies waiting in SM1 (before any SDO transfer could pass them over).
    std::vector<std::vector<uint8_t>> emcy;
    std::vector<uint8_t> raw;
    // At most 16 messages: a slave whose SM1 reads never come up empty (a read of an empty mailbox counted)
    // must not keep the test reading until its budget is gone.
    for (int k = 0; k < 16 && ctx.mbx_read_raw(raw, ctx.ms(200)) == Error::Ok; ++k)
        if ((raw[5] & 0x0F) == 3 && raw.size() >= 8 && (raw[7] >> 4) == 1) emcy.push_back(raw);
    ctx.mbx_resync();
    auto reg = ctx.upload_uint(0x1001, 0);
    auto code603f = ctx.upload_uint(0x603F, 0);
    const std::string sw = sw_text(d.status());
    d.finish();
    if (emcy.empty()) return skip("the drive sent no emergency for the fault (statusword " + sw + ")");
    const auto& m = emcy.back();
    const std::string got =
        bytes_hex(std::span<const uint8_t>(m).subspan(0, std::min<std::size_t>(m.size(), 16)));
    if (get16(m.data()) != 10 || m.size() < 16)
        return fail("emergency length", dec(get16(m.data())), "10 (CoE header and 8 bytes)");
    if (const uint16_t coe = get16(&m[6]); coe & 0x0FFF)
        return fail("emergency CoE header: number (bits 0-8) and reserved bits 9-11 not 0", hex(coe),
                    hex(0x1000));
    // An emergency is a new message: its counter is the next one (ETG.1000.4 mailbox counter), never 0 and
    // never the counter of the message before it, which a master takes for a repeat and drops.
    uint8_t prev = before;
    for (const auto& x : emcy) {
        const auto c = static_cast<uint8_t>((x[5] >> 4) & 7);
        if (c == 0)
            return fail("emergency with mailbox counter 0 (only a start value)", hex(x[5], 2), "1..7");
        if (c == prev)
            return fail("emergency with the mailbox counter of the message before it (a repeat to a master)",
                        dec(c), "a counter other than " + dec(prev));
        prev = c;
    }
    const uint16_t code = get16(&m[8]);
    const uint8_t er = m[10];
    if (code == 0)
        return fail("the fault's emergency has error code 0 (no error)", got, "a fault's error code");
    if (generic_bit) {
        if (!(er & 0x01))
            return fail("error register without bit 0 (generic error) while faulted", got, "bit 0 set");
        return pass("generic error bit", got);
    }
    // CiA 301 error register: the bit of the code's error class is set with it (0x2xxx current bit 1, 0x3xxx
    // voltage bit 2, 0x4xxx temperature bit 3, 0x81xx communication bit 4); other codes name no class bit.
    const uint8_t class_bit = (code >> 8) == 0x81 ? 0x10
                              : (code >> 12) == 2 ? 0x02
                              : (code >> 12) == 3 ? 0x04
                              : (code >> 12) == 4 ? 0x08
                                                  : 0;
    if (class_bit && !(er & class_bit))
        return fail("error register without the bit of the error code's class (" + hex(code) + ")", got,
                    "bit " + hex(class_bit, 2) + " set");
    if (!reg) return fail("0x1001 upload: " + ctx.sdo_error(reg.error()));
    if (*reg != er) return fail("emergency error register against 0x1001", hex(er, 2), hex(*reg, 2));
    if (code603f && (*code603f & 0xFFFF) != code)
        return fail("emergency error code against 0x603F", hex(code), hex(*code603f & 0xFFFF));
    return pass("emergency", got);
}

// ETG.1020 diagnosis history: a drive with 0x10F3 stores the emergency of its fault as a message (diag code
// 0xE800 | error code << 16), newer than what the history held before (0x10F3:02 newest message moves to
// it), and of type warning or error (flags bits 0-3; info is for what is no fault). The message is then
// acknowledged (0x10F3:03), as a master acknowledges what it has read; nothing is deleted.
Outcome fault_history(Context& ctx) {
    if (!ctx.opt.allow_fault) return skip("provokes a drive fault: needs --allow-fault");
    CONFORM_NEED(need_402_profile(ctx));
    CONFORM_PREOP(ctx);
    auto before = ctx.upload_uint(0x10F3, 2);
    if (!before) return skip("no diagnosis history 0x10F3");
    auto max = ctx.upload_uint(0x10F3, 1);
    if (!max || *max == 0) return skip("0x10F3:01 (maximum messages) unreadable or 0 (history.header's)");
    Drive d(ctx);
    if (auto o = faulted_drive(ctx, d)) return *o;
    const auto emcy = drain_emergencies(ctx, d);
    auto after = ctx.upload_uint(0x10F3, 2);
    master::DiagHeader h;
    h.max_messages = static_cast<uint8_t>(*max);
    h.newest = after ? static_cast<uint8_t>(*after) : 0;
    std::vector<master::DiagEntry> fresh;  // newest first, down to the newest of before the fault
    if (after && *after != *before)
        for (uint8_t sub : master::diag_message_order(h, true, false)) {
            if (sub == *before) break;
            auto b = ctx.upload(0x10F3, sub);
            if (!b) continue;
            if (auto e = master::decode_diag_message(*b, sub)) fresh.push_back(*e);
        }
    d.finish();
    uint16_t code = 0;
    for (const auto& x : emcy)
        if (get16(&x[8]) != 0) code = get16(&x[8]);
    if (code == 0) return skip("the drive sent no emergency for the fault (cia402.fault_reset judges that)");
    if (!after) return fail("0x10F3:02 unreadable after the fault: " + ctx.sdo_error(after.error()));
    if (*after == *before)
        return fail("0x10F3:02 (newest message) did not move with the fault's emergency " + hex(code),
                    dec(*after) + " before and after", "a newer message");
    // ETG.1020 diagnosis message flags bits 8-15: the number of parameters that follow the 16 fixed bytes,
    // each its own flags (kind and data type or length) and data. A count the bytes do not hold (or a
    // parameter that cannot be delimited) leaves a master reading past the message or losing its text.
    for (const auto& e : fresh)
        if (e.truncated)
            return fail("message " + hex(e.code, 8) + " at :" + dec(e.subindex) +
                            ": its flags announce more parameters than it holds (or one of no known size)",
                        dec(static_cast<long long>(e.params.size())) + " delimited",
                        "the count of flags 8-15");
    for (const auto& e : fresh)
        if (e.from_emergency() && e.emergency_code() == code) {
            if (e.type == 0)
                return fail(
                    "the fault's emergency " + hex(code) + " stored as an info message (flags type 0)",
                    "type 0 (info) at :" + dec(e.subindex), "1 (warning) or 2 (error)");
            // ETG.1020 diagnosis message bytes 8-15: the time stamp of the event (ns of the device's time, DC
            // system time where it has DC): 0 tells no time at all.
            if (e.timestamp_ns == 0)
                return fail("the fault's message " + hex(e.code, 8) + " carries time stamp 0",
                            "0 at :" + dec(e.subindex), "the time of the event");
            // ETG.1020: writing a message's subindex to 0x10F3:03 acknowledges the messages up to it, and
            // :03 reads back what was written. Acknowledging the fault's message is what a master does with
            // it; a refusal is left to the sdo group (an abort is an answer), a write taken but not kept is
            // a defect here.
            const std::string where =
                "diag code " + hex(e.code, 8) + " type " + dec(e.type) + " at :" + dec(e.subindex);
            CONFORM_PREOP(ctx);                // the drive was left in INIT
            (void)ctx.upload_uint(0x10F3, 3);  // what it held: a device that keeps it shows it again
            if (Error w = ctx.download_uint(0x10F3, 3, e.subindex, 1); w != Error::Ok)
                return pass("stored (its acknowledgement not taken: " + ctx.sdo_error(w) + ")", where);
            auto acked = ctx.upload_uint(0x10F3, 3);
            if (!acked || *acked != e.subindex)
                return fail("0x10F3:03 (newest acknowledged message) = " + dec(e.subindex) +
                                " acknowledged, but it reads another value",
                            acked ? dec(*acked) : "unreadable: " + ctx.sdo_error(acked.error()),
                            dec(e.subindex));
            return pass("stored and acknowledged", where);
        }
    std::string seen;
    for (const auto& e : fresh)
        seen += hex(e.code, 8) + " ";
    return fail("the fault's emergency " + hex(code) + " is not among the messages stored since",
                seen.empty() ? "none" : seen,
                "diag code " + hex((static_cast<uint32_t>(code) << 16) | 0xE800, 8));
}

Outcome transition(Context& ctx, const DsState& from, uint16_t c, const DsState& want, const char* what) {
    CONFORM_NEED(need_402_profile(ctx));
    Drive d(ctx);
    if (auto e = d.start(); !e.empty()) {
        if (e.find("not in the process data") != std::string::npos) return skip(e);
        return fail(e);
    }
    if (!d.to(from)) {
        std::string s = sw_text(d.status());
        d.finish();
        return fail(std::string("cannot reach ") + from.name + " first", s, from.name);
    }
    const bool ok = d.command(c, want);
    const std::string s = sw_text(d.status());
    d.finish();
    if (!ok) return fail(std::string(what) + ": controlword " + hex(c) + " in " + from.name, s, want.name);
    return pass(what, s);
}

struct Mode {
    const char* id;
    const char* name;
    int8_t value;
    uint32_t bit;
};
constexpr Mode kModeList[] = {{"pp", "profile position", 1, 0x001},
                              {"vl", "velocity", 2, 0x002},
                              {"pv", "profile velocity", 3, 0x004},
                              {"tq", "profile torque", 4, 0x008},
                              {"hm", "homing", 6, 0x020},
                              {"ip", "interpolated position", 7, 0x040},
                              {"csp", "cyclic sync position", 8, 0x080},
                              {"csv", "cyclic sync velocity", 9, 0x100},
                              {"cst", "cyclic sync torque", 10, 0x200}};

// 0x6502 could not be read. A drive without the object is one defect, reported by cia402.objects: the
// tests that need the supported modes are skipped, not failed once more each.
Outcome modes_unreadable(Context& ctx, Error e) {
    if (e == Error::SdoAbort && ctx.sdo != nullptr && ctx.sdo->last_abort() == 0x06020000)
        return skip("0x6502 does not exist (a failure of cia402.objects)");
    return fail("0x6502: " + ctx.sdo_error(e));
}

// A standard mode that 0x6502 does not announce, written to 0x6060. readback: judged is only that an
// acknowledged write reads back from 0x6060 (a download response says the value is stored; a refusal is an
// abort); else that the mode is refused or at least not shown by 0x6061.
Outcome unsupported_mode(Context& ctx, bool readback) {
    CONFORM_NEED(need_402_profile(ctx));
    CONFORM_PREOP(ctx);
    auto sup = ctx.upload_uint(0x6502, 0);
    if (!sup) return modes_unreadable(ctx, sup.error());
    int8_t bad = 0;
    for (const Mode& md : kModeList)
        if (!(*sup & md.bit)) {
            bad = md.value;
            break;
        }
    if (!bad) return skip("every standard mode is supported");
    auto old = ctx.upload_uint(0x6060, 0);
    Error e = ctx.download_uint(0x6060, 0, static_cast<uint8_t>(bad), 1);
    auto stored = ctx.upload(0x6060, 0);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    auto shown = ctx.upload(0x6061, 0);
    if (old) (void)ctx.download_uint(0x6060, 0, *old, 1);
    if (e == Error::SdoAbort) return pass("refused", ctx.sdo_error(e));
    if (readback) {
        // Judged here: an acknowledgement; an answer that is neither (an SDO defect) is the sdo group's.
        if (e != Error::Ok) return pass("not acknowledged", ctx.sdo_error(e));
        if (!stored || stored->empty() || static_cast<int8_t>((*stored)[0]) != bad)
            return fail(
                "0x6060 = " + dec(bad) + " (not in 0x6502) acknowledged, but 0x6060 reads another value",
                stored && !stored->empty() ? dec(static_cast<int8_t>((*stored)[0])) : "unreadable",
                dec(bad) + ", or an abort (0x06090030)");
        return pass("acknowledged and stored");
    }
    if (shown && !shown->empty() && static_cast<int8_t>((*shown)[0]) == bad)
        return fail("unsupported mode " + dec(bad) + " taken and shown", dec(bad), "refused");
    return pass("not taken");
}

}  // namespace

void add_cia402_tests(Catalogue& c) {
    Adder add{c, "cia402"};
    const std::string a = "profile 402";
    add(
        "profile", "0x1000 device type: profile 402 as the ESI's ProfileNo",
        "IEC 61800-7-201 device type 0x1000; ETG.2000 Profile/ProfileNo",
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_esi());
            if (!ctx.esi->profile_no || *ctx.esi->profile_no != 402)
                return skip("the ESI does not give profile 402");
            CONFORM_PREOP(ctx);
            auto v = ctx.upload_uint(0x1000, 0);
            if (!v) return fail("0x1000: " + ctx.sdo_error(v.error()));
            return expect_eq("0x1000 low word", dec(static_cast<long long>(*v & 0xFFFF)), "402");
        },
        "ESI gives profile 402");
    add(
        "objects", "Mandatory drive objects 0x6040, 0x6041, 0x6060, 0x6061, 0x6502 present", kDev,
        [](Context& ctx) {
            CONFORM_NEED(need_402_profile(ctx));
            CONFORM_PREOP(ctx);
            std::string missing;
            for (uint16_t i : {0x6040, 0x6041, 0x6060, 0x6061, 0x6502})
                if (!ctx.upload(i, 0)) missing += hex(i) + " ";
            if (!missing.empty()) return fail("missing", missing, "none");
            return pass();
        },
        a);
    add(
        "option_codes",
        "Option codes 0x6007, 0x605A-0x605E (where present) hold a defined value or a "
        "manufacturer-specific one (negative)",
        "IEC 61800-7-201 (CiA 402) option codes: 0x6007 abort connection 0..3, 0x605A quick stop 0..8, "
        "0x605B shutdown 0..1, 0x605C disable operation 0..1, 0x605D halt 1..4 (0 taken too), 0x605E fault "
        "reaction "
        "0..4; -32768..-1 manufacturer specific, the rest reserved",
        [](Context& ctx) {
            CONFORM_NEED(need_402_profile(ctx));
            CONFORM_PREOP(ctx);
            struct Option {
                uint16_t index;
                int lo, hi;
            };
            std::string seen;
            for (const Option& o : {Option{0x6007, 0, 3}, Option{0x605A, 0, 8}, Option{0x605B, 0, 1},
                                    Option{0x605C, 0, 1}, Option{0x605D, 0, 4}, Option{0x605E, 0, 4}}) {
                auto v = ctx.upload(o.index, 0);
                if (!v || v->size() != 2) continue;  // absent (optional), or not INTEGER16: not judged here
                const int code = static_cast<int16_t>(get16(v->data()));
                seen += hex(o.index) + "=" + dec(code) + " ";
                if (code >= 0 && (code < o.lo || code > o.hi))
                    return fail(hex(o.index) + " holds a reserved option code", dec(code),
                                dec(o.lo) + ".." + dec(o.hi) + " or manufacturer specific (< 0)");
            }
            if (seen.empty()) return skip("no option code object");
            return pass("defined", seen);
        },
        a);
    add(
        "parameters.consistent",
        "Parameter objects (where present) agree with themselves: limit pairs 0x607B/0x607D in order, ratio "
        "denominators 0x608F:02/0x6090:02/0x6091:02/0x6092:02 not 0, 0x60FD bits 4-15 reserved, 0x60B9 "
        "enabled bits as 0x60B8, 0xF010 module profiles not 0",
        "IEC 61800-7-201 (CiA 402): 0x607B position range limit and 0x607D software position limit (:01 min, "
        ":02 max); 0x608F/0x6090 encoder resolution, 0x6091 gear ratio, 0x6092 feed constant (:02 a "
        "divisor); "
        "0x60FD digital inputs bits 4-15 reserved; 0x60B9 touch probe status bits 0/8 (enabled) as 0x60B8 "
        "bits 0/8; ETG.5001.1 0xF010 module profile list",
        [](Context& ctx) {
            CONFORM_NEED(need_402_profile(ctx));
            CONFORM_PREOP(ctx);
            // Read only; each object is optional (absent or of another size: not judged here).
            auto i32 = [&](uint16_t i, uint8_t s) -> std::optional<int32_t> {
                auto v = ctx.upload(i, s);
                if (!v || v->size() != 4) return std::nullopt;
                return static_cast<int32_t>(get32(v->data()));
            };
            std::string seen;
            for (uint16_t i : {0x607B, 0x607D}) {
                auto lo = i32(i, 1), hi = i32(i, 2);
                if (!lo || !hi) continue;
                seen += hex(i) + " ";
                if (*lo > *hi)
                    return fail(hex(i) + " :01 minimum above :02 maximum", dec(*lo) + " > " + dec(*hi),
                                "minimum <= maximum");
            }
            for (uint16_t i : {0x608F, 0x6090, 0x6091, 0x6092}) {
                auto v = ctx.upload(i, 2);
                if (!v || v->size() != 4) continue;
                seen += hex(i) + " ";
                if (get32(v->data()) == 0) return fail(hex(i) + ":02 (a divisor) is 0", "0", "not 0");
            }
            if (auto v = ctx.upload(0x60FD, 0); v && v->size() == 4) {
                seen += "0x60fd ";
                if (get32(v->data()) & 0xFFF0)
                    return fail("0x60FD reserved bits 4-15 set", hex(get32(v->data()), 8), "bits 4-15 clear");
            }
            auto fn = ctx.upload(0x60B8, 0);
            auto st = ctx.upload(0x60B9, 0);
            if (fn && st && fn->size() == 2 && st->size() == 2) {
                seen += "0x60b8/0x60b9 ";
                const uint16_t f = get16(fn->data()), s = get16(st->data());
                // A probe shown enabled that the function word does not enable (the other way round may lag a
                // write by a cycle; nothing here writes 0x60B8).
                if ((s & 0x0101) & ~(f & 0x0101))
                    return fail("0x60B9 shows a touch probe enabled that 0x60B8 does not enable",
                                hex(s) + " (0x60B8 " + hex(f) + ")", "bits 0/8 as 0x60B8");
            }
            // ETG.5001.1 modular device profile: 0xF010 module profile list, one entry per module (:00 the
            // count), each the profile number of its module (402 for a drive axis); 0 names no profile. A
            // slot without a module (its ident 0 in 0xF050, the detected modules, else in 0xF030, the
            // configured ones: a modular device whose default configuration leaves slots empty) has no
            // profile to name.
            auto empty_slot = [&](unsigned s) {
                for (const uint16_t list : {0xF050, 0xF030}) {
                    auto id = ctx.upload(list, static_cast<uint8_t>(s));
                    if (id && id->size() == 4) return get32(id->data()) == 0;
                }
                return false;
            };
            if (auto n = ctx.upload(0xF010, 0); n && n->size() == 1 && (*n)[0] > 0) {
                seen += "0xf010 ";
                for (unsigned s = 1; s <= (*n)[0]; ++s) {
                    auto v = ctx.upload(0xF010, static_cast<uint8_t>(s));
                    if (v && v->size() == 4 && get32(v->data()) == 0 && !empty_slot(s))
                        return fail("0xF010:" + dec(s) + " (module profile) is 0", "0",
                                    "the module's profile number");
                }
            }
            if (seen.empty()) return skip("none of these objects");
            return pass("consistent", seen);
        },
        a);
    add(
        "pdo.control_status", "Controlword in the default RxPDO and statusword in the default TxPDO",
        "ETG.6010 CiA 402 drive profile over EtherCAT (process data)",
        [](Context& ctx) {
            CONFORM_NEED(need_402_profile(ctx));
            CONFORM_PREOP(ctx);
            PdoMap m;
            if (Error e = read_map(ctx, m); e != Error::Ok) return fail("mapping: " + ctx.sdo_error(e));
            return expect_eq(
                "0x6040 out / 0x6041 in",
                std::string(m.find_out(0x6040) ? "yes" : "no") + "/" + (m.find_in(0x6041) ? "yes" : "no"),
                "yes/yes");
        },
        a, Severity::Warning);
    for (const Mode& md : kModeList) {
        add(
            std::string("mode.") + md.id,
            std::string("Mode ") + dec(md.value) + " (" + md.name +
                ") of 0x6502 accepted by 0x6060 (read back) and shown by 0x6061",
            kModes,
            [md](Context& ctx) {
                CONFORM_NEED(need_402_profile(ctx));
                CONFORM_PREOP(ctx);
                auto sup = ctx.upload_uint(0x6502, 0);
                if (!sup) return modes_unreadable(ctx, sup.error());
                if (!(*sup & md.bit))
                    return skip(std::string(md.name) + " not in 0x6502 (" + hex(*sup, 8) + ")");
                auto old = ctx.upload_uint(0x6060, 0);
                if (Error e = ctx.download_uint(0x6060, 0, static_cast<uint8_t>(md.value), 1); e != Error::Ok)
                    return fail("0x6060 = " + dec(md.value) + ": " + ctx.sdo_error(e));
                // An acknowledged download is stored (ETG.1000.6 SDO download: the response confirms the
                // write): 0x6060 reads back the mode written, whatever 0x6061 shows later.
                if (auto back = ctx.upload(0x6060, 0);
                    back && !back->empty() && (*back)[0] != static_cast<uint8_t>(md.value)) {
                    if (old) (void)ctx.download_uint(0x6060, 0, *old, 1);
                    return fail(
                        "0x6060 = " + dec(md.value) + " acknowledged, but 0x6060 reads back another value",
                        dec(static_cast<int8_t>((*back)[0])), dec(md.value));
                }
                uint64_t shown = 0xFF;
                // IEC 61800-7-201: 0x6061 shows the mode in effect now. A drive may take its time to switch,
                // so the display is first read after a settling time; a display that shows the new mode at
                // the read right after, not at that one, follows the reads (it answers with the value of the
                // read before), not the time: it shows a mode no longer in effect to every single read.
                std::this_thread::sleep_for(ctx.ms(100));
                std::optional<uint8_t> first;
                for (int i = 0; i < 100; ++i) {
                    auto v = ctx.upload(0x6061, 0);
                    if (v && !v->empty()) shown = (*v)[0];
                    if (i == 0 && v && !v->empty()) first = (*v)[0];
                    if (shown == static_cast<uint8_t>(md.value)) {
                        if (i == 1 && first && *first != static_cast<uint8_t>(md.value)) {
                            if (old) (void)ctx.download_uint(0x6060, 0, *old, 1);
                            return fail(
                                "0x6061 showed the mode written only at the read after the first, "
                                "right after it (a display one read late)",
                                dec(static_cast<int8_t>(*first)) + " then " + dec(md.value),
                                dec(md.value) + " at the first read after " +
                                    dec(static_cast<long long>(ctx.ms(100).count())) + " ms");
                        }
                        break;
                    }
                    std::this_thread::sleep_for(std::chrono::milliseconds(2));
                }
                std::string where = " (PREOP)";
                if (shown != static_cast<uint8_t>(md.value)) {
                    // A drive whose application runs only with process data (from SAFEOP on) switches its
                    // mode there (IEC 61800-7-201 asks that 0x6061 show the mode in effect, not that PREOP
                    // runs the application): the mode once more, in the image where 0x6060 is mapped.
                    where = " (SAFEOP, process data running)";
                    PdoMap m;
                    if (ctx.to_safeop() == Error::Ok && read_map(ctx, m) == Error::Ok) {
                        prefill_outputs(ctx, m);
                        if (const MappedEntry* e = m.find_out(0x6060))
                            image_set(ctx.pds->outputs(), *e, md.value);
                        (void)ctx.download_uint(0x6060, 0, static_cast<uint8_t>(md.value), 1);
                        for (int i = 0; i < 50 && shown != static_cast<uint8_t>(md.value); ++i) {
                            (void)ctx.cycle(4);
                            if (auto v = ctx.upload(0x6061, 0); v && !v->empty()) shown = (*v)[0];
                        }
                    }
                    (void)ctx.to_preop();
                }
                // The same display in the process data, where the inputs map 0x6061 (a PDO is a second way to
                // read the object): in OP, outputs valid, 0x6060 set where the outputs map it; the drive
                // stays in switch on disabled (controlword 0), nothing moves.
                std::string pd_shown;
                if (shown == static_cast<uint8_t>(md.value)) {
                    Drive d(ctx);
                    if (d.start().empty()) {
                        if (const MappedEntry* in = d.map.find_in(0x6061)) {
                            if (d.mode)
                                image_set(ctx.pds->outputs(), *d.mode, static_cast<uint8_t>(md.value));
                            else
                                (void)ctx.download_uint(0x6060, 0, static_cast<uint8_t>(md.value), 1);
                            uint64_t v = 0xFF;
                            for (int i = 0; i < 200 && v != static_cast<uint8_t>(md.value); ++i) {
                                d.run(1);
                                v = image_get(ctx.pds->inputs(), *in) & 0xFF;
                            }
                            if (v != static_cast<uint8_t>(md.value)) pd_shown = dec(static_cast<int8_t>(v));
                        }
                    }
                    d.finish();
                    (void)ctx.to_preop();
                }
                if (old) (void)ctx.download_uint(0x6060, 0, *old, 1);
                if (!pd_shown.empty())
                    return fail("0x6061 in the process data (OP) after 0x6060 = " + dec(md.value) +
                                    ", while over SDO it shows the mode",
                                pd_shown, dec(md.value));
                return expect_eq("0x6061 after 0x6060 = " + dec(md.value) + where,
                                 dec(static_cast<int8_t>(shown)), dec(md.value));
            },
            "profile 402, mode in 0x6502");
    }
    add(
        "mode.unsupported", "A mode not in 0x6502 is refused by 0x6060 (abort) or not shown by 0x6061",
        kModes, [](Context& ctx) { return unsupported_mode(ctx, false); }, a, Severity::Warning);
    add(
        "mode.reserved_bits", "0x6502 supported drive modes: reserved bits 4 and 11-15 clear", kModes,
        [](Context& ctx) {
            CONFORM_NEED(need_402_profile(ctx));
            CONFORM_PREOP(ctx);
            auto sup = ctx.upload_uint(0x6502, 0);
            if (!sup) return modes_unreadable(ctx, sup.error());
            // Bits 0-3 and 5-9 name the standard modes, 10 the cyclic synchronous torque mode with
            // commutation angle (later editions), 16-31 manufacturer modes; 4 and 11-15 are reserved.
            if (*sup & 0xF810) return fail("reserved bits set", hex(*sup, 8), "bits 4, 11-15 clear");
            return pass("0x6502", hex(*sup, 8));
        },
        a);
    add(
        "mode.unsupported_acknowledged",
        "A mode not in 0x6502 that 0x6060 acknowledges reads back from 0x6060 (an acknowledged write is "
        "done)",
        "ETG.1000.6 SDO download response (the value is stored); IEC 61800-7-201 (CiA 402) 0x6060",
        [](Context& ctx) { return unsupported_mode(ctx, true); }, a);
    add(
        "homing.method_unlisted",
        "A homing method 0x60E3 does not list, written to 0x6098, is refused (the old method written back)",
        "IEC 61800-7-201 (CiA 402) 0x60E3 supported homing methods, 0x6098 homing method; ETG.1000.6 SDO "
        "abort "
        "(value range, 0x0609003x): a value the device declares unsupported is not taken",
        [](Context& ctx) {
            CONFORM_NEED(need_402_profile(ctx));
            CONFORM_PREOP(ctx);
            auto count = ctx.upload_uint(0x60E3, 0);
            auto old = ctx.upload(0x6098, 0);
            if (!count || !old || old->size() != 1) return skip("no 0x60E3 or 0x6098 (INTEGER8)");
            std::set<int> listed;
            for (unsigned s = 1; s <= *count && s < 255; ++s) {
                auto v = ctx.upload(0x60E3, static_cast<uint8_t>(s));
                if (!v || v->empty()) return fail("0x60E3:" + dec(s) + " (within :00) unreadable");
                listed.insert(static_cast<int8_t>((*v)[0]));
            }
            // A method of the standard's numbering (1-35, 37) that the list leaves out: only the SDO write,
            // nothing starts homing (that needs operation enabled and controlword bit 4).
            int bad = 0;
            for (int mth = 1; mth <= 37 && !bad; ++mth)
                if (mth != 36 && !listed.count(mth)) bad = mth;
            if (!bad) return skip("every standard homing method is listed");
            Error e = ctx.download_uint(0x6098, 0, static_cast<uint8_t>(bad), 1);
            (void)ctx.download(0x6098, 0, *old);
            if (e == Error::SdoAbort) return pass("refused", ctx.sdo_error(e));
            if (e != Error::Ok) return pass("not acknowledged", ctx.sdo_error(e));
            return fail("0x6098 = " + dec(bad) + " (not in 0x60E3) acknowledged", "acknowledged",
                        "an abort (0x06090030)");
        },
        a);
    add(
        "dc.shutdown", "Transition 2: shutdown (0x0006) in switch on disabled -> ready to switch on", kDev,
        [](Context& ctx) { return transition(ctx, kSod, 0x0006, kRtso, "transition 2"); }, a);
    add(
        "dc.switch_on", "Transition 3: switch on (0x0007) in ready to switch on -> switched on", kDev,
        [](Context& ctx) { return transition(ctx, kRtso, 0x0007, kSo, "transition 3"); }, a);
    add(
        "dc.enable_operation", "Transition 4: enable operation (0x000F) in switched on -> operation enabled",
        kDev, [](Context& ctx) { return transition(ctx, kSo, 0x000F, kOe, "transition 4"); }, a);
    add(
        "dc.disable_operation",
        "Transition 5: disable operation (0x0007) in operation enabled -> switched on", kDev,
        [](Context& ctx) { return transition(ctx, kOe, 0x0007, kSo, "transition 5"); }, a);
    add(
        "dc.switched_on_shutdown", "Transition 6: shutdown (0x0006) in switched on -> ready to switch on",
        kDev, [](Context& ctx) { return transition(ctx, kSo, 0x0006, kRtso, "transition 6"); }, a);
    add(
        "dc.disable_voltage",
        "Transition 7: disable voltage (0x0000) in ready to switch on -> switch on disabled", kDev,
        [](Context& ctx) { return transition(ctx, kRtso, 0x0000, kSod, "transition 7"); }, a);
    add(
        "dc.enabled_shutdown", "Transition 8: shutdown (0x0006) in operation enabled -> ready to switch on",
        kDev, [](Context& ctx) { return transition(ctx, kOe, 0x0006, kRtso, "transition 8"); }, a);
    add(
        "dc.enabled_disable_voltage",
        "Transition 9: disable voltage (0x0000) in operation enabled -> switch on disabled", kDev,
        [](Context& ctx) { return transition(ctx, kOe, 0x0000, kSod, "transition 9"); }, a);
    add(
        "dc.switched_on_disable_voltage",
        "Transition 10: disable voltage (0x0000) in switched on -> switch on disabled", kDev,
        [](Context& ctx) { return transition(ctx, kSo, 0x0000, kSod, "transition 10"); }, a);
    add(
        "dc.quick_stop", "Transition 11: quick stop (0x0002) in operation enabled, then as 0x605A says",
        "IEC 61800-7-201 (CiA 402) transition 11, quick stop option code 0x605A",
        [](Context& ctx) {
            CONFORM_NEED(need_402_profile(ctx));
            CONFORM_PREOP(ctx);
            auto opt = ctx.upload_uint(0x605A, 0);
            const int16_t code = opt ? static_cast<int16_t>(*opt) : 2;
            Drive d(ctx);
            if (auto e = d.start(); !e.empty())
                return e.find("not in the process data") != std::string::npos ? skip(e) : fail(e);
            if (!d.to(kOe)) {
                std::string s = sw_text(d.status());
                d.finish();
                return fail("cannot reach operation enabled", s, kOe.name);
            }
            // 0x605A 1..4: stop, then switch on disabled; 5..8: stop and stay in quick stop active. A
            // manufacturer-specific code (-32768..-1; KickCAT's and Ingenia's ESIs give -1) says nothing the
            // tool can hold the drive to: either end state after the stop is accepted.
            const bool vendor_code = code < 0;
            const DsState& want = (code >= 5 && code <= 8) ? kQsa : kSod;
            bool left_oe = false;
            image_set(ctx.pds->outputs(), *d.cw, 0x0002);
            const auto deadline = std::chrono::steady_clock::now() + ctx.ms(1500);
            bool ok = false;
            while (std::chrono::steady_clock::now() < deadline) {
                d.run(1);
                const uint16_t s = d.status();
                left_oe = left_oe || (s & kOe.mask) != kOe.value;
                if ((s & want.mask) == want.value || (vendor_code && (s & kQsa.mask) == kQsa.value)) {
                    ok = true;
                    break;
                }
            }
            if (ok && &want == &kQsa) {
                d.run(50);  // it stays there while the quick stop command stands
                ok = (d.status() & kQsa.mask) == kQsa.value;
            }
            const std::string s = sw_text(d.status());
            d.finish();
            if (!ok)
                return fail("quick stop with 0x605A = " + dec(code) +
                                (left_oe ? "" : " (never left operation enabled)"),
                            s, want.name);
            return pass("0x605A = " + dec(code), s);
        },
        a);
    add(
        "dc.quick_stop_exit",
        "Transition 12: disable voltage (0x0000) in quick stop active -> switch on disabled", kDev,
        [](Context& ctx) {
            CONFORM_NEED(need_402_profile(ctx));
            CONFORM_PREOP(ctx);
            auto opt = ctx.upload_uint(0x605A, 0);
            if (!opt || static_cast<int16_t>(*opt) < 5 || static_cast<int16_t>(*opt) > 8)
                return skip("0x605A does not keep the drive in quick stop active");
            Drive d(ctx);
            if (auto e = d.start(); !e.empty())
                return e.find("not in the process data") != std::string::npos ? skip(e) : fail(e);
            if (!d.to(kOe) || !d.command(0x0002, kQsa, 1500)) {
                std::string s = sw_text(d.status());
                d.finish();
                return fail("cannot reach quick stop active", s, kQsa.name);
            }
            const bool ok = d.command(0x0000, kSod);
            const std::string s = sw_text(d.status());
            d.finish();
            if (!ok) return fail("transition 12", s, kSod.name);
            return pass("transition 12", s);
        },
        "profile 402, 0x605A = 5..8");
    add(
        "statusword.bits",
        "Operation enabled, holding in CSP: statusword state bits and bit 4 the same in the image and over "
        "SDO, bit 9 remote set (the controlword is processed), bit 11 internal limit and bit 13 following "
        "error clear; 0x6040 over SDO reads the controlword of the image",
        "IEC 61800-7-201 (CiA 402) statusword 0x6041 state bits 0-3, 5, 6 and bits 4, 9, 11, 13 (csp)",
        [](Context& ctx) {
            CONFORM_NEED(need_402_profile(ctx));
            Drive d(ctx);
            if (auto e = d.start(); !e.empty())
                return e.find("not in the process data") != std::string::npos ? skip(e) : fail(e);
            auto mode = ctx.upload_uint(0x6061, 0);
            const bool csp = mode && (*mode & 0xFF) == 8;
            if (!d.to(kOe)) {
                std::string s = sw_text(d.status());
                d.finish();
                return fail("cannot reach operation enabled", s, kOe.name);
            }
            d.run(20);
            const uint16_t img = d.status();
            auto sdo = ctx.upload_uint(0x6041, 0);
            auto cw = ctx.upload_uint(0x6040, 0);
            d.finish();
            if (!sdo) return fail("0x6041 upload: " + ctx.sdo_error(sdo.error()));
            // The controlword is one object too: over SDO it reads what the process data write into it
            // (enable operation 0x000F: bits 0-3 and 7, the command bits of IEC 61800-7-201).
            if (cw && (*cw & 0x008F) != 0x000F)
                return fail("0x6040 over SDO does not read back the controlword the process data write",
                            hex(*cw & 0xFFFF), "0x000f (bits 0-3, 7)");
            // The state bits (0-3, 5, 6: operation enabled is xxxx xxxx x01x 0111) and bit 4 (voltage
            // enabled) are the same whichever way the statusword is read, in a steady state.
            if ((*sdo & 0x7F) != (img & 0x7F))
                return fail("statusword over SDO differs from the image in bits 0-6 (state, voltage enabled)",
                            "SDO " + sw_text(static_cast<uint16_t>(*sdo)) + ", image " + sw_text(img),
                            "the same bits 0-6");
            for (const auto& [where, sw] :
                 {std::pair<const char*, uint16_t>{"image", img}, {"SDO", static_cast<uint16_t>(*sdo)}}) {
                const std::string w = std::string(where) + ": ";
                if ((sw & 0x6F) != 0x27)
                    return fail(w + "not operation enabled (bits 0-3, 5, 6)", sw_text(sw),
                                "xxxx xxxx x01x 0111");
                if (!(sw & 0x0200))
                    return fail(w + "bit 9 (remote) clear although the drive follows the controlword",
                                sw_text(sw), "bit 9 set");
                if (!csp)
                    continue;  // bits 11 and 13 are mode-specific: checked where the axis is held in CSP
                if (sw & 0x0800)
                    return fail(w + "bit 11 (internal limit active) while holding", sw_text(sw), "clear");
                if (sw & 0x2000)
                    return fail(w + "bit 13 (following error) with the target at the actual position",
                                sw_text(sw), "clear");
            }
            return pass("statusword", sw_text(img) + (csp ? " (csp)" : ""));
        },
        "profile 402");
    add(
        "statusword.target_reached_halt",
        "Profile velocity mode, target velocity 0, halt set, operation enabled: statusword bit 10 (target "
        "reached) set once the axis stands (no motion is commanded)",
        "IEC 61800-7-201 (CiA 402) statusword 0x6041 bit 10 in profile velocity mode: with halt, set at "
        "velocity 0",
        [](Context& ctx) {
            CONFORM_NEED(need_402_profile(ctx));
            CONFORM_PREOP(ctx);
            auto modes = ctx.upload_uint(0x6502, 0);
            if (!modes || !(*modes & 0x04)) return skip("0x6502 does not announce profile velocity mode");
            Drive d(ctx);
            if (auto e = d.start(); !e.empty())
                return e.find("not in the process data") != std::string::npos ? skip(e) : fail(e);
            // Profile velocity, target velocity 0: in the image where mapped, else over SDO.
            if (d.mode)
                image_set(ctx.pds->outputs(), *d.mode, 3);
            else
                (void)ctx.download_uint(0x6060, 0, 3, 1);
            if (const MappedEntry* v = d.map.find_out(0x60FF))
                image_set(ctx.pds->outputs(), *v, 0);
            else
                (void)ctx.download_uint(0x60FF, 0, 0, 4);
            d.run(20);
            auto shown = ctx.upload_uint(0x6061, 0);
            if (!shown || (*shown & 0xFF) != 3) {
                d.finish();
                return skip("the drive did not take profile velocity mode (0x6061 " +
                            (shown ? hex(*shown & 0xFF) : std::string("unreadable")) + ")");
            }
            if (!d.to(kOe)) {
                const std::string s = sw_text(d.status());
                d.finish();
                return fail("cannot reach operation enabled", s, kOe.name);
            }
            image_set(ctx.pds->outputs(), *d.cw, 0x010F);  // halt
            const auto deadline = std::chrono::steady_clock::now() + ctx.ms(1000);
            uint16_t sw = d.status();
            while (!(sw & 0x0400) && std::chrono::steady_clock::now() < deadline) {
                d.run(1);
                sw = d.status();
            }
            d.run(5);
            auto sdo = ctx.upload_uint(0x6041, 0);
            d.finish();
            if (!(sw & 0x0400))
                return fail("image: bit 10 (target reached) clear with halt at velocity 0", sw_text(sw),
                            "bit 10 set");
            if (!sdo) return fail("0x6041 upload: " + ctx.sdo_error(sdo.error()));
            if (!(*sdo & 0x0400))
                return fail("SDO: bit 10 (target reached) clear with halt at velocity 0",
                            sw_text(static_cast<uint16_t>(*sdo)), "bit 10 set");
            return pass("target reached", sw_text(sw));
        },
        "profile 402, 0x6502 announces profile velocity");
    add(
        "fault.emergency",
        "Fault (communication loss while enabled): its emergency has 8 bytes, a non-zero error code as "
        "0x603F, the error register as 0x1001",
        "ETG.1000.6 CoE emergency; ETG.1000.4 mailbox counter; CiA 301 error register 0x1001; IEC "
        "61800-7-201 error code 0x603F",
        [](Context& ctx) { return fault_emergency(ctx, false); }, "profile 402 and --allow-fault");
    add(
        "fault.emergency_generic_bit", "The fault's emergency error register has bit 0 (generic error) set",
        "ETG.1000.6 CoE emergency; CiA 301 error register 0x1001 bit 0 (generic error, at any error)",
        [](Context& ctx) { return fault_emergency(ctx, true); }, "profile 402 and --allow-fault",
        Severity::Warning);
    add("fault.diag_history",
        "Fault (communication loss while enabled): its emergency stored in the diagnosis history 0x10F3 as a "
        "newer message (:02 moves), diag code 0xE800 with the error code, type warning or error, a time "
        "stamp, the parameters its flags count; its acknowledgement (:03) read back",
        "ETG.1020 diagnosis history 0x10F3 (:02 newest message, :03 newest acknowledged message; message "
        "diag code, flags bits 0-3 type and 8-15 parameter count, time stamp); ETG.1000.6 CoE emergency",
        fault_history, "profile 402, 0x10F3 and --allow-fault");
    add(
        "fault_reset",
        "Fault (from a communication loss while enabled) and fault reset (0x0080 edge): transition 15; the "
        "statusword over SDO as in the image, then an error-reset emergency (if any) and 0x1001 bit 0 clear",
        "IEC 61800-7-201 (CiA 402) transitions 13-15, statusword 0x6041; 0x6007 abort connection option; "
        "CiA 301 / ETG.1000.6 emergency error code 0x0000 (error reset), error register 0x1001",
        [](Context& ctx) {
            Drive d(ctx);
            if (auto o = faulted_drive(ctx, d)) return *o;
            // The statusword is one object, whichever way it is read: over SDO it shows the state the image
            // shows (state bits 0-3, 5, 6), in Fault (read in SAFEOP, where no watchdog runs) and after the
            // reset.
            const uint16_t img_fault = d.status();
            // The emergencies of the fault, read out before any SDO transfer could pass them over.
            const auto fault_emcy = drain_emergencies(ctx, d);
            auto sdo_fault = ctx.upload_uint(0x6041, 0);
            master::AlStatus st;
            (void)ctx.enter_op(st, [&d] { d.hold(); });
            (void)d.command(0x0000, kFault, 20);
            const bool ok = d.command(0x0080, kSod, 1000);
            // After the reset (no error left): the emergencies sent end with "error reset" (code 0x0000,
            // CiA 301 / ETG.1000.6), and 0x1001 has no generic error (bit 0). They are read out first: an
            // SDO transfer would pass them over.
            const auto emcy = drain_emergencies(ctx, d);
            const uint16_t img_after = d.status();
            auto sdo_after = ctx.upload_uint(0x6041, 0);
            auto reg = ctx.upload_uint(0x1001, 0);
            const std::string s = sw_text(d.status());
            d.finish();
            if (!ok) return fail("fault reset edge did not leave fault", s, kSod.name);
            if (sdo_fault && (*sdo_fault & 0x6F) != (img_fault & 0x6F))
                return fail("in Fault, 0x6041 over SDO against the image",
                            sw_text(static_cast<uint16_t>(*sdo_fault)), sw_text(img_fault));
            if (sdo_after && (*sdo_after & 0x6F) != (img_after & 0x6F))
                return fail("after the reset, 0x6041 over SDO against the image",
                            sw_text(static_cast<uint16_t>(*sdo_after)), sw_text(img_after));
            if (!emcy.empty() && get16(&emcy.back()[8]) != 0)
                return fail("the last emergency after the fault reset is not \"error reset\" (code 0x0000)",
                            bytes_hex(std::span<const uint8_t>(emcy.back()).subspan(0, 16)), "code 0x0000");
            // CiA 301 / ETG.1000.6 emergency: one message when an error occurs, one (code 0x0000) when it is
            // gone. A drive that signals its faults by emergency signals the reset too, and one that signals
            // a reset had an error to signal: either message alone is a lost emergency.
            bool fault_sent = false;
            for (const auto& x : fault_emcy)
                fault_sent = fault_sent || get16(&x[8]) != 0;
            if (fault_sent && emcy.empty())
                return fail(
                    "an emergency for the fault, but none (\"error reset\", code 0x0000) after the reset",
                    "no emergency", "an emergency with code 0x0000");
            if (!emcy.empty() && !fault_sent)
                return fail(
                    "an \"error reset\" emergency after the reset, but no emergency for the fault itself",
                    "reset " + bytes_hex(std::span<const uint8_t>(emcy.back()).subspan(0, 16)),
                    "the fault's emergency (a non-zero error code) first");
            // The error register an emergency carries is 0x1001 as it is then (CiA 301): after the reset,
            // with no error left, the register of the fault is gone.
            if (!emcy.empty() && reg && emcy.back()[10] != (*reg & 0xFF))
                return fail("the \"error reset\" emergency's error register against 0x1001 after the reset",
                            hex(emcy.back()[10], 2), hex(*reg & 0xFF, 2));
            if (reg && (*reg & 0x01))
                return fail("0x1001 still shows the generic error (bit 0) after the fault reset",
                            hex(*reg, 2), "bit 0 clear");
            return pass("reset", s);
        },
        "profile 402 and --allow-fault");
}

}  // namespace conform
