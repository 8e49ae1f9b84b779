#pragma once
// The ESC's memory unit: the register space 0x0000-0x0FFF and the process RAM from 0x1000, with raw
// little-endian access (no side effects) and the event request registers (0x0210, 0x0220). The register
// addresses and event bits are those of the ESC datasheet (section II, register description).
#include <array>
#include <cstdint>
#include <vector>

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

// True if [a, e) overlaps the register [ra, ra + size).
inline bool overlaps(uint16_t a, uint16_t e, uint16_t ra, unsigned size) {
    return a < ra + size && ra < e;
}

struct Memory {
    explicit Memory(uint32_t ram_kib);

    std::array<uint8_t, 0x1000> regs{};
    std::vector<uint8_t> ram;  // process RAM, fixed size at construction
    uint32_t ram_end = reg::kRamBase;

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
    // The byte at physical address a (register or RAM; the caller checked a < ram_end).
    uint8_t* at(uint32_t a) { return a < reg::kRamBase ? &regs[a] : &ram[a - reg::kRamBase]; }
    void set_al_event(uint32_t bits) { w32(reg::kAlEvent, r32(reg::kAlEvent) | bits); }
    void clear_al_event(uint32_t bits) { w32(reg::kAlEvent, r32(reg::kAlEvent) & ~bits); }
    void set_ecat_event(uint16_t bits) {
        w16(reg::kEcatEvent, static_cast<uint16_t>(r16(reg::kEcatEvent) | bits));
    }
    void clear_ecat_event(uint16_t bits) {
        w16(reg::kEcatEvent, static_cast<uint16_t>(r16(reg::kEcatEvent) & ~bits));
    }
    // Error counters (0x0300-0x0313, 0x0442/0x0443) saturate at 0xFF.
    void count_error(uint16_t a) {
        if (regs[a] != 0xFF) ++regs[a];
    }
};

}  // namespace esc
