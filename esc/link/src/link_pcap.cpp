// PcapLink: libpcap backend. See esc/link_pcap.hpp.
#include "esc/link_pcap.hpp"

#include <pcap/pcap.h>

#include <cstring>

namespace esc {

namespace {

// What an ESC processes (ESC datasheet section I, "EtherCAT protocol", "UDP/IP"): EtherType 0x88A4 and
// EtherCAT in UDP/IP, each also behind an 802.1Q tag. The ESC checks the rest (IP header length 5).
constexpr const char* kFilter =
    "ether proto 0x88a4 or (ip and udp dst port 0x88a4) or "
    "(vlan and (ether proto 0x88a4 or (ip and udp dst port 0x88a4)))";

std::string permission_hint(const std::string& iface) {
    return "no permission to capture on '" + iface +
           "': raw sockets need CAP_NET_RAW (and CAP_NET_ADMIN for promiscuous mode); run as root or "
           "`sudo setcap cap_net_raw,cap_net_admin+ep <program>`";
}

}  // namespace

PcapLink::PcapLink(const std::string& iface) : iface_(iface) {
    check_interface(iface);
    char errbuf[PCAP_ERRBUF_SIZE] = {};
    handle_ = pcap_create(iface.c_str(), errbuf);
    if (handle_ == nullptr) throw LinkError(LinkError::Kind::System, "pcap_create(" + iface + "): " + errbuf);
    auto fail = [this](LinkError::Kind kind, const std::string& what) {
        pcap_close(handle_);
        handle_ = nullptr;
        throw LinkError(kind, what);
    };
    pcap_set_snaplen(handle_, static_cast<int>(kMaxFrameSize));
    pcap_set_promisc(handle_, 1);
    pcap_set_immediate_mode(handle_, 1);
    pcap_set_timeout(handle_, 1);
    // The kernel's receive time stamps to the nanosecond where libpcap can (rx_stamp_ns()); microseconds
    // else.
    (void)pcap_set_tstamp_precision(handle_, PCAP_TSTAMP_PRECISION_NANO);
    const int rc = pcap_activate(handle_);
    if (rc < 0) {
        const std::string detail = pcap_geterr(handle_);
        switch (rc) {
            case PCAP_ERROR_NO_SUCH_DEVICE:
                fail(LinkError::Kind::NoSuchInterface, "network interface '" + iface + "' does not exist");
                break;
            case PCAP_ERROR_PERM_DENIED:
            case PCAP_ERROR_PROMISC_PERM_DENIED:
                fail(LinkError::Kind::PermissionDenied, permission_hint(iface));
                break;
            case PCAP_ERROR_IFACE_NOT_UP:
                fail(LinkError::Kind::InterfaceDown, "network interface '" + iface + "' is down");
                break;
            default:
                fail(LinkError::Kind::System, "pcap_activate(" + iface + "): " + detail);
        }
    }
    stamp_unit_ns_ = pcap_get_tstamp_precision(handle_) == PCAP_TSTAMP_PRECISION_NANO ? 1 : 1000;
    if (pcap_datalink(handle_) != DLT_EN10MB)
        fail(LinkError::Kind::BadArgument, "interface '" + iface + "' is not an Ethernet interface");
    if (pcap_setdirection(handle_, PCAP_D_IN) != 0)
        fail(LinkError::Kind::System, "pcap_setdirection(" + iface + "): " + pcap_geterr(handle_));
    bpf_program prog{};
    if (pcap_compile(handle_, &prog, kFilter, 1, PCAP_NETMASK_UNKNOWN) != 0)
        fail(LinkError::Kind::System, "pcap_compile: " + std::string(pcap_geterr(handle_)));
    const int frc = pcap_setfilter(handle_, &prog);
    pcap_freecode(&prog);
    if (frc != 0) fail(LinkError::Kind::System, "pcap_setfilter: " + std::string(pcap_geterr(handle_)));
    if (pcap_setnonblock(handle_, 1, errbuf) != 0)
        fail(LinkError::Kind::System, "pcap_setnonblock: " + std::string(errbuf));
    fd_ = pcap_get_selectable_fd(handle_);
    if (fd_ < 0) fail(LinkError::Kind::System, "interface '" + iface + "' has no selectable descriptor");
}

PcapLink::~PcapLink() {
    if (handle_ != nullptr) pcap_close(handle_);
}

std::size_t PcapLink::receive(std::span<uint8_t> buf) {
    pcap_pkthdr* hdr = nullptr;
    const u_char* data = nullptr;
    const int rc = pcap_next_ex(handle_, &hdr, &data);
    if (rc != 1 || hdr == nullptr || data == nullptr) return 0;
    const std::size_t n = std::min<std::size_t>(hdr->caplen, buf.size());
    std::memcpy(buf.data(), data, n);
    stamp_ns_ = static_cast<uint64_t>(hdr->ts.tv_sec) * 1'000'000'000ull +
                static_cast<uint64_t>(hdr->ts.tv_usec) * stamp_unit_ns_;
    return pad_to_minimum(buf, n);
}

bool PcapLink::send(std::span<const uint8_t> frame) {
    if (frame.empty()) return false;
    return pcap_inject(handle_, frame.data(), frame.size()) == static_cast<int>(frame.size());
}

}  // namespace esc
