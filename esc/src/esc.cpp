// The emulated ESC: construction, reset values, the public API and frame / datagram processing.
#include <algorithm>
#include <cstring>
#include <memory>
#include <mutex>

#include "esc/wire/datagram.hpp"
#include "esc_impl.hpp"
#include "prefetch.hpp"
#include "util/le.hpp"

namespace esc {

namespace {

using util::get16;
using util::put16;

// Error counters (ESC datasheet section II, 0x0300-0x0313), per port p.
constexpr uint16_t invalid_frame_counter(int p) {
    return static_cast<uint16_t>(0x0300 + 2 * p);
}
constexpr uint16_t rx_error_counter(int p) {
    return static_cast<uint16_t>(0x0301 + 2 * p);
}
constexpr uint16_t forwarded_rx_error_counter(int p) {
    return static_cast<uint16_t>(0x0308 + p);
}

// The first datagram's length word (bit 14: circulating frame, ETG.1000.4) of an EtherCAT frame (type 1),
// nullptr if the frame has none.
uint8_t* first_length_word(std::span<uint8_t> frame) {
    const wire::EcatLocation loc = wire::locate_ecat(frame);
    const std::size_t word = loc.header + 2 + 6;  // EtherCAT header, then the datagram's cmd/idx/adp/ado
    if (!loc.found || frame.size() < word + 2 || (get16(frame.data() + loc.header) >> 12) != 1)
        return nullptr;
    return frame.data() + word;
}

}  // namespace

// ==================================================================================================
// Construction and reset
// ==================================================================================================

namespace {
EscConfig clamped(EscConfig c) {
    c.process_ram_kib = std::min<uint32_t>(c.process_ram_kib, 60);  // RAM must end below 0x10000
    c.fmmu_count = std::min<uint8_t>(c.fmmu_count, 16);
    c.sm_count = std::min<uint8_t>(c.sm_count, 16);
    return c;
}
}  // namespace

Esc::Impl::Impl(const EscConfig& c, const Clock& clk) : cfg(clamped(c)), mem(cfg.process_ram_kib), time(clk) {
    reset_registers();
    sii.load_words(true);
}

const Esc::Impl::RegTables& Esc::Impl::register_tables(uint8_t fmmu_count, uint8_t sm_count) {
    // Built on first use for each pair of counts (at most 17 x 17 after clamping), kept for the process.
    static std::mutex mu;
    static std::array<std::unique_ptr<RegTables>, 17 * 17> built;
    std::lock_guard lock(mu);
    std::unique_ptr<RegTables>& t = built[static_cast<std::size_t>(fmmu_count) * 17 + sm_count];
    if (!t) {
        t = std::make_unique<RegTables>();
        init_tables(*t, fmmu_count, sm_count);
    }
    return *t;
}

void Esc::Impl::init_tables(RegTables& t, uint8_t fmmu_count, uint8_t sm_count) {
    auto ecat = [&](uint16_t a, unsigned n, uint8_t kind, uint8_t mask = 0xFF) {
        for (unsigned i = 0; i < n; ++i) {
            t.ecat_kind[a + i] = kind;
            t.ecat_wmask[a + i] = mask;
        }
    };
    auto pdi = [&](uint16_t a, unsigned n, uint8_t kind, uint8_t mask = 0xFF) {
        for (unsigned i = 0; i < n; ++i) {
            t.pdi_kind[a + i] = kind;
            t.pdi_wmask[a + i] = mask;
        }
    };
    // ECAT side.
    ecat(reg::kStationAddress, 2, kPlain);
    ecat(reg::kRegWriteEnable, 1, kSpecial, 0x01);
    ecat(reg::kRegWriteProtect, 1, kPlain, 0x01);
    ecat(reg::kEscWriteEnable, 1, kSpecial, 0x01);
    ecat(reg::kEscWriteProtect, 1, kPlain, 0x01);
    ecat(reg::kEscResetEcat, 1, kSpecial);
    ecat(reg::kDlControl, 1, kPlain);
    ecat(kDlControlLoop, 1, kSpecial);  // loop settings: the port unit recomputes the loops
    ecat(0x0102, 2, kPlain);
    ecat(0x0108, 2, kPlain);  // physical read/write offset (stored, not applied: see decisions)
    ecat(reg::kAlControl, 2, kSpecial);
    ecat(reg::kEcatEventMask, 2, kPlain);
    ecat(0x0300, 0x14, kSpecial);  // error counters: any write clears
    ecat(reg::kWdDivider, 2, kPlain);
    ecat(reg::kWdTimePdi, 2, kPlain);
    ecat(reg::kWdTimePd, 2, kPlain);
    ecat(reg::kWdCounterPd, 2, kSpecial);
    ecat(reg::kSiiConfig, 1, kSpecial);
    ecat(reg::kSiiControl, 2, kSpecial);
    ecat(reg::kSiiAddress, 12, kSpecial);  // address + data: blocked while busy / PDI owns the interface
    ecat(0x0510, 1, kPlain, 0x01);         // MII: inert, stored
    ecat(0x0512, 4, kPlain);
    ecat(0x0516, 1, kPlain, 0x01);
    for (unsigned n = 0; n < fmmu_count; ++n)
        ecat(static_cast<uint16_t>(reg::kFmmu + 16 * n), 13, kSpecial);
    for (unsigned n = 0; n < sm_count; ++n) {
        uint16_t b = static_cast<uint16_t>(reg::kSm + 8 * n);
        ecat(b, 5, kSpecial);
        ecat(static_cast<uint16_t>(b + 6), 1, kSpecial);
    }
    ecat(reg::kDcRecvTime0, 4, kSpecial);
    ecat(reg::kDcSystemTime, 8, kSpecial);
    ecat(reg::kDcOffset, 12, kPlain);
    ecat(reg::kDcSpeedStart, 2, kSpecial);
    ecat(reg::kDcFilterDiff, 2, kPlain, 0x0F);
    ecat(reg::kDcCyclicControl, 1, kPlain, 0x31);
    ecat(reg::kDcActivation, 1, kSpecial);
    ecat(reg::kDcStartTime, 8, kSpecial);
    ecat(reg::kDcSync0Cycle, 8, kSpecial);
    ecat(reg::kDcLatch0Control, 2, kSpecial);
    ecat(0x0F00, 4, kPlain);  // digital outputs
    ecat(reg::kUserRam, 0x80, kPlain);

    // PDI side.
    pdi(reg::kStationAlias, 2, kPlain);
    pdi(reg::kEscResetPdi, 1, kSpecial);
    pdi(reg::kAlStatus, 2, kSpecial);
    pdi(reg::kAlStatusCode, 2, kPlain);
    pdi(0x0138, 2, kPlain, 0x1F);
    pdi(reg::kAlEventMask, 4, kPlain);
    pdi(reg::kSiiPdiAccess, 1, kPlain, 0x01);
    pdi(reg::kSiiControl, 14, kSpecial);
    for (unsigned n = 0; n < sm_count; ++n)
        pdi(static_cast<uint16_t>(reg::kSm + 8 * n + 7), 1, kSpecial);
    pdi(reg::kDcActivation, 1, kSpecial);
    pdi(reg::kDcStartTime, 8, kSpecial);
    pdi(reg::kDcSync0Cycle, 8, kSpecial);
    pdi(reg::kDcLatch0Control, 2, kSpecial);
    pdi(reg::kUserRam, 0x80, kPlain);
}

void Esc::Impl::reset_registers() {
    mem.regs.fill(0);
    mem.w8(0x0000, cfg.type);
    mem.w8(0x0001, cfg.revision);
    mem.w16(0x0002, cfg.build);
    mem.w8(0x0004, cfg.fmmu_count);
    mem.w8(0x0005, cfg.sm_count);
    mem.w8(0x0006, static_cast<uint8_t>(cfg.process_ram_kib));
    mem.w8(0x0007, cfg.port_descriptor);
    mem.w16(0x0008, cfg.features);
    // DL control: EtherCAT forwarding rule, every port's loop "auto" (open while it has a link), RX FIFO 7.
    mem.w32(reg::kDlControl, 0x00070001);
    // DL status: PDI watchdog reloaded; bit 0 (EEPROM loaded) is set by the EEPROM load, bits 4-15 (links,
    // loops, communication) by the port unit below. A lone ESC with a link on port 0 only: 0x5612.
    mem.w16(reg::kDlStatus, 0x0002);
    mem.w16(reg::kAlControl, 0x0001);
    mem.w16(reg::kAlStatus, 0x0001);
    mem.w32(reg::kAlEventMask, 0x00FFFF2F);
    mem.w16(reg::kEcatEvent, ecev::kDlStatus);
    mem.w32(reg::kAlEvent, 0);
    mem.w16(reg::kWdDivider, 0x09C2);
    mem.w16(reg::kWdTimePdi, 0x03E8);
    mem.w16(reg::kWdTimePd, 0x03E8);
    mem.w16(reg::kWdStatusPd, 0x0001);
    uint16_t sii_control = 0x0060 | 0x1000;  // emulated EEPROM, 8-byte reads, not loaded yet
    if (sii.image().size() > 2048) sii_control |= 0x0080;
    mem.w16(reg::kSiiControl, sii_control);
    mem.w16(reg::kDcSpeedStart, 0x1000);
    mem.w8(reg::kDcFilterDiff, 4);
    mem.w8(reg::kDcFilterSpeed, 12);

    sm.reset();
    rebuild_lookup();
    dc.reset();
    wd.reset();
    ports.reset();
    reset_progress_ecat = reset_progress_pdi = 0;
}

void Esc::Impl::rebuild_lookup() {
    lookup_dirty = false;
    sm.rebuild();
    fmmu.rebuild();
}

// ==================================================================================================
// Frame processing
// ==================================================================================================

int Esc::Impl::receive(std::span<uint8_t> frame, int port, uint64_t rx_clock, FrameCheck* check) {
    // A frame received at a closed or non-existent port is destroyed.
    if (static_cast<unsigned>(port) >= static_cast<unsigned>(kPortCount) || !ports.loop_open(port)) {
        // A correct frame at an auto-close port waiting with its link back opens it, after the frame.
        if (static_cast<unsigned>(port) < static_cast<unsigned>(kPortCount) && !(check && check->crc_bad))
            ports.valid_frame_at_closed_port(port);
        ++stats.frames_destroyed;
        return -1;
    }
    if (port != 0 && dc.port_latch_armed())
        dc.port_received(port, rx_clock != 0 ? rx_clock : time.clock.now_ns());
    if (check && check->crc_bad) {
        // Forwarded, never processed. The first ESC that sees the bad FCS counts an invalid frame (and the
        // PHY's RX error) and marks the frame; the ones after it count a forwarded RX error.
        ++stats.frames_bad_fcs;
        if (!check->marked) {
            mem.count_error(invalid_frame_counter(port));
            mem.count_error(rx_error_counter(port));
            check->marked = true;
        } else {
            mem.count_error(forwarded_rx_error_counter(port));
        }
        return ports.exit_after(port);
    }
    if (port != 0) {
        if (!ports.via_closed_port0(port))
            return ports.exit_after(port);  // does not pass the processing unit
        // Looped back at the closed port 0 into the processing unit: with port 0 closed by its link state
        // the circulating bit is set on the first pass; a frame that comes by with it already set is
        // destroyed and counted as a processing unit error (ESC datasheet section I, "Circulating frames"
        // and Table 57).
        uint8_t* lw = ports.port0_closed_automatically() ? first_length_word(frame) : nullptr;
        if (lw) {
            if (lw[1] & 0x40) {
                mem.count_error(reg::kProcessingUnitErrors);
                ++stats.frames_destroyed;
                return -1;
            }
            lw[1] = static_cast<uint8_t>(lw[1] | 0x40);
        }
    }
    switch (process(frame, port, rx_clock)) {
        case Outcome::Forward:
            return ports.exit_after(port);
        case Outcome::Error:
            // The ESC aborts the frame with a bad FCS and the marking for forwarded errors: the ESCs after it
            // count a forwarded error, a master's NIC discards it. Without a FrameCheck to carry the marking
            // nobody could receive it: it is gone.
            if (check) {
                check->crc_bad = true;
                check->marked = true;
                return ports.exit_after(port);
            }
            ++stats.frames_destroyed;
            return -1;
        case Outcome::Destroy:
            break;
    }
    ++stats.frames_destroyed;
    return -1;
}

// ESC datasheet section I, "EtherCAT protocol", "UDP/IP", "Frame processing" and Table 57 (errors and their
// counters); docs/decisions/esc.md, "Frame tolerance", lists every rule with its test.
Esc::Impl::Outcome Esc::Impl::process(std::span<uint8_t> frame, int port, uint64_t rx_clock) {
    (void)port;  // every processing unit error counts in 0x030C alone, whatever port the frame came in at
    const std::size_t size = frame.size();
    uint8_t* f = frame.data();
    const wire::EcatLocation loc = wire::locate_ecat(frame);
    if (!loc.found) {
        // DL control 0x0100 bit 0, the forwarding rule: 1 (the reset value) destroys non-EtherCAT frames and
        // counts them as processing unit errors, 0 forwards them unchanged.
        ++stats.frames_ignored;
        if ((mem.r8(reg::kDlControl) & 0x01) == 0 && size >= wire::kEthernetHeaderSize)
            return Outcome::Forward;
        mem.count_error(reg::kProcessingUnitErrors);
        return Outcome::Destroy;
    }
    if (!cfg.faults.source_mac_unchanged)
        f[6] |= 0x02;  // source MAC: locally administered bit, as every ESC sets it
    if (loc.udp_checksum != 0) {
        f[loc.udp_checksum] = 0;  // the ESC changes the payload on the fly: checksum "not used"
        f[loc.udp_checksum + 1] = 0;
    }
    const std::size_t hdr = loc.header;
    if (size < hdr + 2) {
        ++stats.frames_malformed;
        ++stats.malformed_no_header;
        mem.count_error(reg::kProcessingUnitErrors);
        return Outcome::Error;
    }
    const uint16_t h = get16(f + hdr);
    if ((h >> 12) != 1) {
        ++stats.frames_ignored;  // EtherCAT frame of another type: forwarded unprocessed
        return Outcome::Forward;
    }
    // The header's Length is not evaluated. The chain is walked first by the datagrams' own lengths and More
    // bits up to the end of the frame: a frame with a length error is lost to the master (bad FCS) and its
    // register operations are discarded, so none of its datagrams is executed (docs/decisions/esc.md).
    std::size_t p = hdr + 2;
    bool chain_ok = true;
    for (;;) {
        if (p + 12 > size || p + 12 + (get16(f + p + 6) & 0x07FF) > size) {
            chain_ok = false;
            ++stats.malformed_datagram;
            break;
        }
        const uint16_t lf = get16(f + p + 6);
        p += 12u + (lf & 0x07FF);
        if (!(lf & 0x8000)) break;
    }
    if (chain_ok && size - p > wire::kMaxPadding) {
        chain_ok = false;
        ++stats.malformed_length;
    }
    if (!chain_ok) {
        ++stats.frames_malformed;
        mem.count_error(reg::kProcessingUnitErrors);
        return Outcome::Error;
    }

    ++stats.frames_processed;
    time.frame_clock = rx_clock != 0 ? rx_clock : time.clock.now_ns();
    time.frame_local = dc.local_at(time.frame_clock);
    time.in_frame = true;
    p = hdr + 2;
    for (;;) {
        const uint16_t lf = get16(f + p + 6);
        const uint16_t dlen = lf & 0x07FF;
        datagram(f + p, f + p + 10, dlen);
        ++stats.datagrams;
        p += 12u + dlen;
        if (!(lf & 0x8000)) break;
    }
    end_of_frame(true);
    time.in_frame = false;
    return Outcome::Forward;
}

void Esc::Impl::end_of_frame(bool ok) {
    // SyncManager buffer changes of ECAT accesses take effect at the end of a correct frame. 0x09F0 latches
    // the local time of the beginning of a frame that changed at least one buffer (docs/decisions/esc.md).
    if (sm.end_of_frame(ok)) mem.w32(reg::kDcEcatBufferChange, static_cast<uint32_t>(time.frame_local));
    dc.end_of_frame(ok);
    sii.end_of_frame(ok);
    frame_write_enable = false;
    frame_esc_write_enable = false;
    mem.regs[reg::kRegWriteEnable] = 0;
    mem.regs[reg::kEscWriteEnable] = 0;
    if (reset_written_this_frame) {
        reset_written_this_frame = false;
        static constexpr uint8_t kSeq[3] = {0x52, 0x45, 0x53};
        const uint8_t v = mem.regs[reg::kEscResetEcat];
        if (ok && v == kSeq[reset_progress_ecat]) {
            ++reset_progress_ecat;
        } else {
            reset_progress_ecat = (ok && v == kSeq[0]) ? 1 : 0;
        }
        if (reset_progress_ecat == 3) {
            timers_touched = true;
            reset_registers();
            sii.load_words(true);
        } else {
            mem.regs[reg::kEscResetEcat] = reset_progress_ecat;
        }
    }
}

void Esc::Impl::datagram(uint8_t* d, uint8_t* data, uint16_t len) {
    if (d[0] == static_cast<uint8_t>(Command::NOP) || d[0] > static_cast<uint8_t>(Command::FRMW))
        return;  // not for a slave: untouched
    const Command cmd = static_cast<Command>(d[0]);
    const uint16_t adp = get16(d + 2);
    const uint16_t ado = get16(d + 4);
    uint8_t* wkc_p = data + len;
    put16(d + 8,
          static_cast<uint16_t>(get16(d + 8) | (mem.r16(reg::kEcatEvent) & mem.r16(reg::kEcatEventMask))));

    enum Op : uint8_t { kNone, kRead, kWrite, kReadWrite };
    Op op = kNone;
    bool or_read = false;
    switch (cmd) {
        case Command::APRD:
        case Command::APWR:
        case Command::APRW:
            if (adp == 0) op = cmd == Command::APRD ? kRead : cmd == Command::APWR ? kWrite : kReadWrite;
            put16(d + 2, static_cast<uint16_t>(adp + 1));
            break;
        case Command::FPRD:
        case Command::FPWR:
        case Command::FPRW:
        case Command::FRMW: {
            const bool match = adp == mem.r16(reg::kStationAddress) ||
                               ((mem.r8(0x0103) & 0x01) && !cfg.faults.alias_ignored &&
                                adp == mem.r16(reg::kStationAlias)) ||
                               (cmd == Command::FPRD && cfg.faults.fprd_any_address);
            if (cmd == Command::FRMW) {
                op = match ? kRead : kWrite;
            } else if (match) {
                op = cmd == Command::FPRD ? kRead : cmd == Command::FPWR ? kWrite : kReadWrite;
            }
            break;
        }
        case Command::BRD:
        case Command::BWR:
        case Command::BRW:
            op = cmd == Command::BRD ? kRead : cmd == Command::BWR ? kWrite : kReadWrite;
            or_read = cmd != Command::BWR;
            put16(d + 2, static_cast<uint16_t>(adp + 1));
            break;
        case Command::ARMW:
            op = adp == 0 ? kRead : kWrite;
            put16(d + 2, static_cast<uint16_t>(adp + 1));
            break;
        case Command::LRD:
        case Command::LWR:
        case Command::LRW: {
            const uint32_t la = static_cast<uint32_t>(adp) | (static_cast<uint32_t>(ado) << 16);
            sm.set_lock_mask(sm.enabled_mask());
            const uint16_t inc = fmmu.logical(*this, cmd, la, data, len);
            if (lookup_dirty) rebuild_lookup();
            if (inc) put16(wkc_p, static_cast<uint16_t>(get16(wkc_p) + inc));
            return;
        }
        default:
            return;
    }
    if (op == kNone) return;

    const uint16_t lock_before = sm.enabled_mask();
    uint16_t inc = 0;
    const uint8_t* wsrc = data;
    DatagramScratch& sc = datagram_scratch();  // BRD/BRW OR-read, xxRW write data
    uint8_t* scratch_a = sc.a.data();
    uint8_t* scratch_ok = sc.ok.data();
    if (op == kReadWrite) {
        std::memcpy(sc.b.data(), data, len);
        wsrc = sc.b.data();
    }
    if (op == kRead || op == kReadWrite) {
        bool any;
        if (or_read) {
            std::memset(scratch_ok, 0, len);
            any = phys_read(ado, scratch_a, scratch_ok, len, Side::Ecat);
            for (uint16_t i = 0; i < len; ++i)
                if (scratch_ok[i]) data[i] = static_cast<uint8_t>(data[i] | scratch_a[i]);
        } else {
            any = phys_read(ado, data, nullptr, len, Side::Ecat);
        }
        if (any) inc = 1;
    }
    if (op == kWrite || op == kReadWrite) {
        sm.set_lock_mask(lock_before);
        if (phys_write(ado, wsrc, nullptr, len, Side::Ecat))
            inc = static_cast<uint16_t>(inc + (op == kWrite ? 1 : 2));
        if (lookup_dirty) rebuild_lookup();
    }
    if (cmd == Command::APRD && inc && cfg.faults.wkc_aprd) ++inc;
    if (inc) put16(wkc_p, static_cast<uint16_t>(get16(wkc_p) + inc));
}

// ==================================================================================================
// Public API
// ==================================================================================================

Esc::Esc(const EscConfig& config, const Clock& clock) : impl_(std::make_unique<Impl>(config, clock)) {}
Esc::~Esc() = default;

// A frame at a port, with the signals kept: a frame the processing unit executed leaves the exact time of the
// next timer event (its writes may have started, moved or stopped one), and a masked AL event it raised or
// an EEPROM word it wrote wakes the PDI side.
int Esc::Impl::receive_signalled(std::span<uint8_t> frame, int port, uint64_t rx_clock, FrameCheck* check,
                                 std::unique_lock<EscLock>& lock) {
    const uint32_t before = masked_events();
    const uint64_t processed = stats.frames_processed;
    ++sig->activity;
    const int r = receive(frame, port, rx_clock, check);
    if (stats.frames_processed != processed) {
        // Only a frame that may have moved a timer earlier makes the due time unknown (the runtime's next
        // tick settles it); a process-data frame that re-triggers a running watchdog only moves it later,
        // and a due time that is early costs one tick that finds nothing.
        // With no SYNC pulse scheduled the exact figure costs a few loads (a master's drift compensation
        // writes 0x0910 of every ESC in every cycle); with one, the DC arithmetic is left to the next tick,
        // out of the frame's way.
        if (timers_touched || wd.take_started()) {
            timers_touched = false;
            sig->due_ns = dc.armed() ? 0 : due(time.frame_clock);
        } else if (dc_time_touched && dc.armed()) {
            sig->due_ns = 0;
        }
        dc_time_touched = false;
        note_events(before);
    }
    if (sii.callbacks_pending()) {
        sig->wake = 1;
        sii.flush_callbacks(lock);
    }
    return r;
}

bool Esc::process_frame(std::span<uint8_t> frame, uint64_t rx_time_ns) {
    std::unique_lock lock(impl_->mu);
    return impl_->receive_signalled(frame, 0, rx_time_ns, nullptr, lock) == 0;
}

int Esc::receive(std::span<uint8_t> frame, int port, uint64_t rx_clock_ns) {
    std::unique_lock lock(impl_->mu);
    return impl_->receive_signalled(frame, port, rx_clock_ns, nullptr, lock);
}

int Esc::receive(std::span<uint8_t> frame, int port, uint64_t rx_clock_ns, FrameCheck& check) {
    std::unique_lock lock(impl_->mu);
    return impl_->receive_signalled(frame, port, rx_clock_ns, &check, lock);
}

void Esc::prefetch(bool deep) const {
    const Impl& m = *impl_;
    if (deep) {
        m.fmmu.prefetch_ram(m.mem);
        return;
    }
    prefetch_lines(&m, 2 * kCacheLine);  // configuration, lock, register tables
    // The registers a cyclic frame reads or writes: station address and write enables, DL control, the
    // event registers, the watchdogs, the SyncManagers' status, the DC system time and its filter; then
    // the units' state.
    for (const uint16_t a : {0x0000, 0x0100, 0x0200, 0x0220, 0x0400, 0x0440, 0x0800, 0x0810, 0x0900, 0x0920})
        prefetch_lines(&m.mem.regs[a], 1);
    prefetch_lines(&m.mem.ram, sizeof m.mem.ram + sizeof m.mem.ram_end);
    prefetch_lines(&m.time, sizeof m.time);
    prefetch_lines(&m.wd, sizeof m.wd);
    m.sm.prefetch();
    m.fmmu.prefetch_state();
    prefetch_lines(&m.dc, sizeof m.dc);
    prefetch_lines(&m.ports, sizeof m.ports);
    prefetch_lines(&m.sii, sizeof m.sii);
    prefetch_lines(&m.lookup_dirty, 1);
    prefetch_lines(&m.frame_write_enable, 3);
    prefetch_lines(&m.stats, sizeof m.stats);
    prefetch_lines(&m.sig, sizeof m.sig + sizeof m.timers_touched);
}

void Esc::set_link(int port, bool up) {
    std::lock_guard lock(impl_->mu);
    impl_->ports.set_link(port, up);
    impl_->sig->due_ns = impl_->due(impl_->time.clock.now_ns());
}

bool Esc::link(int port) const {
    if (static_cast<unsigned>(port) >= static_cast<unsigned>(kPortCount)) return false;
    std::lock_guard lock(impl_->mu);
    return impl_->ports.link(port);
}

bool Esc::port_open(int port) const {
    if (static_cast<unsigned>(port) >= static_cast<unsigned>(kPortCount)) return false;
    std::lock_guard lock(impl_->mu);
    return impl_->ports.port_open(port);
}

uint8_t Esc::port_descriptor() const {
    return impl_->cfg.port_descriptor;
}

void Esc::read(uint16_t address, std::span<uint8_t> out) {
    // An empty span is no access: nothing read, the PDI watchdog not triggered, and no memset/memcpy on
    // the null pointer an empty span may carry.
    if (out.empty()) return;
    std::lock_guard lock(impl_->mu);
    impl_->wd.pdi_touch();
    impl_->sig->due_ns = 0;  // the PDI watchdog restarts at the next tick
    std::memset(out.data(), 0, out.size());
    impl_->phys_read(address, out.data(), nullptr, static_cast<uint32_t>(out.size()), Side::Pdi);
    if (impl_->lookup_dirty) impl_->rebuild_lookup();
}

void Esc::write(uint16_t address, std::span<const uint8_t> in) {
    if (in.empty()) return;  // no access, as for read()
    std::unique_lock lock(impl_->mu);
    impl_->wd.pdi_touch();
    impl_->sig->due_ns = 0;  // the PDI watchdog restarts at the next tick; a write may change a timer
    impl_->phys_write(address, in.data(), nullptr, static_cast<uint32_t>(in.size()), Side::Pdi);
    if (impl_->lookup_dirty) impl_->rebuild_lookup();
    impl_->sii.flush_callbacks(lock);
}

bool Esc::irq() const {
    std::lock_guard lock(impl_->mu);
    return (impl_->mem.r32(reg::kAlEvent) & impl_->mem.r32(reg::kAlEventMask)) != 0;
}

void Esc::tick() {
    tick(impl_->time.clock.now_ns());
}

void Esc::tick(uint64_t now_clock) {
    std::lock_guard lock(impl_->mu);
    const uint32_t before = impl_->masked_events();
    const bool wd_changed = impl_->wd.run(now_clock);
    if (impl_->dc.run(now_clock) || wd_changed) ++impl_->sig->activity;
    impl_->note_events(before);
    impl_->sig->due_ns = impl_->due(now_clock);
}

uint64_t Esc::Impl::next_event(uint64_t now_clock) const {
    return std::min(dc.next_event(now_clock), wd.next_event(now_clock));
}

uint64_t Esc::Impl::due(uint64_t now_clock) const {
    return wd.settled() ? next_event(now_clock) : now_clock;
}

void Esc::set_signals(EscSignals* signals) {
    std::lock_guard lock(impl_->mu);
    impl_->sig = signals != nullptr ? signals : &impl_->own_signals;
    impl_->sig->due_ns = impl_->due(impl_->time.clock.now_ns());
    impl_->sig->wake = impl_->masked_events() != 0 ? 1 : 0;
    impl_->sig->clock = &impl_->time.clock;
}

uint64_t Esc::next_event_ns() const {
    return next_event_ns(impl_->time.clock.now_ns());
}

uint64_t Esc::next_event_ns(uint64_t now_clock) const {
    std::lock_guard lock(impl_->mu);
    return impl_->next_event(now_clock);
}

const Clock& Esc::clock() const {
    return impl_->time.clock;
}

uint64_t Esc::local_time_ns() const {
    std::lock_guard lock(impl_->mu);
    return impl_->dc.local_at(impl_->time.clock.now_ns());
}

void Esc::load_eeprom(std::span<const uint8_t> image) {
    std::lock_guard lock(impl_->mu);
    impl_->sii.set_image(image.data(), image.size());
    impl_->sig->due_ns = 0;  // tick() to settle what the loaded words set
    uint16_t c = impl_->mem.r16(reg::kSiiControl);
    c = static_cast<uint16_t>(impl_->sii.image().size() > 2048 ? (c | 0x0080) : (c & ~0x0080));
    impl_->mem.w16(reg::kSiiControl, c);
    impl_->sii.load_words(true);
}

std::span<const uint8_t> Esc::eeprom() const {
    std::lock_guard lock(impl_->mu);
    return impl_->sii.image();
}

void Esc::on_eeprom_write(std::function<void(uint16_t, uint16_t)> callback) {
    std::lock_guard lock(impl_->mu);
    impl_->sii.on_write(std::move(callback));
}

EscStats Esc::stats() const {
    std::lock_guard lock(impl_->mu);
    return impl_->stats;
}

}  // namespace esc
