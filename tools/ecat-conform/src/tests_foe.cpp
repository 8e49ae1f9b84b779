// Group foe: Bootstrap and FoE: entry into BOOT with the SII's bootstrap mailbox, writes refused outside
// Bootstrap, unknown file names and wrong passwords refused with their FoE error codes. No firmware is
// written unless asked: an accepted write request is cancelled at once with an FoE error packet; with
// --allow-foe-write --foe-file --foe-image one whole write goes through, packet by packet.
#include <thread>

#include "testkit.hpp"

namespace conform {

namespace {

using master::Error;
constexpr const char* kFoe = "ETG.1000.6 FoE (File access over EtherCAT) services and error codes";
constexpr const char* kBoot = "ETG.1000.6 BOOT state; SII bootstrap mailbox words 0x14-0x17";

struct FoeAnswer {
    Error error = Error::Ok;
    uint8_t opcode = 0;
    uint8_t reserved = 0;  // the header's second byte (ETG.1000.6 FoE header: reserved, 0)
    uint32_t value = 0;
    std::string text;
    std::string describe() const {
        if (error != Error::Ok) return std::string(master::to_string(error));
        if (opcode == 5) return "ERR " + hex(value) + (text.empty() ? "" : " \"" + text + "\"");
        if (opcode == 4) return "ACK " + dec(value);
        return "opcode " + dec(opcode);
    }
};

FoeAnswer foe_request(Context& ctx, uint8_t opcode, uint32_t value, const std::string& name) {
    FoeAnswer a;
    std::vector<uint8_t> p(6, 0);
    p[0] = opcode;
    put32(&p[2], value);
    p.insert(p.end(), name.begin(), name.end());
    if ((a.error = ctx.mbx->send(master::MailboxType::FoE, p)) != Error::Ok) return a;
    for (;;) {
        master::MailboxMessage m;
        if ((a.error = ctx.mbx->receive(m, ctx.ms(1000))) != Error::Ok) return a;
        if (m.type == master::MailboxType::Error) {
            a.error = Error::MailboxError;
            return a;
        }
        if (m.type != master::MailboxType::FoE) continue;
        if (m.payload.size() < 6) {
            a.error = Error::MailboxProtocol;
            return a;
        }
        a.opcode = m.payload[0];
        a.reserved = m.payload[1];
        a.value = get32(&m.payload[2]);
        a.text.assign(m.payload.begin() + 6, m.payload.end());
        break;
    }
    if (a.opcode == 4 || a.opcode == 3) {
        // Accepted: cancel before anything is stored.
        std::vector<uint8_t> e(6 + 9, 0);
        e[0] = 5;
        put32(&e[2], 0x8000);
        const char* t = "cancelled";
        std::copy(t, t + 9, e.begin() + 6);
        (void)ctx.mbx->send(master::MailboxType::FoE, e);
    }
    return a;
}

Outcome expect_foe_error(const FoeAnswer& a, std::initializer_list<uint32_t> codes, const std::string& what) {
    std::string want;
    for (auto c : codes)
        want += (want.empty() ? "ERR " : " or ") + hex(c);
    if (a.error != Error::Ok) return fail(what + ": no FoE answer", a.describe(), want);
    if (a.opcode != 5) return fail(what + ": not refused", a.describe(), want);
    if (a.reserved != 0)
        return fail(what + ": FoE header byte 1 (reserved) not 0", hex(a.reserved, 2) + " in " + a.describe(),
                    "0");
    for (auto c : codes)
        if (a.value == c) return pass(what, a.describe());
    return fail(what + ": FoE error code", a.describe(), want);
}

// FoE read of --foe-file in BOOT (reading changes nothing): either refused with an FoE error, or DATA packets
// numbered from 1 up by one, header byte 1 reserved (0), each acknowledged with its number; the first
// kReadPackets are read, then the read is ended with an error request (ETG.1000.6 FoE: either side may end a
// transfer with an error) unless the file ended first (a packet shorter than the others).
Outcome foe_read(Context& ctx) {
    constexpr unsigned kReadPackets = 8;
    FoeAnswer first;
    std::vector<uint8_t> rrq(6, 0);
    rrq[0] = 1;
    put32(&rrq[2], ctx.opt.foe_password);
    rrq.insert(rrq.end(), ctx.opt.foe_file.begin(), ctx.opt.foe_file.end());
    if (Error e = ctx.mbx->send(master::MailboxType::FoE, rrq); e != Error::Ok)
        return fail("read request not sent: " + err(e));
    std::string seen;
    // A DATA packet shorter than the mailbox allows (SM1 minus mailbox and FoE headers) ends the file.
    const std::size_t full = ctx.mbx->config().in_size > 12 ? ctx.mbx->config().in_size - 12u : 0u;
    for (uint32_t want = 1; want <= kReadPackets; ++want) {
        master::MailboxMessage m;
        Error e = ctx.mbx->receive(m, ctx.ms(1000));
        while (e == Error::Ok && m.type != master::MailboxType::FoE && m.type != master::MailboxType::Error)
            e = ctx.mbx->receive(m, ctx.ms(1000));
        if (e != Error::Ok)
            return fail(
                "no answer to " + std::string(want == 1 ? "the read request" : "the ACK") + ": " + err(e),
                seen);
        if (m.type == master::MailboxType::Error) return fail("mailbox error answer", seen);
        if (m.payload.size() < 6) return fail("FoE answer shorter than its header", bytes_hex(m.payload));
        const uint8_t op = m.payload[0];
        const uint32_t value = get32(&m.payload[2]);
        if (op == 5 && want == 1) return pass("read refused (optional)", "ERR " + hex(value));
        if (op == 6 && want == 1) return pass("read answered BUSY (not judged)", "BUSY " + dec(value));
        if (op != 3)
            return fail("answer to packet " + dec(want) + " not DATA", "opcode " + dec(op), "3 (DATA)");
        seen += dec(value) + " ";
        if (m.payload[1] != 0) return fail("DATA header byte 1 (reserved) not 0", hex(m.payload[1], 2), "0");
        if (value != want) return fail("DATA packet number", seen, "1, 2, 3, ...");
        const std::size_t n = m.payload.size() - 6;
        // The last packet read (the file's short one, or the last the tool reads) is answered with the ACK
        // of another number: the server refuses it with 0x8005 (packet number wrong), which ends the read.
        const bool last = n < full || want == kReadPackets;
        std::vector<uint8_t> ack(6, 0);
        ack[0] = 4;
        put32(&ack[2], last ? value + 5 : value);
        (void)ctx.mbx->send(master::MailboxType::FoE, ack);
        if (!last) continue;
        master::MailboxMessage r;
        Error e2 = ctx.mbx->receive(r, ctx.ms(1000));
        while (e2 == Error::Ok && r.type != master::MailboxType::FoE && r.type != master::MailboxType::Error)
            e2 = ctx.mbx->receive(r, ctx.ms(1000));
        const bool refused = e2 == Error::Ok && r.type == master::MailboxType::FoE && r.payload.size() >= 6 &&
                             r.payload[0] == 5;
        if (refused && get32(&r.payload[2]) == 0x8005)
            return pass(std::string(n < full ? "file read to its end" : "DATA packets numbered from 1") +
                            "; ACK " + dec(value + 5) + " refused with 0x8005",
                        seen);
        if (!refused) {
            // Not ended by the server: the tool ends the read.
            std::vector<uint8_t> end(6, 0);
            end[0] = 5;
            put32(&end[2], 0x8000);
            (void)ctx.mbx->send(master::MailboxType::FoE, end);
        }
        const std::string got = e2 != Error::Ok                      ? std::string("no answer")
                                : r.type != master::MailboxType::FoE ? std::string("a mailbox error reply")
                                : r.payload.size() < 6               ? std::string("a short FoE packet")
                                : refused                            ? "ERR " + hex(get32(&r.payload[2]))
                                                                     : "opcode " + dec(r.payload[0]);
        return fail("ACK " + dec(value + 5) + " to DATA " + dec(value) + " (packet number wrong)", got,
                    "ERR 0x8005");
    }
    return pass("DATA packets numbered from 1", seen);
}

#define CONFORM_BOOT(ctx)                                                                                  \
    CONFORM_NEED((ctx).need_foe());                                                                        \
    CONFORM_NEED((ctx).need_boot());                                                                       \
    if (Error _b = (ctx).to_boot(); _b != Error::Ok)                                                       \
    return fail(                                                                                           \
        "cannot enter BOOT with the SII's bootstrap mailbox: " + err(_b),                                  \
        state_text(static_cast<uint8_t>((ctx).last_status.state | ((ctx).last_status.error ? 0x10 : 0))) + \
            " code " + hex((ctx).last_status.code),                                                        \
        "BOOT")

// One whole FoE write (ETG.1000.6 FoE): WRQ answered by ACK 0, DATA packets 1..n each answered by the ACK of
// its number (BUSY in between allowed: the packet is sent again), the last one shorter than a full packet
// (an empty one when the file fills its last packet), the final ACK within the budget. Returns "" or what
// went wrong; busy counts the BUSY answers.
std::string foe_write_whole(Context& ctx, const std::string& name, uint32_t password,
                            std::span<const uint8_t> file, unsigned& busy, unsigned& packets) {
    auto receive = [&](uint8_t& opcode, uint32_t& value, std::string& text) -> std::string {
        for (;;) {
            master::MailboxMessage m;
            if (Error e = ctx.mbx->receive(m, ctx.ms(5000)); e != Error::Ok) return "no answer: " + err(e);
            if (m.type == master::MailboxType::Error) return "a mailbox error reply";
            if (m.type != master::MailboxType::FoE) continue;
            if (m.payload.size() < 6) return "an FoE packet of " + dec(m.payload.size()) + " bytes";
            opcode = m.payload[0];
            value = get32(&m.payload[2]);
            text.assign(m.payload.begin() + 6, m.payload.end());
            return "";
        }
    };
    std::vector<uint8_t> p(6, 0);
    p[0] = 2;  // WRQ
    put32(&p[2], password);
    p.insert(p.end(), name.begin(), name.end());
    if (Error e = ctx.mbx->send(master::MailboxType::FoE, p); e != Error::Ok)
        return "WRQ not sent: " + err(e);
    uint8_t op = 0;
    uint32_t value = 0;
    std::string text;
    if (auto w = receive(op, value, text); !w.empty()) return "WRQ: " + w;
    if (op == 5) return "WRQ refused: ERR " + hex(value) + " \"" + text + "\"";
    if (op != 4 || value != 0)
        return "WRQ answered by opcode " + dec(op) + " value " + dec(value) + ", not ACK 0";
    const std::size_t chunk = ctx.mbx->config().out_size - 6 - 6;  // mailbox header, FoE header
    std::size_t at = 0;
    uint32_t number = 0;
    for (;;) {
        const std::size_t n = std::min(chunk, file.size() - at);
        ++number;
        std::vector<uint8_t> d(6, 0);
        d[0] = 3;  // DATA
        put32(&d[2], number);
        d.insert(d.end(), file.begin() + static_cast<std::ptrdiff_t>(at),
                 file.begin() + static_cast<std::ptrdiff_t>(at + n));
        for (;;) {
            if (Error e = ctx.mbx->send(master::MailboxType::FoE, d); e != Error::Ok)
                return "DATA " + dec(number) + " not sent: " + err(e);
            if (auto w = receive(op, value, text); !w.empty()) return "DATA " + dec(number) + ": " + w;
            if (op != 6) break;  // BUSY: the same packet again after a pause
            if (++busy > 1000) return "BUSY answered more than 1000 times";
            std::this_thread::sleep_for(std::chrono::milliseconds(10));
        }
        ++packets;
        if (op == 5) return "DATA " + dec(number) + " refused: ERR " + hex(value) + " \"" + text + "\"";
        if (op != 4) return "DATA " + dec(number) + " answered by opcode " + dec(op);
        if (value != number) return "DATA " + dec(number) + " answered by ACK " + dec(value);
        at += n;
        if (n < chunk) return "";  // the short packet ended the file and was acknowledged
    }
}

}  // namespace

void add_foe_tests(Catalogue& c) {
    Adder add{c, "foe"};
    const std::string a = "FoE and a bootstrap mailbox in the SII";
    add(
        "boot.enter", "INIT -> BOOT with the SII's bootstrap mailbox when FoE is announced", kBoot,
        [](Context& ctx) {
            CONFORM_BOOT(ctx);
            (void)ctx.to_init();
            return pass("BOOT reached");
        },
        a);
    add(
        "boot.mailbox_layout", "In BOOT the mailbox SMs hold the bootstrap layout and answer FoE", kBoot,
        [](Context& ctx) {
            CONFORM_BOOT(ctx);
            uint8_t sm[16] = {};
            (void)ctx.m.read(ctx.addr, master::reg::Sm0, sm);
            const SiiImage& s = *ctx.sii;
            std::string got = hex(get16(sm)) + "/" + dec(get16(sm + 2)) + " " + hex(get16(sm + 8)) + "/" +
                              dec(get16(sm + 10));
            std::string want = hex(s.word(0x14)) + "/" + dec(s.word(0x15)) + " " + hex(s.word(0x16)) + "/" +
                               dec(s.word(0x17));
            FoeAnswer r = foe_request(ctx, 1, ctx.opt.foe_password, "ecat-conform-probe");
            (void)ctx.to_init();
            if (got != want) return fail("SM0/SM1 in BOOT", got, want);
            if (r.error != Error::Ok) return fail("no FoE answer in BOOT", r.describe(), "an FoE packet");
            return pass("FoE answers", r.describe());
        },
        a);
    add(
        "write_outside_boot",
        "FoE write request in PREOP refused: 0x8008 (bootstrap only), or 0x8001 for a name not given by "
        "--foe-file",
        kFoe,
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_foe());
            CONFORM_NEED(ctx.need_boot());
            CONFORM_PREOP(ctx);
            const std::string name = ctx.opt.foe_file.empty() ? "ecat-conform.bin" : ctx.opt.foe_file;
            FoeAnswer r = foe_request(ctx, 2, ctx.opt.foe_password, name);
            ctx.mbx_resync();
            // A name the device does not know may be refused as unknown (0x8001) by a device that also serves
            // files outside Bootstrap; the firmware file it does know can only be refused as Bootstrap-only.
            if (ctx.opt.foe_file.empty())
                return expect_foe_error(r, {0x8008, 0x8001}, "write \"" + name + "\" in PREOP");
            return expect_foe_error(r, {0x8008}, "write \"" + name + "\" in PREOP");
        },
        "FoE and a bootstrap mailbox");
    add(
        "unknown_name", "FoE write request of an unknown file name in BOOT: error 0x8001 (not found)", kFoe,
        [](Context& ctx) {
            CONFORM_BOOT(ctx);
            FoeAnswer r = foe_request(ctx, 2, ctx.opt.foe_password, "ecat-conform-no-such-file.bin");
            (void)ctx.to_init();
            return expect_foe_error(r, {0x8001}, "unknown name");
        },
        a);
    add(
        "wrong_password", "FoE write request with a wrong password in BOOT: error 0x800A (no rights)", kFoe,
        [](Context& ctx) {
            if (ctx.opt.foe_file.empty()) return skip("needs --foe-file (a file name the device accepts)");
            CONFORM_BOOT(ctx);
            FoeAnswer r = foe_request(ctx, 2, ctx.opt.foe_password ^ 0x5A5A5A5Au, ctx.opt.foe_file);
            (void)ctx.to_init();
            return expect_foe_error(r, {0x800A}, "password " + hex(ctx.opt.foe_password ^ 0x5A5A5A5Au, 8));
        },
        "--foe-file given");
    add(
        "read_unknown", "FoE read request of an unknown file in BOOT: error 0x8001 (not found) or 0x800F",
        kFoe,
        [](Context& ctx) {
            CONFORM_BOOT(ctx);
            FoeAnswer r = foe_request(ctx, 1, ctx.opt.foe_password, "ecat-conform-no-such-file.bin");
            (void)ctx.to_init();
            return expect_foe_error(r, {0x8001, 0x800F}, "read of an unknown name");
        },
        a);
    add(
        "unexpected_packet",
        "FoE ACK and DATA packets with no transfer running, in BOOT: each refused with error 0x8004, "
        "illegal",
        kFoe,
        [](Context& ctx) {
            CONFORM_BOOT(ctx);
            // ETG.1000.6 FoE: a packet the server's state does not expect (an ACK without a read, DATA
            // without a write) is an illegal request; the answer is an error request with 0x8004.
            FoeAnswer ack = foe_request(ctx, 4, 1, "");
            ctx.mbx_resync();
            FoeAnswer data = foe_request(ctx, 3, 1, "ecat-conform");
            ctx.mbx_resync();
            (void)ctx.to_init();
            if (Outcome o = expect_foe_error(ack, {0x8004}, "ACK 1 without a read"); o.status != Status::Pass)
                return o;
            return expect_foe_error(data, {0x8004}, "DATA 1 without a write");
        },
        a);
    add(
        "read_file",
        "FoE read of --foe-file in BOOT: refused with an FoE error, or DATA packets numbered from 1, each "
        "acknowledged (up to 8; the last with a wrong number, refused with 0x8005)",
        kFoe,
        [](Context& ctx) {
            if (ctx.opt.foe_file.empty()) return skip("needs --foe-file (a file name the device knows)");
            CONFORM_BOOT(ctx);
            Outcome o = foe_read(ctx);
            ctx.mbx_resync();
            (void)ctx.to_init();
            return o;
        },
        "--foe-file given");
    add(
        "write_complete",
        "A whole FoE write of --foe-image as --foe-file in BOOT: ACK 0 to the request, each DATA packet "
        "acknowledged with its number (BUSY allowed), the final ACK; then INIT and PREOP again",
        kFoe,
        [](Context& ctx) {
            if (!ctx.opt.allow_foe_write)
                return skip("writes the device's firmware: needs --allow-foe-write");
            if (ctx.opt.foe_file.empty() || ctx.opt.foe_image.empty())
                return skip("needs --foe-file and --foe-image (the device's own firmware)");
            CONFORM_BOOT(ctx);
            unsigned busy = 0, packets = 0;
            const std::string w = foe_write_whole(ctx, ctx.opt.foe_file, ctx.opt.foe_password,
                                                  ctx.opt.foe_image, busy, packets);
            const std::string how = dec(ctx.opt.foe_image.size()) + " bytes in " + dec(packets) +
                                    " packets, " + dec(busy) + " BUSY";
            if (!w.empty()) {
                ctx.mbx_resync();
                (void)ctx.to_init();
                return fail("FoE write of \"" + ctx.opt.foe_file + "\": " + w, how,
                            "every packet acknowledged");
            }
            master::AlStatus st = ctx.request_raw(1, ctx.ms(10000));
            if (st.state != 1 || st.error)
                return fail("BOOT -> INIT after the write",
                            state_text(static_cast<uint8_t>(st.state | (st.error ? 0x10 : 0))), "INIT");
            if (Error e = ctx.to_preop(); e != Error::Ok)
                return fail("INIT -> PREOP after the write: " + err(e), how, "PREOP");
            return pass("written and acknowledged", how);
        },
        "--allow-foe-write, --foe-file and --foe-image given");
    add(
        "boot.exit", "BOOT -> INIT leaves Bootstrap; INIT -> PREOP works again", kBoot,
        [](Context& ctx) {
            CONFORM_BOOT(ctx);
            master::AlStatus st = ctx.request_raw(1, ctx.ms(5000));
            if (st.state != 1 || st.error)
                return fail("BOOT -> INIT",
                            state_text(static_cast<uint8_t>(st.state | (st.error ? 0x10 : 0))), "INIT");
            if (Error e = ctx.to_preop(); e != Error::Ok) return fail("INIT -> PREOP after BOOT: " + err(e));
            return pass("back in PREOP");
        },
        a);
}

}  // namespace conform
