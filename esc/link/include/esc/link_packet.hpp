#pragma once
// PacketLink: a Link over an AF_PACKET raw socket bound to one interface. A socket filter passes what an ESC
// processes (ESC datasheet section I, "EtherCAT protocol"): EtherType 0x88A4, VLAN-tagged frames, and
// IPv4/UDP to port 0x88A4. The kernel takes a VLAN tag off into the ring slot's header; receive() puts it
// back where it was, so the frame and its reply carry it as on a wire. Receives through a TPACKET_V2
// memory-mapped ring (one frame per slot, so poll() wakes per frame; TPACKET_V3 would hand over whole blocks
// after a retire timeout of at least a millisecond). Own transmissions are dropped by PACKET_IGNORE_OUTGOING
// and, as a second line, by skipping slots marked PACKET_OUTGOING. The interface is put in promiscuous mode
// (PACKET_MR_PROMISC) because masters do not always send to broadcast. Sends with send() on the bound socket,
// bypassing the qdisc (PACKET_QDISC_BYPASS). Each slot carries the kernel's receive time stamp
// (rx_stamp_ns()).
#include <string>

#include "esc/link.hpp"

namespace esc {

class PacketLink final : public Link {
  public:
    // Throws LinkError.
    explicit PacketLink(const std::string& iface);
    ~PacketLink() override;
    PacketLink(const PacketLink&) = delete;
    PacketLink& operator=(const PacketLink&) = delete;

    int fd() const override { return fd_; }
    std::size_t receive(std::span<uint8_t> buf) override;
    bool send(std::span<const uint8_t> frame) override;
    std::string describe() const override { return "packet:" + iface_; }
    // The ring slot's time stamp (tp_sec/tp_nsec, CLOCK_REALTIME): taken by the kernel when it delivered the
    // frame to the socket, whether or not this process was running then.
    uint64_t rx_stamp_ns() const override { return stamp_ns_; }

  private:
    std::string iface_;
    int fd_ = -1;
    int ifindex_ = 0;
    uint8_t* ring_ = nullptr;
    std::size_t ring_size_ = 0;
    std::size_t frame_size_ = 0;
    std::size_t frame_count_ = 0;
    std::size_t next_ = 0;   // ring slot to look at next
    uint64_t stamp_ns_ = 0;  // receive time stamp of the frame receive() returned last, 0: none
};

}  // namespace esc
