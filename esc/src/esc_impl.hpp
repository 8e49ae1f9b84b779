#pragma once
// Internal state of the emulated ESC. Not a public header: only esc/src/*.cpp include it.
// Esc::Impl composes the units, each owning its state: memory (registers + process RAM, memory.hpp),
// SyncManagers (sync_manager.hpp), FMMUs (fmmu.hpp), distributed clocks (dc.hpp), SII EEPROM interface
// (sii_interface.hpp), watchdogs (watchdog.hpp), ports (ports.hpp). Impl itself keeps what spans units: frame
// and datagram processing (esc.cpp), the register access rules of both sides and the routing of physical
// accesses over registers, SyncManager areas and RAM (access.cpp), AL control, the write enables and the ESC
// reset.
#include <array>
#include <cstdint>
#include "dc.hpp"
#include "esc/esc.hpp"
#include "esc_lock.hpp"
#include "fmmu.hpp"
#include "frame_time.hpp"
#include "memory.hpp"
#include "ports.hpp"
#include "sii_interface.hpp"
#include "sync_manager.hpp"
#include "watchdog.hpp"

namespace esc {

struct Esc::Impl final {
    Impl(const EscConfig& c, const Clock& clk);

    // ---------------------------------------------------------------- configuration
    EscConfig cfg;  // counts and RAM size clamped to what the address space holds
    mutable EscLock mu{cfg.thread_safe};
    // Handling class and write mask of each register byte, per side (RegKind). A function of the FMMU and
    // SM counts alone: one set for every ESC of that configuration (register_tables()), so the 16 KiB
    // are read from the cache, not once per ESC of a line.
    struct RegTables {
        std::array<uint8_t, 0x1000> ecat_kind{}, pdi_kind{};
        std::array<uint8_t, 0x1000> ecat_wmask{}, pdi_wmask{};
    };
    static const RegTables& register_tables(uint8_t fmmu_count, uint8_t sm_count);
    const RegTables& tables{register_tables(cfg.fmmu_count, cfg.sm_count)};

    // ---------------------------------------------------------------- units
    Memory mem;
    FrameTime time;
    Watchdogs wd{mem, time};
    SyncManagers sm{mem, wd, cfg.sm_count};
    Fmmus fmmu{mem, cfg.fmmu_count};
    DistributedClocks dc{mem, time, cfg};
    Ports ports{mem, cfg.port_descriptor};
    SiiInterface sii{mem, cfg.faults};
    bool lookup_dirty = false;  // SM / FMMU configuration written: rebuild their decoded state

    // ---------------------------------------------------------------- frame-scoped state
    bool frame_write_enable = false;      // 0x0020 written with bit 0 in this frame
    bool frame_esc_write_enable = false;  // 0x0030 likewise
    bool reset_written_this_frame = false;

    // ---------------------------------------------------------------- ESC reset sequences
    uint8_t reset_progress_ecat = 0;
    uint8_t reset_progress_pdi = 0;

    EscStats stats{};

    // ---------------------------------------------------------------- signals (EscSignals)
    EscSignals own_signals{};
    EscSignals* sig = &own_signals;
    // An ECAT write reached the watchdog, SII, FMMU, SM or DC registers (0x0400-0x09FF) or the ESC was reset
    // in this frame: its timers may have moved (EscSignals::due_ns unknown after the frame).
    bool timers_touched = false;
    // An ECAT write reached only the DC time registers (0x0900-0x097F) in this frame: the due time moves
    // only if a SYNC pulse is scheduled.
    bool dc_time_touched = false;

    // ---------------------------------------------------------------- functions
    static void init_tables(RegTables& t, uint8_t fmmu_count, uint8_t sm_count);
    void reset_registers();
    void rebuild_lookup();

    // Frame processing.
    int receive(std::span<uint8_t> frame, int port, uint64_t rx_clock, FrameCheck* check);
    // receive(), the EscSignals kept, the EEPROM write callbacks called (outside the lock).
    int receive_signalled(std::span<uint8_t> frame, int port, uint64_t rx_clock, FrameCheck* check,
                          std::unique_lock<EscLock>& lock);
    // What became of a frame at the processing unit: forwarded (processed or not), destroyed, or forwarded
    // with a frame error (hardware aborts it with a bad FCS and the forwarded-error marking).
    enum class Outcome { Forward, Destroy, Error };
    Outcome process(std::span<uint8_t> frame, int port, uint64_t rx_clock);
    void end_of_frame(bool ok);
    void datagram(uint8_t* hdr, uint8_t* data, uint16_t len);

    // Physical memory access (whole address space: registers, RAM, SM areas). Return true if any byte
    // was accessible. read: inaccessible bytes of dst are left untouched, ok[] (optional) marks accessible
    // bytes. write: bm (optional) is a per-byte bit mask of the bits to write.
    bool phys_read(uint32_t a, uint8_t* dst, uint8_t* ok, uint32_t n, Side side);
    bool phys_write(uint32_t a, const uint8_t* src, const uint8_t* bm, uint32_t n, Side side);
    // An access [a, end) of one side reached the last byte of an SM over the register space: close it.
    void close_register_sms(uint32_t a, uint32_t end, bool write, Side side);
    // Write protection of an ECAT write (0x0020/0x0030 and their enables of this frame); the PDI writes
    // freely.
    bool reg_write_protected(Side side) const {
        return side == Side::Ecat && (mem.regs[reg::kRegWriteProtect] & 0x01) && !frame_write_enable;
    }
    bool esc_write_protected(Side side) const {
        return side == Side::Ecat && (mem.regs[reg::kEscWriteProtect] & 0x01) && !frame_esc_write_enable;
    }
    // A register byte a protected write does not reach (the enables themselves and, for the register
    // protection, the user RAM from 0x0F80 stay writable).
    static bool write_blocked(uint16_t addr, bool esc_prot, bool reg_prot) {
        if (esc_prot && addr != reg::kEscWriteEnable) return true;
        return reg_prot && addr < reg::kUserRam && addr != reg::kRegWriteEnable &&
               addr != reg::kEscWriteEnable;
    }
    void reg_read(uint16_t a, uint8_t* dst, uint32_t n, Side side);
    bool reg_write(uint16_t a, const uint8_t* src, const uint8_t* bm, uint32_t n, Side side);
    void reg_special_write(uint16_t a, uint16_t e, const uint8_t* src, const uint8_t* bm, Side side);
    uint64_t merged(uint16_t reg_addr, unsigned size, uint16_t a, uint16_t e, const uint8_t* src,
                    const uint8_t* bm) const;

    uint64_t next_event(uint64_t now_clock) const;
    // EscSignals::due_ns at now_clock: next_event(), or now while a watchdog status bit has to settle.
    uint64_t due(uint64_t now_clock) const;
    // The masked AL event request (what the PDI interrupt line shows).
    uint32_t masked_events() const { return mem.r32(reg::kAlEvent) & mem.r32(reg::kAlEventMask); }
    // After a frame or a tick: wake when a masked event rose that was not up before (events_before).
    void note_events(uint32_t events_before) {
        if ((masked_events() & ~events_before) != 0) sig->wake = 1;
    }
};

}  // namespace esc
