#pragma once
// Internal state of the emulated ESC. Not a public header: only esc/src/*.cpp include it.
#include <array>
#include <cstdint>
#include <functional>
#include <mutex>
#include <vector>

#include "esc/esc.hpp"

namespace esc {

namespace reg {
constexpr uint16_t kType = 0x0000;
constexpr uint16_t kStationAddress = 0x0010;
constexpr uint16_t kStationAlias = 0x0012;
constexpr uint16_t kRegWriteEnable = 0x0020;
constexpr uint16_t kRegWriteProtect = 0x0021;
constexpr uint16_t kEscWriteEnable = 0x0030;
constexpr uint16_t kEscWriteProtect = 0x0031;
constexpr uint16_t kEscResetEcat = 0x0040;
constexpr uint16_t kEscResetPdi = 0x0041;
constexpr uint16_t kDlControl = 0x0100;
constexpr uint16_t kDlStatus = 0x0110;
constexpr uint16_t kAlControl = 0x0120;
constexpr uint16_t kAlStatus = 0x0130;
constexpr uint16_t kAlStatusCode = 0x0134;
constexpr uint16_t kPdiControl = 0x0140;
constexpr uint16_t kEscConfig = 0x0141;
constexpr uint16_t kPdiConfig = 0x0150;
constexpr uint16_t kSyncLatchConfig = 0x0151;
constexpr uint16_t kExtPdiConfig = 0x0152;
constexpr uint16_t kEcatEventMask = 0x0200;
constexpr uint16_t kAlEventMask = 0x0204;
constexpr uint16_t kEcatEvent = 0x0210;
constexpr uint16_t kAlEvent = 0x0220;
constexpr uint16_t kInvalidFrameCounter = 0x0300;
constexpr uint16_t kProcessingUnitErrors = 0x030C;
constexpr uint16_t kWdDivider = 0x0400;
constexpr uint16_t kWdTimePdi = 0x0410;
constexpr uint16_t kWdTimePd = 0x0420;
constexpr uint16_t kWdStatusPd = 0x0440;
constexpr uint16_t kWdCounterPd = 0x0442;
constexpr uint16_t kWdCounterPdi = 0x0443;
constexpr uint16_t kSiiConfig = 0x0500;
constexpr uint16_t kSiiPdiAccess = 0x0501;
constexpr uint16_t kSiiControl = 0x0502;
constexpr uint16_t kSiiAddress = 0x0504;
constexpr uint16_t kSiiData = 0x0508;
constexpr uint16_t kFmmu = 0x0600;
constexpr uint16_t kSm = 0x0800;
constexpr uint16_t kDcRecvTime0 = 0x0900;
constexpr uint16_t kDcSystemTime = 0x0910;
constexpr uint16_t kDcRecvTimePu = 0x0918;
constexpr uint16_t kDcOffset = 0x0920;
constexpr uint16_t kDcDelay = 0x0928;
constexpr uint16_t kDcDiff = 0x092C;
constexpr uint16_t kDcSpeedStart = 0x0930;
constexpr uint16_t kDcSpeedDiff = 0x0932;
constexpr uint16_t kDcFilterDiff = 0x0934;
constexpr uint16_t kDcFilterSpeed = 0x0935;
constexpr uint16_t kDcCyclicControl = 0x0980;
constexpr uint16_t kDcActivation = 0x0981;
constexpr uint16_t kDcPulseLength = 0x0982;
constexpr uint16_t kDcActivationStatus = 0x0984;
constexpr uint16_t kDcSync0Status = 0x098E;
constexpr uint16_t kDcSync1Status = 0x098F;
constexpr uint16_t kDcStartTime = 0x0990;
constexpr uint16_t kDcNextSync1 = 0x0998;
constexpr uint16_t kDcSync0Cycle = 0x09A0;
constexpr uint16_t kDcSync1Cycle = 0x09A4;
constexpr uint16_t kDcLatch0Control = 0x09A8;
constexpr uint16_t kDcLatch1Control = 0x09A9;
constexpr uint16_t kDcLatch0Status = 0x09AE;
constexpr uint16_t kDcLatchTimes = 0x09B0;
constexpr uint16_t kDcEcatBufferChange = 0x09F0;
constexpr uint16_t kUserRam = 0x0F80;
constexpr uint32_t kRamBase = 0x1000;
}  // namespace reg

// AL event request bits (0x0220).
namespace alev {
constexpr uint32_t kAlControl = 1u << 0;
constexpr uint32_t kDcLatch = 1u << 1;
constexpr uint32_t kSync0 = 1u << 2;
constexpr uint32_t kSync1 = 1u << 3;
constexpr uint32_t kSmActivation = 1u << 4;
constexpr uint32_t kEepromEmulation = 1u << 5;
constexpr uint32_t kWatchdogPd = 1u << 6;
constexpr uint32_t kSm0 = 1u << 8;
}  // namespace alev

// ECAT event request bits (0x0210).
namespace ecev {
constexpr uint16_t kDcLatch = 1u << 0;
constexpr uint16_t kDlStatus = 1u << 2;
constexpr uint16_t kAlStatus = 1u << 3;
constexpr uint16_t kSm0 = 1u << 4;
}  // namespace ecev

enum class Side : uint8_t { Ecat, Pdi };

// Handling class of one register byte (per side).
enum RegKind : uint8_t {
    kRo = 0,   // read-only from this side
    kPlain,    // stored through the write mask, no side effect
    kSpecial,  // stored by a handler after the byte loop
};

struct SyncManager {
    // Decoded configuration (from the registers, refreshed by rebuild_lookup()).
    uint16_t start = 0;
    uint16_t length = 0;
    uint8_t control = 0;
    bool enabled = false;      // activate bit 0 and length > 0
    bool mailbox = false;      // control bits 1:0 == 10
    bool ecat_writes = false;  // direction: ECAT writes, PDI reads (control bits 3:2 == 01)
    bool area_valid = false;   // whole buffer area (3*length for buffered) inside the memory
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

struct FmmuMap {
    uint64_t lbit_start = 0;  // first mapped logical bit (absolute bit address)
    uint64_t lbit_end = 0;    // one past the last mapped logical bit
    uint64_t pbit_start = 0;  // physical bit of lbit_start
    bool read = false;
    bool write = false;
};

struct SmArea {
    uint32_t start = 0;
    uint32_t end = 0;  // exclusive
    uint8_t sm = 0;
};

struct Esc::Impl {
    Impl(const EscConfig& c, const Clock& clk);

