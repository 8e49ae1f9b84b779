// Group pd: process data: default PDO layout against the ESI, SAFEOP and OP with working counters, inputs
// valid in SAFEOP, outputs applied in OP only, logical commands, a remapped assignment.
#include <algorithm>
#include <chrono>
#include <thread>

#include "pdo_map.hpp"

namespace conform {

namespace {

using master::Error;
constexpr const char* kPd =
    "ETG.1000.6 process data and the state machine (SAFEOP: inputs valid, outputs safe; OP: outputs applied)";
constexpr const char* kPdEsi = "ETG.2000 RxPdo/TxPdo and Sm; ETG.1000.6 PDO assignment 0x1C12/0x1C13";

std::string pdo_list(const std::vector<uint16_t>& v) {
    std::string s;
    for (auto x : v)
        s += hex(x) + " ";
    return s;
}

Outcome assign_vs_esi(Context& ctx, bool outputs) {
    CONFORM_NEED(ctx.need_coe());
    CONFORM_NEED(ctx.need_esi());
    CONFORM_PREOP(ctx);
    const uint16_t idx = outputs ? 0x1C12 : 0x1C13;
    // ETG.1000.6: 0x1C10+n describes SM n; a device whose ESI has no SM of this direction and no PDO
    // for it (a mailbox-only gateway) need not have the object.
    const char* kind = outputs ? "Outputs" : "Inputs";
    const bool sm_declared = std::any_of(ctx.esi->sms.begin(), ctx.esi->sms.end(),
                                         [kind](const esi::EsiSm& sm) { return sm.type == kind; });
    if (!sm_declared && (outputs ? ctx.esi->rxpdos : ctx.esi->txpdos).empty())
        return skip(std::string("the ESI declares no ") + kind + " SM and no PDO of this direction");
    auto n = ctx.upload_uint(idx, 0);
    if (!n) return fail(hex(idx) + ": " + ctx.sdo_error(n.error()));
    std::vector<uint16_t> got, want;
    for (uint8_t i = 1; i <= *n; ++i)
        if (auto p = ctx.upload_uint(idx, i)) got.push_back(static_cast<uint16_t>(*p));
    for (const auto& p : outputs ? ctx.esi->rxpdos : ctx.esi->txpdos)
        if (p.sm == (outputs ? 2 : 3)) want.push_back(p.index);
    return expect_eq(hex(idx) + " default assignment", pdo_list(got), pdo_list(want));
}

Outcome mapping_vs_esi(Context& ctx, bool outputs) {
    CONFORM_NEED(ctx.need_coe());
    CONFORM_NEED(ctx.need_esi());
    CONFORM_PREOP(ctx);
    std::string got, want;
    for (const auto& p : outputs ? ctx.esi->rxpdos : ctx.esi->txpdos) {
        auto n = ctx.upload_uint(p.index, 0);
        if (!n) return fail(hex(p.index) + ": " + ctx.sdo_error(n.error()));
        got += hex(p.index) + "[";
        for (uint8_t i = 1; i <= *n; ++i)
            if (auto e = ctx.upload_uint(p.index, i)) got += hex(*e, 8) + " ";
        got += "] ";
        want += hex(p.index) + "[";
        for (const auto& e : p.entries)
            want += hex((uint64_t{e.index} << 16) | (uint64_t{e.subindex} << 8) | e.bit_len, 8) + " ";
        want += "] ";
    }
    return expect_eq("mapping objects", got, want);
}

// The layout as a master finds it (over CoE, else from the SII: a device without mailbox, whose outputs and
// inputs SMs may be SM0/SM1) against the ESI's PDOs assigned by default to that SM.
Outcome sm_size_vs_esi(Context& ctx, bool outputs) {
    CONFORM_NEED(ctx.need_pd_layout());
    CONFORM_NEED(ctx.need_esi());
    CONFORM_PREOP(ctx);
    if (Error e = ctx.discover_pd(); e != Error::Ok) return fail("layout: " + ctx.sdo_error(e));
    // Every SM of the direction (a device may have several: SM2 and SM4 for outputs, ...).
    std::string got, want, names;
    for (const master::ProcessDataSm& sm : ctx.pds->layout().sms) {
        if (sm.outputs != outputs) continue;
        unsigned bits = 0;
        for (const auto& p : outputs ? ctx.esi->rxpdos : ctx.esi->txpdos)
            if (p.sm == sm.index) bits += p.bits();
        names += (names.empty() ? "SM" : "/SM") + dec(sm.index);
        got += "SM" + dec(sm.index) + " " + dec(sm.length) + " ";
        want += "SM" + dec(sm.index) + " " + dec((bits + 7) / 8) + " ";
    }
    if (names.empty()) {
        // No SM of this direction: the ESI must assign no PDO of it to any SM either.
        unsigned bits = 0;
        for (const auto& p : outputs ? ctx.esi->rxpdos : ctx.esi->txpdos)
            if (p.sm >= 0) bits += p.bits();
        if (bits)
            return fail(std::string("the ESI assigns ") + (outputs ? "RxPdos" : "TxPdos") +
                            " to an SM, the SII has no " + (outputs ? "outputs" : "inputs") + " SM",
                        "0 bytes", dec((bits + 7) / 8) + " bytes");
        return skip(std::string("no ") + (outputs ? "outputs" : "inputs") + " SM and no PDO assigned to one");
    }
    return expect_eq(names + " bytes of the default assignment", got, want);
}

// The mapped output entries that are safe to change (not the controlword, not a mode), in mapping order.
std::vector<const MappedEntry*> harmless_outputs(const PdoMap& m) {
    std::vector<const MappedEntry*> r;
    for (const auto& e : m.outputs)
        if (e.index != 0x6040 && e.index != 0x6060 && e.bits >= 8 && e.bits % 8 == 0 && e.index >= 0x2000)
            r.push_back(&e);
    return r;
}

Outcome inputs_match(Context& ctx, uint8_t state) {
    CONFORM_NEED(ctx.need_coe());
    if (Error x = ctx.to_init(); x != Error::Ok) return fail("cannot reach INIT", err(x));
    CONFORM_PREOP(ctx);
    {
        // Fill the input SM's buffers with a pattern first (plain RAM while SM3 is off): inputs the slave
        // never writes then show up as the pattern, not as stale values of an earlier run.
        master::ProcessDataSession s(ctx.m, ctx.addr, *ctx.sdo);
        if (Error x = s.discover(); x != Error::Ok) return fail("layout: " + ctx.sdo_error(x));
        for (const master::ProcessDataSm& sm : s.layout().sms) {
            if (sm.outputs) continue;
            std::vector<uint8_t> pattern(3u * sm.length, 0xA5);
            for (std::size_t k = 0; k < pattern.size(); k += 256) {
                const std::size_t n = std::min<std::size_t>(256, pattern.size() - k);
                (void)ctx.m.write(ctx.addr, static_cast<uint16_t>(sm.start + k),
                                  std::span<const uint8_t>(pattern.data() + k, n));
            }
        }
    }
    Error e = state == 8 ? ctx.to_op() : ctx.to_safeop();
    if (e != Error::Ok) return fail("cannot reach the state: " + err(e));
    if (!ctx.has_process_data()) return skip("no process data (no PDO assigned to a process-data SM)");
    PdoMap m;
    if (Error x = read_map(ctx, m); x != Error::Ok) return fail("mapping: " + ctx.sdo_error(x));
    (void)ctx.cycle(5);
    unsigned compared = 0;
    for (const auto& in : m.inputs) {
        if (in.bits % 8) continue;
        auto a = ctx.upload_uint(in.index, in.sub);
        (void)ctx.cycle(2);
        const uint64_t pd = image_get(ctx.pds->inputs(), in);
        auto b = ctx.upload_uint(in.index, in.sub);
        if (!a || !b || *a != *b) continue;  // changing value: not comparable
        ++compared;
        if (pd != *a)
            return fail(hex(in.index) + ":" + dec(in.sub) + " in the input image differs from its object",
                        hex(pd), hex(*a));
    }
    if (!compared) return skip("no input entry with a steady value to compare");
    return pass(dec(compared) + " entries equal their objects");
}

Outcome outputs(Context& ctx, bool op) {
    CONFORM_NEED(ctx.need_coe());
    Error e = op ? ctx.to_op() : ctx.to_safeop();
    if (e != Error::Ok) return fail("cannot reach the state: " + err(e));
    if (!ctx.has_process_data()) return skip("no process data (no PDO assigned to a process-data SM)");
    PdoMap m;
    if (Error x = read_map(ctx, m); x != Error::Ok) return fail("mapping: " + ctx.sdo_error(x));
    const std::vector<const MappedEntry*> candidates = harmless_outputs(m);
    if (candidates.empty()) return skip("no mapped output entry other than controlword and mode");
    prefill_outputs(ctx, m);
    // The first one SDO can read: an output object may be write-only (ETG.1000.6 access "wo"; the upload is
    // refused with 0x06010001), and then what the outputs did to it cannot be seen by SDO.
    const MappedEntry* o = nullptr;
    master::Result<uint64_t> before = master::Error::InvalidArgument;
    for (const MappedEntry* c : candidates) {
        before = ctx.upload_uint(c->index, c->sub);
        if (!before && before.error() == Error::SdoAbort && ctx.sdo->last_abort() == 0x06010001) continue;
        o = c;
        break;
    }
    if (!o) return skip("every mapped output entry is write-only (SDO abort 0x06010001)");
    if (!before) return fail("upload: " + ctx.sdo_error(before.error()));
    const uint64_t mask = o->bits >= 64 ? ~uint64_t{0} : (uint64_t{1} << o->bits) - 1;
    const uint64_t v = (*before + 7) & mask;
    image_set(ctx.pds->outputs(), *o, v);
    (void)ctx.cycle(10);
    auto after = ctx.upload_uint(o->index, o->sub);
    image_set(ctx.pds->outputs(), *o, *before);
    (void)ctx.cycle(5);
    if (!after) return fail("upload: " + ctx.sdo_error(after.error()));
    const std::string what = hex(o->index) + ":" + dec(o->sub) + " after outputs carried " + hex(v);
    if (op) return expect_eq(what, hex(*after), hex(v));
    return expect_eq(what + " in SAFEOP (outputs must not be applied)", hex(*after), hex(*before));
}

Outcome cycle_wkc(Context& ctx, uint8_t state) {
    CONFORM_NEED(ctx.need_pd_layout());
    Error e = state == 8 ? ctx.to_op() : ctx.to_safeop();
    if (e != Error::Ok) return fail("cannot reach the state: " + err(e));
    if (!ctx.has_process_data()) return skip("no process data (no PDO assigned to a process-data SM)");
    (void)ctx.cycle(3);
    Error c = ctx.pds->cycle();
    return expect_eq("LRW working counter", c == Error::Timeout ? "no reply" : dec(ctx.pds->last_wkc()),
                     dec(ctx.pds->expected_wkc()));
}

Outcome logical_only(Context& ctx, master::Command cmd) {
    CONFORM_NEED(ctx.need_pd_layout());
    if (Error e = ctx.to_op(); e != Error::Ok) return fail("cannot reach OP: " + err(e));
    if (!ctx.has_process_data()) return skip("no process data (no PDO assigned to a process-data SM)");
    const auto& l = ctx.pds->layout();
    std::vector<uint8_t> img(static_cast<std::size_t>(l.output_bytes()) + l.input_bytes());
    if (cmd == master::Command::LWR)
        std::copy(ctx.pds->outputs().begin(), ctx.pds->outputs().end(), img.begin());
    master::Datagram d = master::Datagram::logical(cmd, master::ProcessDataSession::kLogicalBase, img);
    if (Error e = ctx.m.exchange(d); e != Error::Ok) return fail("no reply", err(e));
    (void)ctx.cycle(2);
    const bool has = cmd == master::Command::LRD ? l.input_bytes() > 0 : l.output_bytes() > 0;
    return expect_eq(std::string(cmd == master::Command::LRD ? "LRD" : "LWR") + " over outputs and inputs",
                     dec(d.wkc), has ? "1" : "0");
}

// LRW over the image with 8 guard bytes before and after it (logical addresses no FMMU maps): the slave
// reads and writes only the bytes of its FMMUs, so the guard bytes come back as sent (on a line they are the
// next slave's), and the working counter is the image's.
Outcome logical_guard(Context& ctx) {
    CONFORM_NEED(ctx.need_pd_layout());
    if (Error e = ctx.to_op(); e != Error::Ok) return fail("cannot reach OP: " + err(e));
    if (!ctx.has_process_data()) return skip("no process data (no PDO assigned to a process-data SM)");
    constexpr std::size_t kGuard = 8;
    const auto& l = ctx.pds->layout();
    const std::size_t n = static_cast<std::size_t>(l.output_bytes()) + l.input_bytes();
    std::vector<uint8_t> img(n + 2 * kGuard);
    for (std::size_t i = 0; i < img.size(); ++i)
        img[i] = static_cast<uint8_t>(0x5A ^ (i * 0x1D));
    std::copy(ctx.pds->outputs().begin(), ctx.pds->outputs().end(), img.begin() + kGuard);
    const std::vector<uint8_t> sent = img;
    master::Datagram d = master::Datagram::logical(
        master::Command::LRW, master::ProcessDataSession::kLogicalBase - static_cast<uint32_t>(kGuard), img);
    if (Error e = ctx.m.exchange(d); e != Error::Ok) return fail("no reply", err(e));
    (void)ctx.cycle(2);
    std::string changed;
    for (std::size_t i = 0; i < img.size(); ++i) {
        if (i >= kGuard && i < kGuard + n) continue;
        if (img[i] != sent[i])
            changed += (changed.empty() ? "" : " ") +
                       std::string(i < kGuard ? "before-" + dec(static_cast<long long>(kGuard - i))
                                              : "after+" + dec(static_cast<long long>(i - kGuard - n))) +
                       ":" + hex(sent[i], 2) + "->" + hex(img[i], 2);
    }
    if (!changed.empty())
        return fail("bytes outside the slave's FMMUs changed by the LRW", changed, "guard bytes as sent");
    return expect_eq("LRW with guard bytes: working counter", dec(d.wkc), dec(ctx.pds->expected_wkc()));
}

// In OP with process data exchanged every cycle, the ESC registers the master configured read back as written
// (ESC datasheet: SyncManager 0x0800+8n start, length, control and activate; FMMU 0x0600+16n, all read/write
// for EtherCAT), the process-data SMs are not deactivated by the PDI (0x0807+8n bit 0) and the SM watchdog
// status (0x0440 bit 0) says active: outputs come in time (1: active or disabled, 0: expired).
Outcome op_registers(Context& ctx) {
    CONFORM_NEED(ctx.need_pd_layout());
    if (Error e = ctx.to_op(); e != Error::Ok) return fail("cannot reach OP: " + err(e));
    if (!ctx.has_process_data()) return skip("no process data (no PDO assigned to a process-data SM)");
    // The watchdog counters 0x0442/0x0443 cleared (a write to either clears both, ESC datasheet section II):
    // while outputs come every cycle, the process-data counter must stay 0 (it counts expiries only).
    (void)ctx.wr<uint16_t>(0x0442, 0);
    (void)ctx.cycle(5);
    const auto& l = ctx.pds->layout();
    std::string got, want;
    for (const master::ProcessDataSm& sm : l.sms) {
        if (!sm.length || sm.index >= 16) continue;
        uint8_t r[8] = {};
        const auto base = static_cast<uint16_t>(master::reg::Sm0 + 8 * sm.index);
        if (Error e = ctx.m.read(ctx.addr, base, r); e != Error::Ok)
            return fail("SM" + dec(sm.index) + " unreadable", err(e));
        (void)ctx.cycle(1);
        const std::string n = "SM" + dec(sm.index) + " ";
        got += n + hex(get16(r)) + "/" + dec(get16(r + 2)) + " control " + hex(r[4], 2) + " activate " +
               hex(r[6] & 0x01, 2) + " PDI deactivated " + dec(r[7] & 0x01) + "; ";
        want += n + hex(sm.start) + "/" + dec(sm.length) + " control " + hex(sm.control, 2) + " activate " +
                hex(0x01, 2) + " PDI deactivated 0; ";
    }
    // The FMMUs of the layout from FMMU0 on (the session's set-up: outputs SMs, then inputs SMs, adjacent
    // ones sharing an FMMU), each at its place in the image.
    const std::vector<master::ProcessDataLayout::Fmmu> fmmus = l.fmmus();
    std::vector<uint8_t> f(16 * fmmus.size());
    if (Error e = ctx.m.read(ctx.addr, master::reg::Fmmu0, f); e != Error::Ok)
        return fail("FMMU0-" + dec(fmmus.size() - 1) + " unreadable", err(e));
    (void)ctx.cycle(1);
    for (std::size_t k = 0; k < fmmus.size(); ++k) {
        const master::ProcessDataLayout::Fmmu& want_f = fmmus[k];
        const uint32_t logical = master::ProcessDataSession::kLogicalBase +
                                 (want_f.outputs ? 0 : l.output_bytes()) + want_f.offset;
        const uint8_t* x = f.data() + 16 * k;
        const std::string n = "FMMU" + dec(k) + " ";
        got += n + hex(get32(x), 8) + "/" + dec(get16(x + 4)) + " bits " + dec(x[6]) + "-" + dec(x[7]) +
               " -> " + hex(get16(x + 8)) + "." + dec(x[10]) + " type " + hex(x[11], 2) + " enable " +
               dec(x[12] & 1) + "; ";
        want += n + hex(logical, 8) + "/" + dec(want_f.length) + " bits 0-7 -> " + hex(want_f.physical) +
                ".0 type " + hex(want_f.outputs ? 0x02 : 0x01, 2) + " enable 1; ";
    }
    // Only outputs written through an SM with the watchdog trigger (control bit 6) keep the watchdog
    // running; an input-only device's watchdog may show expired (ESC datasheet 0x0420, 0x0440).
    if (std::any_of(l.sms.begin(), l.sms.end(), [](const master::ProcessDataSm& sm) {
            return sm.outputs && sm.length && (sm.control & 0x40);
        })) {
        auto wd = ctx.rd<uint16_t>(0x0440);
        (void)ctx.cycle(1);
        if (!wd) return fail("SM watchdog status 0x0440 unreadable", err(wd.error()));
        got += "0x0440 bit 0 " + dec(*wd & 1);
        want += "0x0440 bit 0 1";
        auto wc = ctx.rd<uint8_t>(0x0442);
        (void)ctx.cycle(1);
        if (!wc) return fail("SM watchdog counter 0x0442 unreadable", err(wc.error()));
        got += ", 0x0442 " + dec(*wc);
        want += ", 0x0442 0";
    }
    // DL status 0x0110 bit 1 (PDI watchdog: 1 reloaded, 0 expired): in OP the application on the PDI reads
    // and writes the process data SMs every cycle, which reloads it (ESC datasheet 0x0110, 0x0410); a PDI
    // watchdog time of 0 switches it off.
    if (auto pdi_wd = ctx.rd<uint16_t>(0x0410); pdi_wd && *pdi_wd && ctx.has_mailbox()) {
        auto dl = ctx.rd<uint16_t>(esc::reg::kDlStatus);
        (void)ctx.cycle(1);
        if (!dl) return fail("DL status 0x0110 unreadable", err(dl.error()));
        got += std::string(got.empty() ? "" : ", ") + "0x0110 bit 1 " + dec((*dl >> 1) & 1);
        want += std::string(want.empty() ? "" : ", ") + "0x0110 bit 1 1";
    }
    return expect_eq("SM/FMMU registers as configured, watchdog status while outputs come", got, want);
}

// OP held while the master exchanges process data in time: for about a second (longer than the SM watchdog
// of the default settings) the outputs come every 2 ms; then AL status must still be OP without error. A
// slave that leaves OP (a watchdog that counts too fast, an application that gives up) drops the outputs a
// machine relies on. A master whose own frames were late past the watchdog time proves nothing: skipped.
Outcome op_state_kept(Context& ctx) {
    CONFORM_NEED(ctx.need_pd_layout());
    if (Error e = ctx.to_op(); e != Error::Ok) return fail("cannot reach OP: " + err(e));
    if (!ctx.pds || !ctx.has_process_data()) return skip("no process data");
    auto div = ctx.rd<uint16_t>(0x0400);
    auto wd = ctx.rd<uint16_t>(0x0420);
    // ESC datasheet: watchdog time = 0x0420 * (0x0400 + 2) * 40 ns; 0 switches the watchdog off.
    const double wd_ms = div && wd ? *wd * (*div + 2.0) * 40e-6 : 0.0;
    const auto end = std::chrono::steady_clock::now() + ctx.ms(1000);
    auto last_ok = std::chrono::steady_clock::now();
    double worst_ms = 0;
    unsigned cycles = 0, lost = 0;
    while (std::chrono::steady_clock::now() < end) {
        const Error e = ctx.pds->cycle();
        const auto now = std::chrono::steady_clock::now();
        if (e == Error::Ok) {
            worst_ms = std::max(worst_ms, std::chrono::duration<double, std::milli>(now - last_ok).count());
            last_ok = now;
        } else {
            ++lost;
        }
        ++cycles;
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    auto al = ctx.rd<uint16_t>(master::reg::AlStatus);
    auto code = ctx.rd<uint16_t>(esc::reg::kAlStatusCode);
    if (!al) return fail("AL status unreadable after the cycles", err(al.error()));
    const std::string got = hex(*al) + " code " + (code ? hex(*code) : std::string("unreadable")) +
                            " after " + dec(cycles) + " cycles (" + dec(lost) + " lost, longest gap " +
                            dec(static_cast<long long>(worst_ms)) + " ms, watchdog " +
                            dec(static_cast<long long>(wd_ms)) + " ms)";
    if ((*al & 0x1F) == 0x08) return pass("OP kept", got);
    if (wd_ms > 0 && worst_ms >= wd_ms)
        return skip("the master's own process data came later than the watchdog time: " + got);
    return fail("left OP while the master exchanged process data every 2 ms", got, "0x0008 (OP, no error)");
}

}  // namespace

void add_pd_tests(Catalogue& c) {
    Adder add{c, "pd"};
    add(
        "assign.rx_vs_esi", "Default RxPDO assignment 0x1C12 equals the ESI's RxPdo with Sm=2", kPdEsi,
        [](Context& ctx) { return assign_vs_esi(ctx, true); }, "CoE and ESI");
    add(
        "assign.tx_vs_esi", "Default TxPDO assignment 0x1C13 equals the ESI's TxPdo with Sm=3", kPdEsi,
        [](Context& ctx) { return assign_vs_esi(ctx, false); }, "CoE and ESI");
    add(
        "mapping.rx_vs_esi", "RxPDO mapping objects equal the ESI's RxPdo entries", kPdEsi,
        [](Context& ctx) { return mapping_vs_esi(ctx, true); }, "CoE and ESI");
    add(
        "mapping.tx_vs_esi", "TxPDO mapping objects equal the ESI's TxPdo entries", kPdEsi,
        [](Context& ctx) { return mapping_vs_esi(ctx, false); }, "CoE and ESI");
    add(
        "sm2.size_vs_esi",
        "Outputs SM sizes (SM2, and SM4... where the device has them) of the default assignment equal the "
        "ESI's RxPdo bit lengths per SM",
        kPdEsi, [](Context& ctx) { return sm_size_vs_esi(ctx, true); },
        "ESI (layout over CoE, else from the SII)");
    add(
        "sm3.size_vs_esi",
        "Inputs SM sizes (SM3, and SM5... where the device has them) of the default assignment equal the "
        "ESI's TxPdo bit lengths per SM",
        kPdEsi, [](Context& ctx) { return sm_size_vs_esi(ctx, false); },
        "ESI (layout over CoE, else from the SII)");
    add(
        "safeop.wkc", "SAFEOP: LRW over outputs and inputs has the exact working counter", kPd,
        [](Context& ctx) { return cycle_wkc(ctx, 4); }, "process data (layout over CoE, else from the SII)");
    add(
        "safeop.inputs_valid", "SAFEOP: inputs in the image equal their objects", kPd,
        [](Context& ctx) { return inputs_match(ctx, 4); }, "CoE");
    add(
        "safeop.outputs_not_applied", "SAFEOP: outputs received are not applied to the objects", kPd,
        [](Context& ctx) { return outputs(ctx, false); }, "CoE");
    add(
        "op.wkc", "OP: LRW over outputs and inputs has the exact working counter", kPd,
        [](Context& ctx) { return cycle_wkc(ctx, 8); }, "process data (layout over CoE, else from the SII)");
    add(
        "op.inputs_valid", "OP: inputs in the image equal their objects", kPd,
        [](Context& ctx) { return inputs_match(ctx, 8); }, "CoE");
    add(
        "op.outputs_applied", "OP: outputs received are applied to the objects", kPd,
        [](Context& ctx) { return outputs(ctx, true); }, "CoE");
    add(
        "op.lrd_wkc", "OP: LRD over the image: working counter 1 (only the inputs are readable)",
        "ETG.1000.4 working counter of LRD",
        [](Context& ctx) { return logical_only(ctx, master::Command::LRD); },
        "process data (layout over CoE, else from the SII)");
    add(
        "op.lwr_wkc", "OP: LWR over the image: working counter 1 (only the outputs are writable)",
        "ETG.1000.4 working counter of LWR",
        [](Context& ctx) { return logical_only(ctx, master::Command::LWR); },
        "process data (layout over CoE, else from the SII)");
    add("op.logical_guard",
        "OP: LRW over the image with 8 guard bytes before and after: the guard bytes come back unchanged, "
        "working counter as without them",
        "ETG.1000.4 logical addressing (a slave processes only the bytes its FMMUs map)", logical_guard,
        "process data (layout over CoE, else from the SII)");
    add(
        "op.state_kept", "OP: kept for a second of process data every 2 ms (AL status still OP, no error)",
        "ETG.1000.6 state machine (OP while the outputs come in time); ESC datasheet SM watchdog 0x0420 with "
        "divider 0x0400",
        [](Context& ctx) { return op_state_kept(ctx); }, "process data (layout over CoE, else from the SII)");
    add(
        "op.esc_registers",
        "OP: SM and FMMU registers read back as configured, SMs not deactivated by the PDI, SM watchdog "
        "status active, no watchdog expiry counted (0x0442)",
        "ETG.1000.4 SyncManager and FMMU; ESC datasheet SyncManager 0x0800+8n (0x0806 activate, 0x0807 PDI "
        "control), FMMU 0x0600+16n, watchdog status 0x0440, watchdog counter 0x0442",
        [](Context& ctx) { return op_registers(ctx); }, "process data (layout over CoE, else from the SII)");
    add(
        "remap.safeop",
        "Another ESI RxPDO assigned in PREOP: SAFEOP with the new SM2 size and exact working counter", kPdEsi,
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_esi());
            if (!ctx.esi->coe.pdo_assign) return skip("the ESI does not announce PdoAssign");
            CONFORM_PREOP(ctx);
            auto n = ctx.upload_uint(0x1C12, 0);
            auto first = ctx.upload_uint(0x1C12, 1);
            if (!n || !first || *n != 1) return skip("needs exactly one assigned RxPDO");
            const EsiPdo* other = nullptr;
            for (const auto& p : ctx.esi->rxpdos)
                if (p.index != *first && !p.entries.empty()) {
                    other = &p;
                    break;
                }
            if (!other) return skip("no other RxPDO in the ESI");
            (void)ctx.download_uint(0x1C12, 0, 0, 1);
            (void)ctx.download_uint(0x1C12, 1, other->index, 2);
            (void)ctx.download_uint(0x1C12, 0, 1, 1);
            Error e = ctx.to_safeop();
            std::string got = "not reached: " + err(e);
            if (e == Error::Ok)
                for (const master::ProcessDataSm& sm : ctx.pds->layout().sms)
                    if (sm.index == 2) got = dec(sm.length);
            Error cy = e == Error::Ok ? (ctx.cycle(3), ctx.pds->cycle()) : e;
            (void)ctx.to_preop();
            (void)ctx.download_uint(0x1C12, 0, 0, 1);
            (void)ctx.download_uint(0x1C12, 1, *first, 2);
            (void)ctx.download_uint(0x1C12, 0, *n, 1);
            (void)ctx.to_init();
            if (e != Error::Ok) return fail("SAFEOP with " + hex(other->index), got);
            if (cy != Error::Ok) return fail("cycle with the new mapping", err(cy));
            return expect_eq("SM2 bytes with " + hex(other->index), got, dec((other->bits() + 7) / 8));
        },
        "ESI announces PdoAssign");
}

}  // namespace conform
