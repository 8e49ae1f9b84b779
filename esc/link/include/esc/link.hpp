#pragma once
// A link carries whole Ethernet frames (destination MAC .. payload, no FCS) between the ESC and the wire.
//
// Implementations (each in its own header):
//   esc/link_pcap.hpp      PcapLink      libpcap, immediate mode, inbound only, BPF: EtherCAT (also VLAN,
//   UDP) esc/link_packet.hpp    PacketLink    AF_PACKET socket with a TPACKET_V2 memory-mapped receive ring
//   esc/link_loopback.hpp  LoopbackLink  two in-process ends joined by frame queues (tests)
//   esc/link_capture.hpp   PcapWriter    records frames to a .pcap file for Wireshark
#include <time.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>

namespace esc {

class Link {
  public:
    virtual ~Link() = default;
    // File descriptor that becomes readable when a frame may be waiting (for poll()); -1 if none.
    virtual int fd() const = 0;
    // Receives one frame into buf without blocking. Returns its length, 0 if nothing is waiting.
    // Frames this host sent itself (PACKET_OUTGOING) are never returned.
    // A frame longer than buf is truncated to buf.size(). A frame shorter than the Ethernet minimum (60 bytes
    // without FCS) is returned padded with zeros to 60, as the sender's NIC puts it on a wire (a veth pads
    // nothing), so the reply has the length a hardware ESC returns (docs/decisions/esc.md, "Frame
    // tolerance").
    virtual std::size_t receive(std::span<uint8_t> buf) = 0;
    // Sends one frame. Returns false on error.
    virtual bool send(std::span<const uint8_t> frame) = 0;
    // (extension) Short description for logs, e.g. "packet:ecat0".
    virtual std::string describe() const { return {}; }
    // (extension) When the frame the last receive() returned arrived: the kernel's receive timestamp, in ns
    // on the time base of stamp_now_ns() (CLOCK_REALTIME for the kernel's stamps); 0 if the link has none.
    // A frame waits in the link while its reader is busy or descheduled; its stamp says when it came, so the
    // ESC can take it at that time, as silicon does (docs/decisions/link.md, "Receive timestamps").
    virtual uint64_t rx_stamp_ns() const { return 0; }
    // (extension) Now, on the time base of rx_stamp_ns(). A reader converts a stamp to its own clock with the
    // difference of the two clocks' "now".
    virtual uint64_t stamp_now_ns() const {
        timespec ts{};
        ::clock_gettime(CLOCK_REALTIME, &ts);
        return static_cast<uint64_t>(ts.tv_sec) * 1'000'000'000ull + static_cast<uint64_t>(ts.tv_nsec);
    }
};

// Why a link could not be opened. The message says what to do about it.
class LinkError : public std::runtime_error {
  public:
    enum class Kind {
        NoSuchInterface,   // the interface name does not exist
        PermissionDenied,  // no CAP_NET_RAW (raw sockets) / CAP_NET_ADMIN (promiscuous mode, veth)
        InterfaceDown,     // the interface exists but is administratively down
        BadArgument,       // unknown backend name, empty interface name, ...
        System,            // any other failure of the operating system or libpcap
    };
    LinkError(Kind kind, const std::string& message) : std::runtime_error(message), kind_(kind) {}
    Kind kind() const { return kind_; }

  private:
    Kind kind_;
};

// Largest frame a link returns (Ethernet header + 1500 payload + VLAN tag, rounded up).
inline constexpr std::size_t kMaxFrameSize = 2048;
// The Ethernet minimum without FCS; receive() pads shorter frames to it.
inline constexpr std::size_t kMinFrameSize = 60;
// Pads frame[0, n) with zeros to kMinFrameSize within buf; returns the new length.
inline std::size_t pad_to_minimum(std::span<uint8_t> buf, std::size_t n) {
    if (n == 0 || n >= kMinFrameSize || buf.size() < kMinFrameSize) return n;
    for (std::size_t i = n; i < kMinFrameSize; ++i)
        buf[i] = 0;
    return kMinFrameSize;
}

// Throws LinkError (NoSuchInterface / InterfaceDown) unless iface exists and is up.
void check_interface(const std::string& iface);

// Backend names understood by open_link().
inline constexpr const char* kBackendPcap = "pcap";
inline constexpr const char* kBackendPacket = "packet";
// The backend open_link() uses when none is named (the faster one measured, see docs/decisions/link.md).
const char* default_link_backend();

// Opens iface with the named backend ("pcap" | "packet"; empty = default_link_backend()).
// Throws LinkError on failure.
std::unique_ptr<Link> open_link(const std::string& iface, const std::string& backend = {});

}  // namespace esc