    // ---------------------------------------------------------------- configuration & storage
    EscConfig cfg;
    const Clock& clock;
    mutable std::mutex mu;
    std::array<uint8_t, 0x1000> regs{};
    std::vector<uint8_t> ram;  // process RAM, fixed size at construction
    uint32_t mem_end = reg::kRamBase;
    uint8_t fmmu_count = 0;
    uint8_t sm_count = 0;
    std::array<uint8_t, 0x1000> ecat_kind{}, pdi_kind{};
    std::array<uint8_t, 0x1000> ecat_wmask{}, pdi_wmask{};

    // ---------------------------------------------------------------- derived lookups
    std::array<SyncManager, 16> sm{};
    std::array<FmmuMap, 16> fmmu_map{};
    uint8_t fmmu_active = 0;
    std::array<SmArea, 16> sm_areas{};  // enabled SMs' areas sorted by start
    uint8_t sm_area_count = 0;
    uint16_t sm_enabled_mask = 0;  // activate bit 0 of every SM (lock rule E3)
    bool lookup_dirty = false;

    // ---------------------------------------------------------------- frame-scoped state
    uint64_t frame_clock = 0;             // Clock time of the frame being processed
    uint64_t frame_local = 0;             // DC local time of that frame
    bool frame_write_enable = false;      // 0x0020 written with bit 0 in this frame
    bool frame_esc_write_enable = false;  // 0x0030 likewise
    bool reset_written_this_frame = false;
    uint16_t sm_pending_mask = 0;
    uint16_t sm_lock_mask = 0;  // SMs enabled before the current datagram (E3 lock rule)
    bool in_frame = false;
    bool eeprom_pending = false;
    bool dc_latch_pending = false;
    std::array<uint8_t, 2048> scratch_a{}, scratch_b{}, scratch_ok{}, lrw_src{};

