// Group esm: the EtherCAT state machine: every valid transition, every invalid request with its AL status
// code, error acknowledge, mailbox and process-data SM checks, the SM watchdog, Bootstrap, identification.
#include <algorithm>
#include <thread>

#include "testkit.hpp"

namespace conform {

namespace {

using master::Error;
constexpr const char* kEsm = "ETG.1000.6 EtherCAT state machine (state transitions)";
constexpr const char* kCodes = "ETG.1000.6 AL status codes";
// What an ESC with device emulation does instead of a state machine.
constexpr const char* kEmulation = "ESC datasheet section II 0x0141 (device emulation)";

const char* short_name(uint8_t s) {
    switch (s) {
        case 1:
            return "init";
        case 2:
            return "preop";
        case 3:
            return "boot";
        case 4:
            return "safeop";
        case 8:
            return "op";
    }
    return "?";
}

std::string status_text(const master::AlStatus& s) {
    return state_text(static_cast<uint8_t>(s.state | (s.error ? 0x10 : 0))) + " code " + hex(s.code);
}

std::string needs_for(const Context& ctx, uint8_t a, uint8_t b) {
    if (a == 3 || b == 3) {
        if (auto r = ctx.need_boot(); !r.empty()) return r;
    }
    // A device without mailbox runs the same state sequence with process data only; its process-data layout
    // comes from the SII where there is no CoE (ETG.1000.6 ESM; ETG.2010 SyncM/PDO categories).
    if (a >= 4 || b >= 4) {
        if (auto r = ctx.need_pd_layout(); !r.empty()) return "the process-data layout: " + r;
    }
    return {};
}

Outcome valid(Context& ctx, uint8_t from, uint8_t to) {
    CONFORM_NEED(needs_for(ctx, from, to));
    if (Error e = ctx.reach(from); e != Error::Ok)
        return fail(std::string("cannot reach ") + short_name(from) + ": " + err(e) +
                    (e == Error::AlRefused ? " (" + status_text(ctx.last_status) + ")" : ""));
    master::AlStatus st;
    if (from == 2 && to == 4) {
        if (Error e = ctx.discover_pd(); e != Error::Ok)
            return fail("process-data layout: " + ctx.sdo_error(e));
        if (Error e = ctx.configure_pd(); e != Error::Ok)
            return fail("process-data set-up: " + ctx.sdo_error(e));
        st = ctx.request_raw(4, ctx.ms(5000));
    } else if (from == 1 && to == 2 && !ctx.has_mailbox()) {
        st = ctx.request_raw(2, ctx.ms(5000));  // no mailbox to set up
    } else if (from == 1 && (to == 2 || to == 3)) {
        ctx.mbx = std::make_unique<master::Mailbox>(ctx.m, ctx.addr, ctx.ms(1000));
        if (Error e = ctx.mbx->configure_from_sii(to == 3); e != Error::Ok)
            return fail("mailbox set-up: " + err(e));
        st = ctx.request_raw(to, ctx.ms(5000));
        ctx.mbx.reset();
    } else if (to == 8) {
        (void)ctx.request_op(st);
        if (auto c = ctx.rd<uint16_t>(esc::reg::kAlStatusCode)) st.code = *c;
    } else {
        st = ctx.request_raw(to, ctx.ms(5000));
    }
    const std::string want = state_text(to) + " code " + hex(0);
    if (st.state != to || st.error) {
        (void)ctx.ack_error();
        if (st.state == to)
            return fail(
                "the state was reached but shown with the error indication (AL status bit 4 belongs to "
                "a refused or left state)",
                status_text(st), want);
        return fail("transition refused or not completed", status_text(st), want);
    }
    if (to == 1) ctx.in_preop = false;
    return pass("reached", status_text(st));
}

// With device emulation (ESC configuration 0x0141 bit 0) the ESC sets AL status to the state written to AL
// control (ESC datasheet section II, 0x0141, 0x0120, 0x0130): nothing refuses, no error indication, code 0.
// That is what such a device must do for a request another device refuses.
Outcome emulated(Context& ctx, uint8_t from, uint8_t to) {
    if (Error e = ctx.reach(from); e != Error::Ok)
        return fail(std::string("cannot reach ") + short_name(from) + ": " + err(e),
                    status_text(ctx.last_status));
    master::AlStatus st = ctx.request_raw(to, ctx.ms(1000));
    (void)ctx.to_init();
    const std::string want = state_text(to & 0x0F) + " code " + hex(0);
    if (st.error || st.state != (to & 0x0F) || st.code != 0)
        return fail("device emulation: AL status does not follow AL control", status_text(st), want);
    return pass("device emulation: the ESC took the request as written", status_text(st));
}

Outcome invalid(Context& ctx, uint8_t from, uint8_t to, uint16_t code) {
    CONFORM_NEED(needs_for(ctx, from, from));
    if (ctx.device_emulation) return emulated(ctx, from, to);
    if (Error e = ctx.reach(from); e != Error::Ok)
        return fail(
            std::string("cannot reach ") + short_name(from) + ": " + err(e),
            state_text(static_cast<uint8_t>(ctx.last_status.state | (ctx.last_status.error ? 0x10 : 0))) +
                " code " + hex(ctx.last_status.code));
    if (from == 8) (void)ctx.cycle(2);
    master::AlStatus st = ctx.request_raw(to, ctx.ms(1000));
    // The slave may take a moment to set the error indication.
    for (int i = 0; i < 20 && !st.error && st.state == from; ++i) {
        if (from == 8) (void)ctx.cycle(1);
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
        st = ctx.request_raw(to, ctx.ms(1));
    }
    (void)ctx.ack_error();
    ctx.in_preop = false;
    const std::string want = state_text(static_cast<uint8_t>(from | 0x10)) + " code " + hex(code);
    if (!st.error || st.state != from || st.code != code)
        return fail("invalid request not refused as specified", status_text(st), want);
    return pass("refused", status_text(st));
}

// Writes SM n's 8 register bytes (disabled first).
Error write_sm(Context& ctx, unsigned n, uint16_t start, uint16_t len, uint8_t control, bool enable) {
    uint8_t sm[8] = {};
    const uint8_t off[8] = {};
    (void)ctx.m.write(ctx.addr, static_cast<uint16_t>(master::reg::Sm0 + 8 * n), off);
    put16(sm, start);
    put16(sm + 2, len);
    sm[4] = control;
    sm[6] = enable ? 1 : 0;
    return ctx.m.write(ctx.addr, static_cast<uint16_t>(master::reg::Sm0 + 8 * n), sm);
}

Outcome bad_mailbox(Context& ctx, int variant) {
    CONFORM_NEED(ctx.need_mailbox());
    CONFORM_NEED(ctx.need_state_machine());
    if (Error e = ctx.to_init(); e != Error::Ok) return fail("cannot reach INIT", err(e));
    const SiiImage& s = *ctx.sii;
    uint16_t o_start = s.word(0x18), o_len = s.word(0x19), i_start = s.word(0x1A), i_len = s.word(0x1B);
    bool o_en = true, i_en = true;
    if (variant == 0) o_len = static_cast<uint16_t>(o_len - 2);
    if (variant == 1) i_start = static_cast<uint16_t>(i_start + 0x10);
    if (variant == 2) o_en = i_en = false;
    if (variant == 3)
        o_start = s.word(0x14), o_len = s.word(0x15), i_start = s.word(0x16), i_len = s.word(0x17);
    (void)write_sm(ctx, 0, o_start, o_len, 0x26, o_en);
    (void)write_sm(ctx, 1, i_start, i_len, 0x22, i_en);
    master::AlStatus st = ctx.request_raw(2, ctx.ms(2000));
    (void)ctx.ack_error();
    (void)ctx.to_init();
    const std::string want = "INIT+ERR code " + hex(0x0016);
    if (st.state != 1 || !st.error || st.code != 0x0016)
        return fail("PREOP with a wrong mailbox SM", status_text(st), want);
    return pass("refused", status_text(st));
}

Outcome bad_pd_sm(Context& ctx, bool outputs, bool address) {
    CONFORM_NEED(ctx.need_pd_layout());
    CONFORM_NEED(ctx.need_state_machine());
    if (Error e = ctx.to_preop(); e != Error::Ok) return fail("cannot reach PREOP", err(e));
    if (Error e = ctx.discover_pd(); e != Error::Ok) return fail("process-data layout: " + ctx.sdo_error(e));
    if (Error e = ctx.configure_pd(); e != Error::Ok) return fail("process-data set-up: " + ctx.sdo_error(e));
    const auto& l = ctx.pds->layout();
    if (!l.bytes(outputs))
        return skip(outputs ? "no outputs (no RxPDO assigned)" : "no inputs (no TxPDO assigned)");
    // The first SM of the direction with data: SM2/SM3 with a mailbox, SM0/SM1 on a device without one.
    const master::ProcessDataSm& sm = *l.first(outputs);
    (void)write_sm(ctx, sm.index, static_cast<uint16_t>(sm.start + (address ? 0x40 : 0)),
                   static_cast<uint16_t>(sm.length + (address ? 0 : 1)), sm.control, true);
    master::AlStatus st = ctx.request_raw(4, ctx.ms(2000));
    (void)ctx.ack_error();
    ctx.in_preop = false;
    const uint16_t code = outputs ? 0x001D : 0x001E;
    const std::string want = "PREOP+ERR code " + hex(code);
    if (st.state != 2 || !st.error || st.code != code)
        return fail("SAFEOP with a wrong SM", status_text(st), want);
    return pass("refused", status_text(st));
}

// AL status codes a refusal of a DC or synchronisation setting may carry (ETG.1000.6 AL status codes):
// sync error 0x001A, watchdog configuration 0x001F (with the SM watchdog test), inconsistent settings
// 0x0026, the synchronisation family 0x0027-0x002E and the DC family 0x0030-0x0037.
bool sync_refusal_code(uint16_t code, bool watchdog) {
    return code == 0x001A || code == 0x0026 || (code >= 0x0027 && code <= 0x002E) ||
           (code >= 0x0030 && code <= 0x0037) || (watchdog && code == 0x001F);
}

// PREOP -> SAFEOP with the process data and SYNC0 set up as a master does (ETG.1020 DC set-up: cycle time,
// start time on the cycle grid ahead, then 0x0980/0x0981 AssignActivate), with the given AssignActivate and
// cycle time, optionally with an SM watchdog of one divider unit (0x0420 = 1). A device may take the
// setting (not judged here: it runs or reports later); a refusal must name it with a code of its family
// (sync_refusal_code), not another situation's code.
Outcome sync_setting(Context& ctx, uint16_t assign_activate, uint32_t cycle, bool short_watchdog,
                     const std::string& what) {
    CONFORM_NEED(ctx.need_dc());
    CONFORM_NEED(need_sync0_op_mode(ctx));  // DC SYNC settings of a device that has a SYNC0 mode
    CONFORM_NEED(ctx.need_pd_layout());
    CONFORM_NEED(ctx.need_state_machine());
    if (Error e = ctx.to_preop(); e != Error::Ok) return fail("cannot reach PREOP", err(e));
    if (Error e = ctx.discover_pd(); e != Error::Ok) return fail("process-data layout: " + ctx.sdo_error(e));
    if (short_watchdog && !ctx.pds->layout().output_bytes()) return skip("no outputs: no SM watchdog");
    auto wd = ctx.rd<uint16_t>(0x0420);
    if (!wd) return fail("0x0420 unreadable", err(wd.error()));
    if (short_watchdog && *wd == 0) return skip("process-data watchdog disabled (0x0420 = 0)");
    master::DcConfig dc;
    dc.enable = true;
    dc.cycle_ns = cycle;
    dc.assign_activate = assign_activate;
    dc.start_delay = std::chrono::milliseconds(ctx.ms(100).count());
    if (Error e = ctx.configure_pd(dc); e != Error::Ok) {
        (void)ctx.wr<uint16_t>(esc::reg::kDcCyclicControl, 0);
        return fail("process-data and DC set-up: " + ctx.sdo_error(e));
    }
    if (short_watchdog) (void)ctx.wr<uint16_t>(0x0420, 1);
    const master::AlStatus st = ctx.request_raw(4, ctx.ms(2000));
    (void)ctx.wr<uint16_t>(esc::reg::kDcCyclicControl, 0);
    (void)ctx.wr<uint16_t>(0x0420, *wd);
    (void)ctx.ack_error();
    (void)ctx.to_init();
    ctx.in_preop = false;
    if (st.state == 4 && !st.error) return pass(what + ": taken", status_text(st));
    if (st.state != 2 || !st.error)
        return fail(what + ": neither SAFEOP nor refused in PREOP", status_text(st), "SAFEOP, or PREOP+ERR");
    if (!sync_refusal_code(st.code, short_watchdog))
        return fail(what + ": refused with the code of another situation", status_text(st),
                    short_watchdog
                        ? "0x001F, or a synchronisation code (0x001A, 0x0026-0x002E, 0x0030-0x0037)"
                        : "a synchronisation code (0x001A, 0x0026-0x002E, 0x0030-0x0037)");
    return pass(what + ": refused", status_text(st));
}

// PREOP -> SAFEOP synchronous with the SM2 event (0x1C32:01 = 1) at a cycle time (0x1C32:02) half the minimum
// the slave names (0x1C32:05). Refused at the write (an abort) or at the transition, the refusal names the
// cycle (0x002E cycle time too small, or 0x001A / 0x0026-0x002D of the synchronisation family), not a DC
// code (0x0030-0x0037: no DC runs) or another situation's. Taken is not judged. 0x1C32:01/:02 are written
// back in PREOP, the slave left in INIT.
Outcome sm_cycle_below_min(Context& ctx) {
    CONFORM_NEED(ctx.need_coe());
    CONFORM_NEED(ctx.need_pd_layout());
    CONFORM_NEED(ctx.need_state_machine());
    if (Error e = ctx.to_preop(); e != Error::Ok) return fail("cannot reach PREOP", err(e));
    auto sup = ctx.upload_uint(0x1C32, 4);
    auto min = ctx.upload_uint(0x1C32, 5);
    auto old1 = ctx.upload_uint(0x1C32, 1);
    auto old2 = ctx.upload_uint(0x1C32, 2);
    if (!sup || !(*sup & 0x02)) return skip("0x1C32:04 does not announce SM2-event synchronisation (bit 1)");
    if (!min || *min < 2 || !old1 || !old2)
        return skip("no 0x1C32:05 minimum cycle time (or :01/:02 unreadable)");
    auto restore = [&] {
        (void)ctx.ack_error();
        (void)ctx.to_preop();
        (void)ctx.download_uint(0x1C32, 2, *old2, 4);
        (void)ctx.download_uint(0x1C32, 1, *old1, 2);
        (void)ctx.to_init();
        ctx.in_preop = false;
    };
    if (ctx.download_uint(0x1C32, 1, 1, 2) != Error::Ok) {
        restore();
        return skip("0x1C32:01 = 1 (SM2 event) not taken");
    }
    const uint64_t cycle = *min / 2;
    if (Error e = ctx.download_uint(0x1C32, 2, cycle, 4); e != Error::Ok) {
        restore();
        return pass("refused at the write of 0x1C32:02 = " + dec(static_cast<long long>(cycle)),
                    ctx.sdo_error(e));
    }
    Error e = ctx.discover_pd();
    if (e == Error::Ok) e = ctx.configure_pd();
    if (e != Error::Ok) {
        restore();
        return fail("process-data set-up: " + ctx.sdo_error(e));
    }
    const master::AlStatus st = ctx.request_raw(4, ctx.ms(2000));
    restore();
    const std::string what = "SM2-event synchronisation at " + dec(static_cast<long long>(cycle)) +
                             " ns, below 0x1C32:05 = " + dec(static_cast<long long>(*min)) + " ns";
    if (st.state == 4 && !st.error) return pass(what + ": taken", status_text(st));
    if (st.state != 2 || !st.error)
        return fail(what + ": neither SAFEOP nor refused in PREOP", status_text(st), "SAFEOP, or PREOP+ERR");
    const bool sync_family = st.code == 0x001A || (st.code >= 0x0026 && st.code <= 0x002E);
    if (!sync_family)
        return fail(what + ": refused with the code of another situation", status_text(st),
                    "0x002E (cycle time too small), or 0x001A / 0x0026-0x002D; not a DC code (no DC runs)");
    return pass(what + ": refused", status_text(st));
}

}  // namespace

void add_esm_tests(Catalogue& c) {
    Adder add{c, "esm"};
    struct T {
        uint8_t from, to;
    };
    for (T t : {T{1, 2}, T{2, 4}, T{4, 8}, T{8, 4}, T{4, 2}, T{2, 1}, T{8, 2}, T{8, 1}, T{4, 1}, T{1, 3},
                T{3, 1}, T{1, 1}, T{2, 2}, T{4, 4}, T{8, 8}}) {
        std::string id = std::string(short_name(t.from)) + "_to_" + short_name(t.to);
        std::string applies;
        if (t.from == 3 || t.to == 3)
            applies = "bootstrap mailbox in the SII";
        else if (t.from >= 4 || t.to >= 4)
            applies = "process-data layout (over CoE, else from the SII)";
        add(
            id,
            "Valid transition " + std::string(master::al_state_name(t.from)) + " -> " +
                std::string(master::al_state_name(t.to)) + ": reached without error, AL status code 0",
            kEsm, [t](Context& ctx) { return valid(ctx, t.from, t.to); }, applies);
    }
    for (T t : {T{1, 4}, T{1, 8}, T{2, 8}, T{2, 3}, T{4, 3}, T{8, 3}, T{3, 2}, T{3, 4}, T{3, 8}}) {
        std::string id = std::string("invalid.") + short_name(t.from) + "_to_" + short_name(t.to);
        add(
            id,
            "Invalid request " + std::string(master::al_state_name(t.from)) + " -> " +
                std::string(master::al_state_name(t.to)) +
                ": refused with 0x0011, state kept (device emulation: taken as written)",
            std::string(kEsm) + "; " + kCodes + " (0x0011); " + kEmulation,
            [t](Context& ctx) { return invalid(ctx, t.from, t.to, 0x0011); },
            t.from == 3 ? "bootstrap mailbox in the SII" : "");
    }
    for (uint8_t s : {uint8_t{0x05}, uint8_t{0x06}, uint8_t{0x07}, uint8_t{0x09}}) {
        add("unknown_state_" + hex(s, 2).substr(2),
            "Unknown requested state " + hex(s, 2) +
                ": refused with 0x0012 (device emulation: taken as written)",
            std::string(kCodes) + " (0x0012); " + kEmulation,
            [s](Context& ctx) { return invalid(ctx, 2, s, 0x0012); });
    }
    add(
        "boot.not_supported",
        "INIT -> BOOT without a bootstrap mailbox: refused with 0x0013 (device emulation: taken as written)",
        std::string(kCodes) + " (0x0013); " + kEmulation,
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_sii());
            if (ctx.need_boot().empty()) return skip("the SII announces a bootstrap mailbox");
            return invalid(ctx, 1, 3, 0x0013);
        },
        "no bootstrap mailbox in the SII");
    add(
        "boot.wrong_mailbox", "INIT -> BOOT with the standard mailbox layout: refused with 0x0015",
        std::string(kCodes) + " (0x0015)",
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_boot());
            CONFORM_NEED(ctx.need_mailbox());
            const SiiImage& s = *ctx.sii;
            if (s.word(0x14) == s.word(0x18) && s.word(0x15) == s.word(0x19) &&
                s.word(0x16) == s.word(0x1A) && s.word(0x17) == s.word(0x1B))
                return skip("bootstrap and standard mailbox have the same layout");
            (void)ctx.to_init();
            (void)write_sm(ctx, 0, s.word(0x18), s.word(0x19), 0x26, true);
            (void)write_sm(ctx, 1, s.word(0x1A), s.word(0x1B), 0x22, true);
            master::AlStatus st = ctx.request_raw(3, ctx.ms(2000));
            (void)ctx.ack_error();
            (void)ctx.to_init();
            if (st.state != 1 || !st.error || st.code != 0x0015)
                return fail("BOOT with the standard mailbox", status_text(st), "INIT+ERR code 0x0015");
            return pass("refused", status_text(st));
        },
        "bootstrap mailbox differs from the standard one");
    add(
        "mbx.sm0_length", "INIT -> PREOP with a wrong SM0 length: refused with 0x0016",
        std::string(kCodes) + " (0x0016)", [](Context& ctx) { return bad_mailbox(ctx, 0); },
        "mailbox slave, no device emulation");
    add(
        "mbx.sm1_address", "INIT -> PREOP with a wrong SM1 start address: refused with 0x0016",
        std::string(kCodes) + " (0x0016)", [](Context& ctx) { return bad_mailbox(ctx, 1); },
        "mailbox slave, no device emulation");
    add(
        "mbx.sm_disabled", "INIT -> PREOP with the mailbox SMs not activated: refused with 0x0016",
        std::string(kCodes) + " (0x0016)", [](Context& ctx) { return bad_mailbox(ctx, 2); },
        "mailbox slave, no device emulation");
    add(
        "mbx.boot_layout_in_preop", "INIT -> PREOP with the bootstrap mailbox layout: refused with 0x0016",
        std::string(kCodes) + " (0x0016)",
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_boot());
            const SiiImage& s = *ctx.sii;
            if (s.word(0x14) == s.word(0x18) && s.word(0x15) == s.word(0x19) &&
                s.word(0x16) == s.word(0x1A) && s.word(0x17) == s.word(0x1B))
                return skip("bootstrap and standard mailbox have the same layout");
            return bad_mailbox(ctx, 3);
        },
        "bootstrap mailbox differs from the standard one");
    add(
        "sm2.length", "PREOP -> SAFEOP with a wrong SM2 (outputs) length: refused with 0x001D",
        std::string(kCodes) + " (0x001D)", [](Context& ctx) { return bad_pd_sm(ctx, true, false); },
        "outputs, no device emulation");
    add(
        "sm2.address", "PREOP -> SAFEOP with a wrong SM2 (outputs) start address: refused with 0x001D",
        std::string(kCodes) + " (0x001D)", [](Context& ctx) { return bad_pd_sm(ctx, true, true); },
        "outputs, no device emulation");
    add(
        "sm3.length", "PREOP -> SAFEOP with a wrong SM3 (inputs) length: refused with 0x001E",
        std::string(kCodes) + " (0x001E)", [](Context& ctx) { return bad_pd_sm(ctx, false, false); },
        "inputs, no device emulation");
    add(
        "sm3.address", "PREOP -> SAFEOP with a wrong SM3 (inputs) start address: refused with 0x001E",
        std::string(kCodes) + " (0x001E)", [](Context& ctx) { return bad_pd_sm(ctx, false, true); },
        "inputs, no device emulation");
    const std::string kDcCodes =
        std::string(kCodes) +
        " (0x0030 invalid DC SYNC configuration, 0x0035-0x0037 DC cycle times, "
        "0x001F invalid watchdog configuration); ETG.1020 DC set-up; ESC datasheet DC activation 0x0981";
    add(
        "dc.sync0_cycle_zero",
        "PREOP -> SAFEOP with SYNC0 activated at cycle time 0: taken, or refused with a DC/synchronisation "
        "code",
        kDcCodes, [](Context& ctx) { return sync_setting(ctx, 0x0300, 0, false, "SYNC0 with cycle time 0"); },
        "DC, process data, no device emulation");
    add(
        "dc.sync1_without_sync0",
        "PREOP -> SAFEOP with SYNC1 activated without SYNC0: taken, or refused with a DC/synchronisation "
        "code",
        kDcCodes,
        [](Context& ctx) { return sync_setting(ctx, 0x0500, 1'000'000, false, "SYNC1 without SYNC0"); },
        "DC, process data, no device emulation");
    add(
        "dc.watchdog_below_cycle",
        "PREOP -> SAFEOP in SYNC0 mode (1 ms) with an SM watchdog of one divider unit: taken, or refused "
        "with "
        "0x001F or a synchronisation code",
        kDcCodes,
        [](Context& ctx) {
            return sync_setting(ctx, 0x0300, 1'000'000, true, "SM watchdog below the cycle");
        },
        "DC, outputs with an SM watchdog, no device emulation");
    add("sync.sm_cycle_below_min",
        "PREOP -> SAFEOP synchronous with the SM2 event at half the minimum cycle time 0x1C32:05: taken, or "
        "refused with 0x002E (or another synchronisation code), not a DC code",
        std::string(kCodes) +
            " (0x002E cycle time too small; 0x0030-0x0037 are DC's); ETG.1020 0x1C32:01, "
            ":02, :05",
        sm_cycle_below_min, "CoE, 0x1C32 with SM2-event synchronisation, no device emulation");
    add("error.sticky", "With the error indication set, a request without acknowledge is not executed",
        "ETG.1000.6 AL control (error indication acknowledge)", [](Context& ctx) {
            CONFORM_NEED(ctx.need_state_machine());
            if (Error e = ctx.to_init(); e != Error::Ok) return fail("cannot reach INIT", err(e));
            master::AlStatus st = ctx.request_raw(8, ctx.ms(1000));  // I -> O: refused
            if (!st.error)
                return fail("INIT -> OP did not set the error indication", status_text(st), "INIT+ERR");
            if (ctx.has_mailbox()) {  // else INIT -> PREOP needs nothing set up
                ctx.mbx = std::make_unique<master::Mailbox>(ctx.m, ctx.addr, ctx.ms(1000));
                (void)ctx.mbx->configure_from_sii();
            }
            master::AlStatus st2 = ctx.request_raw(2, ctx.ms(100));  // no acknowledge bit
            (void)ctx.ack_error();
            (void)ctx.to_init();
            if (st2.state != 1 || !st2.error)
                return fail("executed without acknowledge", status_text(st2), "INIT+ERR");
            return pass("ignored", status_text(st2));
        });
    add(
        "error.ack", "Error acknowledge (PREOP + 0x10) clears the error indication and keeps the state",
        "ETG.1000.6 AL control (error indication acknowledge)",
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_state_machine());
            if (Error e = ctx.to_preop(); e != Error::Ok) return fail("cannot reach PREOP", err(e));
            master::AlStatus st = ctx.request_raw(8, ctx.ms(1000));  // P -> O: refused
            if (!st.error)
                return fail("PREOP -> OP did not set the error indication", status_text(st), "PREOP+ERR");
            (void)ctx.m.write_reg<uint16_t>(ctx.addr, master::reg::AlControl, 0x12);
            master::AlStatus st2;
            for (int i = 0; i < 200; ++i) {
                if (auto s = ctx.m.al_status(ctx.addr)) st2 = *s;
                if (!st2.error) break;
                std::this_thread::sleep_for(std::chrono::milliseconds(1));
            }
            ctx.in_preop = false;
            if (st2.state != 2 || st2.error) return fail("after acknowledge", status_text(st2), "PREOP");
            return pass("acknowledged", status_text(st2));
        },
        "a state machine (no device emulation)");
    add("error.code_cleared",
        "AL status code 0x0000 once the error is acknowledged (at the latest with the next successful "
        "transition)",
        kCodes, [](Context& ctx) {
            if (Error e = ctx.to_init(); e != Error::Ok) return fail("cannot reach INIT", err(e));
            (void)ctx.request_raw(8, ctx.ms(1000));
            (void)ctx.ack_error();
            master::AlStatus st2;
            if (auto s = ctx.m.al_status(ctx.addr)) st2 = *s;
            if (st2.code == 0) return pass("AL status code", hex(0));
            // Kept after the acknowledge: a slave may clear it only with the next successful transition,
            // but a code that outlives a successful transition reports an error that is not there.
            const uint16_t acked = st2.code;
            if (ctx.device_emulation) return fail("AL status code after the acknowledge", hex(acked), hex(0));
            const Error e = ctx.to_preop();
            master::AlStatus st3;
            if (auto s = ctx.m.al_status(ctx.addr)) st3 = *s;
            (void)ctx.to_init();
            if (e != Error::Ok) return fail("INIT -> PREOP after the acknowledge: " + err(e));
            if (st3.code != 0)
                return fail("AL status code still set after a successful INIT -> PREOP",
                            hex(st3.code) + " (after the acknowledge " + hex(acked) + ")", hex(0));
            return Outcome{Status::Warn,
                           "AL status code cleared only by the next transition, not by the acknowledge",
                           hex(acked) + " after the acknowledge", hex(0)};
        });
    add(
        "watchdog.op_to_safeop", "SM watchdog: outputs stop in OP -> SAFEOP with error 0x001B",
        std::string(kCodes) + " (0x001B); ESC SyncManager watchdog (0x0400, 0x0420)",
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_pd_layout());
            if (Error e = ctx.to_op(); e != Error::Ok)
                return fail("cannot reach OP: " + err(e), status_text(ctx.last_status));
            if (!ctx.pds || !ctx.pds->layout().output_bytes()) return skip("no outputs: no SM watchdog");
            // The PD watchdog is fed only by writes to an SM whose control byte has the watchdog trigger
            // (bit 6); it starts with the first such write. Outputs through an SM without it (ESI ControlByte
            // #x24, as SOES- and SSC-based devices declare) never start it: nothing expires, nothing to react
            // to (ESC datasheet section II, SM control 0x0804 bit 6 and process data watchdog 0x0420/0x0440).
            const master::ProcessDataLayout& l = ctx.pds->layout();
            if (std::none_of(l.sms.begin(), l.sms.end(), [](const master::ProcessDataSm& sm) {
                    return sm.outputs && sm.length && (sm.control & 0x40);
                }))
                return skip("no outputs SM has the watchdog trigger (control " +
                            hex(l.first(true)->control, 2) + ", bit 6 clear): the SM watchdog never runs");
            auto div = ctx.rd<uint16_t>(esc::reg::kWdDivider);
            auto wd = ctx.rd<uint16_t>(esc::reg::kWdTimePd);
            if (!div || !wd) return fail("watchdog registers unreadable");
            if (*wd == 0) return skip("process-data watchdog disabled (0x0420 = 0)");
            const double ms = (*div + 2.0) * 40e-9 * *wd * 1000.0;
            const auto deadline = std::chrono::steady_clock::now() +
                                  std::chrono::milliseconds(static_cast<long>(ms * 2 + 50)) + ctx.ms(200);
            master::AlStatus st;
            for (;;) {
                std::this_thread::sleep_for(std::chrono::milliseconds(2));
                if (auto s = ctx.m.al_status(ctx.addr)) st = *s;
                if (st.error || std::chrono::steady_clock::now() > deadline) break;
                if (ctx.device_emulation) {
                    if (auto w = ctx.rd<uint16_t>(esc::reg::kWdStatusPd); w && !(*w & 0x0001)) break;
                }
            }
            (void)ctx.ack_error();
            if (ctx.device_emulation) {
                // No controller to change the state: the ESC keeps OP and shows the expiry in the watchdog
                // status 0x0440 bit 0 (0 = expired; ESC datasheet section II, 0x0440), clearing the outputs.
                auto wds = ctx.rd<uint16_t>(esc::reg::kWdStatusPd);
                const std::string got = status_text(st) + ", 0x0440 " + (wds ? hex(*wds) : "?");
                if (st.state != 8 || st.error || !wds || (*wds & 0x0001))
                    return fail(
                        "device emulation: watchdog expiry not shown in 0x0440 (or the state changed)", got,
                        "OP code 0x0000, 0x0440 bit 0 clear");
                return pass("device emulation: expiry in 0x0440, state kept", got);
            }
            const std::string want = "SAFEOP+ERR code " + hex(0x001B);
            if (st.state != 4 || !st.error || st.code != 0x001B)
                return fail("no watchdog reaction " + dec(static_cast<long long>(ms * 2 + 250)) +
                                " ms after the last outputs (watchdog " + dec(static_cast<long long>(ms)) +
                                " ms)",
                            status_text(st), want);
            return pass("watchdog", status_text(st));
        },
        "outputs and a non-zero watchdog time");
    add(
        "identification",
        "Device identification: AL control bit 5 -> AL status bit 5, 0x0134 = station alias",
        "ETG.1000.6 device identification (AL control/status bit 5); ETG.2000 Info/IdentificationReg134",
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_esi());
            if (!ctx.esi->identification_reg134)
                return skip("the ESI does not announce IdentificationReg134");
            (void)ctx.to_init();
            // AL control is a handshake register on an ESC without device emulation: a write that comes
            // before the application read the previous one (the 0x0001 of to_init) is not taken (ESC
            // datasheet, AL control 0x0120). So the request is repeated every 50 ms until the bit shows, as
            // a master does; a write lost on a loaded host is retried the same way.
            bool loaded = false;
            std::optional<uint16_t> last;
            master::Error werr = master::Error::Timeout;
            const auto deadline = std::chrono::steady_clock::now() + ctx.ms(1000);
            auto next_write = std::chrono::steady_clock::now();
            while (!loaded && std::chrono::steady_clock::now() < deadline) {
                if (std::chrono::steady_clock::now() >= next_write) {
                    if (ctx.wr<uint16_t>(master::reg::AlControl, 0x0021) == master::Error::Ok)
                        werr = master::Error::Ok;
                    next_write = std::chrono::steady_clock::now() + std::chrono::milliseconds(50);
                }
                auto s = ctx.rd<uint16_t>(master::reg::AlStatus);
                if (s) last = *s;
                loaded = s && (*s & 0x20);
                if (!loaded) std::this_thread::sleep_for(std::chrono::milliseconds(1));
            }
            // The slave writes 0x0134 before it sets the bit, so 0x0134 is valid once the bit is seen.
            auto id = ctx.rd<uint16_t>(esc::reg::kAlStatusCode);
            (void)ctx.wr<uint16_t>(master::reg::AlControl, 0x0001);
            if (werr != master::Error::Ok)
                return fail("AL control 0x0021 was not written: " + std::string(master::to_string(werr)), "",
                            "written");
            if (!loaded)
                return fail("AL status bit 5 (identification loaded) not set within " +
                                dec(static_cast<long long>(ctx.ms(1000).count())) + " ms",
                            last ? "AL status " + hex(*last) : "no AL status read", "bit 5 set");
            auto alias = ctx.rd<uint16_t>(esc::reg::kStationAlias);
            return expect_eq("0x0134", id ? hex(*id) : "?", alias ? hex(*alias) : "?");
        },
        "ESI announces IdentificationReg134");
}

}  // namespace conform
