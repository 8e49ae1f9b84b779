// Cyclic process data with one slave: layout discovery, SM/FMMU set-up, DC/SYNC0, LRW cycles.
#include "master/session.hpp"

#include <time.h>

#include <algorithm>
#include <thread>

#include "util/le.hpp"

namespace master {

using Clock = std::chrono::steady_clock;

namespace {
using util::get16;
using util::get64;
using util::put16;
using util::put32;
using util::put64;
// EtherCAT system time: ns since 2000-01-01 (ESC datasheet section I §9).
uint64_t master_system_time() {
    timespec ts{};
    clock_gettime(CLOCK_REALTIME, &ts);
    constexpr uint64_t k2000 = 946'684'800ull;
    return (static_cast<uint64_t>(ts.tv_sec) - k2000) * 1'000'000'000ull + static_cast<uint64_t>(ts.tv_nsec);
}
void sleep_until(Clock::time_point t) {
    std::this_thread::sleep_until(t);
}
}  // namespace

ProcessDataSession::ProcessDataSession(Master& master, Address slave, SdoClient& sdo)
    : m_(master), slave_(slave), sdo_(sdo) {}

Error ProcessDataSession::pdo_bytes(uint16_t assign_index, std::vector<uint16_t>& pdos, uint16_t& bytes) {
    pdos.clear();
    uint32_t bits = 0;
    uint8_t b[4] = {};
    auto n = sdo_.upload(assign_index, 0, b);
    if (!n) return n.error();
    const uint8_t count = b[0];
    for (uint8_t i = 1; i <= count; ++i) {
        auto r = sdo_.upload(assign_index, i, b);
        if (!r) return r.error();
        const uint16_t pdo = get16(b);
        pdos.push_back(pdo);
        auto c = sdo_.upload(pdo, 0, b);
        if (!c) return c.error();
        const uint8_t entries = b[0];
        for (uint8_t e = 1; e <= entries; ++e) {
            auto x = sdo_.upload(pdo, e, b);
            if (!x) return x.error();
            bits += b[0];  // low byte of index<<16 | sub<<8 | bit length
        }
    }
    bytes = static_cast<uint16_t>((bits + 7) / 8);
    return Error::Ok;
}

Error ProcessDataSession::discover() {
    // SM2/SM3 start and control from the SII SyncM category (41).
    auto img = m_.sii_read_image(slave_);
    if (!img) return img.error();
    const auto& s = *img;
    bool found = false;
    for (std::size_t w = sii::FirstCategory; 2 * w + 4 <= s.size();) {
        const uint16_t type = get16(&s[2 * w]);
        const uint16_t len = get16(&s[2 * w + 2]);
        if (type == sii::CategoryEnd) break;
        const std::size_t data = 2 * w + 4;
        if (type == 41 && data + 2u * len <= s.size()) {
            for (std::size_t k = 0; (k + 1) * 8 <= 2u * len; ++k) {
                const uint8_t* sm = &s[data + 8 * k];
                const uint8_t kind = sm[7];
                if (kind == 3) {
                    layout_.sm2_start = get16(sm);
                    layout_.sm2_control = sm[4];
                    found = true;
                } else if (kind == 4) {
                    layout_.sm3_start = get16(sm);
                    layout_.sm3_control = sm[4];
                    found = true;
                }
            }
        }
        w += 2 + len;
    }
    if (!found) return Error::SiiFormat;
    if (Error e = pdo_bytes(0x1C12, layout_.rx_pdos, layout_.sm2_length); e != Error::Ok) return e;
    if (Error e = pdo_bytes(0x1C13, layout_.tx_pdos, layout_.sm3_length); e != Error::Ok) return e;
    image_.assign(static_cast<std::size_t>(layout_.sm2_length) + layout_.sm3_length, 0);
    return Error::Ok;
}

uint16_t ProcessDataSession::expected_wkc() const {
    return static_cast<uint16_t>((layout_.sm2_length ? 2 : 0) + (layout_.sm3_length ? 1 : 0));
}

Error ProcessDataSession::configure(const DcConfig& dc) {
    if (image_.empty() && layout_.sm2_length + layout_.sm3_length == 0) return Error::InvalidArgument;
    // Sync mode first: the slave checks it against 0x0981 on PREOP -> SAFEOP.
    const uint8_t mode_out[2] = {static_cast<uint8_t>(dc.enable ? 2 : 1), 0};
    if (Error e = sdo_.download(0x1C32, 1, mode_out); e != Error::Ok) return e;
    const uint8_t mode_in[2] = {static_cast<uint8_t>(dc.enable ? 2 : (layout_.sm2_length ? 0x22 : 1)), 0};
    if (Error e = sdo_.download(0x1C33, 1, mode_in); e != Error::Ok) {
        const uint8_t plain[2] = {static_cast<uint8_t>(dc.enable ? 2 : 1), 0};
        if (sdo_.download(0x1C33, 1, plain) != Error::Ok) return e;
    }
    if (dc.enable) {
        uint8_t cyc[4];
        put32(cyc, dc.cycle_ns);
        if (Error e = sdo_.download(0x1C32, 2, cyc); e != Error::Ok) return e;
        (void)sdo_.download(0x1C33, 2, cyc);  // some slaves derive it from 0x1C32 and refuse the write
    }
    // SM2/SM3: disabled first, then start, length, control and activate in one write (ESC datasheet section I
    // §8).
    uint8_t sm[16] = {};
    const uint8_t off[16] = {};
    if (Error e = m_.write(slave_, static_cast<uint16_t>(reg::Sm0 + 16), off); e != Error::Ok) return e;
    put16(sm + 0, layout_.sm2_start);
    put16(sm + 2, layout_.sm2_length);
    sm[4] = layout_.sm2_control;
    sm[6] = layout_.sm2_length ? 1 : 0;
    put16(sm + 8, layout_.sm3_start);
    put16(sm + 10, layout_.sm3_length);
    sm[12] = layout_.sm3_control;
    sm[14] = layout_.sm3_length ? 1 : 0;
    if (Error e = m_.write(slave_, static_cast<uint16_t>(reg::Sm0 + 16), sm); e != Error::Ok) return e;
    // FMMU0: outputs (write), FMMU1: inputs (read), logically back to back from kLogicalBase (ESC datasheet
    // section I §7).
    uint8_t fm[32] = {};
    auto fmmu = [](uint8_t* f, uint32_t logical, uint16_t length, uint16_t physical, uint8_t type) {
        put32(f, logical);
        put16(f + 4, length);
        f[6] = 0;
        f[7] = 7;
        put16(f + 8, physical);
        f[10] = 0;
        f[11] = type;
        f[12] = length ? 1 : 0;
    };
    fmmu(fm, kLogicalBase, layout_.sm2_length, layout_.sm2_start, 0x02);
    fmmu(fm + 16, kLogicalBase + layout_.sm2_length, layout_.sm3_length, layout_.sm3_start, 0x01);
    if (Error e = m_.write(slave_, reg::Fmmu0, fm); e != Error::Ok) return e;
    image_.assign(static_cast<std::size_t>(layout_.sm2_length) + layout_.sm3_length, 0);
    lrw_ = Datagram::logical(Command::LRW, kLogicalBase, image_);
    if (dc.enable) return configure_dc(dc);
    // Not DC: SYNC0 left running by an earlier session would contradict sync mode 1 (AL code 0x0030).
    const uint8_t zero2[2] = {};
    if (Error e = m_.write(slave_, esc::reg::kDcCyclicControl, zero2); e != Error::Ok) return e;
    dc_ = false;
    return Error::Ok;
}

Error ProcessDataSession::configure_dc(const DcConfig& dc) {
    // Latch receive times with a broadcast write to 0x0900, read the slave's local time of that frame
    // (0x0918) and make its system time the master's: offset = master time - local time (ESC datasheet
    // section I §9.1). A single slave is the reference clock: propagation delay 0, no drift compensation.
    const uint8_t latch[4] = {};
    const uint64_t master_now = master_system_time();
    auto w = m_.broadcast_write(esc::reg::kDcRecvTime0, latch);
    if (!w) return w.error();
    uint8_t t[8];
    if (Error e = m_.read(slave_, esc::reg::kDcRecvTimePu, t); e != Error::Ok) return e;
    uint8_t off[8];
    put64(off, master_now - get64(t));
    if (Error e = m_.write(slave_, esc::reg::kDcOffset, off); e != Error::Ok) return e;
    const uint8_t zero4[4] = {};
    if (Error e = m_.write(slave_, esc::reg::kDcDelay, zero4); e != Error::Ok) return e;
    uint8_t speed[2];
    if (Error e = m_.read(slave_, esc::reg::kDcSpeedStart, speed); e != Error::Ok) return e;
    if (Error e = m_.write(slave_, esc::reg::kDcSpeedStart, speed); e != Error::Ok)
        return e;  // resets the filters
    // SYNC0: deactivate, cycle time, start time on the cycle grid in the near future, activate.
    const uint8_t zero2[2] = {};
    if (Error e = m_.write(slave_, esc::reg::kDcCyclicControl, zero2); e != Error::Ok) return e;
    uint8_t cyc[4];
    put32(cyc, dc.cycle_ns);
    if (Error e = m_.write(slave_, esc::reg::kDcSync0Cycle, cyc); e != Error::Ok) return e;
    uint8_t now[8];
    if (Error e = m_.read(slave_, reg::DcSystemTime, now); e != Error::Ok) return e;
    const uint64_t delay = static_cast<uint64_t>(std::chrono::nanoseconds(dc.start_delay).count());
    uint64_t start = get64(now) + delay;
    if (dc.cycle_ns) start = (start / dc.cycle_ns + 1) * dc.cycle_ns;
    start = static_cast<uint64_t>(static_cast<int64_t>(start) + dc.shift_ns);
    uint8_t st[8];
    put64(st, start);
    if (Error e = m_.write(slave_, esc::reg::kDcStartTime, st); e != Error::Ok) return e;
    uint8_t aa[2];
    put16(aa, dc.assign_activate);
    if (Error e = m_.write(slave_, esc::reg::kDcCyclicControl, aa); e != Error::Ok) return e;
    // From now on every cycle carries an FRMW of the reference clock's system time.
    dg_[1] = Datagram{Command::FRMW, slave_.value, reg::DcSystemTime, time_};
    dc_ = slave_.mode == Address::Mode::Station;
    return Error::Ok;
}

Error ProcessDataSession::cycle() {
    if (image_.empty()) return Error::InvalidArgument;
    const auto t0 = Clock::now();
    const Error e = m_.exchange(std::span<Datagram>(dg_, dc_ ? 2 : 1), 0);
    ++stats_.cycles;
    if (e == Error::Timeout) {
        ++stats_.lost;
        return e;
    }
    if (e != Error::Ok) return e;
    const auto rtt = std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - t0);
    stats_.rtt_min = std::min(stats_.rtt_min, rtt);
    stats_.rtt_max = std::max(stats_.rtt_max, rtt);
    stats_.rtt_sum += rtt;
    if (dc_) ref_time_ = get64(time_.data());
    if (lrw_.wkc != expected_wkc()) {
        ++stats_.wkc_errors;
        return Error::WorkingCounter;
    }
    return Error::Ok;
}

