// SyncManagers: mailbox (1-buffer) and buffered (3-buffer) modes, both directions, both sides.
#include <algorithm>
#include <cstring>
#include <utility>

#include "esc_impl.hpp"

namespace esc {

void Esc::Impl::sm_reset_state(unsigned n) {
    SyncManager& s = sm[n];
    s.full = s.prod_open = s.cons_open = false;
    s.irq_write = s.irq_read = false;
    s.pending = s.pending_write = false;
    s.last_written = 3;
    s.user = 0;
    s.next = 1;
    s.free = 2;
    s.next_valid = false;
    sm_pending_mask = static_cast<uint16_t>(sm_pending_mask & ~(1u << n));
    sm_update_status(n);
}

void Esc::Impl::sm_update_status(unsigned n) {
    SyncManager& s = sm[n];
    const uint8_t st = static_cast<uint8_t>((s.irq_write ? 0x01 : 0) | (s.irq_read ? 0x02 : 0) |
                                            (s.full ? 0x08 : 0) | ((s.last_written & 0x03) << 4) |
                                            (s.cons_open ? 0x40 : 0) | (s.prod_open ? 0x80 : 0));
    regs[reg::kSm + 8 * n + 5] = st;
    // Events: the PDI is interested in what ECAT did and vice versa.
    const uint8_t ctrl = r8(static_cast<uint16_t>(reg::kSm + 8 * n + 4));
    const bool active = (r8(static_cast<uint16_t>(reg::kSm + 8 * n + 6)) & 0x01) && !s.pdi_disabled;
    const bool al = active && (ctrl & 0x20) && (s.ecat_writes ? s.irq_write : s.irq_read);
    const uint32_t albit = alev::kSm0 << n;
    if (al) {
        set_al_event(albit);
    } else {
        clear_al_event(albit);
    }
    if (n < 8) {
        const bool ec = active && (ctrl & 0x10) && (s.ecat_writes ? s.irq_read : s.irq_write);
        const uint16_t ecbit = static_cast<uint16_t>(ecev::kSm0 << n);
        if (ec) {
            set_ecat_event(ecbit);
        } else {
            clear_ecat_event(ecbit);
        }
    }
}

void Esc::Impl::sm_commit(unsigned n, bool write, Side side) {
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
        if (side == Side::Ecat && (s.control & 0x40)) wd_pd_trigger();
    } else {
        s.cons_open = false;
        if (s.mailbox) s.full = false;
        s.irq_read = true;
    }
    sm_update_status(n);
}

bool Esc::Impl::sm_access(unsigned n, uint32_t off, uint8_t* dst, const uint8_t* src, const uint8_t* bm,
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
        copy(mem(s.start));
        if (write) {
            s.irq_write = true;
            s.irq_read = false;
            if (side == Side::Ecat && (s.control & 0x40)) wd_pd_trigger();
        } else {
            s.irq_read = true;
            s.irq_write = false;
        }
        sm_update_status(n);
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
    copy(mem(s.start + buf + off));
    if (off + cnt == len) {
        if (side == Side::Ecat) {
            s.pending = true;
            s.pending_write = write;
            sm_pending_mask = static_cast<uint16_t>(sm_pending_mask | (1u << n));
        } else {
            sm_commit(n, write, side);
            return true;
        }
    }
    sm_update_status(n);
    return true;
}

void Esc::Impl::sm_activate_written(unsigned n, uint8_t value) {
    const uint16_t a = static_cast<uint16_t>(reg::kSm + 8 * n + 6);
    const uint8_t old = regs[a];
    const uint8_t v = static_cast<uint8_t>(value & 0xC3);
    regs[a] = v;
    set_al_event(alev::kSmActivation);
    if ((old ^ v) & 0x01) {
        lookup_dirty = true;
        sm_reset_state(n);
    }
}

void Esc::Impl::sm_pdi_control_written(unsigned n, uint8_t value) {
    const uint16_t a = static_cast<uint16_t>(reg::kSm + 8 * n + 7);
    SyncManager& s = sm[n];
    const bool deact = value & 0x01;
    regs[a] = static_cast<uint8_t>(value & 0x03);
    if (deact != s.pdi_disabled) {
        s.pdi_disabled = deact;
        sm_reset_state(n);
    }
}

}  // namespace esc
