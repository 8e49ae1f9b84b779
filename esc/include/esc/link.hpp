#pragma once
// A link carries whole Ethernet frames (destination MAC .. payload, no FCS) between the ESC and the wire.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>

namespace esc {

class Link {
public:
    virtual ~Link() = default;
    // File descriptor that becomes readable when a frame may be waiting (for poll()); -1 if none.
    virtual int fd() const = 0;
    // Receives one frame into buf without blocking. Returns its length, 0 if nothing is waiting.
    // Frames this host sent itself (PACKET_OUTGOING) are never returned.
    virtual std::size_t receive(std::span<uint8_t> buf) = 0;
    // Sends one frame. Returns false on error.
    virtual bool send(std::span<const uint8_t> frame) = 0;
};

}  // namespace esc
