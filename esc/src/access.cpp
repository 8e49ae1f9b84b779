// Access to the ESC's memory: routing of an access over registers, SyncManager areas and process RAM, and
// the register read/write rules of both sides (ECAT, PDI), which hand the unit registers to their units.
#include <algorithm>
#include <cstring>

#include "esc_impl.hpp"

namespace esc {

bool Esc::Impl::phys_read(uint32_t a, uint8_t* dst, uint8_t* ok, uint32_t n, Side side) {
    const uint32_t end = a + n;
    bool any = false;
    uint32_t p = a;
    while (p < end) {
        const SmArea* hit = sm.first_area(p, end);
        const uint32_t seg_end = hit ? std::max(p, hit->start) : end;
        if (p < seg_end) {
            if (p < reg::kRamBase) {
                const uint32_t q = std::min(seg_end, reg::kRamBase);
                reg_read(static_cast<uint16_t>(p), dst + (p - a), q - p, side);
                if (ok) std::memset(ok + (p - a), 1, q - p);
                any = true;
                p = q;
            }
            if (p < seg_end && p < mem.ram_end) {
                const uint32_t q = std::min(seg_end, mem.ram_end);
                std::memcpy(dst + (p - a), &mem.ram[p - reg::kRamBase], q - p);
                if (ok) std::memset(ok + (p - a), 1, q - p);
                any = true;
                p = q;
            }
            if (p < seg_end) p = seg_end;  // beyond the memory: not accessible
        }
        if (hit && p < end) {
            const uint32_t q = std::min(end, hit->end);
            if (sm.access(hit->sm, p - hit->start, dst + (p - a), nullptr, nullptr, q - p, false, side)) {
                any = true;
                if (ok) std::memset(ok + (p - a), 1, std::min(q, hit->start + sm.length(hit->sm)) - p);
            }
            p = q;
        }
    }
    if (!sm.register_sms().empty()) close_register_sms(a, end, false, side);
    return any;
}

bool Esc::Impl::phys_write(uint32_t a, const uint8_t* src, const uint8_t* bm, uint32_t n, Side side) {
    const uint32_t end = a + n;
    if (side == Side::Ecat && a < 0x0A00 && end > 0x0400) {
        // The DC time registers (receive times, system time, offset, delay, speed counter and filters) move
        // no timer of their own, only the SYNC pulses through the local time: they leave the due time
        // alone unless a pulse is scheduled. A master's drift compensation writes 0x0910 of every ESC in
        // every cycle.
        if (a >= reg::kDcRecvTime0 && end <= reg::kDcCyclicControl)
            dc_time_touched = true;
        else
            timers_touched = true;
    }
    bool any = false;
    uint32_t p = a;
    const bool esc_protected = esc_write_protected(side);
    while (p < end) {
        const SmArea* hit = sm.first_area(p, end);
        const uint32_t seg_end = hit ? std::max(p, hit->start) : end;
        if (p < seg_end) {
            if (p < reg::kRamBase) {
                const uint32_t q = std::min(seg_end, reg::kRamBase);
                if (reg_write(static_cast<uint16_t>(p), src + (p - a), bm ? bm + (p - a) : nullptr, q - p,
                              side))
                    any = true;
                p = q;
            }
            if (p < seg_end && p < mem.ram_end) {
                const uint32_t q = std::min(seg_end, mem.ram_end);
                if (!esc_protected) {
                    uint8_t* m = &mem.ram[p - reg::kRamBase];
                    const uint8_t* s = src + (p - a);
                    if (bm) {
                        const uint8_t* mk = bm + (p - a);
                        for (uint32_t i = 0; i < q - p; ++i)
                            m[i] = static_cast<uint8_t>((m[i] & ~mk[i]) | (s[i] & mk[i]));
                    } else {
                        std::memcpy(m, s, q - p);
                    }
                    any = true;
                }
                p = q;
            }
            if (p < seg_end) p = seg_end;
        }
        if (hit && p < end) {
            const uint32_t q = std::min(end, hit->end);
            if (!esc_protected && sm.access(hit->sm, p - hit->start, nullptr, src + (p - a),
                                            bm ? bm + (p - a) : nullptr, q - p, true, side))
                any = true;
            p = q;
        }
    }
    if (!sm.register_sms().empty()) close_register_sms(a, end, true, side);
    return any;
}

void Esc::Impl::close_register_sms(uint32_t a, uint32_t end, bool write, Side side) {
    // The SM's last byte was accessed if it lies in this access, in the memory, and (a write) was not
    // write-protected; the data itself went where the byte's own rules sent it.
    for (const SmWatch& w : sm.register_sms()) {
        if (w.last < a || w.last >= end || w.last >= mem.ram_end) continue;
        if (write) {
            const bool esc_prot = esc_write_protected(side);
            const bool blocked = w.last < reg::kRamBase ? write_blocked(static_cast<uint16_t>(w.last),
                                                                        esc_prot, reg_write_protected(side))
                                                        : esc_prot;
            if (blocked) continue;
        }
        sm.close_transparent(w.sm, write, side);
    }
}

uint64_t Esc::Impl::merged(uint16_t r, unsigned size, uint16_t a, uint16_t e, const uint8_t* src,
                           const uint8_t* bm) const {
    uint64_t v = 0;
    for (unsigned i = 0; i < size; ++i) {
        const uint16_t addr = static_cast<uint16_t>(r + i);
        uint8_t b = mem.regs[addr];
        if (addr >= a && addr < e) {
            const uint8_t m = bm ? bm[addr - a] : 0xFF;
            b = static_cast<uint8_t>((b & ~m) | (src[addr - a] & m));
        }
        v |= static_cast<uint64_t>(b) << (8 * i);
    }
    return v;
}

void Esc::Impl::reg_read(uint16_t a, uint8_t* dst, uint32_t n, Side side) {
    const uint16_t e = static_cast<uint16_t>(a + n);
    // Values computed at the moment of the access.
    if (a < 0x0A00 && e > reg::kDcRecvTime0) dc.before_read(a, e, side);
    std::memcpy(dst, &mem.regs[a], n);
    if (side == Side::Ecat) {
        if (overlaps(a, e, reg::kDlStatus, 2)) mem.clear_ecat_event(ecev::kDlStatus);
        if (overlaps(a, e, reg::kAlStatus, 2)) mem.clear_ecat_event(ecev::kAlStatus);
        return;
    }
    if (overlaps(a, e, reg::kAlControl, 2)) mem.clear_al_event(alev::kAlControl);
    if (overlaps(a, e, reg::kSm, 8u * cfg.sm_count)) {
        for (unsigned k = 0; k < cfg.sm_count; ++k)
            if (overlaps(a, e, static_cast<uint16_t>(reg::kSm + 8 * k + 6), 1))
                mem.clear_al_event(alev::kSmActivation);
    }
    if (overlaps(a, e, reg::kWdStatusPd, 2)) mem.clear_al_event(alev::kWatchdogPd);
    dc.after_pdi_read(a, e);
    if (overlaps(a, e, reg::kDcLatch0Status, 0x22)) mem.clear_al_event(alev::kDcLatch);
}

bool Esc::Impl::reg_write(uint16_t a, const uint8_t* src, const uint8_t* bm, uint32_t n, Side side) {
    const uint8_t* kind = side == Side::Ecat ? tables.ecat_kind.data() : tables.pdi_kind.data();
    const uint8_t* wmask = side == Side::Ecat ? tables.ecat_wmask.data() : tables.pdi_wmask.data();
    const bool reg_prot = reg_write_protected(side);
    const bool esc_prot = esc_write_protected(side);
    bool any = false;
    bool special = false;
    for (uint32_t i = 0; i < n; ++i) {
        const uint16_t addr = static_cast<uint16_t>(a + i);
        if (write_blocked(addr, esc_prot, reg_prot)) continue;
        any = true;
        if (kind[addr] == kPlain) {
            const uint8_t m = static_cast<uint8_t>(wmask[addr] & (bm ? bm[i] : 0xFF));
            mem.regs[addr] = static_cast<uint8_t>((mem.regs[addr] & ~m) | (src[i] & m));
        } else if (kind[addr] == kSpecial) {
            special = true;
        }
    }
    if (special) {
        // Protection applies per byte; the special handlers see only the unprotected part of the write.
        if (esc_prot || reg_prot) {
            // Only 0x0020/0x0030 can be special and unprotected here.
            for (uint16_t only : {reg::kRegWriteEnable, reg::kEscWriteEnable}) {
                if (only >= a && only < a + n && (!esc_prot || only == reg::kEscWriteEnable))
                    reg_special_write(only, static_cast<uint16_t>(only + 1), src + (only - a),
                                      bm ? bm + (only - a) : nullptr, side);
            }
        } else {
            reg_special_write(a, static_cast<uint16_t>(a + n), src, bm, side);
        }
    }
    return any;
}

void Esc::Impl::reg_special_write(uint16_t a, uint16_t e, const uint8_t* src, const uint8_t* bm, Side side) {
    auto M = [&](uint16_t r, unsigned size) { return merged(r, size, a, e, src, bm); };
    auto hit = [&](uint16_t r, unsigned size) { return overlaps(a, e, r, size); };
    // Bytes of [r, r+size) the write covers (with a non-zero mask).
    auto covers = [&](uint16_t r, unsigned size) {
        for (unsigned i = 0; i < size; ++i) {
            const uint16_t x = static_cast<uint16_t>(r + i);
            if (x < a || x >= e) return false;
        }
        return true;
    };

    if (side == Side::Ecat) {
        if (hit(reg::kRegWriteEnable, 1)) {
            frame_write_enable = M(reg::kRegWriteEnable, 1) & 0x01;
            mem.regs[reg::kRegWriteEnable] = frame_write_enable ? 1 : 0;
        }
        if (hit(reg::kEscWriteEnable, 1)) {
            frame_esc_write_enable = M(reg::kEscWriteEnable, 1) & 0x01;
            mem.regs[reg::kEscWriteEnable] = frame_esc_write_enable ? 1 : 0;
        }
        if (a >= reg::kUserRam) return;  // nothing special above
        if (hit(reg::kEscResetEcat, 1)) {
            mem.regs[reg::kEscResetEcat] = static_cast<uint8_t>(M(reg::kEscResetEcat, 1));
            reset_written_this_frame = true;
        }
        if (hit(reg::kAlControl, 2)) {
            const uint16_t v = static_cast<uint16_t>(M(reg::kAlControl, 2) & 0x003F);
            const bool emulation = mem.r8(reg::kEscConfig) & 0x01;
            // Device emulation off: AL control is a mailbox, blocked until the PDI read the last value.
            if (emulation || !(mem.r32(reg::kAlEvent) & alev::kAlControl)) {
                mem.w16(reg::kAlControl, v);
                mem.set_al_event(alev::kAlControl);
                if (emulation) {
                    const uint16_t st =
                        static_cast<uint16_t>((mem.r16(reg::kAlStatus) & ~0x001F) | (v & 0x000F));
                    mem.w16(reg::kAlStatus, st);
                    mem.set_ecat_event(ecev::kAlStatus);
                }
            }
        }
        if (hit(kDlControlLoop, 1)) {
            mem.w8(kDlControlLoop, static_cast<uint8_t>(M(kDlControlLoop, 1)));
            ports.dl_control_written();
        }
        // Error counters (ESC datasheet section II, 0x0300-0x0313): a write clears a whole group whatever
        // byte it hits and whatever value it carries: any RX error counter byte (0x0300-0x030B) clears the
        // invalid-frame, RX error and forwarded-RX error counters of every port; 0x030C the processing unit
        // counter; 0x030D the PDI error counter; any lost-link byte (0x0310-0x0313) the four lost-link
        // counters.
        const auto clear = [&](uint16_t from, uint16_t len) {
            for (uint16_t x = from; x < from + len; ++x)
                mem.regs[x] = 0;
        };
        if (hit(0x0300, 0x0C)) clear(0x0300, 0x0C);
        if (hit(0x030C, 1)) clear(0x030C, 1);
        if (hit(0x030D, 1)) clear(0x030D, 2);
        if (hit(0x0310, 4)) clear(0x0310, 4);
        if (hit(reg::kWdCounterPd, 2)) {
            mem.regs[reg::kWdCounterPd] = 0;
            mem.regs[reg::kWdCounterPdi] = 0;
        }
        if (hit(reg::kSiiConfig, 1)) {
            const uint8_t v = static_cast<uint8_t>(M(reg::kSiiConfig, 1) & 0x03);
            mem.w8(reg::kSiiConfig, v);
            // Force ECAT access: takes the interface back from the PDI.
            if (v & 0x02)
                mem.w8(reg::kSiiPdiAccess, static_cast<uint8_t>(mem.r8(reg::kSiiPdiAccess) & ~0x01));
        }
        const bool pdi_owns_sii = (mem.r8(reg::kSiiConfig) & 0x01) && (mem.r8(reg::kSiiPdiAccess) & 0x01);
        const bool sii_busy = mem.r16(reg::kSiiControl) & 0x8000;
        if (hit(reg::kSiiAddress, 12) && !pdi_owns_sii && !sii_busy) {
            for (uint16_t x = std::max<uint16_t>(a, reg::kSiiAddress); x < std::min<uint16_t>(e, 0x0510); ++x)
                mem.regs[x] = static_cast<uint8_t>(M(x, 1));
        }
        if (hit(reg::kSiiControl, 2) && !pdi_owns_sii && !sii_busy) {
            // Only bit 0 (write enable) and bits 10:8 (command) are writable; IgH sets read-only bits.
            const uint16_t v = static_cast<uint16_t>(M(reg::kSiiControl, 2));
            uint16_t c = static_cast<uint16_t>((mem.r16(reg::kSiiControl) & ~0x0701) | (v & 0x0701));
            if (((v >> 8) & 0x07) == 0) {
                c = static_cast<uint16_t>(c & ~0x6000);  // command 000 clears the error bits
            } else {
                c = static_cast<uint16_t>(c | 0x8000);  // busy until the end of the frame
                sii.request();
            }
            mem.w16(reg::kSiiControl, c);
        }
        if (hit(reg::kFmmu, 16u * cfg.fmmu_count)) {
            static constexpr uint8_t kMask[13] = {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x07,
                                                  0x07, 0xFF, 0xFF, 0x07, 0x03, 0x01};
            const uint16_t lo = std::max<uint16_t>(a, reg::kFmmu);
            const uint16_t hi =
                std::min<uint16_t>(e, static_cast<uint16_t>(reg::kFmmu + 16u * cfg.fmmu_count));
            for (uint16_t x = lo; x < hi; ++x) {
                const unsigned off = (x - reg::kFmmu) % 16;
                if (off > 0x0C) continue;
                const uint8_t m = static_cast<uint8_t>(kMask[off] & (bm ? bm[x - a] : 0xFF));
                mem.regs[x] = static_cast<uint8_t>((mem.regs[x] & ~m) | (src[x - a] & m));
            }
            lookup_dirty = true;
        }
        if (hit(reg::kSm, 8u * cfg.sm_count)) {
            const uint16_t lo = std::max<uint16_t>(a, reg::kSm);
            const uint16_t hi = std::min<uint16_t>(e, static_cast<uint16_t>(reg::kSm + 8u * cfg.sm_count));
            for (uint16_t x = lo; x < hi; ++x) {
                const unsigned n = (x - reg::kSm) / 8;
                const unsigned off = (x - reg::kSm) % 8;
                if (off <= 4) {
                    // Start, length, control: writable only while the SM was disabled before this datagram.
                    if (sm.locked(n)) continue;
                    const uint8_t m = bm ? bm[x - a] : 0xFF;
                    mem.regs[x] = static_cast<uint8_t>((mem.regs[x] & ~m) | (src[x - a] & m));
                    lookup_dirty = true;
                } else if (off == 6) {
                    if (sm.activate_written(n, static_cast<uint8_t>(M(x, 1)))) lookup_dirty = true;
                }
            }
        }
        if (a >= 0x0A00 || e <= reg::kDcRecvTime0) return;
        if (hit(reg::kDcRecvTime0, 4)) dc.receive_time_written();
        if (covers(reg::kDcSystemTime, 4))
            dc.system_time_written(static_cast<uint32_t>(M(reg::kDcSystemTime, 4)));
        if (hit(reg::kDcSpeedStart, 2)) {
            mem.w16(reg::kDcSpeedStart, static_cast<uint16_t>(M(reg::kDcSpeedStart, 2) & 0x7FFF));
            dc.reset_filters();
        }
    }

    // ---- PDI-only registers
    if (side == Side::Pdi) {
        if (hit(reg::kEscResetPdi, 1)) {
            static constexpr uint8_t kSeq[3] = {0x52, 0x45, 0x53};
            const uint8_t v = static_cast<uint8_t>(M(reg::kEscResetPdi, 1));
            if (v == kSeq[reset_progress_pdi]) {
                ++reset_progress_pdi;
            } else {
                reset_progress_pdi = v == kSeq[0] ? 1 : 0;
            }
            if (reset_progress_pdi == 3) {
                reset_registers();
                sii.load_words(true);
                return;
            }
            mem.regs[reg::kEscResetPdi] = reset_progress_pdi;
        }
        if (hit(reg::kAlStatus, 2) && !(mem.r8(reg::kEscConfig) & 0x01)) {
            mem.w16(reg::kAlStatus, static_cast<uint16_t>(M(reg::kAlStatus, 2) & 0x003F));
            mem.set_ecat_event(ecev::kAlStatus);
        }
        const bool pdi_owns_sii = (mem.r8(reg::kSiiConfig) & 0x01) && (mem.r8(reg::kSiiPdiAccess) & 0x01);
        if (hit(reg::kSiiControl, 14) && pdi_owns_sii && !(mem.r16(reg::kSiiControl) & 0x8000)) {
            for (uint16_t x = std::max<uint16_t>(a, reg::kSiiAddress); x < std::min<uint16_t>(e, 0x0510); ++x)
                mem.regs[x] = static_cast<uint8_t>(M(x, 1));
            if (hit(reg::kSiiControl, 2)) {
                const uint16_t v = static_cast<uint16_t>(M(reg::kSiiControl, 2));
                uint16_t c = static_cast<uint16_t>((mem.r16(reg::kSiiControl) & ~0x2701) | (v & 0x2701));
                mem.w16(reg::kSiiControl, c);
                if ((v >> 8) & 0x07) sii.execute();
            }
        }
        if (hit(reg::kSm, 8u * cfg.sm_count)) {
            for (unsigned n = 0; n < cfg.sm_count; ++n) {
                const uint16_t x = static_cast<uint16_t>(reg::kSm + 8 * n + 7);
                if (hit(x, 1)) sm.pdi_control_written(n, static_cast<uint8_t>(M(x, 1)));
            }
        }
        if (a >= 0x0A00 || e <= reg::kDcRecvTime0) return;
    }

    // ---- DC SYNC/latch configuration: writable by the side that owns the unit (0x0980).
    const uint8_t owner = mem.r8(reg::kDcCyclicControl);
    const bool sync_mine = (side == Side::Pdi) == ((owner & 0x01) != 0);
    if (sync_mine) {
        if (hit(reg::kDcStartTime, 8) && !(mem.r8(reg::kDcActivation) & 0x01)) {
            mem.w64(reg::kDcStartTime, M(reg::kDcStartTime, 8));
            dc.start_time_written(!hit(0x0994, 4));
        }
        if (hit(reg::kDcSync0Cycle, 8)) {
            mem.w32(reg::kDcSync0Cycle, static_cast<uint32_t>(M(reg::kDcSync0Cycle, 4)));
            mem.w32(reg::kDcSync1Cycle, static_cast<uint32_t>(M(reg::kDcSync1Cycle, 4)));
        }
        if (hit(reg::kDcActivation, 1)) {
            const uint8_t old = mem.r8(reg::kDcActivation);
            const uint8_t v = static_cast<uint8_t>(M(reg::kDcActivation, 1));
            mem.w8(reg::kDcActivation, v);
            dc.activation_written(old, v);
        }
    }
    if (hit(reg::kDcLatch0Control, 1) && (side == Side::Pdi) == ((owner & 0x10) != 0))
        mem.w8(reg::kDcLatch0Control, static_cast<uint8_t>(M(reg::kDcLatch0Control, 1) & 0x03));
    if (hit(reg::kDcLatch1Control, 1) && (side == Side::Pdi) == ((owner & 0x20) != 0))
        mem.w8(reg::kDcLatch1Control, static_cast<uint8_t>(M(reg::kDcLatch1Control, 1) & 0x03));
}

}  // namespace esc
