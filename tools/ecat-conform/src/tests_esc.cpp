// Group esc: datagram commands and their working counters, addressing, frames, ESC registers.
#include <algorithm>
#include <chrono>
#include <optional>
#include <thread>

#include "testkit.hpp"

namespace conform {

namespace {

using master::Command;
using master::Datagram;
using master::Error;

constexpr const char* kCmdClause = "ETG.1000.4 datagram commands and working counter";
constexpr const char* kRegClause = "ETG.1000.4 register access; ESC datasheet register description";
constexpr uint16_t kEventMask = 0x0200;  // ECAT event mask: read/write from EtherCAT, no side effect

struct Sent {
    Error error = Error::Ok;
    uint16_t wkc = 0;
    uint16_t adp = 0;  // as sent
    std::vector<uint8_t> data;
    Command cmd = Command::NOP;
    uint16_t ado = 0;
    std::size_t length = 0;
    // The datagram as sent and what came back, for failure messages.
    std::string describe() const {
        static constexpr const char* kNames[] = {"NOP", "APRD", "APWR", "APRW", "FPRD", "FPWR", "FPRW", "BRD",
                                                 "BWR", "BRW",  "LRD",  "LWR",  "LRW",  "ARMW", "FRMW"};
        const auto c = static_cast<std::size_t>(cmd);
        return std::string(c < std::size(kNames) ? kNames[c] : "cmd?") + " adp " + hex(adp) + " ado " +
               hex(ado) + " len " + std::to_string(length) + " -> wkc " + std::to_string(wkc) + " data " +
               bytes_hex(data, 16);
    }
};

Sent send(Context& ctx, Command c, uint16_t adp, uint16_t ado, std::vector<uint8_t> data) {
    Sent s;
    s.data = std::move(data);
    s.cmd = c;
    s.adp = adp;
    s.ado = ado;
    s.length = s.data.size();
    Datagram d{c, adp, ado, s.data};
    s.error = ctx.m.exchange(d);
    s.wkc = d.wkc;
    return s;
}

uint16_t my_adp(const Context& ctx) {
    return static_cast<uint16_t>(-static_cast<int>(ctx.opt.slave));
}

Outcome check_wkc(const Sent& s, uint16_t expected, const std::string& what) {
    if (s.error != Error::Ok) return fail(what + ": no reply", err(s.error), "a reply");
    if (s.wkc != expected)
        return fail(what + ": working counter", dec(s.wkc) + " (" + s.describe() + ")", dec(expected));
    return pass(what, "wkc " + dec(s.wkc));
}

std::vector<uint8_t> le16(uint16_t v) {
    return {static_cast<uint8_t>(v), static_cast<uint8_t>(v >> 8)};
}

// Maps FMMU (last one) onto the event mask register: logical kLog..kLog+1, read and write enabled.
constexpr uint32_t kLog = 0x00E00000;
Error map_event_mask(Context& ctx, uint8_t fmmu) {
    uint8_t f[16] = {};
    put32(f, kLog);
    put16(f + 4, 2);
    f[6] = 0;  // start bit
    f[7] = 7;  // stop bit
    put16(f + 8, kEventMask);
    f[10] = 0;
    f[11] = 0x03;  // read + write
    f[12] = 0x01;  // enable
    return ctx.m.write(ctx.addr, static_cast<uint16_t>(master::reg::Fmmu0 + 16 * fmmu), f);
}

Outcome logical(Context& ctx, Command c) {
    auto n = ctx.rd<uint8_t>(0x0004);
    if (!n) return fail("FMMU count 0x0004 unreadable", err(n.error()));
    if (*n == 0) return skip("the ESC has no FMMU (0x0004 = 0)");
    auto before = ctx.rd<uint16_t>(kEventMask);
    if (!before) return fail("event mask 0x0200 unreadable", err(before.error()));
    const uint8_t fmmu = static_cast<uint8_t>(*n - 1);
    if (Error e = map_event_mask(ctx, fmmu); e != Error::Ok) return fail("FMMU set-up write failed", err(e));
    const uint16_t v = static_cast<uint16_t>(*before ^ 0x0100);
    Sent s = send(ctx, c, static_cast<uint16_t>(kLog & 0xFFFF), static_cast<uint16_t>(kLog >> 16),
                  c == Command::LRD ? std::vector<uint8_t>{0, 0} : le16(v));
    auto after = ctx.rd<uint16_t>(kEventMask);
    uint8_t off[16] = {};
    (void)ctx.m.write(ctx.addr, static_cast<uint16_t>(master::reg::Fmmu0 + 16 * fmmu), off);
    (void)ctx.wr<uint16_t>(kEventMask, *before);
    const uint16_t want = c == Command::LRD ? 1 : c == Command::LWR ? 1 : 3;
    Outcome o = check_wkc(s, want, "through an FMMU onto 0x0200");
    if (o.status != Status::Pass) return o;
    if (c != Command::LWR && get16(s.data.data()) != *before)
        return fail("read data", hex(get16(s.data.data())), hex(*before));
    if (c != Command::LRD && (!after || *after != v))
        return fail("written value not in the register", after ? hex(*after) : err(after.error()), hex(v));
    return o;
}

Outcome physical_rw(Context& ctx, Command c) {
    auto before = ctx.rd<uint16_t>(kEventMask);
    if (!before) return fail("event mask 0x0200 unreadable", err(before.error()));
    const bool auto_inc = c == Command::APRD || c == Command::APWR || c == Command::APRW;
    const uint16_t adp = auto_inc ? my_adp(ctx) : ctx.station;
    const uint16_t v = static_cast<uint16_t>(*before ^ 0x0004);
    const bool reads = c == Command::APRD || c == Command::FPRD;
    const bool rw = c == Command::APRW || c == Command::FPRW;
    Sent s = send(ctx, c, adp, kEventMask, reads ? std::vector<uint8_t>{0, 0} : le16(v));
    auto after = ctx.rd<uint16_t>(kEventMask);
    (void)ctx.wr<uint16_t>(kEventMask, *before);
    Outcome o = check_wkc(s, rw ? 3 : 1, "on the read/write register 0x0200");
    if (o.status != Status::Pass) return o;
    if ((reads || rw) && get16(s.data.data()) != *before)
        return fail("data read (before the write)", hex(get16(s.data.data())), hex(*before));
    if (!reads && (!after || *after != v))
        return fail("register after the write", after ? hex(*after) : err(after.error()), hex(v));
    return o;
}

Outcome broadcast(Context& ctx, Command c) {
    auto before = ctx.rd<uint16_t>(kEventMask);
    if (!before) return fail("event mask 0x0200 unreadable", err(before.error()));
    const uint16_t n = ctx.slave_count;
    if (c == Command::BRD) {
        Sent s = send(ctx, c, 0, 0x0000, {0, 0});
        return check_wkc(s, n, "BRD 0x0000 over " + dec(n) + " slave(s)");
    }
    Sent s = send(ctx, c, 0, kEventMask, le16(*before));
    (void)ctx.wr<uint16_t>(kEventMask, *before);
    return check_wkc(s, static_cast<uint16_t>(c == Command::BRW ? 3 * n : n),
                     "on 0x0200 over " + dec(n) + " slave(s)");
}

Outcome read_modify_write(Context& ctx, Command c) {
    if (ctx.slave_count != 1)
        return skip("needs the slave alone on the bus (other slaves would take the write)");
    const uint16_t adp = c == Command::ARMW ? my_adp(ctx) : ctx.station;
    auto expected = ctx.rd<uint16_t>(esc::reg::kType);
    Sent s = send(ctx, c, adp, 0x0000, {0, 0});
    Outcome o = check_wkc(s, 1, "addressed slave reads 0x0000");
    if (o.status != Status::Pass) return o;
    if (expected && get16(s.data.data()) != *expected)
        return fail("data", hex(get16(s.data.data())), hex(*expected));
    return o;
}

std::vector<uint8_t> frame_with(std::span<const uint8_t> datagrams, std::size_t pad_to,
                                const master::MacAddress& src) {
    std::vector<uint8_t> f(14, 0);
    for (int i = 0; i < 6; ++i)
        f[static_cast<std::size_t>(i)] = 0xFF;
    std::copy(src.begin(), src.end(), f.begin() + 6);
    f[12] = 0x88;
    f[13] = 0xA4;
    f.push_back(static_cast<uint8_t>(datagrams.size() & 0xFF));
    f.push_back(static_cast<uint8_t>(0x10 | ((datagrams.size() >> 8) & 0x07)));
    f.insert(f.end(), datagrams.begin(), datagrams.end());
    if (f.size() < pad_to) f.resize(pad_to, 0);
    return f;
}

std::vector<uint8_t> datagram(Command c, uint8_t index, uint16_t adp, uint16_t ado,
                              std::span<const uint8_t> data, uint16_t length_field) {
    // Sized once (header, data, working counter): GCC 12 at -O3 misjudges an insert into a 10-byte vector.
    std::vector<uint8_t> d(10 + data.size() + 2, 0);
    d[0] = static_cast<uint8_t>(c);
    d[1] = index;
    put16(&d[2], adp);
    put16(&d[4], ado);
    put16(&d[6], length_field);
    std::copy(data.begin(), data.end(), d.begin() + 10);
    return d;
}

// DL status against the topology the tool sees: port 0 carries our frames (link, communication, open); a
// slave with successors has another port open with communication; the last one has no communication on
// any other port, and a port without link whose loop control is auto or auto-close is closed. Ports the
// port descriptor 0x0007 says are not implemented show neither link nor communication; port 0, which the
// frames come in at, is implemented.
Outcome dl_status_ports(Context& ctx) {
    auto s = ctx.rd<uint16_t>(esc::reg::kDlStatus);
    if (!s) return fail("0x0110 unreadable", err(s.error()));
    auto desc = ctx.rd<uint8_t>(0x0007);
    if (!desc) return fail("0x0007 unreadable", err(desc.error()));
    auto ctl = ctx.rd<uint8_t>(0x0101);
    if (!ctl) return fail("0x0101 (DL control loop bits) unreadable", err(ctl.error()));
    const bool last = ctx.opt.slave + 1u >= ctx.slave_count;
    std::string problems;
    auto bad = [&](const std::string& p) { problems += (problems.empty() ? "" : "; ") + p; };
    if (!(*s & 0x0001)) bad("PDI not operational (bit 0: EEPROM not loaded)");
    bool successor = false;
    for (int port = 0; port < 4; ++port) {
        const bool implemented = ((*desc >> (2 * port)) & 3) != 0;
        const bool link = *s & (1u << (4 + port));
        const bool closed = *s & (1u << (8 + 2 * port));
        const bool comm = *s & (1u << (9 + 2 * port));
        const unsigned loop_cfg = (*ctl >> (2 * port)) & 3;
        const std::string p = "port " + dec(port) + ": ";
        if (port == 0) {
            if (!implemented) bad(p + "0x0007 says not implemented, yet the frames come in there");
            if (!link) bad(p + "no link, yet the frames come in there");
            if (!comm) bad(p + "no communication, yet the frames come in there");
            if (closed && loop_cfg == 0)
                bad(p + "loop closed under auto loop control, yet the frames go on from there");
            continue;
        }
        if (!implemented) {
            if (link || comm) bad(p + "link or communication on a port 0x0007 says is not implemented");
            continue;
        }
        if (comm && !link) bad(p + "communication without link");
        if (!link && !closed && loop_cfg <= 1) bad(p + "no link but loop open (loop control auto)");
        if (link && closed && loop_cfg == 0) bad(p + "link but loop closed (loop control auto opens it)");
        if (comm && !closed) successor = true;
        if (last && comm) bad(p + "communication on a port with nothing behind it (last slave of the line)");
    }
    if (!last && !successor) bad("slaves follow, yet no port other than 0 is open with communication");
    if (!problems.empty())
        return fail(
            problems, hex(*s) + " (0x0007 " + hex(*desc, 2) + ", 0x0101 " + hex(*ctl, 2) + ")",
            last ? "port 0 link+comm+open, others no communication" : "port 0 and a successor port open");
    return pass("DL status", hex(*s));
}

Outcome al_status_bits(Context& ctx) {
    // From INIT, whatever the test before left (a failed test is not put back to INIT by the runner).
    (void)ctx.to_init();
    for (int round = 0; round < 2; ++round) {
        if (round == 1 && ctx.need_mailbox().empty() && ctx.to_preop() != Error::Ok)
            return fail("cannot reach PREOP for the second reading");
        auto s = ctx.rd<uint16_t>(esc::reg::kAlStatus);
        if (!s) return fail("0x0130 unreadable", err(s.error()));
        const unsigned st = *s & 0x0F;
        const std::string where = round ? "in PREOP" : "in INIT";
        if (st != 1 && st != 2 && st != 3 && st != 4 && st != 8)
            return fail(where + ": state bits 0-3 not a state", hex(*s), "1, 2, 3, 4 or 8");
        // Bits 6-7 are reserved; 8-15 are left alone (application specific in some profiles).
        if (*s & 0x00C0) return fail(where + ": reserved bits 6-7 set", hex(*s), "bits 6-7 clear");
        if (*s & 0x0020)
            return fail(where + ": ID bit 5 set although AL control bit 5 was never requested", hex(*s),
                        "bit 5 clear");
        if (round == 0 && st != 1) return fail("state after INIT requested", hex(*s), "1 (INIT)");
    }
    (void)ctx.to_init();
    return pass("INIT and PREOP readings defined");
}

Outcome features(Context& ctx) {
    auto f = ctx.rd<uint16_t>(0x0008);
    if (!f) return fail("0x0008 unreadable", err(f.error()));
    Outcome lrw = logical(ctx, Command::LRW);
    Outcome fprw = physical_rw(ctx, Command::FPRW);
    const bool lrw_works = lrw.status == Status::Pass, rw_works = fprw.status == Status::Pass;
    if ((*f & 0x0200) && lrw_works)
        return fail("bit 9 says LRW is not supported, yet LRW works", hex(*f), "bit 9 clear");
    if ((*f & 0x0400) && rw_works)
        return fail("bit 10 says BRW/APRW/FPRW are not supported, yet FPRW works", hex(*f), "bit 10 clear");
    if (!(*f & 0x0200) && !lrw_works && lrw.status != Status::Skip)
        return fail("bit 9 clear (LRW supported), yet LRW fails: " + lrw.message, hex(*f), "LRW working");
    if (!(*f & 0x0400) && !rw_works)
        return fail("bit 10 clear (FPRW supported), yet FPRW fails: " + fprw.message, hex(*f),
                    "FPRW working");
    return pass("features", hex(*f));
}

// Watchdog divider 0x0400, PDI watchdog time 0x0410, SM watchdog time 0x0420: read/write for EtherCAT (ESC
// datasheet section II); each takes another value and reads it back, then its own value is put back.
Outcome watchdog_rw(Context& ctx) {
    std::string got, want;
    for (uint16_t reg : {uint16_t{0x0400}, uint16_t{0x0410}, uint16_t{0x0420}}) {
        auto before = ctx.rd<uint16_t>(reg);
        if (!before) return fail(hex(reg) + " unreadable", err(before.error()));
        const auto v = static_cast<uint16_t>(*before ^ 0x0011);
        const Error w = ctx.wr<uint16_t>(reg, v);
        auto after = ctx.rd<uint16_t>(reg);
        (void)ctx.wr<uint16_t>(reg, *before);
        auto restored = ctx.rd<uint16_t>(reg);
        if (w != Error::Ok) return fail(hex(reg) + " not writable", err(w));
        got += hex(reg) + ": " + (after ? hex(*after) : err(after.error())) + ", back " +
               (restored ? hex(*restored) : err(restored.error())) + "; ";
        want += hex(reg) + ": " + hex(v) + ", back " + hex(*before) + "; ";
    }
    return expect_eq("watchdog registers written and read back", got, want);
}

Outcome dl_control_rw(Context& ctx) {
    uint8_t before[4] = {};
    if (Error e = ctx.m.read(ctx.addr, 0x0100, before); e != Error::Ok)
        return fail("0x0100 unreadable", err(e));
    auto desc = ctx.rd<uint8_t>(0x0007);
    if (!desc) return fail("0x0007 unreadable", err(desc.error()));
    // Loop control (bits 8-15) of the implemented ports; of the first implemented port after 0 it is set to
    // "closed" (0b11) and read back, then everything is restored and read back.
    uint8_t loop_mask = 0;
    int probe = -1;
    for (int p = 0; p < 4; ++p)
        if ((*desc >> (2 * p)) & 3) {
            loop_mask = static_cast<uint8_t>(loop_mask | (3u << (2 * p)));
            if (p > 0 && probe < 0) probe = p;
        }
    uint8_t v[4] = {before[0], before[1], before[2], before[3]};
    if (probe > 0) v[1] = static_cast<uint8_t>(v[1] | (3u << (2 * probe)));
    Error w = ctx.m.write(ctx.addr, 0x0100, v);
    uint8_t after[4] = {};
    Error r = ctx.m.read(ctx.addr, 0x0100, after);
    (void)ctx.m.write(ctx.addr, 0x0100, before);
    uint8_t restored[4] = {};
    Error r2 = ctx.m.read(ctx.addr, 0x0100, restored);
    if (w != Error::Ok || r != Error::Ok || r2 != Error::Ok) return fail("0x0100 access failed");
    // Bit 0 (forwarding rule), loop control of the implemented ports, bits 16-18 (RX FIFO size) are
    // read/write.
    auto shown = [](const uint8_t* b) { return bytes_hex(std::span<const uint8_t>(b, 3)); };
    auto mask = [loop_mask](const uint8_t* b) {
        return std::vector<uint8_t>{static_cast<uint8_t>(b[0] & 0x01), static_cast<uint8_t>(b[1] & loop_mask),
                                    static_cast<uint8_t>(b[2] & 0x07)};
    };
    if (mask(after) != mask(v)) return fail("written value read back", shown(after), shown(v));
    if (mask(restored) != mask(before))
        return fail("restored value read back", shown(restored), shown(before));
    return pass("0x0100", shown(before));
}

}  // namespace

void add_esc_tests(Catalogue& c) {
    Adder add{c, "esc"};
    add("nop.wkc", "NOP: no slave acts, working counter stays 0, data unchanged", kCmdClause,
        [](Context& ctx) {
            Sent s = send(ctx, Command::NOP, ctx.station, 0x0000, {0xA5, 0x5A});
            Outcome o = check_wkc(s, 0, "NOP");
            if (o.status == Status::Pass && (s.data[0] != 0xA5 || s.data[1] != 0x5A))
                return fail("NOP data changed", bytes_hex(s.data), "a5 5a");
            return o;
        });
    for (Command cmd :
         {Command::APRD, Command::APWR, Command::APRW, Command::FPRD, Command::FPWR, Command::FPRW}) {
        static const char* names[] = {"", "aprd", "apwr", "aprw", "fprd", "fpwr", "fprw"};
        const std::string n = names[static_cast<int>(cmd)];
        const bool rw = cmd == Command::APRW || cmd == Command::FPRW;
        std::string up = n;
        for (auto& ch : up)
            ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
        add(n + ".wkc",
            up + ": working counter " + (rw ? "3" : "1") + " on a read/write register, data " +
                (rw ? "read before write" : "as the register holds"),
            kCmdClause, [cmd](Context& ctx) { return physical_rw(ctx, cmd); });
    }
    add("brd.wkc", "BRD: working counter = number of slaves", kCmdClause,
        [](Context& ctx) { return broadcast(ctx, Command::BRD); });
    add("bwr.wkc", "BWR: working counter = number of slaves", kCmdClause,
        [](Context& ctx) { return broadcast(ctx, Command::BWR); });
    add("brw.wkc", "BRW: working counter = 3 x number of slaves on a read/write register", kCmdClause,
        [](Context& ctx) { return broadcast(ctx, Command::BRW); });
    add("lrd.wkc", "LRD through a read FMMU: working counter 1, data of the mapped register", kCmdClause,
        [](Context& ctx) { return logical(ctx, Command::LRD); });
    add("lwr.wkc", "LWR through a write FMMU: working counter 1, register written", kCmdClause,
        [](Context& ctx) { return logical(ctx, Command::LWR); });
    add("lrw.wkc", "LRW through a read/write FMMU: working counter 3", kCmdClause,
        [](Context& ctx) { return logical(ctx, Command::LRW); });
    add(
        "armw.wkc", "ARMW: the addressed slave reads (working counter 1)", kCmdClause,
        [](Context& ctx) { return read_modify_write(ctx, Command::ARMW); }, "the slave is alone on the bus");
    add(
        "frmw.wkc", "FRMW: the addressed slave reads (working counter 1)", kCmdClause,
        [](Context& ctx) { return read_modify_write(ctx, Command::FRMW); }, "the slave is alone on the bus");
    add("aprd.adp_increment", "Auto-increment address: every slave increments ADP", kCmdClause,
        [](Context& ctx) {
            uint8_t b[2] = {};
            Datagram d{Command::APRD, my_adp(ctx), 0x0000, b};
            // The reply's ADP is not kept by Master::exchange: send a raw frame.
            auto dg = datagram(Command::APRD, 0xA1, my_adp(ctx), 0x0000, b, 2);
            auto reply = ctx.raw_exchange(frame_with(dg, 60, ctx.m.options().source_mac), 0xA1, ctx.ms(200));
            if (reply.size() < 16 + 12) return fail("no reply to a raw APRD frame");
            const uint16_t adp = get16(&reply[16 + 2]);
            const uint16_t want = static_cast<uint16_t>(my_adp(ctx) + ctx.slave_count);
            (void)d;
            return expect_eq("ADP in the returned datagram", hex(adp), hex(want));
        });
    add("brd.adp_increment", "Broadcast: every slave increments ADP", kCmdClause, [](Context& ctx) {
        uint8_t b[2] = {};
        auto dg = datagram(Command::BRD, 0xA2, 0x0000, 0x0000, b, 2);
        auto reply = ctx.raw_exchange(frame_with(dg, 60, ctx.m.options().source_mac), 0xA2, ctx.ms(200));
        if (reply.size() < 16 + 12) return fail("no reply to a raw BRD frame");
        return expect_eq("ADP in the returned datagram", hex(get16(&reply[18])), hex(ctx.slave_count));
    });
    add("fprd.no_match", "FPRD to an unused station address: working counter 0", kCmdClause,
        [](Context& ctx) {
            Sent s = send(ctx, Command::FPRD, 0xF00D, 0x0000, {0, 0});
            return check_wkc(s, 0, "FPRD 0xf00d");
        });
    add("fpwr.no_match", "FPWR to an unused station address changes nothing", kCmdClause, [](Context& ctx) {
        auto before = ctx.rd<uint16_t>(kEventMask);
        if (!before) return fail("0x0200 unreadable", err(before.error()));
        Sent s = send(ctx, Command::FPWR, 0xF00D, kEventMask, le16(static_cast<uint16_t>(*before ^ 0x0010)));
        auto after = ctx.rd<uint16_t>(kEventMask);
        Outcome o = check_wkc(s, 0, "FPWR 0xf00d");
        if (o.status != Status::Pass) return o;
        if (!after || *after != *before)
            return fail("register changed", after ? hex(*after) : "?", hex(*before));
        return o;
    });
    add("aprd.no_match", "APRD past the last slave: working counter 0", kCmdClause, [](Context& ctx) {
        Sent s =
            send(ctx, Command::APRD, static_cast<uint16_t>(-static_cast<int>(ctx.slave_count)), 0, {0, 0});
        return check_wkc(s, 0, "APRD position " + dec(ctx.slave_count));
    });
    add("frame.source_mac", "Returned frame: source MAC with the locally administered bit set",
        "ETG.1000.4 frame processing (source address, bit 1 of the first octet)", [](Context& ctx) {
            uint8_t b[2] = {};
            auto dg = datagram(Command::FPRD, 0xA3, ctx.station, 0x0000, b, 2);
            master::MacAddress src{0x00, 0x11, 0x22, 0x33, 0x44, 0x55};
            auto reply = ctx.raw_exchange(frame_with(dg, 60, src), 0xA3, ctx.ms(200));
            if (reply.size() < 14) return fail("no reply");
            std::vector<uint8_t> want(src.begin(), src.end());
            want[0] |= 0x02;
            return expect_eq("source MAC", bytes_hex(std::span<const uint8_t>(reply).subspan(6, 6)),
                             bytes_hex(want));
        });
    add("frame.length_kept", "Returned frame has the length of the frame sent", "ETG.1000.4 frame processing",
        [](Context& ctx) {
            uint8_t b[2] = {};
            auto dg = datagram(Command::FPRD, 0xA4, ctx.station, 0x0000, b, 2);
            auto f = frame_with(dg, 60, ctx.m.options().source_mac);
            auto reply = ctx.raw_exchange(f, 0xA4, ctx.ms(200));
            if (reply.empty()) return fail("no reply");
            if (reply.size() != f.size()) return fail("frame length", dec(reply.size()), dec(f.size()));
            return check_wkc(Sent{Error::Ok, get16(&reply[16 + 12]), 0, {}}, 1, "padded minimum frame");
        });
    add("frame.multiple_datagrams", "Frame of several datagrams: each answered with its own working counter",
        kCmdClause, [](Context& ctx) {
            uint8_t a[2] = {}, b[2] = {}, d3[2] = {};
            Datagram d[3] = {{Command::FPRD, ctx.station, 0x0000, a},
                             {Command::FPRD, 0xF00D, 0x0000, b},
                             {Command::BRD, 0, 0x0000, d3}};
            if (Error e = ctx.m.exchange(d); e != Error::Ok) return fail("no reply", err(e));
            std::string got = dec(d[0].wkc) + "/" + dec(d[1].wkc) + "/" + dec(d[2].wkc);
            return expect_eq("working counters FPRD/FPRD(no match)/BRD", got, "1/0/" + dec(ctx.slave_count));
        });
    add("frame.truncated_datagram", "Datagram longer than its frame: not executed",
        "ETG.1000.4 frame processing (frames with errors are not executed)", [](Context& ctx) {
            auto before = ctx.rd<uint16_t>(kEventMask);
            if (!before) return fail("0x0200 unreadable", err(before.error()));
            auto v = le16(static_cast<uint16_t>(*before ^ 0x0020));
            auto dg = datagram(Command::FPWR, 0xA5, ctx.station, kEventMask, v, 200);  // says 200 bytes
            auto f = frame_with(dg, 60, ctx.m.options().source_mac);
            auto reply = ctx.raw_exchange(f, 0xA5, ctx.ms(50));
            auto after = ctx.rd<uint16_t>(kEventMask);
            (void)ctx.wr<uint16_t>(kEventMask, *before);
            if (!after) return fail("0x0200 unreadable afterwards", err(after.error()));
            if (*after != *before) return fail("the truncated write was executed", hex(*after), hex(*before));
            return pass("not executed", reply.empty() ? "dropped" : "returned unexecuted");
        });
    add(
        "frame.short_unpadded",
        "Frame under the Ethernet minimum: dropped or answered correctly, never garbled",
        "ETG.1000.4 frame processing; IEEE 802.3 minimum frame size",
        [](Context& ctx) {
            uint8_t b[2] = {};
            auto dg = datagram(Command::FPRD, 0xA6, ctx.station, 0x0000, b, 2);
            auto f = frame_with(dg, 0, ctx.m.options().source_mac);
            auto expected = ctx.rd<uint16_t>(esc::reg::kType);
            auto reply = ctx.raw_exchange(f, 0xA6, ctx.ms(50));
            if (reply.empty()) return pass("short frame dropped");
            if (reply.size() < 30) return fail("reply cut short", dec(reply.size()) + " bytes", ">= 30");
            const uint16_t wkc = get16(&reply[28]);
            if (wkc != 1 || !expected || get16(&reply[26]) != *expected)
                return fail("garbled reply", "wkc " + dec(wkc) + " data " + hex(get16(&reply[26])),
                            "wkc 1 data " + (expected ? hex(*expected) : "?"));
            return pass("answered correctly");
        },
        {}, Severity::Warning);
    add("frame.bad_length_field",
        "EtherCAT header length not evaluated (a master writing the frame length, or garbage): executed by "
        "the "
        "datagram lengths",
        "ETG.1000.4 frame structure; ESC datasheet section I, EtherCAT header: the length field is ignored "
        "by ESCs",
        [](Context& ctx) {
            auto before = ctx.rd<uint16_t>(kEventMask);
            if (!before) return fail("0x0200 unreadable", err(before.error()));
            const uint16_t want = static_cast<uint16_t>(*before ^ 0x0040);
            auto v = le16(want);
            auto dg = datagram(Command::FPWR, 0xA7, ctx.station, kEventMask, v, 2);
            auto f = frame_with(dg, 60, ctx.m.options().source_mac);
            f[14] = 0xF0;  // length 0x7F0: far past the 60-byte frame
            f[15] = 0x17;
            auto reply = ctx.raw_exchange(f, 0xA7, ctx.ms(50));
            auto after = ctx.rd<uint16_t>(kEventMask);
            (void)ctx.wr<uint16_t>(kEventMask, *before);
            if (!after) return fail("0x0200 unreadable afterwards", err(after.error()));
            if (reply.size() < 30) return fail("no reply to a frame a hardware ESC executes");
            if (*after != want || get16(&reply[28]) != 1)
                return fail("not executed", "0x0200 " + hex(*after) + " wkc " + dec(get16(&reply[28])),
                            "0x0200 " + hex(want) + " wkc 1");
            return pass("executed, answered");
        });
    add("frame.wrong_type", "EtherCAT header type other than 1 (datagrams): not executed",
        "ETG.1000.4 EtherCAT frame header (type)", [](Context& ctx) {
            auto before = ctx.rd<uint16_t>(kEventMask);
            if (!before) return fail("0x0200 unreadable", err(before.error()));
            auto v = le16(static_cast<uint16_t>(*before ^ 0x0080));
            auto dg = datagram(Command::FPWR, 0xA8, ctx.station, kEventMask, v, 2);
            auto f = frame_with(dg, 60, ctx.m.options().source_mac);
            f[15] = static_cast<uint8_t>((f[15] & 0x0F) | 0xE0);  // type 14
            (void)ctx.raw_exchange(f, 0xA8, ctx.ms(50));
            auto after = ctx.rd<uint16_t>(kEventMask);
            (void)ctx.wr<uint16_t>(kEventMask, *before);
            if (!after) return fail("0x0200 unreadable afterwards", err(after.error()));
            if (*after != *before)
                return fail("a frame of another type was executed", hex(*after), hex(*before));
            return pass("not executed");
        });

    // ---- registers ----
    add("reg.esc_info", "ESC information registers 0x0000-0x0009 readable in one datagram", kRegClause,
        [](Context& ctx) {
            uint8_t b[10] = {};
            if (Error e = ctx.m.read(ctx.addr, esc::reg::kType, b); e != Error::Ok)
                return fail("FPRD 0x0000/10", err(e));
            if (b[4] == 0 && b[5] == 0)
                return fail("no FMMU and no SM announced", bytes_hex(b), "FMMUs/SMs > 0");
            return pass("read", bytes_hex(b));
        });
    add(
        "reg.fmmu_count", "FMMUs in 0x0004 cover the ESI's Fmmu list",
        "ETG.2000 Device/Fmmu; ESC register 0x0004",
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_esi());
            auto n = ctx.rd<uint8_t>(0x0004);
            if (!n) return fail("0x0004 unreadable", err(n.error()));
            if (*n < ctx.esi->fmmus.size())
                return fail("too few FMMUs", dec(*n),
                            ">= " + dec(static_cast<long long>(ctx.esi->fmmus.size())));
            return pass("FMMUs", dec(*n));
        },
        "ESI given");
    add(
        "reg.sm_count", "SyncManagers in 0x0005 cover the ESI's Sm list",
        "ETG.2000 Device/Sm; ESC register 0x0005",
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_esi());
            auto n = ctx.rd<uint8_t>(0x0005);
            if (!n) return fail("0x0005 unreadable", err(n.error()));
            if (*n < ctx.esi->sms.size())
                return fail("too few SyncManagers", dec(*n),
                            ">= " + dec(static_cast<long long>(ctx.esi->sms.size())));
            return pass("SMs", dec(*n));
        },
        "ESI given");
    add(
        "reg.ram_size", "Process RAM (0x0006) holds every SM of the ESI",
        "ETG.2000 Device/Sm; ESC register 0x0006",
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_esi());
            auto kb = ctx.rd<uint8_t>(0x0006);
            if (!kb) return fail("0x0006 unreadable", err(kb.error()));
            uint32_t end = 0;
            for (const auto& s : ctx.esi->sms)
                end = std::max<uint32_t>(end, static_cast<uint32_t>(s.start) + 3u * s.default_size);
            const uint32_t top = 0x1000u + 1024u * *kb;
            if (end > top) return fail("an ESI SM (3 buffers) ends past the RAM", hex(end), "<= " + hex(top));
            return pass("RAM", dec(*kb) + " KiB");
        },
        "ESI given");
    add(
        "reg.dc_feature", "ESC features 0x0008: DC available as the ESI's Dc element says",
        "ETG.2000 Device/Dc; ESC register 0x0008 bit 2",
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_esi());
            auto f = ctx.rd<uint16_t>(0x0008);
            if (!f) return fail("0x0008 unreadable", err(f.error()));
            const bool dc = *f & 0x0004;
            if (ctx.esi->has_dc && !dc)
                return fail("the ESI has Dc but the ESC has no DC", hex(*f), "bit 2 set");
            // Bit 3 (64-bit DC): a 32-bit DC unit reads 0 in 0x0914-0x0917, the upper half of the system
            // time; a system time that counts there is 64 bits wide, whatever bit 3 says.
            if (dc && !(*f & 0x0008)) {
                auto hi = ctx.rd<uint32_t>(0x0914);
                if (hi && *hi)
                    return fail("bit 3 clear (32-bit DC), yet the system time's upper half 0x0914 counts",
                                hex(*f) + ", 0x0914 " + hex(*hi, 8), "bit 3 set, or 0x0914 = 0");
            }
            return pass("features", hex(*f));
        },
        "ESI given");
    add("reg.station_alias", "Configured station alias 0x0012 loaded from SII word 4",
        "ETG.1000.6 SII (configured station alias); ESC register 0x0012", [](Context& ctx) {
            CONFORM_NEED(ctx.need_sii());
            auto a = ctx.rd<uint16_t>(esc::reg::kStationAlias);
            if (!a) return fail("0x0012 unreadable", err(a.error()));
            return expect_eq("station alias", hex(*a), hex(ctx.sii->word(4)));
        });
    add("reg.alias_addressing", "FPRD by station alias once DL control enables alias addressing",
        "ETG.1000.4 node addressing (station alias); ESC register 0x0100 bit 24", [](Context& ctx) {
            auto a = ctx.rd<uint16_t>(esc::reg::kStationAlias);
            if (!a) return fail("0x0012 unreadable", err(a.error()));
            if (*a == 0) return skip("station alias is 0 (not set in the SII)");
            auto dl = ctx.rd<uint8_t>(0x0103);
            if (!dl) return fail("0x0103 unreadable", err(dl.error()));
            (void)ctx.wr<uint8_t>(0x0103, static_cast<uint8_t>(*dl | 0x01));
            Sent s = send(ctx, Command::FPRD, *a, 0x0000, {0, 0});
            (void)ctx.wr<uint8_t>(0x0103, *dl);
            return check_wkc(s, 1, "FPRD to alias " + hex(*a));
        });
    add("reg.station_address_rw", "Station address 0x0010 writable; FPRD follows the new address",
        "ETG.1000.4 node addressing (configured station address)", [](Context& ctx) {
            const uint16_t tmp = 0x7E57;
            if (Error e = ctx.wr<uint16_t>(esc::reg::kStationAddress, tmp); e != Error::Ok)
                return fail("write 0x0010", err(e));
            Sent s = send(ctx, Command::FPRD, tmp, 0x0010, {0, 0});
            (void)ctx.m.write_reg<uint16_t>(master::Address::station(tmp), 0x0010, ctx.station);
            (void)ctx.m.write_reg<uint16_t>(ctx.pos, 0x0010, ctx.station);
            Outcome o = check_wkc(s, 1, "FPRD at the new address");
            if (o.status == Status::Pass && get16(s.data.data()) != tmp)
                return fail("0x0010 read back", hex(get16(s.data.data())), hex(tmp));
            return o;
        });
    add("reg.al_status_readonly", "AL status 0x0130 cannot be written by the master",
        "ETG.1000.6 AL status register (read-only for EtherCAT)", [](Context& ctx) {
            auto before = ctx.rd<uint16_t>(esc::reg::kAlStatus);
            if (!before) return fail("0x0130 unreadable", err(before.error()));
            (void)send(ctx, Command::FPWR, ctx.station, 0x0130, le16(0x0008));
            auto after = ctx.rd<uint16_t>(esc::reg::kAlStatus);
            std::string restored;
            if (after && *after != *before) {
                // The write was taken: put the slave back (its value, then INIT), so that only this test
                // fails; a slave that stays stuck gets an ESC reset where it has one.
                (void)send(ctx, Command::FPWR, ctx.station, 0x0130, le16(*before));
                if (ctx.to_init() != Error::Ok) {
                    if (ctx.esc_reset()) {
                        (void)ctx.m.assign_station_addresses(ctx.slave_count);
                        restored = ctx.to_init() == Error::Ok
                                       ? " (the slave stayed stuck; an ESC reset restored it)"
                                       : " (the slave stayed stuck, even after an ESC reset)";
                    } else {
                        restored = " (the slave stayed stuck; it has no ESC reset)";
                    }
                }
            }
            if (!after) return fail("0x0130 unreadable", err(after.error()));
            return expect_eq("AL status after a write to it" + restored, hex(*after), hex(*before));
        });
    add("reg.type_readonly", "ESC type 0x0000 cannot be written by the master", kRegClause, [](Context& ctx) {
        auto before = ctx.rd<uint16_t>(esc::reg::kType);
        if (!before) return fail("0x0000 unreadable", err(before.error()));
        (void)send(ctx, Command::FPWR, ctx.station, 0x0000, le16(static_cast<uint16_t>(~*before)));
        auto after = ctx.rd<uint16_t>(esc::reg::kType);
        if (after && *after != *before) (void)send(ctx, Command::FPWR, ctx.station, 0x0000, le16(*before));
        if (!after) return fail("0x0000 unreadable", err(after.error()));
        return expect_eq("0x0000 after a write to it", hex(*after), hex(*before));
    });
    add("reg.dl_status", "DL status 0x0110: PDI operational, per port link, loop and communication as cabled",
        "ETG.1000.4 DL status register 0x0110; ESC datasheet 0x0007 port descriptor, 0x0100 loop control",
        dl_status_ports);
    add("reg.al_status_bits",
        "AL status 0x0130: a defined state, ID bit clear unless asked, reserved bits 6-7 clear",
        "ETG.1000.6 AL status register 0x0130", al_status_bits);
    add("reg.features", "ESC features 0x0008 agree with the commands: LRW (bit 9), BRW/APRW/FPRW (bit 10)",
        "ESC datasheet register 0x0008 (ESC features supported); ETG.1000.4 datagram commands", features);
    add("reg.dl_control_rw", "DL control 0x0100: the value written reads back (loop control, forwarding)",
        "ETG.1000.4 DL control register 0x0100", dl_control_rw);
    add("reg.watchdog_rw",
        "Watchdog divider 0x0400, PDI and SM watchdog times 0x0410/0x0420: the value written reads back",
        "ETG.1000.4 register access; ESC datasheet section II watchdog registers 0x0400-0x0420 (read/write "
        "for "
        "EtherCAT)",
        watchdog_rw);
    add("reg.protection_offset",
        "Write protection 0x0020/0x0030 off (no master of this run enables it), physical read/write offset "
        "0x0108 reads back as written",
        "ETG.1000.4 register access; ESC datasheet section II 0x0020 register write protection, 0x0030 ESC "
        "write "
        "protection (bit 0, 0 after reset; bits 1-7 reserved), 0x0108-0x0109 physical read/write offset "
        "(read/write for EtherCAT)",
        [](Context& ctx) {
            for (uint16_t reg : {uint16_t{0x0020}, uint16_t{0x0030}}) {
                auto v = ctx.rd<uint8_t>(reg);
                if (!v) return fail(hex(reg) + " unreadable", err(v.error()));
                // Set, the ESC would refuse the register writes this run makes (and reads back).
                if (*v)
                    return fail(hex(reg) + " write protection on, or reserved bits set", hex(*v, 2), "0x00");
            }
            auto before = ctx.rd<uint16_t>(0x0108);
            if (!before) return fail("0x0108 unreadable", err(before.error()));
            const auto v = static_cast<uint16_t>(*before ^ 0x0101);
            const Error w = ctx.wr<uint16_t>(0x0108, v);
            auto after = ctx.rd<uint16_t>(0x0108);
            (void)ctx.wr<uint16_t>(0x0108, *before);
            auto restored = ctx.rd<uint16_t>(0x0108);
            if (w != Error::Ok) return fail("0x0108 not writable", err(w));
            return expect_eq("0x0108 written and read back, then put back",
                             (after ? hex(*after) : err(after.error())) + ", " +
                                 (restored ? hex(*restored) : err(restored.error())),
                             hex(v) + ", " + hex(*before));
        });
    add("reg.event_request", "ECAT event request 0x0210: reserved bits 1 and 12-15 clear",
        "ETG.1000.4 register access; ESC datasheet section II ECAT event request register 0x0210",
        [](Context& ctx) {
            auto v = ctx.rd<uint16_t>(0x0210);
            if (!v) return fail("0x0210 unreadable", err(v.error()));
            if (*v & 0xF002) return fail("reserved bits set", hex(*v), "bits 1, 12-15 clear");
            return pass("0x0210", hex(*v));
        });
    add("reg.al_status_event",
        "ECAT event request 0x0210 bit 3: set when the slave changes AL status (PREOP -> INIT)",
        "ESC datasheet section II ECAT event request 0x0210 bit 3 (AL status event: AL status changed by the "
        "PDI, cleared by reading AL status 0x0130-0x0131); ETG.1000.4 datagram IRQ field",
        [](Context& ctx) {
            CONFORM_PREOP(ctx);
            // Reading AL status clears a pending event. (Bit 3 is not required clear right after it: a
            // firmware that writes AL status again, even the same value, raises it again.)
            (void)ctx.rd<uint16_t>(master::reg::AlStatus);
            if (Error e = ctx.wr<uint16_t>(master::reg::AlControl, 0x0001); e != Error::Ok)
                return fail("AL control write", err(e));
            // Watched without reading 0x0130 (that read clears the event): the bit comes with the change.
            bool seen = false;
            const auto until = std::chrono::steady_clock::now() +
                               std::chrono::milliseconds(static_cast<int>(2000 * ctx.opt.timeout_scale));
            while (!seen && std::chrono::steady_clock::now() < until) {
                auto ev = ctx.rd<uint16_t>(0x0210);
                seen = ev && (*ev & 0x0008);
                if (!seen) std::this_thread::sleep_for(std::chrono::milliseconds(5));
            }
            auto al = ctx.rd<uint16_t>(master::reg::AlStatus);
            (void)ctx.to_init();
            if (!al) return fail("0x0130 unreadable", err(al.error()));
            if ((*al & 0x0F) != 0x01)
                return skip("the slave did not reach INIT (esm.preop_to_init judges that)");
            if (!seen)
                return fail("AL status changed to INIT, 0x0210 bit 3 never set", hex(*al),
                            "bit 3 set until 0x0130 is read");
            return pass("set by the change of AL status");
        });
    add("reg.pdi_control",
        "PDI control 0x0140 and PDI/sync configuration 0x0150-0x0151 loaded from SII words 0-1",
        "ETG.1000.6 SII configuration area; ESC datasheet 0x0140 (loaded from EEPROM word 0), 0x0150-0x0151 "
        "(from word 1), also from the data the PDI gives where it emulates the EEPROM",
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_sii());
            auto p = ctx.rd<uint8_t>(esc::reg::kPdiControl);
            if (!p) return fail("0x0140 unreadable", err(p.error()));
            auto cfg = ctx.rd<uint16_t>(0x0150);
            if (!cfg) return fail("0x0150 unreadable", err(cfg.error()));
            return expect_eq("PDI control 0x0140, PDI configuration 0x0150-0x0151",
                             hex(*p, 2) + ", " + hex(*cfg),
                             hex(ctx.sii->word(0) & 0xFF, 2) + ", " + hex(ctx.sii->word(1)));
        });
    add("reg.error_counters",
        "Error counters 0x0300-0x0313: cleared by a write; port 0 (the tool's frames), forwarded, processing "
        "unit and port 0 lost link stay 0 over clean frames",
        "ESC datasheet section II error counters 0x0300-0x0313 (a write clears); ETG.1000.4 frame "
        "processing",
        [](Context& ctx) {
            std::vector<uint8_t> zero(0x14, 0);
            if (Error e = ctx.m.write(ctx.addr, 0x0300, zero); e != Error::Ok)
                return fail("write 0x0300-0x0313", err(e));
            for (int i = 0; i < 20; ++i)
                (void)ctx.rd<uint16_t>(esc::reg::kType);
            uint8_t cnt[0x14] = {};
            if (Error e = ctx.m.read(ctx.addr, 0x0300, cnt); e != Error::Ok)
                return fail("0x0300-0x0313 unreadable", err(e));
            // Ports other than 0 are left alone: what is cabled there (or not) is not the tool's to know.
            const struct {
                uint16_t reg;
                const char* name;
            } watched[] = {{0x0300, "port 0 invalid frames"},
                           {0x0301, "port 0 RX errors"},
                           {0x0308, "port 0 forwarded RX errors"},
                           {0x030C, "processing unit errors"},
                           {0x0310, "port 0 lost link"}};
            std::string bad;
            for (const auto& w : watched)
                if (cnt[w.reg - 0x0300])
                    bad += std::string(bad.empty() ? "" : ", ") + w.name + " " + dec(cnt[w.reg - 0x0300]);
            if (!bad.empty())
                return fail("counters not 0 after a clear and 20 clean frames: " + bad,
                            bytes_hex(std::span<const uint8_t>(cnt, 0x14), 0x14), "0 on port 0");
            return pass("cleared, stay 0", bytes_hex(std::span<const uint8_t>(cnt, 0x14), 0x14));
        });
    add("reg.al_event_request",
        "AL event request 0x0220 bit 0 (AL control event) clear once a requested state change is done",
        "ETG.1000.4 register access; ESC datasheet section II AL event request 0x0220 (bit 0 set by an ECAT "
        "write to AL control, cleared when the PDI reads 0x0120); 0x0141 bit 0 device emulation",
        [](Context& ctx) {
            if (auto cfg = ctx.rd<uint8_t>(esc::reg::kEscConfig); cfg && (*cfg & 0x01))
                return skip(
                    "device emulation (0x0141 bit 0): the ESC copies AL control, no application reads it");
            CONFORM_NEED(ctx.need_state_machine());
            if (ctx.to_init() != Error::Ok) return fail("cannot reach INIT");
            // INIT -> PREOP: the application read AL control to make the change, so the event is taken.
            if (Error e = ctx.to_preop(); e != Error::Ok) return fail("cannot reach PREOP", err(e));
            auto ev = ctx.rd<uint32_t>(0x0220);
            if (!ev) return fail("0x0220 unreadable", err(ev.error()));
            if (*ev & 0x01)
                return fail("AL control event still pending after the change to PREOP was done", hex(*ev, 8),
                            "bit 0 clear (the application read AL control)");
            return pass("0x0220", hex(*ev, 8));
        });
    add("reg.esc_reset",
        "ESC reset ('R', 'E', 'S' to 0x0040) from PREOP: where the device has one (its station address is "
        "cleared), AL status is back to INIT",
        "ETG.1000.4 register access; ESC datasheet section II ESC reset ECAT 0x0040 (the ESC and the "
        "application restart: AL status INIT)",
        [](Context& ctx) {
            CONFORM_NEED(ctx.need_state_machine());
            if (Error e = ctx.to_preop(); e != Error::Ok) return fail("cannot reach PREOP", err(e));
            if (!ctx.esc_reset()) {
                (void)ctx.to_init();
                return skip("no ESC reset (the station address still answers after the sequence)");
            }
            (void)ctx.m.assign_station_addresses(ctx.slave_count);
            std::optional<uint16_t> al;
            for (int i = 0; i < 50; ++i) {
                if (auto v = ctx.rd<uint16_t>(esc::reg::kAlStatus)) {
                    al = *v;
                    if ((*v & 0x0F) == 0x01) break;
                }
                std::this_thread::sleep_for(ctx.ms(20));
            }
            (void)ctx.to_init();
            if (!al) return fail("AL status unreadable after the ESC reset");
            if ((*al & 0x0F) != 0x01)
                return fail("AL status after an ESC reset from PREOP", hex(*al), "INIT (0x0001)");
            return pass("reset to INIT", hex(*al));
        });
    add("reg.process_ram",
        "Process RAM outside the SyncManagers (its last 8 bytes, in INIT) reads back as written",
        "ETG.1000.4 register access; ESC datasheet section II process data RAM 0x1000 (size 0x0006): "
        "read/write for EtherCAT",
        [](Context& ctx) {
            auto kb = ctx.rd<uint8_t>(0x0006);
            if (!kb) return fail("0x0006 unreadable", err(kb.error()));
            if (*kb == 0) return skip("no process RAM (0x0006 = 0)");
            if (ctx.to_init() != Error::Ok) return fail("cannot reach INIT");
            // The RAM ends where 0x0006 says, within the ESC's 64 KiB address space.
            const uint16_t at = static_cast<uint16_t>(std::min(0x1000u + 1024u * *kb, 0x10000u) - 8u);
            uint8_t old[8] = {};
            if (Error e = ctx.m.read(ctx.addr, at, old); e != Error::Ok)
                return fail(hex(at) + " unreadable", err(e));
            uint8_t pattern[8], back[8] = {};
            for (int i = 0; i < 8; ++i)
                pattern[i] = static_cast<uint8_t>(0xA5 ^ (old[i] + 0x11 * (i + 1)));
            Error w = ctx.m.write(ctx.addr, at, pattern);
            Error r = ctx.m.read(ctx.addr, at, back);
            (void)ctx.m.write(ctx.addr, at, old);
            if (w != Error::Ok) return fail("write " + hex(at), err(w));
            if (r != Error::Ok) return fail("read back " + hex(at), err(r));
            return expect_eq("RAM " + hex(at) + "..+7", bytes_hex(std::span<const uint8_t>(back, 8), 8),
                             bytes_hex(std::span<const uint8_t>(pattern, 8), 8));
        });
    add("reg.al_control_rw",
        "AL control 0x0120 accepts the master's request (INIT stays INIT) and reads back the value written",
        "ETG.1000.6 AL control register; ESC datasheet 0x0120 AL control (read/write for EtherCAT)",
        [](Context& ctx) {
            Sent s = send(ctx, Command::FPWR, ctx.station, 0x0120, le16(0x0001));
            Outcome o = check_wkc(s, 1, "FPWR AL control");
            if (o.status != Status::Pass) return o;
            Sent r = send(ctx, Command::FPRD, ctx.station, 0x0120, std::vector<uint8_t>(2, 0));
            if (Outcome w = check_wkc(r, 1, "FPRD AL control"); w.status != Status::Pass) return w;
            return expect_eq("0x0120 after 0x0001 written", hex(get16(r.data.data())), hex(0x0001));
        });
    add("reg.rw_offset_span", "A read spanning several registers (0x0000..0x00FF) counts once",
        "ETG.1000.4 working counter (one increment per datagram)", [](Context& ctx) {
            Sent s = send(ctx, Command::FPRD, ctx.station, 0x0000, std::vector<uint8_t>(256, 0));
            return check_wkc(s, 1, "FPRD 256 bytes");
        });
}

}  // namespace conform
