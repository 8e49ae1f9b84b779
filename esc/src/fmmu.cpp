// FMMU unit (fmmu.hpp): decoding of the FMMU registers into mappings. The mapping of LRD/LWR/LRW onto the
// physical memory is a template in fmmu.hpp, so that its physical accesses call Esc::Impl directly.
#include "fmmu.hpp"

#include <algorithm>

#include "prefetch.hpp"

namespace esc {

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

void Fmmus::prefetch_state() const {
    prefetch_lines(&active_, sizeof active_ + 2 * sizeof(FmmuMap));  // the count and the first two mappings
}

void Fmmus::prefetch_ram(const Memory& m) const {
    for (uint8_t k = 0; k < active_; ++k) {
        const uint64_t pa = map_[k].pbit_start >> 3;
        if (pa < reg::kRamBase || pa >= m.ram_end) continue;
        // The mapped bytes and, for a 3-buffer SM behind them, its other two buffers (at most four lines).
        const uint64_t bytes = ((map_[k].lbit_end - map_[k].lbit_start + 7) >> 3) * 3;
        const uint64_t n = std::min<uint64_t>({bytes, 4 * kCacheLine, m.ram_end - pa});
        prefetch_lines(&m.ram[pa - reg::kRamBase], n);
    }
}

}  // namespace esc
