#pragma once
// EtherCAT frame and datagram layout (ETG.1000.4 §5.3, §5.4): Ethernet II header with EtherType 0x88A4, the
// 2-byte EtherCAT header (length 10:0, type 15:12 = 1 for datagrams), a chain of datagrams (10-byte header,
// data, 2-byte working counter), padded to the 60-byte Ethernet minimum. Header-only; nothing allocates.
#include <cstddef>
#include <cstdint>
#include <span>

namespace esc {

// Datagram command (ETG.1000.4 Table 13 "CMD").
enum class Command : uint8_t {
    NOP = 0,
    APRD = 1,
    APWR = 2,
    APRW = 3,
    FPRD = 4,
    FPWR = 5,
    FPRW = 6,
    BRD = 7,
    BWR = 8,
    BRW = 9,
    LRD = 10,
    LWR = 11,
    LRW = 12,
    ARMW = 13,
    FRMW = 14,
};

}  // namespace esc

namespace esc::wire {

constexpr uint16_t kEtherType = 0x88A4;
constexpr uint16_t kEtherTypeVlan = 0x8100;  // one 802.1Q tag before the EtherType
constexpr std::size_t kMacSize = 6;
constexpr std::size_t kEthernetHeaderSize = 14;
constexpr std::size_t kEcatHeaderSize = 2;
constexpr std::size_t kFrameHeaderSize = kEthernetHeaderSize + kEcatHeaderSize;  // first datagram at 16
constexpr std::size_t kDatagramHeaderSize = 10;
constexpr std::size_t kWkcSize = 2;
constexpr std::size_t kDatagramOverhead = kDatagramHeaderSize + kWkcSize;  // header + working counter
constexpr std::size_t kMinFrameSize = 60;                                  // without FCS
constexpr std::size_t kMaxFrameSize = 1514;                                // without FCS
constexpr std::size_t kMaxDatagramsLength = 1498;  // the 11-bit length field's room in 1500
constexpr std::size_t kMaxDatagramData = kMaxDatagramsLength - kDatagramOverhead;  // 1486

// EtherCAT header (after the EtherType): bits 10:0 length of the datagram chain, bits 15:12 type.
constexpr uint16_t kEcatLengthMask = 0x07FF;
constexpr uint8_t kEcatTypeDatagrams = 1;
constexpr uint16_t ecat_header(std::size_t chain_length) {
    return static_cast<uint16_t>((chain_length & kEcatLengthMask) | (kEcatTypeDatagrams << 12));
}

// Datagram header offsets and the length/flags word (bytes 6-7).
constexpr std::size_t kDgCommand = 0;
constexpr std::size_t kDgIndex = 1;
constexpr std::size_t kDgAdp = 2;  // position / station address; low half of a logical address
constexpr std::size_t kDgAdo = 4;  // register offset; high half of a logical address
constexpr std::size_t kDgLengthFlags = 6;
constexpr std::size_t kDgIrq = 8;
constexpr uint16_t kDgLengthMask = 0x07FF;
constexpr uint16_t kDgCirculating = 0x4000;  // C: the frame has circulated once
constexpr uint16_t kDgMore = 0x8000;         // M: another datagram follows

constexpr uint32_t logical_address(uint16_t adp, uint16_t ado) {
    return static_cast<uint32_t>(adp) | (static_cast<uint32_t>(ado) << 16);
}

// Writes the Ethernet II and EtherCAT headers (16 bytes) at out[0]: destination broadcast (ESCs do not
// evaluate it), the given source, EtherType 0x88A4, chain_length in the EtherCAT header.
inline void put_frame_header(uint8_t* out, const uint8_t (&source)[kMacSize], std::size_t chain_length) {
    for (std::size_t i = 0; i < kMacSize; ++i) {
        out[i] = 0xFF;
        out[kMacSize + i] = source[i];
    }
    out[12] = static_cast<uint8_t>(kEtherType >> 8);
    out[13] = static_cast<uint8_t>(kEtherType & 0xFF);
    const uint16_t h = ecat_header(chain_length);
    out[14] = static_cast<uint8_t>(h);
    out[15] = static_cast<uint8_t>(h >> 8);
}

// Writes one datagram header (10 bytes) at out[0].
inline void put_datagram_header(uint8_t* out, uint8_t command, uint8_t index, uint16_t adp, uint16_t ado,
                                std::size_t length, bool more, uint16_t irq = 0, bool circulating = false) {
    const uint16_t lf = static_cast<uint16_t>((length & kDgLengthMask) | (circulating ? kDgCirculating : 0) |
                                              (more ? kDgMore : 0));
    out[0] = command;
    out[1] = index;
    out[2] = static_cast<uint8_t>(adp);
    out[3] = static_cast<uint8_t>(adp >> 8);
    out[4] = static_cast<uint8_t>(ado);
    out[5] = static_cast<uint8_t>(ado >> 8);
    out[6] = static_cast<uint8_t>(lf);
    out[7] = static_cast<uint8_t>(lf >> 8);
    out[8] = static_cast<uint8_t>(irq);
    out[9] = static_cast<uint8_t>(irq >> 8);
}

// One datagram of a received frame, as DatagramReader returns it (views into the frame).
struct DatagramView {
    uint8_t command = 0;
    uint8_t index = 0;
    uint16_t adp = 0;
    uint16_t ado = 0;
    uint16_t length_flags = 0;  // the length/flags word as found in the frame
    uint16_t irq = 0;
    std::span<const uint8_t> data;
    uint16_t wkc = 0;
    std::size_t offset = 0;  // of the datagram header in the frame
    bool circulating() const { return (length_flags & kDgCirculating) != 0; }
    bool more() const { return (length_flags & kDgMore) != 0; }
    uint32_t logical() const { return logical_address(adp, ado); }
};

// Where a frame's EtherCAT header is, as an ESC finds it (ESC datasheet section I, "EtherCAT protocol" and
// "UDP/IP"): after EtherType 0x88A4, after one IEEE 802.1Q tag (not evaluated, not modified), or in an
// IPv4/UDP datagram to port 0x88A4. For UDP/IP an ESC evaluates only EtherType 0x0800, IP version 4, IP
// header length 5, protocol 0x11 and the UDP destination port; the UDP checksum it clears, since it changes
// the payload.
constexpr uint16_t kEtherTypeIpv4 = 0x0800;
constexpr uint16_t kUdpPortEcat = 0x88A4;
constexpr std::size_t kIpv4HeaderSize = 20;
constexpr std::size_t kUdpHeaderSize = 8;
struct EcatLocation {
    bool found = false;            // an EtherCAT frame (the header itself may lie past the end: a runt)
    std::size_t header = 0;        // offset of the 2-byte EtherCAT header
    std::size_t udp_checksum = 0;  // offset of the UDP checksum; 0 if not carried in UDP/IP
};
inline EcatLocation locate_ecat(std::span<const uint8_t> frame, bool accept_vlan = true) {
    EcatLocation loc;
    const std::size_t size = frame.size();
    if (size < kEthernetHeaderSize) return loc;
    std::size_t off = 12;
    uint16_t type = static_cast<uint16_t>((frame[off] << 8) | frame[off + 1]);
    if (accept_vlan && type == kEtherTypeVlan) {
        off += 4;
        if (size < off + 2) return loc;
        type = static_cast<uint16_t>((frame[off] << 8) | frame[off + 1]);
    }
    off += 2;
    if (type == kEtherType) {
        loc.found = true;
        loc.header = off;
    } else if (type == kEtherTypeIpv4 && size >= off + kIpv4HeaderSize + kUdpHeaderSize) {
        const uint8_t* ip = frame.data() + off;
        const uint16_t port = static_cast<uint16_t>((ip[kIpv4HeaderSize + 2] << 8) | ip[kIpv4HeaderSize + 3]);
        if (ip[0] == 0x45 && ip[9] == 0x11 && port == kUdpPortEcat) {
            loc.found = true;
            loc.udp_checksum = off + kIpv4HeaderSize + 6;
            loc.header = off + kIpv4HeaderSize + kUdpHeaderSize;
        }
    }
    return loc;
}

// An ESC ignores the EtherCAT header's Length (ESC datasheet section I, Table 2: "The EtherCAT header length
// field is ignored by ESCs, they rely on the datagram length fields"): it walks the datagrams by their own
// lengths and More bits up to the real end of the frame. What follows the last datagram is padding; more than
// kMaxPadding bytes of it is a frame length error (ibid., Table 57), as is a datagram that runs past the end.
constexpr std::size_t kMaxPadding = 64;

// Walks the datagram chain of a frame without copying, as an ESC does (above). valid() is false for anything
// that is not an EtherCAT type-1 frame or has no room for the EtherCAT header; next() returns false at the
// end of the chain and sets malformed() if a datagram ran past the end of the frame (or the frame ended where
// a datagram with M = 1 promised another).
class DatagramReader {
  public:
    // accept_vlan: one 802.1Q tag may precede the EtherType. check_type: the frame must be EtherCAT
    // (EtherType, VLAN, UDP/IP as locate_ecat) of type 1 (false: the chain starts at byte 16, a test's view
    // of a frame).
    explicit DatagramReader(std::span<const uint8_t> frame, bool accept_vlan = true, bool check_type = true)
        : frame_(frame) {
        std::size_t off = kEthernetHeaderSize;
        if (check_type) {
            const EcatLocation loc = locate_ecat(frame, accept_vlan);
            if (!loc.found) return;
            off = loc.header;
        }
        if (frame.size() < off + kEcatHeaderSize) return;
        const uint16_t header = static_cast<uint16_t>(frame[off] | (frame[off + 1] << 8));
        if (check_type && (header >> 12) != kEcatTypeDatagrams) return;
        pos_ = off + kEcatHeaderSize;
        end_ = frame.size();
        valid_ = true;
    }
    bool valid() const { return valid_; }
    bool malformed() const { return malformed_; }
    std::span<const uint8_t> source_mac() const { return frame_.subspan(kMacSize, kMacSize); }

