#pragma once
// FMMU unit: bit-exact mapping of logical addresses (LRD/LWR/LRW) onto the physical memory
// (ETG.1000.4 and ESC datasheet section I, FMMU; registers 0x0600 + 16n).
#include <algorithm>
#include <array>
#include <concepts>
#include <cstdint>
#include <cstring>

#include "esc/wire/datagram.hpp"
#include "memory.hpp"

namespace esc {

// The physical memory as the FMMUs reach it (registers, RAM and SyncManager areas, ECAT side rules).
// read: inaccessible bytes of dst are left untouched, ok[] (optional) marks accessible bytes.
// write: bm (optional) is a per-byte bit mask of the bits to write. Both return true if any byte was
// accessible. A concept rather than a virtual interface: Fmmus calls the concrete type (Esc::Impl) directly,
// as the LRW hot path runs four such accesses per datagram.
template <class P>
concept PhysicalMemory = requires(P& p, uint32_t a, uint8_t* d, const uint8_t* s, uint32_t n, Side side) {
    { p.phys_read(a, d, d, n, side) } -> std::same_as<bool>;
    { p.phys_write(a, s, s, n, side) } -> std::same_as<bool>;
};

// Work areas of one datagram's processing (the largest datagram fits: its length field has 11 bits). One set
// per thread, shared by every ESC the thread serves: an ESC never processes two datagrams at once, and a
// runtime serving a line of 100 ESCs keeps one set in its cache instead of 100 (each ESC's own scratch was
// 14 KiB of memory that every walk of a frame touched afresh).
struct DatagramScratch {
    std::array<uint8_t, 2048> a, b, ok, src;
};
inline DatagramScratch& datagram_scratch() {
    thread_local DatagramScratch s;
    return s;
}

struct FmmuMap {
    uint64_t lbit_start = 0;  // first mapped logical bit (absolute bit address)
    uint64_t lbit_end = 0;    // one past the last mapped logical bit
    uint64_t pbit_start = 0;  // physical bit of lbit_start
    bool read = false;
    bool write = false;
};

class Fmmus {
  public:
    Fmmus(const Memory& m, uint8_t count) : mem(m), count_(count) {}
    // Re-decodes the FMMU registers into the active mappings.
    void rebuild();
    // Executes LRD, LWR or LRW of len bytes at logical address la on data in place, on the physical
    // memory phys. Returns the working-counter increment.
    template <PhysicalMemory P>
    uint16_t logical(P& phys, Command cmd, uint32_t la, uint8_t* data, uint16_t len);
    // Ask for the cache lines a logical datagram reads here without waiting for them (Esc::prefetch): the
    // count and the first mappings (reads nothing); the process RAM the active mappings map, with room for a
    // 3-buffer SyncManager behind each (reads the mappings: after prefetch_state() had time to work).
    void prefetch_state() const;
    void prefetch_ram(const Memory& m) const;

  private:
    template <PhysicalMemory P>
    bool read(P& phys, const FmmuMap& f, uint64_t b0, uint64_t b1, uint32_t la, uint8_t* data);
    template <PhysicalMemory P>
    bool write(P& phys, const FmmuMap& f, uint64_t b0, uint64_t b1, uint32_t la, const uint8_t* data);

