#pragma once
// Gates for findings of issue 14 that are known and fixed on other branches, so that a harness does not
// stop at them again and again (their crashing inputs are kept in tests/fuzz/known/<harness>/, replayed by
// no test until the fix is merged). Remove a gate together with the merge of its fix; the regression test
// of the fix then covers the input.
#include <cstddef>
#include <cstdint>
#include <span>

#include "esc/pdi.hpp"

namespace fuzz::known {

// Built with -DSOFTECAT_FUZZ_UNGATED, every gate is open: to see whether a known finding is still there.
#ifdef SOFTECAT_FUZZ_UNGATED
constexpr bool kGated = false;
#else
constexpr bool kGated = true;
#endif

// Issue 14 finding 2: a DC speed counter start (0x0930) of 0 or 1 lets the drift limit reach +-100 %, the
// local clock stops and clock_at_local divides by zero (UB: inf cast to an integer). Frames that write
// 0x0930 through a physical address are not processed...
inline bool writes_dc_speed_start(std::span<const uint8_t> frame) {
    if (!kGated) return false;
    std::size_t at = 12;
    auto u16 = [&](std::size_t p) -> unsigned { return frame[p] | frame[p + 1] << 8; };
    auto be16 = [&](std::size_t p) -> unsigned { return frame[p] << 8 | frame[p + 1]; };
    if (frame.size() < at + 2) return false;
    if (be16(at) == 0x8100 && frame.size() >= at + 6) at += 4;  // VLAN tag
    if (be16(at) != 0x88A4) return false;
    at += 4;  // EtherType + EtherCAT header
    for (int n = 0; n < 256 && at + 10 <= frame.size(); ++n) {
        const uint8_t cmd = frame[at];
        const unsigned ado = u16(at + 4);
        const unsigned len_flags = u16(at + 6);
        const unsigned len = len_flags & 0x07FF;
        const bool writes =
            cmd == 2 || cmd == 3 || cmd == 5 || cmd == 6 || cmd == 8 || cmd == 9 || cmd == 13 || cmd == 14;
        if (writes && ado < 0x0932 && ado + len > 0x0930) return true;
        if ((len_flags & 0x8000) == 0) break;
        at += 10 + len + 2;
    }
    return false;
}
// ...and a sequence ends as soon as 0x0930 holds such a value anyway (written through an FMMU, say).
inline bool dc_speed_start_unsafe(esc::Pdi& pdi) {
    if (!kGated) return false;
    uint8_t b[2] = {};
    pdi.read(0x0930, b);
    return ((b[0] | b[1] << 8) & 0x7FFF) <= 1;
}

}  // namespace fuzz::known