    bool next(DatagramView& v) {
        if (!valid_ || done_) return false;
        if (pos_ + kDatagramOverhead > end_) return stop();
        const uint8_t* h = frame_.data() + pos_;
        const uint16_t lf = get16(h + kDgLengthFlags);
        const std::size_t len = lf & kDgLengthMask;
        if (pos_ + kDatagramOverhead + len > end_) return stop();
        v.command = h[kDgCommand];
        v.index = h[kDgIndex];
        v.adp = get16(h + kDgAdp);
        v.ado = get16(h + kDgAdo);
        v.length_flags = lf;
        v.irq = get16(h + kDgIrq);
        v.data = std::span<const uint8_t>(h + kDatagramHeaderSize, len);
        v.wkc = get16(h + kDatagramHeaderSize + len);
        v.offset = pos_;
        pos_ += kDatagramOverhead + len;
        if (!v.more()) done_ = true;
        return true;
    }

  private:
    static uint16_t get16(const uint8_t* p) { return static_cast<uint16_t>(p[0] | (p[1] << 8)); }
    bool stop() {
        done_ = true;
        malformed_ = true;
        return false;
    }
    std::span<const uint8_t> frame_;
    std::size_t pos_ = 0;
    std::size_t end_ = 0;
    bool valid_ = false;
    bool done_ = false;
    bool malformed_ = false;
};

}  // namespace esc::wire
