// The emulated ESC: construction, reset values, the public API and frame / datagram processing.
#include <algorithm>
#include <cstring>

#include "esc_impl.hpp"

namespace esc {

namespace {

constexpr uint16_t kEtherTypeEcat = 0x88A4;
constexpr uint16_t kEtherTypeVlan = 0x8100;

enum Cmd : uint8_t {
    kNop = 0,
    kAprd = 1,
    kApwr = 2,
    kAprw = 3,
    kFprd = 4,
    kFpwr = 5,
    kFprw = 6,
    kBrd = 7,
    kBwr = 8,
    kBrw = 9,
    kLrd = 10,
    kLwr = 11,
    kLrw = 12,
    kArmw = 13,
    kFrmw = 14,
};

uint16_t le16(const uint8_t* p) {
    return static_cast<uint16_t>(p[0] | (p[1] << 8));
}
void put_le16(uint8_t* p, uint16_t v) {
    p[0] = static_cast<uint8_t>(v);
    p[1] = static_cast<uint8_t>(v >> 8);
}

// The built-in SII image of a bare ESC: a valid header (PDI "on-chip bus", DC SYNC/latch units on, SYNC0/1
// mapped to the AL event register, 10 us pulses), identity zero, no categories, 2 KiB (16 Kbit).
std::vector<uint8_t> default_eeprom() {
    std::vector<uint8_t> img(2048, 0xFF);
    std::fill(img.begin(), img.begin() + 0x80, 0x00);
    auto put = [&](unsigned word, uint16_t v) {
        img[2 * word] = static_cast<uint8_t>(v);
        img[2 * word + 1] = static_cast<uint8_t>(v >> 8);
    };
    put(0x00, 0x0C80);  // 0x0140 PDI control 0x80, 0x0141 ESC config: SYNC out unit + latch in unit
    put(0x01, 0xCC00);  // 0x0150 0x00, 0x0151: SYNC0/SYNC1 outputs, mapped to AL event bits 2/3
    put(0x02, 0x03E8);  // SYNC pulse length 1000 x 10 ns
    put(0x07, sii_crc8(img.data(), 14));
    put(0x3E, 0x000F);  // 16 Kbit - 1
    put(0x3F, 0x0001);  // version
    put(0x40, 0xFFFF);  // end of categories
    return img;
}

}  // namespace

uint8_t sii_crc8(const uint8_t* data, std::size_t n) {
    uint8_t crc = 0xFF;
    for (std::size_t i = 0; i < n; ++i) {
        crc ^= data[i];
        for (int b = 0; b < 8; ++b)
            crc = static_cast<uint8_t>((crc & 0x80) ? (crc << 1) ^ 0x07 : (crc << 1));
    }
    return crc;
}

// ==================================================================================================
// Construction and reset
// ==================================================================================================

Esc::Impl::Impl(const EscConfig& c, const Clock& clk) : cfg(c), clock(clk) {
    uint32_t kib = std::min<uint32_t>(c.process_ram_kib, 60);  // RAM must end below 0x10000
    cfg.process_ram_kib = kib;
    ram.assign(kib * 1024, 0);
    mem_end = reg::kRamBase + kib * 1024;
    fmmu_count = std::min<uint8_t>(c.fmmu_count, 16);
    sm_count = std::min<uint8_t>(c.sm_count, 16);
    cfg.fmmu_count = fmmu_count;
    cfg.sm_count = sm_count;
    clock_anchor = clock.now_ns();
    local_anchor = clock_anchor;
    init_tables();
    eeprom = default_eeprom();
    reset_registers();
    load_eeprom_words(true);
}

void Esc::Impl::init_tables() {
    auto ecat = [&](uint16_t a, unsigned n, uint8_t kind, uint8_t mask = 0xFF) {
        for (unsigned i = 0; i < n; ++i) {
            ecat_kind[a + i] = kind;
            ecat_wmask[a + i] = mask;
        }
    };
    auto pdi = [&](uint16_t a, unsigned n, uint8_t kind, uint8_t mask = 0xFF) {
        for (unsigned i = 0; i < n; ++i) {
            pdi_kind[a + i] = kind;
            pdi_wmask[a + i] = mask;
        }
    };
    // ECAT side.
    ecat(reg::kStationAddress, 2, kPlain);
    ecat(reg::kRegWriteEnable, 1, kSpecial, 0x01);
    ecat(reg::kRegWriteProtect, 1, kPlain, 0x01);
    ecat(reg::kEscWriteEnable, 1, kSpecial, 0x01);
    ecat(reg::kEscWriteProtect, 1, kPlain, 0x01);
    ecat(reg::kEscResetEcat, 1, kSpecial);
    ecat(reg::kDlControl, 4, kPlain);
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
    regs.fill(0);
    w8(0x0000, cfg.type);
    w8(0x0001, cfg.revision);
    w16(0x0002, cfg.build);
    w8(0x0004, fmmu_count);
    w8(0x0005, sm_count);
    w8(0x0006, static_cast<uint8_t>(cfg.process_ram_kib));
    w8(0x0007, cfg.port_descriptor);
    w16(0x0008, cfg.features);
    w32(reg::kDlControl, 0x0007C001);
    // Single port: link + communication on port 0, loop of port 0 open, ports 1-3 closed, PDI watchdog
    // reloaded. Bit 0 (EEPROM loaded) is set by the EEPROM load.
    w16(reg::kDlStatus, 0x5612);
    w16(reg::kAlControl, 0x0001);
    w16(reg::kAlStatus, 0x0001);
    w32(reg::kAlEventMask, 0x00FFFF2F);
    w16(reg::kEcatEvent, ecev::kDlStatus);
    w32(reg::kAlEvent, 0);
    w16(reg::kWdDivider, 0x09C2);
    w16(reg::kWdTimePdi, 0x03E8);
    w16(reg::kWdTimePd, 0x03E8);
    w16(reg::kWdStatusPd, 0x0001);
    uint16_t sii = 0x0060 | 0x1000;  // emulated EEPROM, 8-byte reads, not loaded yet
    if (eeprom.size() > 2048) sii |= 0x0080;
    w16(reg::kSiiControl, sii);
    w16(reg::kDcSpeedStart, 0x1000);
    w8(reg::kDcFilterDiff, 4);
    w8(reg::kDcFilterSpeed, 12);

    for (unsigned n = 0; n < 16; ++n) {
        sm[n] = SyncManager{};
        if (n < sm_count) sm_update_status(n);
    }
    sm_pending_mask = 0;
    rebuild_lookup();

    sync_running = sync0_armed = sync1_armed = false;
    sync0_ack = sync1_ack = false;
    rate_integral = 0.0;
    set_rate(0.0, clock.now_ns());
    dc_have_prev = false;
    dc_filter_primed = false;
    dc_diff_filtered = 0.0;
    pd_wd_armed = pdi_wd_armed = pdi_touched = false;
    reset_progress_ecat = reset_progress_pdi = 0;
}

void Esc::Impl::rebuild_lookup() {
    lookup_dirty = false;
    sm_enabled_mask = 0;
    sm_area_count = 0;
    for (unsigned n = 0; n < sm_count; ++n) {
        uint16_t b = static_cast<uint16_t>(reg::kSm + 8 * n);
        SyncManager& s = sm[n];
        s.start = r16(b);
        s.length = r16(b + 2);
        s.control = r8(b + 4);
        uint8_t act = r8(b + 6);
        s.mailbox = (s.control & 0x03) == 0x02;
        s.ecat_writes = ((s.control >> 2) & 0x03) == 0x01;
        s.enabled = (act & 0x01) && s.length > 0;
        if (act & 0x01) sm_enabled_mask = static_cast<uint16_t>(sm_enabled_mask | (1u << n));
        uint32_t area = (s.mailbox || s.length == 1) ? s.length : 3u * s.length;
        uint32_t end = s.start + area;
        // SyncManagers act on the process RAM only (ESC datasheet section I, SyncManager): an area that
        // starts in the register space or does not fit the RAM is not served and captures no address,
        // so the registers (the SM's own included) and the RAM stay reachable (decisions/esc.md).
        s.area_valid = s.start >= reg::kRamBase && end <= mem_end;
        if (!s.enabled || !s.area_valid) continue;
        // Insertion by start address.
        unsigned pos = sm_area_count;
        while (pos > 0 && sm_areas[pos - 1].start > s.start) {
            sm_areas[pos] = sm_areas[pos - 1];
            --pos;
        }
        sm_areas[pos] = SmArea{s.start, end, static_cast<uint8_t>(n)};
        ++sm_area_count;
    }
    fmmu_active = 0;
    for (unsigned n = 0; n < fmmu_count; ++n) {
        uint16_t b = static_cast<uint16_t>(reg::kFmmu + 16 * n);
        uint32_t la = r32(b);
        uint16_t len = r16(b + 4);
        uint8_t lstart = r8(b + 6) & 0x07;
        uint8_t lstop = r8(b + 7) & 0x07;
        uint16_t pa = r16(b + 8);
        uint8_t pstart = r8(b + 0x0A) & 0x07;
        uint8_t type = r8(b + 0x0B) & 0x03;
        if (!(r8(b + 0x0C) & 0x01) || len == 0 || type == 0) continue;
        FmmuMap f;
        f.lbit_start = static_cast<uint64_t>(la) * 8 + lstart;
        f.lbit_end = (static_cast<uint64_t>(la) + len - 1) * 8 + lstop + 1;
        if (f.lbit_end <= f.lbit_start) continue;
        f.pbit_start = static_cast<uint64_t>(pa) * 8 + pstart;
        f.read = type & 0x01;
        f.write = type & 0x02;
        fmmu_map[fmmu_active++] = f;
    }
}

// ==================================================================================================
// Frame processing
// ==================================================================================================

bool Esc::Impl::process(std::span<uint8_t> frame, uint64_t rx_clock) {
    const std::size_t size = frame.size();
    if (size < 14) {
        ++stats.frames_ignored;
        return false;
    }
    uint8_t* f = frame.data();
    std::size_t off = 12;
    uint16_t type = static_cast<uint16_t>((f[12] << 8) | f[13]);
    if (type == kEtherTypeVlan) {
        if (size < 18) {
            ++stats.frames_ignored;
            return false;
        }
        type = static_cast<uint16_t>((f[16] << 8) | f[17]);
        off = 16;
    }
    if (type != kEtherTypeEcat) {
        ++stats.frames_ignored;
        return false;
    }
    if (!cfg.faults.source_mac_unchanged)
        f[6] |= 0x02;  // source MAC: locally administered bit, as every ESC sets it
    const std::size_t hdr = off + 2;
    if (size < hdr + 2) {
        ++stats.frames_malformed;
        ++stats.malformed_no_header;
        count_error(reg::kInvalidFrameCounter);
        count_error(reg::kProcessingUnitErrors);
        return true;
    }
    const uint16_t h = le16(f + hdr);
    if ((h >> 12) != 1) {
        ++stats.frames_ignored;  // EtherCAT frame of another type: forwarded unprocessed
        return true;
    }
    ++stats.frames_processed;
    frame_clock = rx_clock != 0 ? rx_clock : clock.now_ns();
    frame_local = local_at(frame_clock);
    in_frame = true;

    bool ok = true;
    std::size_t p = hdr + 2;
    const std::size_t end = p + (h & 0x07FF);
    if (end > size) {
        ok = false;
        ++stats.malformed_length;
    } else {
        for (;;) {
            if (p + 12 > end) {
                ok = false;
                ++stats.malformed_datagram;
                break;
            }
            const uint16_t lf = le16(f + p + 6);
            const uint16_t dlen = lf & 0x07FF;
            if (p + 12 + dlen > end) {
                ok = false;
                ++stats.malformed_datagram;
                break;
            }
            datagram(f + p, f + p + 10, dlen);
            ++stats.datagrams;
            p += 12u + dlen;
            if (!(lf & 0x8000)) break;
        }
    }
    if (!ok) {
        ++stats.frames_malformed;
        count_error(reg::kInvalidFrameCounter);
        count_error(reg::kProcessingUnitErrors);
    }
    end_of_frame(ok);
    in_frame = false;
    return true;
}

void Esc::Impl::end_of_frame(bool ok) {
    // SyncManager buffer changes of ECAT accesses take effect at the end of a correct frame. 0x09F0 latches
    // the local time of the beginning of a frame that changed at least one buffer (docs/decisions/esc.md).
    uint16_t pend = sm_pending_mask;
    sm_pending_mask = 0;
    bool buffer_changed = false;
    for (unsigned n = 0; pend != 0; ++n, pend = static_cast<uint16_t>(pend >> 1)) {
        if (!(pend & 1)) continue;
        SyncManager& s = sm[n];
        if (!s.pending) continue;
        s.pending = false;
        if (ok) {
            sm_commit(n, s.pending_write, Side::Ecat);
            buffer_changed = true;
        } else {
            (s.pending_write ? s.prod_open : s.cons_open) = false;
            sm_update_status(n);
        }
    }
    if (buffer_changed) w32(reg::kDcEcatBufferChange, static_cast<uint32_t>(frame_local));
    if (dc_latch_pending) {
        dc_latch_pending = false;
        if (ok) {
            const uint32_t t32 = static_cast<uint32_t>(frame_local);
            for (uint16_t port = 0; port < 4; ++port)
                w32(static_cast<uint16_t>(reg::kDcRecvTime0 + 4 * port), t32);
            w64(reg::kDcRecvTimePu, frame_local);
        }
    }
    if (eeprom_pending) {
        eeprom_pending = false;
        if (ok) {
            eeprom_execute(Side::Ecat);
        } else {
            w16(reg::kSiiControl, static_cast<uint16_t>(r16(reg::kSiiControl) & ~0x8000));
        }
    }
    frame_write_enable = false;
    frame_esc_write_enable = false;
    regs[reg::kRegWriteEnable] = 0;
    regs[reg::kEscWriteEnable] = 0;
    if (reset_written_this_frame) {
        reset_written_this_frame = false;
        static constexpr uint8_t kSeq[3] = {0x52, 0x45, 0x53};
        const uint8_t v = regs[reg::kEscResetEcat];
        if (ok && v == kSeq[reset_progress_ecat]) {
            ++reset_progress_ecat;
        } else {
            reset_progress_ecat = (ok && v == kSeq[0]) ? 1 : 0;
        }
        if (reset_progress_ecat == 3) {
            reset_registers();
            load_eeprom_words(true);
        } else {
            regs[reg::kEscResetEcat] = reset_progress_ecat;
        }
    }
}

void Esc::Impl::datagram(uint8_t* d, uint8_t* data, uint16_t len) {
    const uint8_t cmd = d[0];
    if (cmd == kNop || cmd > kFrmw) return;  // not for a slave: untouched
    const uint16_t adp = le16(d + 2);
    const uint16_t ado = le16(d + 4);
    uint8_t* wkc_p = data + len;
    put_le16(d + 8, static_cast<uint16_t>(le16(d + 8) | (r16(reg::kEcatEvent) & r16(reg::kEcatEventMask))));

    enum Op : uint8_t { kNone, kRead, kWrite, kReadWrite };
    Op op = kNone;
    bool or_read = false;
    switch (cmd) {
        case kAprd:
        case kApwr:
        case kAprw:
            if (adp == 0) op = cmd == kAprd ? kRead : cmd == kApwr ? kWrite : kReadWrite;
            put_le16(d + 2, static_cast<uint16_t>(adp + 1));
            break;
        case kFprd:
        case kFpwr:
        case kFprw:
        case kFrmw: {
            const bool match =
                adp == r16(reg::kStationAddress) ||
                ((r8(0x0103) & 0x01) && !cfg.faults.alias_ignored && adp == r16(reg::kStationAlias)) ||
                (cmd == kFprd && cfg.faults.fprd_any_address);
            if (cmd == kFrmw) {
                op = match ? kRead : kWrite;
            } else if (match) {
                op = cmd == kFprd ? kRead : cmd == kFpwr ? kWrite : kReadWrite;
            }
            break;
        }
        case kBrd:
        case kBwr:
        case kBrw:
            op = cmd == kBrd ? kRead : cmd == kBwr ? kWrite : kReadWrite;
            or_read = cmd != kBwr;
            put_le16(d + 2, static_cast<uint16_t>(adp + 1));
            break;
        case kArmw:
            op = adp == 0 ? kRead : kWrite;
            put_le16(d + 2, static_cast<uint16_t>(adp + 1));
            break;
        case kLrd:
        case kLwr:
        case kLrw: {
            const uint32_t la = static_cast<uint32_t>(adp) | (static_cast<uint32_t>(ado) << 16);
            const uint16_t inc = logical(cmd, la, data, len);
            if (lookup_dirty) rebuild_lookup();
            if (inc) put_le16(wkc_p, static_cast<uint16_t>(le16(wkc_p) + inc));
            return;
        }
        default:
            return;
    }
    if (op == kNone) return;

    const uint16_t lock_before = sm_enabled_mask;
    uint16_t inc = 0;
    const uint8_t* wsrc = data;
    if (op == kReadWrite) {
        std::memcpy(scratch_b.data(), data, len);
        wsrc = scratch_b.data();
    }
    if (op == kRead || op == kReadWrite) {
        bool any;
        if (or_read) {
            std::memset(scratch_ok.data(), 0, len);
            any = phys_read(ado, scratch_a.data(), scratch_ok.data(), len, Side::Ecat);
            for (uint16_t i = 0; i < len; ++i)
                if (scratch_ok[i]) data[i] = static_cast<uint8_t>(data[i] | scratch_a[i]);
        } else {
            any = phys_read(ado, data, nullptr, len, Side::Ecat);
        }
        if (any) inc = 1;
    }
    if (op == kWrite || op == kReadWrite) {
        sm_lock_mask = lock_before;
        if (phys_write(ado, wsrc, nullptr, len, Side::Ecat))
            inc = static_cast<uint16_t>(inc + (op == kWrite ? 1 : 2));
        if (lookup_dirty) rebuild_lookup();
    }
    if (cmd == kAprd && inc && cfg.faults.wkc_aprd) ++inc;
    if (inc) put_le16(wkc_p, static_cast<uint16_t>(le16(wkc_p) + inc));
}

// ==================================================================================================
// Public API
// ==================================================================================================

Esc::Esc(const EscConfig& config, const Clock& clock) : impl_(std::make_unique<Impl>(config, clock)) {}
Esc::~Esc() = default;

void Esc::Impl::flush_callbacks(std::unique_lock<std::mutex>& lock) {
    if (eeprom_write_count == 0) return;
    const std::array<EepromWrite, 4> w = eeprom_writes;
    const uint8_t n = eeprom_write_count;
    eeprom_write_count = 0;
    auto cb = on_eeprom_write;
    lock.unlock();
    if (cb)
        for (uint8_t i = 0; i < n; ++i)
            cb(w[i].address, w[i].value);
}

bool Esc::process_frame(std::span<uint8_t> frame, uint64_t rx_time_ns) {
    std::unique_lock lock(impl_->mu);
    const bool r = impl_->process(frame, rx_time_ns);
    impl_->flush_callbacks(lock);
    return r;
}

void Esc::read(uint16_t address, std::span<uint8_t> out) {
    // An empty span is no access: nothing read, the PDI watchdog not triggered, and no memset/memcpy on
    // the null pointer an empty span may carry.
    if (out.empty()) return;
    std::lock_guard lock(impl_->mu);
    impl_->pdi_touch();
    std::memset(out.data(), 0, out.size());
    impl_->phys_read(address, out.data(), nullptr, static_cast<uint32_t>(out.size()), Side::Pdi);
    if (impl_->lookup_dirty) impl_->rebuild_lookup();
}

void Esc::write(uint16_t address, std::span<const uint8_t> in) {
    if (in.empty()) return;  // no access, as for read()
    std::unique_lock lock(impl_->mu);
    impl_->pdi_touch();
    impl_->phys_write(address, in.data(), nullptr, static_cast<uint32_t>(in.size()), Side::Pdi);
    if (impl_->lookup_dirty) impl_->rebuild_lookup();
    impl_->flush_callbacks(lock);
}

bool Esc::irq() const {
    std::lock_guard lock(impl_->mu);
    return (impl_->r32(reg::kAlEvent) & impl_->r32(reg::kAlEventMask)) != 0;
}

void Esc::tick() {
    std::lock_guard lock(impl_->mu);
    const uint64_t now = impl_->clock.now_ns();
    impl_->wd_run(now);
    impl_->dc_run(now);
}

uint64_t Esc::next_event_ns() const {
    std::lock_guard lock(impl_->mu);
    return impl_->next_event();
}

uint64_t Esc::local_time_ns() const {
    std::lock_guard lock(impl_->mu);
    return impl_->local_at(impl_->clock.now_ns());
}

void Esc::load_eeprom(std::span<const uint8_t> image) {
    std::lock_guard lock(impl_->mu);
    impl_->eeprom.assign(image.begin(), image.end());
    uint16_t c = impl_->r16(reg::kSiiControl);
    c = static_cast<uint16_t>(impl_->eeprom.size() > 2048 ? (c | 0x0080) : (c & ~0x0080));
    impl_->w16(reg::kSiiControl, c);
    impl_->load_eeprom_words(true);
}

std::span<const uint8_t> Esc::eeprom() const {
    std::lock_guard lock(impl_->mu);
    return impl_->eeprom;
}

void Esc::on_eeprom_write(std::function<void(uint16_t, uint16_t)> callback) {
    std::lock_guard lock(impl_->mu);
    impl_->on_eeprom_write = std::move(callback);
}

EscStats Esc::stats() const {
    std::lock_guard lock(impl_->mu);
    return impl_->stats;
}

}  // namespace esc
