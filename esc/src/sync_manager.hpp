#pragma once
// SyncManager unit: mailbox (1-buffer) and buffered (3-buffer) modes, both directions, both sides
// (ETG.1000.4 and ESC datasheet section I, SyncManager; registers 0x0800 + 8n).
#include <array>
#include <cstdint>
#include <span>

#include "memory.hpp"
#include "watchdog.hpp"

namespace esc {

struct SyncManager {
    // Decoded configuration (from the registers, refreshed by rebuild()).
    uint16_t start = 0;
    uint16_t length = 0;
    uint8_t control = 0;
    bool enabled = false;       // activate bit 0 and length > 0
    bool mailbox = false;       // control bits 1:0 == 10
    bool ecat_writes = false;   // direction: ECAT writes, PDI reads (control bits 3:2 == 01)
    bool area_valid = false;    // whole buffer area (3*length for buffered) inside the process RAM
    bool in_registers = false;  // starts in the register space: transparent, closed at its last byte
    // Run-time state.
    bool pdi_disabled = false;             // PDI control bit 0
    bool full = false;                     // mailbox full
    bool prod_open = false;                // producer opened a buffer (status bit 7)
    bool cons_open = false;                // consumer opened a buffer (status bit 6)
    bool irq_write = false;                // status bit 0
    bool irq_read = false;                 // status bit 1
    bool pending = false;                  // ECAT-side close waiting for the end of the frame
    bool pending_write = false;            // the pending close is a producer (write) close
    uint8_t last_written = 3;              // status bits 5:4
    uint8_t user = 0, next = 1, free = 2;  // 3-buffer roles
    bool next_valid = false;
};

struct SmArea {
    uint32_t start = 0;
    uint32_t end = 0;  // exclusive
    uint8_t sm = 0;
};

// An enabled SM that starts in the register space (below 0x1000): it captures no address, the bytes it
// covers keep their own rules (registers, RAM), and an access of its last byte closes it as the single-byte
// SM is closed (docs/decisions/esc.md, "SyncManager over the register space").
struct SmWatch {
    uint32_t last = 0;  // start + length - 1
    uint8_t sm = 0;
};

class SyncManagers {
  public:
    SyncManagers(Memory& m, Watchdogs& w, uint8_t count) : mem(m), wd(w), count_(count) {}

    // Power-on / ESC reset state of every SyncManager (registers already reset).
    void reset();
    // Re-decodes the configuration registers and the sorted list of enabled areas.
    void rebuild();
    // First enabled SM area overlapping [p, end), or nullptr.
    const SmArea* first_area(uint32_t p, uint32_t end) const {
        for (uint8_t k = 0; k < area_count_; ++k) {
            const SmArea& s = areas_[k];
            if (s.end > p && s.start < end) return &s;
        }
        return nullptr;
    }
    uint16_t length(unsigned n) const { return sm[n].length; }
    // The enabled SMs over the register space, for the access routing to close them.
    std::span<const SmWatch> register_sms() const { return {watches_.data(), watch_count_}; }
    // Access of the last byte of a transparent SM (single byte, or any SM over the register space) by one
    // side: status, events and the process-data watchdog as the datasheet gives them to the single-byte SM.
    void close_transparent(unsigned n, bool write, Side side);
    // Access of cnt bytes at offset off of SM n's area. Returns false if not accessible (direction, state).
    bool access(unsigned n, uint32_t off, uint8_t* dst, const uint8_t* src, const uint8_t* bm, uint32_t cnt,
                bool write, Side side);
    // ECAT write of the activate register (0x0806 + 8n). Returns true if the configuration changed.
    bool activate_written(unsigned n, uint8_t value);
    // PDI write of the PDI control register (0x0807 + 8n).
    void pdi_control_written(unsigned n, uint8_t value);
    // End of an ECAT frame: buffer closes of the frame take effect if it was correct. Returns true if a
    // buffer changed.
    bool end_of_frame(bool ok) { return pending_mask_ != 0 && commit_pending(ok); }

    // Lock rule E3: start, length and control of an SM enabled before the current datagram are read-only.
    // An SM the PDI deactivated (0x0807.0, what a slave stack does to SM0/SM1 when it enters INIT) is not
    // operating and takes a new configuration, as a master rewriting the mailbox for Bootstrap relies on
    // (docs/decisions/esc.md, "SM configuration after a PDI deactivation").
    uint16_t enabled_mask() const { return static_cast<uint16_t>(enabled_mask_ & ~pdi_disabled_mask_); }
    void set_lock_mask(uint16_t m) { lock_mask_ = m; }
    bool locked(unsigned n) const { return lock_mask_ & (1u << n); }

    // Asks for the cache lines a frame reads here (counts, masks, the first areas and the state of SMs 0-3)
    // without waiting for them (Esc::prefetch); reads nothing.
    void prefetch() const;

  private:
    uint16_t pdi_disabled_mask_ = 0;
    bool commit_pending(bool ok);
    void reset_state(unsigned n);
    void commit(unsigned n, bool write, Side side);
    void update_status(unsigned n);

    // What every frame reads first (the counts and masks, then the areas of the enabled SMs), side by side
    // in the first cache lines; the SMs' own state after them.
    Memory& mem;
    Watchdogs& wd;
    uint8_t count_ = 0;
    uint8_t area_count_ = 0;
    uint8_t watch_count_ = 0;
    uint16_t enabled_mask_ = 0;       // activate bit 0 of every SM
    uint16_t pending_mask_ = 0;       // SMs with a close waiting for the end of the frame
    uint16_t lock_mask_ = 0;          // SMs enabled before the current datagram
    std::array<SmArea, 16> areas_{};  // enabled SMs' areas sorted by start
    std::array<SyncManager, 16> sm{};
    std::array<SmWatch, 16> watches_{};  // enabled SMs over the register space
};

}  // namespace esc
