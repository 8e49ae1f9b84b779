// FMMU unit (fmmu.hpp): decoding of the FMMU registers into mappings. The mapping of LRD/LWR/LRW onto the
// physical memory is a template in fmmu.hpp, so that its physical accesses call Esc::Impl directly.
#include "fmmu.hpp"

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

}  // namespace esc
