// Cyclic process data with one slave or a line of them: layout discovery, SM/FMMU set-up, DC/SYNC0, LRW
// cycles.
#include "master/session.hpp"

#include <algorithm>
#include <array>
#include <iterator>
#include <optional>
#include <thread>
#include <utility>

#include "util/le.hpp"

namespace master {

using Clock = std::chrono::steady_clock;

namespace {
using util::get16;
using util::get64;
using util::put16;
using util::put32;
using util::put64;
void sleep_until(Clock::time_point t) {
    std::this_thread::sleep_until(t);
}
// Room for the LRW of one frame when the FRMW of DC (8 bytes) rides along.
constexpr std::size_t kMaxChunk = kMaxDatagramData - (kDatagramOverhead + 8);
// AL status reads per frame in read_states(): 6 bytes (0x0130..0x0135) each.
constexpr std::size_t kStatesPerFrame = 60;
bool overlaps(uint32_t a, uint32_t a_len, uint32_t b, uint32_t b_len) {
    return a_len && b_len && a < b + b_len && b < a + a_len;
}
}  // namespace

ProcessDataSession::ProcessDataSession(Master& master, Address slave, SdoClient& sdo) : m_(master) {
    slaves_.push_back(Slave{slave, &sdo, {}, 0, 0});
}

ProcessDataSession::ProcessDataSession(Master& master, std::span<const Address> slaves,
                                       std::span<SdoClient* const> sdos)
    : m_(master) {
    for (std::size_t k = 0; k < slaves.size(); ++k)
        slaves_.push_back(Slave{slaves[k], k < sdos.size() ? sdos[k] : nullptr, {}, 0, 0});
}

Error ProcessDataSession::pdo_bytes(SdoClient& sdo, uint16_t assign_index, std::vector<uint16_t>& pdos,
                                    uint16_t& bytes) {
    pdos.clear();
    uint32_t bits = 0;
    uint8_t b[4] = {};
    auto n = sdo.upload(assign_index, 0, b);
    if (!n) return n.error();
    const uint8_t count = b[0];
    for (uint8_t i = 1; i <= count; ++i) {
        auto r = sdo.upload(assign_index, i, b);
        if (!r) return r.error();
        const uint16_t pdo = get16(b);
        pdos.push_back(pdo);
        auto c = sdo.upload(pdo, 0, b);
        if (!c) return c.error();
        const uint8_t entries = b[0];
        for (uint8_t e = 1; e <= entries; ++e) {
            auto x = sdo.upload(pdo, e, b);
            if (!x) return x.error();
            bits += b[0];  // low byte of index<<16 | sub<<8 | bit length
        }
    }
    bytes = static_cast<uint16_t>((bits + 7) / 8);
    return Error::Ok;
}

Error ProcessDataSession::discover() {
    for (Slave& s : slaves_) {
        if (!s.sdo) continue;  // its layout comes from set_layout()
        if (Error e = discover(s); e != Error::Ok) return e;
    }
    return Error::Ok;
}

namespace {

// The SII's process-data SMs (SyncM category 41, ETG.1000.6: per SM 8 bytes, start, default length, control,
// status, enable, type): every SM of type 3 (outputs) and 4 (inputs), in SM order. With `pdos`, each one's
// PDOs and bytes from the TxPDO (50) / RxPDO (51) categories (per PDO 8 bytes: index, entries, SM, ...; then
// 8 per entry, bit length at byte 5): an RxPDO counts for an outputs SM, a TxPDO for an inputs SM.
std::vector<ProcessDataSm> sii_sms(const std::vector<uint8_t>& s, bool pdos) {
    std::vector<ProcessDataSm> sms;
    std::vector<uint32_t> bits;
    for (int pass = 0; pass < 2; ++pass) {  // SMs first: the PDO categories refer to their indices
        for (std::size_t w = sii::FirstCategory; 2 * w + 4 <= s.size();) {
            const uint16_t type = get16(&s[2 * w]);
            const uint16_t len = get16(&s[2 * w + 2]);
            if (type == sii::CategoryEnd) break;
            const std::size_t data = 2 * w + 4;
            const std::size_t end = std::min<std::size_t>(data + 2u * len, s.size());
            if (pass == 0 && type == 41) {
                for (std::size_t k = 0; data + (k + 1) * 8 <= end && k < 16; ++k) {
                    const uint8_t* sm = &s[data + 8 * k];
                    if (sm[7] != 3 && sm[7] != 4) continue;
                    sms.push_back(
                        ProcessDataSm{static_cast<uint8_t>(k), sm[7] == 3, get16(sm), 0, sm[4], {}});
                }
                bits.assign(sms.size(), 0);
            } else if (pass == 1 && pdos && (type == 50 || type == 51)) {
                for (std::size_t p = data; p + 8 <= end;) {
                    const uint16_t index = get16(&s[p]);
                    const uint8_t entries = s[p + 2];
                    const uint8_t n = s[p + 3];
                    uint32_t pdo_bits = 0;
                    std::size_t q = p + 8;
                    for (uint8_t e = 0; e < entries && q + 8 <= end; ++e, q += 8)
                        pdo_bits += s[q + 5];
                    for (std::size_t i = 0; i < sms.size(); ++i)
                        if (sms[i].index == n && sms[i].outputs == (type == 51)) {
                            bits[i] += pdo_bits;
                            sms[i].pdos.push_back(index);
                        }
                    p = q;
                }
            }
            w += 2 + len;
        }
    }
    for (std::size_t i = 0; i < sms.size(); ++i)
        sms[i].length = static_cast<uint16_t>((bits[i] + 7) / 8);
    return sms;
}

}  // namespace

Error ProcessDataSession::discover(Slave& slave) {
    // The process-data SMs from the SII, the PDOs of each from its assignment object 0x1C10 + n (ETG.1000.6).
    // An SM whose assignment object the device does not have (abort 0x06020000 object, 0x06090011 subindex
    // does not exist: a device with fixed PDOs need not have it) keeps the PDOs its SII assigns to it. No
    // process-data SM at all (a device with a mailbox only, e.g. an EoE switch port): no process data, as for
    // a coupler without mailbox.
    auto img = m_.sii_read_image(slave.address);
    if (!img) return img.error();
    std::vector<ProcessDataSm> sms = sii_sms(*img, true);
    for (ProcessDataSm& sm : sms) {
        std::vector<uint16_t> pdos;
        uint16_t bytes = 0;
        const Error e = pdo_bytes(*slave.sdo, static_cast<uint16_t>(0x1C10 + sm.index), pdos, bytes);
        if (e == Error::SdoAbort &&
            (slave.sdo->last_abort() == 0x06020000 || slave.sdo->last_abort() == 0x06090011))
            continue;
        if (e != Error::Ok) return e;
        sm.pdos = std::move(pdos);
        sm.length = bytes;
    }
    slave.layout.sms = std::move(sms);
    return Error::Ok;
}

Error ProcessDataSession::discover_sii(std::size_t k) {
    Slave& slave = slaves_.at(k);
    auto img = m_.sii_read_image(slave.address);
    if (!img) return img.error();
    slave.layout.sms = sii_sms(*img, true);  // none (a coupler): no process data
    return Error::Ok;
}

std::span<uint8_t> ProcessDataSession::outputs(std::size_t k) {
    const Slave& s = slaves_[k];
    if (image_.empty()) return {};
    return {image_.data() + s.out_offset, s.layout.output_bytes()};
}

std::span<const uint8_t> ProcessDataSession::inputs(std::size_t k) const {
    const Slave& s = slaves_[k];
    if (image_.empty()) return {};
    return {image_.data() + out_bytes_ + s.in_offset, s.layout.input_bytes()};
}

uint16_t ProcessDataSession::expected_wkc(std::size_t k) const {
    const ProcessDataLayout& l = slaves_[k].layout;
    return static_cast<uint16_t>((l.output_bytes() ? 2 : 0) + (l.input_bytes() ? 1 : 0));
}

uint16_t ProcessDataSession::expected_wkc() const {
    uint16_t sum = 0;
    if (!chunks_.empty()) {  // a slave split over two frames counts in both
        for (const Chunk& c : chunks_)
            sum = static_cast<uint16_t>(sum + c.expected_wkc);
        return sum;
    }
    for (std::size_t k = 0; k < slaves_.size(); ++k)
        sum = static_cast<uint16_t>(sum + expected_wkc(k));
    return sum;
}

Error ProcessDataSession::configure(const DcConfig& dc) {
    if (slaves_.empty()) return Error::InvalidArgument;
    // The image: every slave's outputs back to back, then every slave's inputs.
    out_bytes_ = in_bytes_ = 0;
    for (Slave& s : slaves_) {
        s.out_offset = out_bytes_;
        s.in_offset = in_bytes_;
        out_bytes_ += s.layout.output_bytes();
        in_bytes_ += s.layout.input_bytes();
    }
    if (out_bytes_ + in_bytes_ == 0) return Error::InvalidArgument;
    if (Error e = check_fmmus(); e != Error::Ok) return e;
    for (Slave& s : slaves_)
        if (Error e = configure(s, dc); e != Error::Ok) return e;
    image_.assign(static_cast<std::size_t>(out_bytes_) + in_bytes_, 0);
    // One LRW per frame, as many frames as the image needs, split where one slave's outputs or inputs end
    // (so that each slave counts once); each frame knows its share of the working counter.
    std::vector<std::size_t> ends;
    for (const Slave& s : slaves_) {
        ends.push_back(s.out_offset + s.layout.output_bytes());
        ends.push_back(out_bytes_ + s.in_offset + s.layout.input_bytes());
    }
    std::sort(ends.begin(), ends.end());
    chunks_.clear();
    for (std::size_t at = 0, len = 0; at < image_.size(); at += len) {
        len = std::min(kMaxChunk, image_.size() - at);
        if (at + len < image_.size()) {
            auto it = std::upper_bound(ends.begin(), ends.end(), at + len);
            if (it != ends.begin() && *std::prev(it) > at) len = *std::prev(it) - at;
        }
        Chunk c;
        const uint32_t pos = static_cast<uint32_t>(at);
        c.dg[0] =
            Datagram::logical(Command::LRW, kLogicalBase + pos, std::span<uint8_t>(image_.data() + at, len));
        for (const Slave& s : slaves_) {
            if (overlaps(pos, static_cast<uint32_t>(len), s.out_offset, s.layout.output_bytes()))
                c.expected_wkc += 2;
            if (overlaps(pos, static_cast<uint32_t>(len), out_bytes_ + s.in_offset, s.layout.input_bytes()))
                c.expected_wkc += 1;
        }
        chunks_.push_back(c);
    }
    frames_.clear();
    for (Chunk& c : chunks_)
        frames_.emplace_back(c.dg, c.count);
    states_.assign(slaves_.size(), AlStatus{});
    state_buf_.assign(kStatesPerFrame * 6, 0);
    if (dc.enable) return configure_dc(dc);
    // Not DC: SYNC0 left running by an earlier session would contradict sync mode 1 (AL code 0x0030).
    const uint8_t zero2[2] = {};
    for (const Slave& s : slaves_)
        if (Error e = m_.write(s.address, esc::reg::kDcCyclicControl, zero2); e != Error::Ok) return e;
    dc_ = false;
    return Error::Ok;
}

Error ProcessDataSession::configure(Slave& slave, const DcConfig& dc) {
    const ProcessDataLayout& layout = slave.layout;
    const Address a = slave.address;
    if (SdoClient* sdo = slave.sdo) {
        // Sync mode first: the slave checks it against 0x0981 on PREOP -> SAFEOP. A slave without 0x1C32
        // (an input terminal has only 0x1C33, a simple one neither: ETG.1020 makes them optional) runs in
        // the mode its SMs and 0x0981 give.
        const auto absent = [sdo](Error e) {
            return e == Error::SdoAbort &&
                   (sdo->last_abort() == 0x06020000 || sdo->last_abort() == 0x06090011);
        };
        // A sync mode the device declares read-only (ETG.1020: RW only if more than one synchronisation type
        // is supported; 0x1C33:01 often follows 0x1C32:01) is refused with 0x06010002: the device runs the
        // one mode it has, and the state transition judges it, as for an absent object.
        const auto fixed = [sdo](Error e) { return e == Error::SdoAbort && sdo->last_abort() == 0x06010002; };
        // A type the device does not announce in :04 may be refused at the write with 0x06090030 (value range
        // exceeded, as the SSC's CheckSyncTypeValue does): the device then runs the mode its SMs and 0x0981
        // give, and PREOP -> SAFEOP judges that, as for a read-only sync type.
        const auto not_taken = [sdo, &fixed](Error e) {
            return fixed(e) || (e == Error::SdoAbort && sdo->last_abort() == 0x06090030);
        };
        // The supported types: 0x1C32:04, else (a device with inputs only) 0x1C33:04.
        const auto supported = [sdo]() -> std::optional<uint8_t> {
            uint8_t sup[2] = {};
            for (const uint16_t index : {uint16_t{0x1C32}, uint16_t{0x1C33}})
                if (auto n = sdo->upload(index, 4, sup); n && *n == 2) return sup[0];
            return std::nullopt;
        };
        // DC SYNC1 (3) for an op mode that activates SYNC1 on a device that announces DC SYNC1 but not SYNC0
        // (0x1C32:04 bit 3 without bit 2, ETG.1020: Beckhoff's EL15xx/EJ7xxx op modes with AssignActivate
        // 0x0700), else DC SYNC0 (2).
        uint8_t dc_mode = 2;
        if (dc.enable && (dc.assign_activate & 0x0400)) {
            if (auto sup = supported(); sup && (*sup & 0x0C) == 0x08) dc_mode = 3;
        }
        // Without DC: synchronous with the SM event (1), unless 0x1C32:04 announces free run (bit 0) and not
        // the SM-synchronous mode (bit 1; ETG.1020 supported synchronization types), as a coupler that runs
        // free or in DC does (Weidmueller's UR20: 0x0005): then free run (0), which it takes.
        bool free_run = false;
        if (!dc.enable) {
            if (auto sup = supported(); sup && (*sup & 0x03) == 0x01) free_run = true;
        }
        const uint8_t sm_mode = free_run ? 0 : 1;
        const uint8_t mode_out[2] = {static_cast<uint8_t>(dc.enable ? dc_mode : sm_mode), 0};
        if (Error e = sdo->download(0x1C32, 1, mode_out); e != Error::Ok && !absent(e) && !not_taken(e))
            return e;
        const uint8_t mode_in[2] = {static_cast<uint8_t>(dc.enable  ? dc_mode
                                                         : free_run ? 0
                                                                    : (layout.output_bytes() ? 0x22 : 1)),
                                    0};
        if (Error e = sdo->download(0x1C33, 1, mode_in); e != Error::Ok && !absent(e) && !fixed(e)) {
            const uint8_t plain[2] = {static_cast<uint8_t>(dc.enable ? dc_mode : sm_mode), 0};
            if (Error e2 = sdo->download(0x1C33, 1, plain); e2 != Error::Ok && !not_taken(e2)) return e;
        }
        if (dc.enable) {
            uint8_t cyc[4];
            put32(cyc, dc.cycle_ns);
            // A read-only cycle time (the ESI's access; the slave takes it from SYNC0) is not an error.
            if (Error e = sdo->download(0x1C32, 2, cyc); e != Error::Ok && !absent(e) && !fixed(e)) return e;
            (void)sdo->download(0x1C33, 2, cyc);  // some slaves derive it from 0x1C32 and refuse the write
        }
    }
    // Every process-data SM: disabled first, then start, length, control and activate in one write (ESC
    // datasheet section I §8); one carrying nothing stays disabled.
    const uint8_t off[8] = {};
    for (const ProcessDataSm& sm : layout.sms) {
        if (sm.index >= 16) continue;
        uint8_t r[8] = {};
        put16(r + 0, sm.start);
        put16(r + 2, sm.length);
        r[4] = sm.control;
        r[6] = sm.length ? 1 : 0;
        const auto base = static_cast<uint16_t>(reg::Sm0 + 8 * sm.index);
        if (Error e = m_.write(a, base, off); e != Error::Ok) return e;
        if (Error e = m_.write(a, base, r); e != Error::Ok) return e;
    }
    // The FMMUs of layout.fmmus() from FMMU0 on: the outputs ones (write) at this slave's place among the
    // outputs, the inputs ones (read) among the inputs; the slave's other FMMUs disabled (ESC datasheet
    // section I §7). check_fmmus() made sure there are enough.
    std::array<uint8_t, 16 * 16> fm{};
    std::size_t used = 0;
    for (const ProcessDataLayout::Fmmu& x : layout.fmmus()) {
        if (used == 16) break;
        uint8_t* f = fm.data() + 16 * used++;
        put32(f, kLogicalBase + (x.outputs ? slave.out_offset : out_bytes_ + slave.in_offset) + x.offset);
        put16(f + 4, x.length);
        f[6] = 0;
        f[7] = 7;
        put16(f + 8, x.physical);
        f[10] = 0;
        f[11] = x.outputs ? 0x02 : 0x01;
        f[12] = 1;
    }
    const std::size_t count = std::min<std::size_t>(slave.fmmus, 16);
    return m_.write(a, reg::Fmmu0, std::span<const uint8_t>(fm.data(), 16 * count));
}

// Every slave's FMMU count (ESC 0x0004) against the FMMUs its layout needs, before any is configured: a
// slave with too few cannot map its image and is not set up half.
Error ProcessDataSession::check_fmmus() {
    for (Slave& s : slaves_) {
        auto n = m_.read_reg<uint8_t>(s.address, 0x0004);
        if (!n) return n.error();
        s.fmmus = *n;
        if (s.layout.fmmus().size() > std::min<std::size_t>(*n, 16)) return Error::TooFewFmmus;
    }
    return Error::Ok;
}

Error ProcessDataSession::configure_dc(const DcConfig& dc) {
    // Delays and offsets (bus.hpp): the first DC slave is the reference clock, its system time the master's.
    reference_ = slaves_.front().address.value;
    if (dc.measure) {
        dc_slaves_.clear();
        for (std::size_t k = 0; k < slaves_.size(); ++k) {
            SlaveInfo info;
            info.position = static_cast<uint16_t>(k);
            info.station = slaves_[k].address.value;
            auto features = m_.read_reg<uint16_t>(slaves_[k].address, 0x0008);
            if (!features) return features.error();
            info.has_dc = (*features & 0x0004) != 0;
            dc_slaves_.push_back(info);
        }
        if (Error e = read_ports(m_, dc_slaves_); e != Error::Ok) return e;
        if (Error e = master::configure_dc(m_, dc_slaves_, dc.measure_options); e != Error::Ok) return e;
        const int ref = reference_clock(dc_slaves_);
        if (ref < 0) return Error::InvalidArgument;
        reference_ = dc_slaves_[static_cast<std::size_t>(ref)].station;
    }
    // SYNC0 on every slave: deactivate, cycle time; then one start time on the cycle grid in the near future
    // (the reference clock's system time, which all others now share), and activate.
    const uint8_t zero2[2] = {};
    uint8_t cyc[4];
    put32(cyc, dc.cycle_ns);
    for (const Slave& s : slaves_) {
        if (Error e = m_.write(s.address, esc::reg::kDcCyclicControl, zero2); e != Error::Ok) return e;
        if (Error e = m_.write(s.address, esc::reg::kDcSync0Cycle, cyc); e != Error::Ok) return e;
    }
    uint8_t now[8];
    if (Error e = m_.read(Address::station(reference_), reg::DcSystemTime, now); e != Error::Ok) return e;
    const uint64_t delay = static_cast<uint64_t>(std::chrono::nanoseconds(dc.start_delay).count());
    uint64_t start = get64(now) + delay;
    if (dc.cycle_ns) start = (start / dc.cycle_ns + 1) * dc.cycle_ns;
    start = static_cast<uint64_t>(static_cast<int64_t>(start) + dc.shift_ns);
    uint8_t st[8];
    put64(st, start);
    uint8_t aa[2];
    put16(aa, dc.assign_activate);
    for (const Slave& s : slaves_) {
        if (Error e = m_.write(s.address, esc::reg::kDcStartTime, st); e != Error::Ok) return e;
        if (Error e = m_.write(s.address, esc::reg::kDcCyclicControl, aa); e != Error::Ok) return e;
    }
    // From now on every cycle carries an FRMW of the reference clock's system time (in its first frame).
    dc_ = true;
    for (const Slave& s : slaves_)
        if (s.address.mode != Address::Mode::Station) dc_ = false;
    if (dc_ && !chunks_.empty()) {
        chunks_.front().dg[1] = Datagram{Command::FRMW, reference_, reg::DcSystemTime, time_};
        chunks_.front().count = 2;
        frames_.front() = std::span<Datagram>(chunks_.front().dg, 2);
    }
    return Error::Ok;
}

Error ProcessDataSession::cycle() {
    if (image_.empty()) return Error::InvalidArgument;
    const auto t0 = Clock::now();
    if (stats_.cycles > 0)
        stats_.gap_max = std::max(
            stats_.gap_max, std::chrono::duration_cast<std::chrono::nanoseconds>(t0 - last_cycle_start_));
    last_cycle_start_ = t0;
    ++stats_.cycles;
    for (Chunk& c : chunks_)
        c.dg[0].wkc = 0;  // a frame that does not come back counts nothing
    const Error e = m_.exchange_frames(frames_);
    if (e != Error::Ok && e != Error::Timeout) return e;
    const bool lost = e == Error::Timeout;
    uint16_t wkc = 0;
    for (const Chunk& c : chunks_)
        wkc = static_cast<uint16_t>(wkc + c.dg[0].wkc);
    if (!lost && chunks_.front().count == 2) ref_time_ = get64(time_.data());
    last_wkc_ = wkc;
    if (lost) {
        ++stats_.lost;
        return Error::Timeout;
    }
    const auto rtt = std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - t0);
    stats_.rtt_min = std::min(stats_.rtt_min, rtt);
    stats_.rtt_max = std::max(stats_.rtt_max, rtt);
    stats_.rtt_sum += rtt;
    if (wkc != expected_wkc()) {
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

Error ProcessDataSession::read_states(std::span<AlStatus> out) {
    if (out.size() < slaves_.size()) return Error::InvalidArgument;
    if (state_buf_.size() < kStatesPerFrame * 6) state_buf_.assign(kStatesPerFrame * 6, 0);
    std::array<Datagram, kStatesPerFrame> dg;
    for (std::size_t first = 0; first < slaves_.size(); first += kStatesPerFrame) {
        const std::size_t n = std::min(kStatesPerFrame, slaves_.size() - first);
        std::fill(state_buf_.begin(), state_buf_.end(), 0);
        for (std::size_t i = 0; i < n; ++i)
            dg[i] = Master::addressed(slaves_[first + i].address, false, reg::AlStatus,
                                      std::span<uint8_t>(state_buf_.data() + 6 * i, 6));
        if (Error e = m_.exchange(std::span<Datagram>(dg.data(), n)); e != Error::Ok) return e;
        for (std::size_t i = 0; i < n; ++i) {
            const uint8_t* b = state_buf_.data() + 6 * i;
            AlStatus s;
            if (dg[i].wkc == 1) {
                s.state = b[0] & 0x0F;
                s.error = (b[0] & kAlErrorAck) != 0;
                s.id_loaded = (b[0] & kAlIdentify) != 0;
                s.code = get16(b + 4);
            }
            out[first + i] = s;
        }
    }
    return Error::Ok;
}

// AL control of the session's slaves: one slave by its address, several with one BWR (every slave on the
// line, as a master bringing up its whole line does).
Error ProcessDataSession::write_al_control(AlState state, bool acknowledge, uint8_t current) {
    if (slaves_.size() == 1) {
        const uint16_t v =
            acknowledge ? static_cast<uint16_t>(current | kAlErrorAck) : static_cast<uint8_t>(state);
        return m_.write_reg<uint16_t>(slaves_.front().address, reg::AlControl, v);
    }
    const uint8_t v[2] = {static_cast<uint8_t>(state), 0};
    auto w = m_.broadcast_write(reg::AlControl, v);
    if (!w) return w.error();
    return *w == 0 ? Error::WorkingCounter : Error::Ok;
}

Error ProcessDataSession::states_reached(AlState state, AlStatus* final, bool& done) {
    done = false;
    if (Error e = read_states(states_); e != Error::Ok) return e;
    if (slaves_.size() == 1 && states_.front().state == 0) return Error::WorkingCounter;  // it did not answer
    bool all = true;
    for (std::size_t k = 0; k < slaves_.size(); ++k) {
        const AlStatus& st = states_[k];
        if (st.error) {
            if (final) *final = st;
            (void)m_.write_reg<uint16_t>(slaves_[k].address, reg::AlControl,
                                         static_cast<uint16_t>(st.state | kAlErrorAck));
            return Error::AlRefused;
        }
        if (st.state != static_cast<uint8_t>(state)) {
            if (all && final) *final = st;
            all = false;
        }
    }
    if (all && final && !slaves_.empty()) *final = states_.front();
    done = all;
    return Error::Ok;
}

Error ProcessDataSession::request_state(AlState state, std::chrono::microseconds period, AlStatus* final,
                                        const std::function<void()>& each_cycle) {
    const auto deadline = Clock::now() + m_.options().al_timeout;
    if (states_.size() != slaves_.size()) states_.assign(slaves_.size(), AlStatus{});
    if (Error e = read_states(states_); e != Error::Ok) return e;
    for (std::size_t k = 0; k < slaves_.size(); ++k) {
        if (!states_[k].error) continue;
        if (Error e = m_.write_reg<uint16_t>(slaves_[k].address, reg::AlControl,
                                             static_cast<uint16_t>(states_[k].state | kAlErrorAck));
            e != Error::Ok)
            return e;
    }
    if (Error e = write_al_control(state, false, 0); e != Error::Ok) return e;
    auto next = Clock::now();
    const auto poll_every =
        std::max<int64_t>(1, std::chrono::milliseconds(5) / std::max(period, std::chrono::microseconds(1)));
    for (int64_t i = 0;; ++i) {
        if (each_cycle) each_cycle();
        (void)cycle();
        if (i % poll_every == 0) {
            bool done = false;
            if (Error e = states_reached(state, final, done); e != Error::Ok) return e;
            if (done) return Error::Ok;
            if (Clock::now() >= deadline) return Error::AlTimeout;
        }
        next += period;
        sleep_until(next);
    }
}

}  // namespace master
