#pragma once
// The frames the benchmarks send (master side), built with the ESC wire vocabulary's FrameBuilder.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "esc/wire/frame_builder.hpp"

namespace bench {

// Commands, builder and reply parsing: the ESC wire vocabulary (esc/wire/datagram.hpp, frame_builder.hpp).
using enum esc::Command;
using esc::wire::datagram_wkc;
using esc::wire::FrameBuilder;

// The typical cyclic frame of a CSP drive: LRW of 32 bytes (16 out + 16 in), FRMW of the DC system time
// (0x0910, 8 bytes) and FPRD of AL status (0x0130, 2 bytes).
inline std::vector<uint8_t> cyclic_frame(uint16_t station, uint8_t idx) {
    std::vector<uint8_t> pd(32, 0);
    FrameBuilder b;
    b.add_logical(LRW, idx, 0, pd);
    b.add_zero(FRMW, static_cast<uint8_t>(idx + 1), station, 0x0910, 8);
    b.add_zero(FPRD, static_cast<uint8_t>(idx + 2), station, 0x0130, 2);
    return b.build();
}

// Frames a master sends to configure one slave for cyclic_frame(): station address, SM2 (outputs at
// 0x1100, 16 bytes), SM3 (inputs at 0x1180, 16 bytes), FMMU0 logical 0..15 -> 0x1100 (write), FMMU1
// logical 16..31 <- 0x1180 (read).
inline std::vector<std::vector<uint8_t>> configuration_frames(uint16_t station) {
    std::vector<std::vector<uint8_t>> frames;
    const uint8_t addr[2] = {static_cast<uint8_t>(station), static_cast<uint8_t>(station >> 8)};
    frames.push_back(FrameBuilder().add(APWR, 1, 0, 0x0010, addr).build());
    const uint8_t sm2[8] = {0x00, 0x11, 16, 0, 0x64, 0, 1, 0};
    const uint8_t sm3[8] = {0x80, 0x11, 16, 0, 0x20, 0, 1, 0};
    frames.push_back(
        FrameBuilder().add(FPWR, 2, station, 0x0810, sm2).add(FPWR, 3, station, 0x0818, sm3).build());
    const uint8_t fmmu0[16] = {0, 0, 0, 0, 16, 0, 0, 7, 0x00, 0x11, 0, 2, 1, 0, 0, 0};
    const uint8_t fmmu1[16] = {16, 0, 0, 0, 16, 0, 0, 7, 0x80, 0x11, 0, 1, 1, 0, 0, 0};
    frames.push_back(
        FrameBuilder().add(FPWR, 4, station, 0x0600, fmmu0).add(FPWR, 5, station, 0x0610, fmmu1).build());
    return frames;
}

}  // namespace bench