Error ProcessDataSession::run(uint64_t count, std::chrono::microseconds period,
                              const std::function<void()>& each_cycle) {
    auto next = Clock::now();
    Error first = Error::Ok;
    for (uint64_t i = 0; i < count; ++i) {
        if (each_cycle) each_cycle();
        const Error e = cycle();
        if (e != Error::Ok && first == Error::Ok) first = e;
        next += period;
        sleep_until(next);
    }
    return first;
}

Error ProcessDataSession::request_state(AlState state, std::chrono::microseconds period, AlStatus* final,
                                        const std::function<void()>& each_cycle) {
    const auto deadline = Clock::now() + m_.options().al_timeout;
    auto st = m_.al_status(slave_);
    if (!st) return st.error();
    if (st->error) {
        if (Error e = m_.write_reg<uint16_t>(slave_, reg::AlControl,
                                             static_cast<uint16_t>(st->state | kAlErrorAck));
            e != Error::Ok)
            return e;
    }
    if (Error e = m_.write_reg<uint16_t>(slave_, reg::AlControl, static_cast<uint8_t>(state)); e != Error::Ok)
        return e;
    auto next = Clock::now();
    const auto poll_every =
        std::max<int64_t>(1, std::chrono::milliseconds(5) / std::max(period, std::chrono::microseconds(1)));
    for (int64_t i = 0;; ++i) {
        if (each_cycle) each_cycle();
        (void)cycle();
        if (i % poll_every == 0) {
            st = m_.al_status(slave_);
            if (!st) return st.error();
            if (final) *final = *st;
            if (st->error) {
                (void)m_.write_reg<uint16_t>(slave_, reg::AlControl,
                                             static_cast<uint16_t>(st->state | kAlErrorAck));
                return Error::AlRefused;
            }
            if (st->state == static_cast<uint8_t>(state)) return Error::Ok;
            if (Clock::now() >= deadline) return Error::AlTimeout;
        }
        next += period;
        sleep_until(next);
    }
}

}  // namespace master
