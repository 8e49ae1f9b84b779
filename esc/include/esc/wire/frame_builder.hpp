#pragma once
// Building EtherCAT frames of datagrams into a byte vector (layout: datagram.hpp): for the benchmarks, the
// tests and tools that build a frame now and then. The master's cyclic path encodes into its own buffer
// with put_frame_header()/put_datagram_header() and allocates nothing.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "esc/wire/datagram.hpp"

namespace esc::wire {

class FrameBuilder {
  public:
    // The master's source MAC the tests and benchmarks use: 01:01:01:01:01:01 (destination broadcast).
    static constexpr uint8_t kDefaultSource[kMacSize] = {0x01, 0x01, 0x01, 0x01, 0x01, 0x01};

    FrameBuilder() : FrameBuilder(kDefaultSource) {}
    explicit FrameBuilder(const uint8_t (&source)[kMacSize]) : f_(kFrameHeaderSize, 0) {
        put_frame_header(f_.data(), source, 0);
    }

    // Device-addressed datagram (ADP/ADO); irq and wkc as they go on the wire (a master sends 0).
    FrameBuilder& add(uint8_t cmd, uint8_t idx, uint16_t adp, uint16_t ado, std::span<const uint8_t> data,
                      uint16_t irq = 0, uint16_t wkc = 0) {
        if (last_ != 0) f_[last_ + kDgLengthFlags + 1] |= static_cast<uint8_t>(kDgMore >> 8);
        last_ = f_.size();
        f_.resize(f_.size() + kDatagramHeaderSize);
        put_datagram_header(f_.data() + last_, cmd, idx, adp, ado, data.size(), false, irq);
        f_.insert(f_.end(), data.begin(), data.end());
        f_.push_back(static_cast<uint8_t>(wkc));
        f_.push_back(static_cast<uint8_t>(wkc >> 8));
        return *this;
    }
    FrameBuilder& add(Command cmd, uint8_t idx, uint16_t adp, uint16_t ado, std::span<const uint8_t> data,
                      uint16_t irq = 0, uint16_t wkc = 0) {
        return add(static_cast<uint8_t>(cmd), idx, adp, ado, data, irq, wkc);
    }
    // A datagram of len zero bytes (a read).
    FrameBuilder& add_zero(uint8_t cmd, uint8_t idx, uint16_t adp, uint16_t ado, std::size_t len) {
        const std::vector<uint8_t> z(len, 0);
        return add(cmd, idx, adp, ado, z);
    }
    FrameBuilder& add_zero(Command cmd, uint8_t idx, uint16_t adp, uint16_t ado, std::size_t len) {
        return add_zero(static_cast<uint8_t>(cmd), idx, adp, ado, len);
    }
    // Logically addressed datagram (32-bit address).
    FrameBuilder& add_logical(uint8_t cmd, uint8_t idx, uint32_t address, std::span<const uint8_t> data) {
        return add(cmd, idx, static_cast<uint16_t>(address & 0xFFFF), static_cast<uint16_t>(address >> 16),
                   data);
    }
    FrameBuilder& add_logical(Command cmd, uint8_t idx, uint32_t address, std::span<const uint8_t> data) {
        return add_logical(static_cast<uint8_t>(cmd), idx, address, data);
    }

    // The frame, its EtherCAT header length set, padded with zeros to min_len.
    std::vector<uint8_t> build(std::size_t min_len = kMinFrameSize) const {
        std::vector<uint8_t> out = f_;
        const uint16_t h = ecat_header(out.size() - kFrameHeaderSize);
        out[kEthernetHeaderSize] = static_cast<uint8_t>(h);
        out[kEthernetHeaderSize + 1] = static_cast<uint8_t>(h >> 8);
        if (out.size() < min_len) out.resize(min_len, 0);
        return out;
    }

  private:
    std::vector<uint8_t> f_;
    std::size_t last_ = 0;
};

// Working counter of datagram n (0-based) of a frame, or -1 if the frame has no such datagram.
inline int datagram_wkc(std::span<const uint8_t> frame, int n) {
    DatagramReader r(frame, false, false);
    DatagramView v;
    for (int i = 0; r.next(v); ++i)
        if (i == n) return v.wkc;
    return -1;
}

}  // namespace esc::wire
