#pragma once
// Tiny EtherCAT frame builder for the benchmarks (master side): Ethernet header, EtherCAT header, a chain of
// datagrams, padding to the 60-byte minimum. Layout per ethercat-protocol.md §1.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace bench {

enum Cmd : uint8_t {
    NOP = 0,
    APRD = 1,
    APWR = 2,
    FPRD = 4,
    FPWR = 5,
    BRD = 7,
    BWR = 8,
    LRD = 10,
    LWR = 11,
    LRW = 12,
    FRMW = 14
};

class FrameBuilder {
  public:
    FrameBuilder() : f_(16, 0) {
        for (std::size_t i = 0; i < 6; ++i)
            f_[i] = 0xFF;
        for (std::size_t i = 6; i < 12; ++i)
            f_[i] = 0x01;
        f_[12] = 0x88;
        f_[13] = 0xA4;
        f_[15] = 0x10;  // EtherCAT header: type 1, length filled in by build()
    }
    // Device-addressed datagram (ADP/ADO).
    FrameBuilder& add(uint8_t cmd, uint8_t idx, uint16_t adp, uint16_t ado, std::span<const uint8_t> data) {
        return add_raw(cmd, idx, static_cast<uint32_t>(adp) | (static_cast<uint32_t>(ado) << 16), data);
    }
    FrameBuilder& add_zero(uint8_t cmd, uint8_t idx, uint16_t adp, uint16_t ado, std::size_t len) {
        std::vector<uint8_t> z(len, 0);
        return add(cmd, idx, adp, ado, z);
    }
    // Logically addressed datagram (32-bit address).
    FrameBuilder& add_logical(uint8_t cmd, uint8_t idx, uint32_t address, std::span<const uint8_t> data) {
        return add_raw(cmd, idx, address, data);
    }
    std::vector<uint8_t> build() const {
        std::vector<uint8_t> out = f_;
        const std::size_t len = out.size() - 16;
        out[14] = static_cast<uint8_t>(len & 0xFF);
        out[15] = static_cast<uint8_t>(0x10 | ((len >> 8) & 0x07));
        if (out.size() < 60) out.resize(60, 0);
        return out;
    }

  private:
    FrameBuilder& add_raw(uint8_t cmd, uint8_t idx, uint32_t addr, std::span<const uint8_t> data) {
        if (last_ != 0) f_[last_ + 7] |= 0x80;  // "more datagrams follow" on the previous one
        last_ = f_.size();
        f_.push_back(cmd);
        f_.push_back(idx);
        for (int i = 0; i < 4; ++i)
            f_.push_back(static_cast<uint8_t>(addr >> (8 * i)));
        f_.push_back(static_cast<uint8_t>(data.size() & 0xFF));
        f_.push_back(static_cast<uint8_t>((data.size() >> 8) & 0x07));
        f_.push_back(0);
        f_.push_back(0);
        f_.insert(f_.end(), data.begin(), data.end());
        f_.push_back(0);
        f_.push_back(0);
        return *this;
    }
    std::vector<uint8_t> f_;
    std::size_t last_ = 0;
};

// Working counter of datagram n (0-based) of a frame, or -1 if the frame has no such datagram.
inline int datagram_wkc(std::span<const uint8_t> f, int n) {
    std::size_t at = 16;
    for (int i = 0;; ++i) {
        if (at + 12 > f.size()) return -1;
        const std::size_t len = (f[at + 6] | (f[at + 7] << 8)) & 0x7FF;
        if (at + 12 + len > f.size()) return -1;
        if (i == n) return f[at + 10 + len] | (f[at + 11 + len] << 8);
        if ((f[at + 7] & 0x80) == 0) return -1;
        at += 12 + len;
    }
}

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