    // ---------------------------------------------------------------- ESC reset sequences
    uint8_t reset_progress_ecat = 0;
    uint8_t reset_progress_pdi = 0;

    // ---------------------------------------------------------------- EEPROM
    std::vector<uint8_t> eeprom;
    std::function<void(uint16_t, uint16_t)> on_eeprom_write;
    struct EepromWrite {
        uint16_t address;
        uint16_t value;
    };
    std::array<EepromWrite, 4> eeprom_writes{};
    uint8_t eeprom_write_count = 0;

    // ---------------------------------------------------------------- DC
    uint64_t clock_anchor = 0;  // Clock time where the local time mapping was last re-anchored
    uint64_t local_anchor = 0;  // local time at clock_anchor
    double rate = 0.0;          // fractional rate correction of the local time (-1e-4 = 100 ppm slower)
    double rate_integral = 0.0;
    bool dc_have_prev = false;
    uint64_t dc_prev_local = 0;
    bool dc_filter_primed = false;
    double dc_diff_filtered = 0.0;
    double dc_speed_filtered = 0.0;
    bool sync_running = false;  // 0x0981 bit 0 and the generation started
    bool sync0_armed = false;   // a SYNC0 pulse is scheduled at next_sync0
    bool sync1_armed = false;
    uint64_t next_sync0 = 0;  // system time
    uint64_t next_sync1 = 0;
    uint64_t last_sync0 = 0;
    uint64_t last_sync1 = 0;
    bool sync0_ack = false;  // 0x098E bit 0 latched (acknowledge mode)
    bool sync1_ack = false;

    // ---------------------------------------------------------------- watchdogs
    bool pd_wd_armed = false;
    uint64_t pd_wd_last = 0;  // Clock time of the last trigger
    bool pdi_wd_armed = false;
    bool pdi_touched = false;
    uint64_t pdi_wd_last = 0;

    EscStats stats{};

    // ---------------------------------------------------------------- functions
    void init_tables();
    void reset_registers();
    void load_eeprom_words(bool power_on);
    void rebuild_lookup();

    // Register access helpers (raw, no side effects).
    uint8_t r8(uint16_t a) const { return regs[a]; }
    uint16_t r16(uint16_t a) const { return static_cast<uint16_t>(regs[a] | (regs[a + 1] << 8)); }
    uint32_t r32(uint16_t a) const {
        return static_cast<uint32_t>(r16(a)) | (static_cast<uint32_t>(r16(a + 2)) << 16);
    }
    uint64_t r64(uint16_t a) const {
        return static_cast<uint64_t>(r32(a)) | (static_cast<uint64_t>(r32(a + 4)) << 32);
    }
    void w8(uint16_t a, uint8_t v) { regs[a] = v; }
    void w16(uint16_t a, uint16_t v) {
        regs[a] = static_cast<uint8_t>(v);
        regs[a + 1] = static_cast<uint8_t>(v >> 8);
    }
    void w32(uint16_t a, uint32_t v) {
        w16(a, static_cast<uint16_t>(v));
        w16(a + 2, static_cast<uint16_t>(v >> 16));
    }
    void w64(uint16_t a, uint64_t v) {
        w32(a, static_cast<uint32_t>(v));
        w32(a + 4, static_cast<uint32_t>(v >> 32));
    }
    uint8_t* mem(uint32_t a) { return a < reg::kRamBase ? &regs[a] : &ram[a - reg::kRamBase]; }
    void set_al_event(uint32_t bits) { w32(reg::kAlEvent, r32(reg::kAlEvent) | bits); }
    void clear_al_event(uint32_t bits) { w32(reg::kAlEvent, r32(reg::kAlEvent) & ~bits); }
    void set_ecat_event(uint16_t bits) {
        w16(reg::kEcatEvent, static_cast<uint16_t>(r16(reg::kEcatEvent) | bits));
    }
    void clear_ecat_event(uint16_t bits) {
        w16(reg::kEcatEvent, static_cast<uint16_t>(r16(reg::kEcatEvent) & ~bits));
    }
    void count_error(uint16_t a) {
        if (regs[a] != 0xFF) ++regs[a];
    }

