#pragma once
// EtherCAT frames as a master builds and parses them: Ethernet II header, EtherCAT header (type 1),
// a chain of datagrams (10-byte header, data, 2-byte working counter), padding to the 60-byte minimum.
// Nothing here allocates; the caller owns all buffers.
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

#include "esc/wire/datagram.hpp"

namespace master {

// Frame layout and the datagram commands: the ESC wire vocabulary (esc/wire/datagram.hpp).
using esc::wire::kDatagramHeaderSize;
using esc::wire::kDatagramOverhead;
using esc::wire::kEcatHeaderSize;
using esc::wire::kEthernetHeaderSize;
using esc::wire::kEtherType;
using esc::wire::kMaxDatagramData;
using esc::wire::kMaxDatagramsLength;
using esc::wire::kMaxFrameSize;
using esc::wire::kMinFrameSize;
using Command = esc::Command;

// One datagram of a request. data is both the payload sent and, after the exchange, the payload
// returned; wkc and irq are filled from the reply.
struct Datagram {
    Command command = Command::NOP;
    uint16_t adp = 0;  // position (as 0, -1, -2, ...) or station address; low half of a logical address
    uint16_t ado = 0;  // register offset; high half of a logical address
    std::span<uint8_t> data;
    uint16_t wkc = 0;
    uint16_t irq = 0;
    uint8_t index = 0;  // assigned by the master when sent

    static Datagram logical(Command c, uint32_t address, std::span<uint8_t> d) {
        return Datagram{c, static_cast<uint16_t>(address & 0xFFFF), static_cast<uint16_t>(address >> 16), d};
    }
};

using MacAddress = std::array<uint8_t, 6>;

// Bytes a frame holding these datagrams needs on the wire (before padding to 60).
std::size_t frame_size(std::span<const Datagram> datagrams);

// Writes the frame into out; datagram i gets index first_index + i. Returns the frame length (padded to
// 60 bytes), or 0 if the datagrams do not fit one frame or out is too small.
std::size_t encode_frame(std::span<const Datagram> datagrams, uint8_t first_index, const MacAddress& source,
                         std::span<uint8_t> out);

// A parsed view of one datagram inside a received frame.
struct DatagramView {
    Command command;
    uint8_t index;
    uint16_t adp;
    uint16_t ado;
    bool circulating;
    bool more;
    uint16_t irq;
    std::span<const uint8_t> data;
    uint16_t wkc;
};

// Walks the datagram chain of a received frame. Rejects anything that is not a well-formed EtherCAT
// type-1 frame (wrong EtherType, length field past the end, more-bit chain running past the length).
class FrameReader {
  public:
    explicit FrameReader(std::span<const uint8_t> frame);
    bool valid() const { return valid_; }
    std::span<const uint8_t> source_mac() const { return frame_.subspan(6, 6); }
    // Next datagram, or nullopt at the end of the chain.
    std::optional<DatagramView> next();

  private:
    std::span<const uint8_t> frame_;
    esc::wire::DatagramReader reader_;
    bool valid_ = false;
};

}  // namespace master
