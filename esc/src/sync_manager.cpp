// SyncManager unit (sync_manager.hpp): mailbox (1-buffer) and buffered (3-buffer) modes, both directions,
// both sides.
#include <algorithm>
#include <cstring>
#include <utility>

#include "sync_manager.hpp"

#include "prefetch.hpp"

namespace esc {

void SyncManagers::reset_state(unsigned n) {
    SyncManager& s = sm[n];
    s.full = s.prod_open = s.cons_open = false;
    s.irq_write = s.irq_read = false;
    s.pending = s.pending_write = false;
    s.last_written = 3;
    s.user = 0;
    s.next = 1;
    s.free = 2;
    s.next_valid = false;
    pending_mask_ = static_cast<uint16_t>(pending_mask_ & ~(1u << n));
    update_status(n);
}

void SyncManagers::update_status(unsigned n) {
    SyncManager& s = sm[n];
    const uint8_t st = static_cast<uint8_t>((s.irq_write ? 0x01 : 0) | (s.irq_read ? 0x02 : 0) |
                                            (s.full ? 0x08 : 0) | ((s.last_written & 0x03) << 4) |
                                            (s.cons_open ? 0x40 : 0) | (s.prod_open ? 0x80 : 0));
    mem.regs[reg::kSm + 8 * n + 5] = st;
    // Events: the PDI is interested in what ECAT did and vice versa.
    const uint8_t ctrl = mem.r8(static_cast<uint16_t>(reg::kSm + 8 * n + 4));
    const bool active = (mem.r8(static_cast<uint16_t>(reg::kSm + 8 * n + 6)) & 0x01) && !s.pdi_disabled;
    const bool al = active && (ctrl & 0x20) && (s.ecat_writes ? s.irq_write : s.irq_read);
    const uint32_t albit = alev::kSm0 << n;
    if (al) {
        mem.set_al_event(albit);
    } else {
        mem.clear_al_event(albit);
    }
    if (n < 8) {
        const bool ec = active && (ctrl & 0x10) && (s.ecat_writes ? s.irq_read : s.irq_write);
        const uint16_t ecbit = static_cast<uint16_t>(ecev::kSm0 << n);
        if (ec) {
            mem.set_ecat_event(ecbit);
        } else {
            mem.clear_ecat_event(ecbit);
        }
    }
}

void SyncManagers::commit(unsigned n, bool write, Side side) {
    SyncManager& s = sm[n];
    if (write) {
        s.prod_open = false;
        if (s.mailbox) {
            s.full = true;
        } else {
            std::swap(s.free, s.next);
            s.next_valid = true;
            s.last_written = s.next;
        }
        s.irq_write = true;
        if (side == Side::Ecat && (s.control & 0x40)) wd.pd_trigger();
    } else {
        s.cons_open = false;
        if (s.mailbox) s.full = false;
        s.irq_read = true;
    }
    update_status(n);
}

bool SyncManagers::access(unsigned n, uint32_t off, uint8_t* dst, const uint8_t* src, const uint8_t* bm,
                          uint32_t cnt, bool write, Side side) {
    SyncManager& s = sm[n];
    if (!s.area_valid || s.pdi_disabled) return false;
    const uint32_t len = s.length;
    if (off >= len) return false;  // buffers 2 and 3 of a buffered SM are not directly accessible
    cnt = std::min(cnt, len - off);
    const bool producer = (side == Side::Ecat) == s.ecat_writes;
    if (write != producer) return false;  // wrong direction

    auto copy = [&](uint8_t* m) {
        if (write) {
            for (uint32_t i = 0; i < cnt; ++i) {
                const uint8_t mk = bm ? bm[i] : 0xFF;
                m[i] = static_cast<uint8_t>((m[i] & ~mk) | (src[i] & mk));
            }
        } else {
            std::memcpy(dst, m, cnt);
        }
    };

    if (len == 1) {  // single byte: transparent, only interrupt and watchdog
        copy(mem.at(s.start));
        close_transparent(n, write, side);
        return true;
    }
    if (s.pending) return false;  // closed in this frame: the end address cannot be accessed twice
    if (s.mailbox && s.full != !write) return false;  // write needs empty, read needs full

    bool& open = write ? s.prod_open : s.cons_open;
    if (!open) {
        if (off != 0) return false;  // a buffer must be opened at its start address
        open = true;
        if (write) {
            s.irq_read = false;
        } else {
            s.irq_write = false;
            if (!s.mailbox && s.next_valid) {
                std::swap(s.user, s.next);
                s.next_valid = false;
            }
        }
    }
    const uint32_t buf = s.mailbox ? 0 : static_cast<uint32_t>(write ? s.free : s.user) * len;
    copy(mem.at(s.start + buf + off));
    if (off + cnt == len) {
        if (side == Side::Ecat) {
            s.pending = true;
            s.pending_write = write;
            pending_mask_ = static_cast<uint16_t>(pending_mask_ | (1u << n));
        } else {
            commit(n, write, side);
            return true;
        }
    }
    update_status(n);
    return true;
}

void SyncManagers::close_transparent(unsigned n, bool write, Side side) {
    SyncManager& s = sm[n];
    if (s.pdi_disabled) return;
    // Only the producer's write and the consumer's read close it; the other side's accesses are plain.
    if (write != ((side == Side::Ecat) == s.ecat_writes)) return;
    if (write) {
        s.irq_write = true;
        s.irq_read = false;
        if (side == Side::Ecat && (s.control & 0x40)) wd.pd_trigger();
    } else {
        s.irq_read = true;
        s.irq_write = false;
    }
    update_status(n);
}

bool SyncManagers::activate_written(unsigned n, uint8_t value) {
    const uint16_t a = static_cast<uint16_t>(reg::kSm + 8 * n + 6);
    const uint8_t old = mem.regs[a];
    const uint8_t v = static_cast<uint8_t>(value & 0xC3);
    mem.regs[a] = v;
    mem.set_al_event(alev::kSmActivation);
    if ((old ^ v) & 0x01) {
        reset_state(n);
        return true;
    }
    return false;
}

void SyncManagers::pdi_control_written(unsigned n, uint8_t value) {
    const uint16_t a = static_cast<uint16_t>(reg::kSm + 8 * n + 7);
    SyncManager& s = sm[n];
    const bool deact = value & 0x01;
    mem.regs[a] = static_cast<uint8_t>(value & 0x03);
    if (deact != s.pdi_disabled) {
        s.pdi_disabled = deact;
        pdi_disabled_mask_ = static_cast<uint16_t>(deact ? (pdi_disabled_mask_ | (1u << n))
                                                         : (pdi_disabled_mask_ & ~(1u << n)));
        reset_state(n);
    }
}

void SyncManagers::reset() {
    for (unsigned n = 0; n < 16; ++n) {
        sm[n] = SyncManager{};
        if (n < count_) update_status(n);
    }
    pending_mask_ = 0;
    pdi_disabled_mask_ = 0;
}

void SyncManagers::prefetch() const {
    // Reads nothing: the counts, masks and first areas, and the state of SMs 0-3 (mailbox and process data).
    prefetch_lines(this, static_cast<std::size_t>(reinterpret_cast<const char*>(&areas_[2]) -
                                                  reinterpret_cast<const char*>(this)));
    prefetch_lines(&sm[0], 4 * sizeof(SyncManager));
}

void SyncManagers::rebuild() {
    enabled_mask_ = 0;
    area_count_ = 0;
    watch_count_ = 0;
    for (unsigned n = 0; n < count_; ++n) {
        uint16_t b = static_cast<uint16_t>(reg::kSm + 8 * n);
        SyncManager& s = sm[n];
        s.start = mem.r16(b);
        s.length = mem.r16(b + 2);
        s.control = mem.r8(b + 4);
        uint8_t act = mem.r8(b + 6);
        s.mailbox = (s.control & 0x03) == 0x02;
        s.ecat_writes = ((s.control >> 2) & 0x03) == 0x01;
        s.enabled = (act & 0x01) && s.length > 0;
        if (act & 0x01) enabled_mask_ = static_cast<uint16_t>(enabled_mask_ | (1u << n));
        uint32_t area = (s.mailbox || s.length == 1) ? s.length : 3u * s.length;
        uint32_t end = s.start + area;
        // Buffers (3-buffer redirection, mailbox gating) live in the process RAM: an area that fits it is
        // served as a buffer and captures its addresses. An SM that starts in the register space (the
        // digital-output SM on 0x0F00 of a digital I/O ESC) has no buffer of its own: the bytes keep their
        // own rules and its last byte closes it as the single-byte SM is closed (ESC datasheet section I,
        // SyncManager; section II, 0x0F00 digital I/O output data). One that starts in the RAM but runs past
        // its end is not served (decisions/esc.md).
        s.in_registers = s.start < reg::kRamBase;
        s.area_valid = !s.in_registers && end <= mem.ram_end;
        if (!s.enabled) continue;
        if (s.in_registers) {
            watches_[watch_count_++] =
                SmWatch{static_cast<uint32_t>(s.start) + s.length - 1u, static_cast<uint8_t>(n)};
            continue;
        }
        if (!s.area_valid) continue;
        // Insertion by start address.
        unsigned pos = area_count_;
        while (pos > 0 && areas_[pos - 1].start > s.start) {
            areas_[pos] = areas_[pos - 1];
            --pos;
        }
        areas_[pos] = SmArea{s.start, end, static_cast<uint8_t>(n)};
        ++area_count_;
    }
}

bool SyncManagers::commit_pending(bool ok) {
    uint16_t pend = pending_mask_;
    pending_mask_ = 0;
    bool buffer_changed = false;
    for (unsigned n = 0; pend != 0; ++n, pend = static_cast<uint16_t>(pend >> 1)) {
        if (!(pend & 1)) continue;
        SyncManager& s = sm[n];
        if (!s.pending) continue;
        s.pending = false;
        if (ok) {
            commit(n, s.pending_write, Side::Ecat);
            buffer_changed = true;
        } else {
            (s.pending_write ? s.prod_open : s.cons_open) = false;
            update_status(n);
        }
    }
    return buffer_changed;
}

}  // namespace esc
