// FMMU unit (fmmu.hpp): bit-exact mapping of logical addresses (LRD/LWR/LRW) onto the physical memory.
#include <algorithm>
#include <cstring>

#include "fmmu.hpp"

namespace esc {

namespace {
// Mask of the bits [lo, hi] (inclusive) of a byte.
uint8_t bit_mask(unsigned lo, unsigned hi) {
    return static_cast<uint8_t>((0xFFu << lo) & (0xFFu >> (7 - hi)));
}
}  // namespace

void Fmmus::rebuild() {
    active_ = 0;
    for (unsigned n = 0; n < count_; ++n) {
        uint16_t b = static_cast<uint16_t>(reg::kFmmu + 16 * n);
        uint32_t la = mem.r32(b);
        uint16_t len = mem.r16(b + 4);
        uint8_t lstart = mem.r8(b + 6) & 0x07;
        uint8_t lstop = mem.r8(b + 7) & 0x07;
        uint16_t pa = mem.r16(b + 8);
        uint8_t pstart = mem.r8(b + 0x0A) & 0x07;
        uint8_t type = mem.r8(b + 0x0B) & 0x03;
        if (!(mem.r8(b + 0x0C) & 0x01) || len == 0 || type == 0) continue;
        FmmuMap f;
        f.lbit_start = static_cast<uint64_t>(la) * 8 + lstart;
        f.lbit_end = (static_cast<uint64_t>(la) + len - 1) * 8 + lstop + 1;
        if (f.lbit_end <= f.lbit_start) continue;
        f.pbit_start = static_cast<uint64_t>(pa) * 8 + pstart;
        f.read = type & 0x01;
        f.write = type & 0x02;
        map_[active_++] = f;
    }
}

uint16_t Fmmus::logical(Command cmd, uint32_t la, uint8_t* data, uint16_t len) {
    if (len == 0) return 0;
    const uint64_t b0 = static_cast<uint64_t>(la) * 8;
    const uint64_t b1 = b0 + static_cast<uint64_t>(len) * 8;
    const bool do_read = cmd != Command::LWR;   // LRD, LRW
    const bool do_write = cmd != Command::LRD;  // LWR, LRW
    const uint8_t* wsrc = data;
    if (do_read && do_write) {
        std::memcpy(lrw_src.data(), data, len);  // writes take the incoming data, reads happen first
        wsrc = lrw_src.data();
    }
    bool any_r = false, any_w = false;
    if (do_read) {
        for (uint8_t k = 0; k < active_; ++k) {
            const FmmuMap& f = map_[k];
            if (!f.read) continue;
            const uint64_t i0 = std::max(b0, f.lbit_start), i1 = std::min(b1, f.lbit_end);
            if (i0 < i1 && read(f, i0, i1, la, data)) any_r = true;
        }
    }
    if (do_write) {
        const uint8_t count = active_;  // a write may reconfigure FMMUs: use this datagram's set
        for (uint8_t k = 0; k < count; ++k) {
            const FmmuMap f = map_[k];
            if (!f.write) continue;
            const uint64_t i0 = std::max(b0, f.lbit_start), i1 = std::min(b1, f.lbit_end);
            if (i0 < i1 && write(f, i0, i1, la, wsrc)) any_w = true;
        }
    }
    if (cmd == Command::LRD) return any_r ? 1 : 0;
    if (cmd == Command::LWR) return any_w ? 1 : 0;
    return static_cast<uint16_t>((any_r ? 1 : 0) + (any_w ? 2 : 0));
}

bool Fmmus::read(const FmmuMap& f, uint64_t i0, uint64_t i1, uint32_t la, uint8_t* data) {
    const uint64_t pb0 = f.pbit_start + (i0 - f.lbit_start);
    const uint64_t nbits = i1 - i0;
    const uint64_t pa0 = pb0 >> 3;
    const uint64_t pa1 = (pb0 + nbits - 1) >> 3;
    if (pa0 >= 0x10000) return false;
    const uint32_t np = static_cast<uint32_t>(std::min<uint64_t>(pa1, 0xFFFF) - pa0 + 1);
    std::memset(scratch_ok.data(), 0, np);
    if (!phys.phys_read(static_cast<uint32_t>(pa0), scratch_a.data(), scratch_ok.data(), np, Side::Ecat))
        return false;
    const uint64_t lbyte0 = i0 >> 3, lbyte1 = (i1 - 1) >> 3;
    if (((pb0 ^ i0) & 7) == 0) {
        // Same bit position in logical and physical bytes: byte-wise with edge masks.
        for (uint64_t j = lbyte0; j <= lbyte1; ++j) {
            const uint64_t k = j - lbyte0;
            if (k >= np || !scratch_ok[k]) continue;
            const unsigned lo = j == lbyte0 ? static_cast<unsigned>(i0 & 7) : 0;
            const unsigned hi = j == lbyte1 ? static_cast<unsigned>((i1 - 1) & 7) : 7;
            const uint8_t m = bit_mask(lo, hi);
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

bool Fmmus::write(const FmmuMap& f, uint64_t i0, uint64_t i1, uint32_t la, const uint8_t* data) {
    const uint64_t pb0 = f.pbit_start + (i0 - f.lbit_start);
    const uint64_t nbits = i1 - i0;
    const uint64_t pa0 = pb0 >> 3;
    const uint64_t pa1 = (pb0 + nbits - 1) >> 3;
    if (pa0 >= 0x10000) return false;
    const uint32_t np = static_cast<uint32_t>(std::min<uint64_t>(pa1, 0xFFFF) - pa0 + 1);
    std::memset(scratch_b.data(), 0, np);  // bit masks
    const uint64_t lbyte0 = i0 >> 3, lbyte1 = (i1 - 1) >> 3;
    if (((pb0 ^ i0) & 7) == 0) {
        for (uint64_t j = lbyte0; j <= lbyte1; ++j) {
            const uint64_t k = j - lbyte0;
            if (k >= np) break;
            const unsigned lo = j == lbyte0 ? static_cast<unsigned>(i0 & 7) : 0;
            const unsigned hi = j == lbyte1 ? static_cast<unsigned>((i1 - 1) & 7) : 7;
            scratch_b[k] = bit_mask(lo, hi);
            scratch_a[k] = data[j - la];
        }
    } else {
        std::memset(scratch_a.data(), 0, np);
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
    return phys.phys_write(static_cast<uint32_t>(pa0), scratch_a.data(), scratch_b.data(), np, Side::Ecat);
}

}  // namespace esc
