// Group mbx: the mailbox: counter handling, repeat request, error replies for invalid header, length, type
// and unsupported protocol, SyncManager mailbox behaviour.
#include <thread>

#include "testkit.hpp"

namespace conform {

namespace {

using master::Error;
constexpr const char* kMbx = "ETG.1000.4 mailbox (header, counter); ETG.1000.6 mailbox error reply";
constexpr const char* kSmStatus = "ESC datasheet SyncManager status register 0x0805+8n; ETG.1000.4 mailbox";
constexpr const char* kRepeat = "ETG.1000.4 mailbox repeat request (SM1 repeat / repeat acknowledge)";

std::vector<uint8_t> message(uint8_t type, uint8_t counter, std::span<const uint8_t> payload,
                             int length = -1) {
    std::vector<uint8_t> m(6 + payload.size(), 0);
    put16(m.data(), static_cast<uint16_t>(length < 0 ? payload.size() : static_cast<std::size_t>(length)));
    m[5] = static_cast<uint8_t>((type & 0x0F) | ((counter & 7) << 4));
    for (std::size_t i = 0; i < payload.size(); ++i)
        m[6 + i] = payload[i];
    return m;
}

// CoE SDO upload request of 0x1000:00 (every CoE slave has it).
std::vector<uint8_t> upload_1000() {
    return {0x00, 0x20, 0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0};
}

// Sends a raw message and waits for one answer; empty when none came in `wait`.
std::vector<uint8_t> ask(Context& ctx, const std::vector<uint8_t>& msg, std::chrono::milliseconds wait) {
    if (ctx.mbx_write_raw(msg) != Error::Ok) return {};
    std::vector<uint8_t> r;
    for (;;) {
        if (ctx.mbx_read_raw(r, wait) != Error::Ok) return {};
        // Emergencies (CoE service 1) are not answers.
        if ((r[5] & 0x0F) == 3 && r.size() > 7 && (r[7] >> 4) == 1) continue;
        return r;
    }
}

Outcome mailbox_error(Context& ctx, const std::vector<uint8_t>& msg, std::vector<uint16_t> accepted,
                      const std::string& what) {
    CONFORM_NEED(ctx.need_coe());
    CONFORM_PREOP(ctx);
    ctx.mbx_resync();
    auto r = ask(ctx, msg, ctx.ms(300));
    ctx.mbx_resync();
    std::string want;
    for (auto a : accepted)
        want += (want.empty() ? "" : " or ") + hex(a);
    want = "mailbox error (type 0, service 0x0001) detail " + want;
    if (r.empty()) return fail(what + ": no answer", "none", want);
    const uint8_t type = r[5] & 0x0F;
    if (type != 0)
        return fail(what + ": not a mailbox error reply",
                    "type " + dec(type) + " " + bytes_hex(std::span<const uint8_t>(r).subspan(0, 16)), want);
    const uint16_t len = get16(r.data());
    // ETG.1000.4 mailbox error reply: Type (0x0001) and Detail, length 4.
    if (len != 4 || get16(&r[6]) != 0x0001)
        return fail(what + ": malformed mailbox error reply",
                    "length " + dec(len) + " service " + hex(get16(&r[6])), "length 4, " + want);
    // A mailbox error reply is a new message of the slave like any other: it carries the next counter, 1..7
    // (ETG.1000.4 mailbox header counter; 0 is only the start value, response.counter), else a master that
    // keeps the counter of the last reply may take it for a repeat, or for no message at all.
    if (((r[5] >> 4) & 7) == 0)
        return fail(what + ": mailbox error reply with counter 0 (only a start value)", hex(r[5], 2),
                    "counter 1..7 (byte 5 bits 4-6)");
    const uint16_t detail = get16(&r[8]);
    for (auto a : accepted)
        if (a == detail) return pass(what, "detail " + hex(detail));
    return fail(what + ": mailbox error detail", hex(detail), want);
}

uint8_t unannounced_type(uint16_t protocols) {
    if (!(protocols & 0x20)) return 0x0F;  // VoE
    if (!(protocols & 0x10)) return 0x05;  // SoE
    if (!(protocols & 0x01)) return 0x01;  // AoE
    if (!(protocols & 0x02)) return 0x02;  // EoE
    return 0;
}

}  // namespace

void add_mbx_tests(Catalogue& c) {
    Adder add{c, "mbx"};
    add(
        "counter.repeat_not_executed", "A request repeating the previous counter is not executed again", kMbx,
        {&Context::need_coe},
        [](Context& ctx) {
            ctx.mbx_resync();
            auto p = upload_1000();
            auto r0 = ask(ctx, message(3, 0, p), ctx.ms(500));
            auto r1 = ask(ctx, message(3, 3, p), ctx.ms(500));
            auto r2 = ask(ctx, message(3, 3, p), ctx.ms(100));
            ctx.mbx_resync();
            if (r0.empty() || r1.empty()) return fail("no answer to a plain request (counters 0, 3)");
            if (!r2.empty())
                return fail("the repeated counter 3 was executed again", "an answer", "no answer");
            return pass("dropped");
        },
        "CoE");
    add(
        "counter.next_executed", "After a dropped repeat, the next counter is executed", kMbx,
        {&Context::need_coe},
        [](Context& ctx) {
            ctx.mbx_resync();
            auto p = upload_1000();
            (void)ask(ctx, message(3, 0, p), ctx.ms(500));
            (void)ask(ctx, message(3, 5, p), ctx.ms(500));
            (void)ask(ctx, message(3, 5, p), ctx.ms(100));
            auto r = ask(ctx, message(3, 6, p), ctx.ms(500));
            ctx.mbx_resync();
            if (r.empty()) return fail("counter 6 after 5 not answered", "none", "an SDO upload response");
            return pass("answered");
        },
        "CoE");
    add(
        "counter.wraps", "Counters 1..7 then 1 again are all executed", kMbx, {&Context::need_coe},
        [](Context& ctx) {
            ctx.mbx_resync();
            auto p = upload_1000();
            (void)ask(ctx, message(3, 0, p), ctx.ms(500));
            for (uint8_t k : {1, 2, 3, 4, 5, 6, 7, 1}) {
                if (ask(ctx, message(3, k, p), ctx.ms(500)).empty()) {
                    ctx.mbx_resync();
                    return fail("counter " + dec(k) + " not answered");
                }
            }
            ctx.mbx_resync();
            return pass("all answered");
        },
        "CoE");
    add(
        "response.counter",
        "Slave replies carry counters 1..7, each new reply another counter than the one before (never stuck)",
        kMbx, {&Context::need_coe},
        [](Context& ctx) {
            ctx.mbx_resync();
            auto p = upload_1000();
            std::vector<int> seen;
            std::string list;
            // Request counters 0 (always executed), 1, 2, 3: none repeats the one a test before may have
            // left.
            for (uint8_t k = 0; k < 4; ++k) {
                auto a = ask(ctx, message(3, k, p), ctx.ms(500));
                if (a.empty()) {
                    ctx.mbx_resync();
                    return fail("no answer to request " + dec(k), list.empty() ? "none" : list);
                }
                seen.push_back((a[5] >> 4) & 7);
                list += (list.empty() ? "" : ", ") + dec(seen.back());
            }
            ctx.mbx_resync();
            for (std::size_t i = 0; i < seen.size(); ++i) {
                if (seen[i] == 0) return fail("reply counter 0 (only a start value)", list, "1..7");
                if (i > 0 && seen[i] == seen[i - 1])
                    return fail("reply counter did not advance for a new reply", list,
                                "a new counter each reply");
            }
            return pass("counters", list);
        },
        "CoE");
    add(
        "response.header",
        "Reply header: length within SM1, channel and reserved bits 0, type CoE (3) for a CoE request", kMbx,
        {&Context::need_coe},
        [](Context& ctx) {
            ctx.mbx_resync();
            auto a = ask(ctx, message(3, 0, upload_1000()), ctx.ms(500));
            ctx.mbx_resync();
            if (a.empty()) return fail("no answer to an SDO upload of 0x1000");
            const std::string got = bytes_hex(std::span<const uint8_t>(a).subspan(0, 6));
            const uint16_t len = get16(a.data());
            if (len + 6u > a.size())
                return fail("length past the SM1 buffer", got, "<= " + dec(a.size() - 6));
            if (a[4] & 0x3F) return fail("channel (byte 4 bits 0-5) not 0", got, "byte 4 & 0x3F = 0");
            if (a[5] & 0x80) return fail("reserved bit 7 of byte 5 set", got, "byte 5 bit 7 clear");
            if ((a[5] & 0x0F) != 3) return fail("reply type", dec(a[5] & 0x0F), "3 (CoE)");
            return pass("header", got);
        },
        "CoE");
    add(
        "sm.status",
        "SM0/SM1 status (0x0805/0x080D): reserved bit 2 clear; SM1 mailbox full only while a reply waits",
        kSmStatus, {&Context::need_coe},
        [](Context& ctx) {
            ctx.mbx_resync();
            const uint16_t sm0 = master::reg::Sm0 + 5, sm1 = master::reg::Sm0 + 8 + 5;
            auto idle0 = ctx.rd<uint8_t>(sm0);
            auto idle1 = ctx.rd<uint8_t>(sm1);
            if (!idle0 || !idle1) return fail("SM status unreadable");
            if (Error e = ctx.mbx_write_raw(message(3, 0, upload_1000())); e != Error::Ok)
                return fail("request not written: " + err(e));
            master::Result<uint8_t> full = Error::Timeout;
            const auto deadline = std::chrono::steady_clock::now() + ctx.ms(500);
            do {
                full = ctx.rd<uint8_t>(sm1);
            } while (full && !(*full & 0x08) && std::chrono::steady_clock::now() < deadline);
            std::vector<uint8_t> reply;
            const Error re = ctx.mbx_read_raw(reply, ctx.ms(500));
            auto after = ctx.rd<uint8_t>(sm1);
            ctx.mbx_resync();
            const std::string seen = "SM0 idle " + hex(*idle0, 2) + ", SM1 idle " + hex(*idle1, 2) +
                                     ", reply waiting " + (full ? hex(*full, 2) : err(full.error())) +
                                     ", read " + (after ? hex(*after, 2) : err(after.error()));
            for (auto v : {idle0, idle1, full, after})
                if (v && (*v & 0x04)) return fail("reserved bit 2 set", seen, "bit 2 clear");
            if (*idle1 & 0x08) return fail("SM1 mailbox full with no reply waiting", seen, "bit 3 clear");
            if (!full || !(*full & 0x08))
                return fail("SM1 never showed mailbox full for a reply", seen, "bit 3 set");
            if (re != Error::Ok) return fail("reply not read: " + err(re), seen);
            if (!after || (*after & 0x08))
                return fail("SM1 mailbox full after the reply was read", seen, "bit 3 clear");
            return pass("status", seen);
        },
        "CoE");
    add(
        "sm.config",
        "SM0/SM1 in PREOP: registers read back as configured, not deactivated by the PDI (0x0807/0x080F "
        "bit 0)",
        "ESC datasheet SyncManager registers 0x0800+8n (read/write for EtherCAT; 0x0807 PDI control bit 0: "
        "SM deactivated); ETG.1000.4 mailbox",
        {&Context::need_mailbox},
        [](Context& ctx) {
            const auto& mc = ctx.mbx->config();
            uint8_t r[16] = {};
            if (Error e = ctx.m.read(ctx.addr, master::reg::Sm0, r); e != Error::Ok)
                return fail("SM0/SM1 unreadable", err(e));
            auto show = [](uint16_t start, uint16_t len, uint8_t control, uint8_t act, uint8_t pdi) {
                return hex(start) + "/" + dec(len) + " control " + hex(control, 2) + " enable " +
                       dec(act & 1) + " PDI deactivated " + dec(pdi & 1);
            };
            const std::string got = "SM0 " + show(get16(r), get16(r + 2), r[4], r[6], r[7]) + "; SM1 " +
                                    show(get16(r + 8), get16(r + 10), r[12], r[14], r[15]);
            const std::string want =
                "SM0 " + show(mc.out_start, mc.out_size, master::Mailbox::kSm0ControlDefault, 1, 0) +
                "; SM1 " + show(mc.in_start, mc.in_size, master::Mailbox::kSm1ControlDefault, 1, 0);
            return expect_eq("SM0/SM1 registers", got, want);
        },
        "mailbox slave");
    add(
        "repeat.request", "Repeat request (SM1 toggle) puts the last response back, identical", kRepeat,
        {&Context::need_coe},
        [](Context& ctx) {
            ctx.mbx_resync();
            auto first = ask(ctx, message(3, 0, upload_1000()), ctx.ms(500));
            if (first.empty()) {
                ctx.mbx_resync();
                return fail("no answer to the request");
            }
            const uint16_t act = static_cast<uint16_t>(master::reg::Sm0 + 8 + 6);
            auto a = ctx.rd<uint8_t>(act);
            if (!a) return fail("SM1 activate register unreadable", err(a.error()));
            const uint8_t toggled = static_cast<uint8_t>(*a ^ 0x02);
            (void)ctx.wr<uint8_t>(act, toggled);
            bool acked = false;
            const auto deadline = std::chrono::steady_clock::now() + ctx.ms(500);
            while (std::chrono::steady_clock::now() < deadline) {
                auto p = ctx.rd<uint8_t>(static_cast<uint16_t>(act + 1));
                if (p && ((*p ^ toggled) & 0x02) == 0) {
                    acked = true;
                    break;
                }
                std::this_thread::sleep_for(std::chrono::microseconds(200));
            }
            std::vector<uint8_t> again;
            Error e = acked ? ctx.mbx_read_raw(again, ctx.ms(300)) : Error::MailboxTimeout;
            ctx.mbx_resync();
            if (!acked) return fail("repeat not acknowledged (0x080F bit 1 never followed 0x080E bit 1)");
            if (e != Error::Ok)
                return fail("no message in SM1 after the repeat acknowledge", err(e), "the last response");
            const std::size_t n = 6u + get16(first.data());
            if (again.size() < n ||
                !std::equal(first.begin(), first.begin() + static_cast<std::ptrdiff_t>(n), again.begin()))
                return fail("repeated message differs", bytes_hex(again, 16), bytes_hex(first, 16));
            return pass("repeated");
        },
        "CoE");
    add(
        "sm1.empty_read", "Reading an empty SM1 mailbox: working counter 0",
        "ETG.1000.4 SyncManager mailbox mode (read of an empty buffer)", {&Context::need_mailbox},
        [](Context& ctx) {
            ctx.mbx_resync();
            const auto& cfg = ctx.mbx->config();
            std::vector<uint8_t> buf(cfg.in_size);
            master::Datagram d = master::Master::addressed(ctx.addr, false, cfg.in_start, buf);
            if (Error e = ctx.m.exchange(d); e != Error::Ok) return fail("no reply", err(e));
            return expect_eq("working counter", dec(d.wkc), "0");
        },
        "mailbox slave");
    add(
        "sm0.partial_write", "A write that does not reach the end of SM0 is not taken as a request",
        "ETG.1000.4 SyncManager mailbox mode (buffer written completely)", {&Context::need_coe},
        [](Context& ctx) {
            ctx.mbx_resync();
            auto m = message(3, 0, upload_1000());
            const auto& cfg = ctx.mbx->config();
            master::Datagram d = master::Master::addressed(ctx.addr, true, cfg.out_start, m);
            (void)ctx.m.exchange(d);
            std::vector<uint8_t> r;
            Error e = ctx.mbx_read_raw(r, ctx.ms(100));
            // Complete the buffer so that SM0 is free again.
            std::vector<uint8_t> last(1, 0);
            master::Datagram end = master::Master::addressed(
                ctx.addr, true, static_cast<uint16_t>(cfg.out_start + cfg.out_size - 1), last);
            (void)ctx.m.exchange(end);
            std::this_thread::sleep_for(std::chrono::milliseconds(5));
            ctx.mbx_resync();
            if (e == Error::Ok)
                return fail("answered a message whose buffer was not completed", bytes_hex(r, 12),
                            "no answer");
            return pass("not taken");
        },
        "CoE");
    add(
        "error.unsupported_protocol", "Request of a protocol the SII does not announce: mailbox error 0x0002",
        kMbx,
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_coe());
            const uint8_t t = unannounced_type(ctx.protocols());
            if (!t) return skip("every protocol is announced");
            uint8_t p[8] = {};
            return mailbox_error(ctx, message(t, 0, p), {0x0002}, "type " + hex(t, 1));
        },
        "CoE");
    add(
        "error.reserved_type", "Request with a reserved mailbox type (0x6): mailbox error 0x0002", kMbx,
        [](Context& ctx) {
            uint8_t p[8] = {};
            return mailbox_error(ctx, message(0x06, 0, p), {0x0002}, "type 0x6");
        },
        "CoE");
    add(
        "error.type_zero", "Request with mailbox type 0 (error): mailbox error 0x0002 or invalid header",
        kMbx,
        [](Context& ctx) {
            uint8_t p[8] = {};
            return mailbox_error(ctx, message(0x00, 0, p), {0x0002, 0x0005}, "type 0");
        },
        "CoE", Severity::Warning);
    add(
        "error.length_zero", "Request with length 0: mailbox error (invalid header or size too short)", kMbx,
        [](Context& ctx) {
            return mailbox_error(ctx, message(3, 0, upload_1000(), 0), {0x0005, 0x0006}, "length 0");
        },
        "CoE");
    add(
        "error.length_too_long", "Request longer than SM0 can hold: mailbox error (invalid header or size)",
        kMbx,
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_coe());
            const int len = ctx.sii->word(0x19) - 6 + 10;
            return mailbox_error(ctx, message(3, 0, upload_1000(), len), {0x0005, 0x0008},
                                 "length " + dec(len));
        },
        "CoE");
    add(
        "error.coe_too_short", "CoE request shorter than the CoE header: mailbox error (size too short)",
        kMbx,
        [](Context& ctx) {
            uint8_t p[1] = {0x00};
            return mailbox_error(ctx, message(3, 0, p), {0x0006, 0x0001}, "1-byte CoE");
        },
        "CoE");
    add(
        "error.coe_unknown_service", "CoE request with an unknown service (0): a mailbox error answer", kMbx,
        [](Context& ctx) {
            uint8_t p[10] = {0x00, 0x00, 0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0};
            return mailbox_error(ctx, message(3, 0, p), {0x0001, 0x0004, 0x0006}, "CoE service 0");
        },
        "CoE", Severity::Warning);
    add(
        "error.coe_unknown_service_detail",
        "CoE request with an unknown service (0) answered with a mailbox error reply: its detail names "
        "this fault (0x0004 service not supported; 0x0001 syntax or 0x0006 size too short as general "
        "readings), not another one (0x0002 unsupported protocol for a protocol the device serves, 0x0003 "
        "channel, 0x0008 size)",
        kMbx,
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_coe());
            CONFORM_PREOP(ctx);
            ctx.mbx_resync();
            uint8_t p[10] = {0x00, 0x00, 0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0};
            auto r = ask(ctx, message(3, 0, p), ctx.ms(300));
            ctx.mbx_resync();
            // Whether a mailbox error reply comes at all is error.coe_unknown_service's (a warning); judged
            // here is only a reply that is one.
            if (r.size() < 10 || (r[5] & 0x0F) != 0 || get16(r.data()) != 4 || get16(&r[6]) != 0x0001)
                return skip("no mailbox error reply (see mbx.error.coe_unknown_service)");
            const uint16_t detail = get16(&r[8]);
            if (detail != 0x0004 && detail != 0x0001 && detail != 0x0005 && detail != 0x0006)
                return fail("CoE service 0: the mailbox error detail names another fault", hex(detail),
                            "0x0004 (service not supported), 0x0001, 0x0005 or 0x0006");
            return pass("CoE service 0", "detail " + hex(detail));
        },
        "CoE");
    add(
        "error.channel",
        "Request on channel 1 (reserved): answered as on channel 0, or mailbox error 0x0003 (invalid "
        "channel)",
        kMbx,
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_coe());
            CONFORM_PREOP(ctx);
            ctx.mbx_resync();
            std::vector<uint8_t> m = message(3, 0, upload_1000());
            m[4] = 0x01;  // channel 1
            auto r = ask(ctx, m, ctx.ms(300));
            ctx.mbx_resync();
            const std::string want = "a CoE answer (channel ignored) or mailbox error detail 0x0003";
            if (r.empty()) return fail("channel 1: no answer", "none", want);
            const uint8_t type = r[5] & 0x0F;
            if (type == 3) return pass("channel ignored", "CoE answer");
            // ETG.1000.4 mailbox error reply detail 0x0003: invalid channel (0x0005, invalid header, names
            // the same fault more generally).
            if (type != 0 || get16(r.data()) != 4 || get16(&r[6]) != 0x0001)
                return fail("channel 1: neither a CoE answer nor a mailbox error reply",
                            "type " + dec(type) + " " + bytes_hex(std::span<const uint8_t>(r).subspan(0, 12)),
                            want);
            const uint16_t detail = get16(&r[8]);
            if (detail != 0x0003 && detail != 0x0005)
                return fail("channel 1: mailbox error detail", hex(detail), "0x0003 (or 0x0005)");
            return pass("refused", "detail " + hex(detail));
        },
        "CoE");
    add(
        "mailbox_after_error", "After a mailbox error, a correct request is answered normally", kMbx,
        {&Context::need_coe},
        [](Context& ctx) {
            ctx.mbx_resync();
            uint8_t p[8] = {};
            (void)ask(ctx, message(0x06, 0, p), ctx.ms(300));
            auto r = ask(ctx, message(3, 1, upload_1000()), ctx.ms(500));
            ctx.mbx_resync();
            if (r.empty() || (r[5] & 0x0F) != 3)
                return fail("no CoE answer after a mailbox error", r.empty() ? "none" : bytes_hex(r, 12));
            return pass("answered");
        },
        "CoE");
}

}  // namespace conform
