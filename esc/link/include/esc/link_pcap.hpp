#pragma once
// PcapLink: a Link over libpcap. Opens the interface promiscuous, in immediate mode (every frame is handed
// over as it arrives, no buffering timeout), snaplen 2048, inbound only (pcap_setdirection PCAP_D_IN, so
// our own replies never come back in), with a BPF filter for EtherCAT frames (EtherType 0x88A4, UDP port
// 0x88A4, also VLAN-tagged), non-blocking, and exposes pcap_get_selectable_fd() for poll(). Sends with
// pcap_inject(). Each frame carries the kernel's receive time stamp (CLOCK_REALTIME, rx_stamp_ns()), to the
// nanosecond where libpcap can.
#include <string>

#include "esc/link.hpp"

struct pcap;

namespace esc {

class PcapLink final : public Link {
  public:
    // Throws LinkError.
    explicit PcapLink(const std::string& iface);
    ~PcapLink() override;
    PcapLink(const PcapLink&) = delete;
    PcapLink& operator=(const PcapLink&) = delete;

    int fd() const override { return fd_; }
    std::size_t receive(std::span<uint8_t> buf) override;
    bool send(std::span<const uint8_t> frame) override;
    std::string describe() const override { return "pcap:" + iface_; }
    uint64_t rx_stamp_ns() const override { return stamp_ns_; }

  private:
    std::string iface_;
    struct pcap* handle_ = nullptr;
    int fd_ = -1;
    uint64_t stamp_unit_ns_ = 1000;  // of pcap_pkthdr::ts.tv_usec: 1 with nanosecond precision
    uint64_t stamp_ns_ = 0;          // receive time stamp of the frame receive() returned last
};

}  // namespace esc
