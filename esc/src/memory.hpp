#pragma once
// The ESC's memory unit: the register space 0x0000-0x0FFF and the process RAM from 0x1000, with raw
// little-endian access (no side effects) and the event request registers (0x0210, 0x0220). Register
// addresses and event bits: esc/wire/registers.hpp (esc_wire).
#include <array>
#include <cstdint>
#include <vector>

#include "esc/wire/registers.hpp"
#include "util/le.hpp"

namespace esc {

enum class Side : uint8_t { Ecat, Pdi };

// Handling class of one register byte (per side).
enum RegKind : uint8_t {
    kRo = 0,   // read-only from this side
    kPlain,    // stored through the write mask, no side effect
    kSpecial,  // stored by a handler after the byte loop
};

// DL control byte 1: the loop setting of each port (2 bits per port; ports.hpp).
constexpr uint16_t kDlControlLoop = 0x0101;

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
    uint16_t r16(uint16_t a) const { return util::get16(&regs[a]); }
    uint32_t r32(uint16_t a) const { return util::get32(&regs[a]); }
    uint64_t r64(uint16_t a) const { return util::get64(&regs[a]); }
    void w8(uint16_t a, uint8_t v) { regs[a] = v; }
    void w16(uint16_t a, uint16_t v) { util::put16(&regs[a], v); }
    void w32(uint16_t a, uint32_t v) { util::put32(&regs[a], v); }
    void w64(uint16_t a, uint64_t v) { util::put64(&regs[a], v); }
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