    void flush_callbacks(std::unique_lock<std::mutex>& lock);  // EEPROM write callbacks, outside the lock

    // Frame processing.
    bool process(std::span<uint8_t> frame, uint64_t rx_clock);
    void end_of_frame(bool ok);
    void datagram(uint8_t* hdr, uint8_t* data, uint16_t len);

    // Physical memory access (whole address space: registers, RAM, SM areas). Return true if any byte
    // was accessible. read: inaccessible bytes of dst are left untouched, ok[] (optional) marks accessible
    // bytes. write: bm (optional) is a per-byte bit mask of the bits to write.
    bool phys_read(uint32_t a, uint8_t* dst, uint8_t* ok, uint32_t n, Side side);
    bool phys_write(uint32_t a, const uint8_t* src, const uint8_t* bm, uint32_t n, Side side);
    void reg_read(uint16_t a, uint8_t* dst, uint32_t n, Side side);
    bool reg_write(uint16_t a, const uint8_t* src, const uint8_t* bm, uint32_t n, Side side);
    void reg_special_write(uint16_t a, uint16_t e, const uint8_t* src, const uint8_t* bm, Side side);
    uint64_t merged(uint16_t reg_addr, unsigned size, uint16_t a, uint16_t e, const uint8_t* src,
                    const uint8_t* bm) const;
    bool overlaps(uint16_t a, uint16_t e, uint16_t ra, unsigned size) const {
        return a < ra + size && ra < e;
    }

    // SyncManagers.
    bool sm_access(unsigned n, uint32_t off, uint8_t* dst, const uint8_t* src, const uint8_t* bm,
                   uint32_t cnt, bool write, Side side);
    void sm_reset_state(unsigned n);
    void sm_commit(unsigned n, bool write, Side side);
    void sm_update_status(unsigned n);
    void sm_activate_written(unsigned n, uint8_t value);
    void sm_pdi_control_written(unsigned n, uint8_t value);

    // FMMUs / logical addressing. Returns the WKC increment.
    uint16_t logical(uint8_t cmd, uint32_t la, uint8_t* data, uint16_t len);
    bool fmmu_read(const FmmuMap& f, uint64_t b0, uint64_t b1, uint32_t la, uint8_t* data);
    bool fmmu_write(const FmmuMap& f, uint64_t b0, uint64_t b1, uint32_t la, const uint8_t* data);

    // EEPROM.
    uint16_t eeprom_word(uint64_t word) const;
    void eeprom_execute(Side side);
    bool eeprom_crc_ok() const;

    // DC and watchdogs.
    uint64_t local_at(uint64_t clock_ns) const;
    uint64_t clock_at_local(uint64_t local) const;
    void set_rate(double new_rate, uint64_t at_clock);
    void dc_system_time_written(uint32_t received);
    void dc_reset_filters();
    void dc_activation_written(uint8_t old_value, uint8_t value);
    void dc_start_time_written(bool only_low32);
    void dc_run(uint64_t now_clock);
    void dc_fire_sync0(uint64_t t);
    void dc_fire_sync1(uint64_t t);
    void dc_update_readback();
    uint64_t wd_increment_ns() const { return (static_cast<uint64_t>(r16(reg::kWdDivider)) + 2) * 40; }
    void wd_pd_trigger();
    void wd_run(uint64_t now_clock);
    uint64_t next_event() const;
    void pdi_touch() { pdi_touched = true; }
    uint64_t cur_clock() const { return in_frame ? frame_clock : clock.now_ns(); }
    uint64_t cur_local() const { return in_frame ? frame_local : local_at(clock.now_ns()); }
};

uint8_t sii_crc8(const uint8_t* data, std::size_t n);

}  // namespace esc