    const Memory& mem;
    uint8_t count_ = 0;
    uint8_t active_ = 0;  // before the maps: a frame reads it with the first of them, in one cache line
    std::array<FmmuMap, 16> map_{};
};

// Mask of the bits [lo, hi] (inclusive) of a byte.
inline uint8_t fmmu_bit_mask(unsigned lo, unsigned hi) {
    return static_cast<uint8_t>((0xFFu << lo) & (0xFFu >> (7 - hi)));
}

template <PhysicalMemory P>
uint16_t Fmmus::logical(P& phys, Command cmd, uint32_t la, uint8_t* data, uint16_t len) {
    if (len == 0) return 0;
    const uint64_t b0 = static_cast<uint64_t>(la) * 8;
    const uint64_t b1 = b0 + static_cast<uint64_t>(len) * 8;
    const bool do_read = cmd != Command::LWR;   // LRD, LRW
    const bool do_write = cmd != Command::LRD;  // LWR, LRW
    const uint8_t* wsrc = data;
    if (do_read && do_write) {
        // Writes take the incoming data, reads happen first: the bytes a write FMMU takes are kept (at their
        // offsets in the datagram; nothing else of the copy is read).
        uint8_t* src = datagram_scratch().src.data();
        for (uint8_t k = 0; k < active_; ++k) {
            const FmmuMap& f = map_[k];
            if (!f.write) continue;
            const uint64_t i0 = std::max(b0, f.lbit_start), i1 = std::min(b1, f.lbit_end);
            if (i0 >= i1) continue;
            const uint64_t j0 = (i0 >> 3) - la, j1 = ((i1 - 1) >> 3) - la;
            std::memcpy(src + j0, data + j0, j1 - j0 + 1);
        }
        wsrc = src;
    }
    bool any_r = false, any_w = false;
    if (do_read) {
        for (uint8_t k = 0; k < active_; ++k) {
            const FmmuMap& f = map_[k];
            if (!f.read) continue;
            const uint64_t i0 = std::max(b0, f.lbit_start), i1 = std::min(b1, f.lbit_end);
            if (i0 < i1 && read(phys, f, i0, i1, la, data)) any_r = true;
        }
    }
    if (do_write) {
        const uint8_t count = active_;  // a write may reconfigure FMMUs: use this datagram's set
        for (uint8_t k = 0; k < count; ++k) {
            const FmmuMap f = map_[k];
            if (!f.write) continue;
            const uint64_t i0 = std::max(b0, f.lbit_start), i1 = std::min(b1, f.lbit_end);
            if (i0 < i1 && write(phys, f, i0, i1, la, wsrc)) any_w = true;
        }
    }
    if (cmd == Command::LRD) return any_r ? 1 : 0;
    if (cmd == Command::LWR) return any_w ? 1 : 0;
    return static_cast<uint16_t>((any_r ? 1 : 0) + (any_w ? 2 : 0));
}

template <PhysicalMemory P>
bool Fmmus::read(P& phys, const FmmuMap& f, uint64_t i0, uint64_t i1, uint32_t la, uint8_t* data) {
    const uint64_t pb0 = f.pbit_start + (i0 - f.lbit_start);
    const uint64_t nbits = i1 - i0;
    const uint64_t pa0 = pb0 >> 3;
    const uint64_t pa1 = (pb0 + nbits - 1) >> 3;
    if (pa0 >= 0x10000) return false;
    const uint32_t np = static_cast<uint32_t>(std::min<uint64_t>(pa1, 0xFFFF) - pa0 + 1);
    DatagramScratch& sc = datagram_scratch();
    uint8_t* scratch_a = sc.a.data();
    uint8_t* scratch_ok = sc.ok.data();
    std::memset(scratch_ok, 0, np);
    if (!phys.phys_read(static_cast<uint32_t>(pa0), scratch_a, scratch_ok, np, Side::Ecat)) return false;
    const uint64_t lbyte0 = i0 >> 3, lbyte1 = (i1 - 1) >> 3;
    if (((pb0 ^ i0) & 7) == 0) {
        // Same bit position in logical and physical bytes: byte-wise with edge masks.
        for (uint64_t j = lbyte0; j <= lbyte1; ++j) {
            const uint64_t k = j - lbyte0;
            if (k >= np || !scratch_ok[k]) continue;
            const unsigned lo = j == lbyte0 ? static_cast<unsigned>(i0 & 7) : 0;
            const unsigned hi = j == lbyte1 ? static_cast<unsigned>((i1 - 1) & 7) : 7;
            const uint8_t m = fmmu_bit_mask(lo, hi);
            uint8_t& d = data[j - la];
            d = static_cast<uint8_t>((d & ~m) | (scratch_a[k] & m));
        }
        return true;
    }
    for (uint64_t t = 0; t < nbits; ++t) {
        const uint64_t pbit = pb0 + t, lbit = i0 + t;
        const uint64_t k = (pbit >> 3) - pa0;
        if (k >= np || !scratch_ok[k]) continue;
        const uint8_t bit = static_cast<uint8_t>(1u << (lbit & 7));
        uint8_t& d = data[(lbit >> 3) - la];
        if ((scratch_a[k] >> (pbit & 7)) & 1) {
            d = static_cast<uint8_t>(d | bit);
        } else {
            d = static_cast<uint8_t>(d & ~bit);
        }
    }
    return true;
}

template <PhysicalMemory P>
bool Fmmus::write(P& phys, const FmmuMap& f, uint64_t i0, uint64_t i1, uint32_t la, const uint8_t* data) {
    const uint64_t pb0 = f.pbit_start + (i0 - f.lbit_start);
    const uint64_t nbits = i1 - i0;
    const uint64_t pa0 = pb0 >> 3;
    const uint64_t pa1 = (pb0 + nbits - 1) >> 3;
    if (pa0 >= 0x10000) return false;
    const uint32_t np = static_cast<uint32_t>(std::min<uint64_t>(pa1, 0xFFFF) - pa0 + 1);
    DatagramScratch& sc = datagram_scratch();
    uint8_t* scratch_a = sc.a.data();
    uint8_t* scratch_b = sc.b.data();
    std::memset(scratch_b, 0, np);  // bit masks
    const uint64_t lbyte0 = i0 >> 3, lbyte1 = (i1 - 1) >> 3;
    if (((pb0 ^ i0) & 7) == 0) {
        for (uint64_t j = lbyte0; j <= lbyte1; ++j) {
            const uint64_t k = j - lbyte0;
            if (k >= np) break;
            const unsigned lo = j == lbyte0 ? static_cast<unsigned>(i0 & 7) : 0;
            const unsigned hi = j == lbyte1 ? static_cast<unsigned>((i1 - 1) & 7) : 7;
            scratch_b[k] = fmmu_bit_mask(lo, hi);
            scratch_a[k] = data[j - la];
        }
    } else {
        std::memset(scratch_a, 0, np);
        for (uint64_t t = 0; t < nbits; ++t) {
            const uint64_t pbit = pb0 + t, lbit = i0 + t;
            const uint64_t k = (pbit >> 3) - pa0;
            if (k >= np) break;
            const uint8_t pm = static_cast<uint8_t>(1u << (pbit & 7));
            scratch_b[k] = static_cast<uint8_t>(scratch_b[k] | pm);
            if ((data[(lbit >> 3) - la] >> (lbit & 7)) & 1)
                scratch_a[k] = static_cast<uint8_t>(scratch_a[k] | pm);
        }
    }
    return phys.phys_write(static_cast<uint32_t>(pa0), scratch_a, scratch_b, np, Side::Ecat);
}

}  // namespace esc
