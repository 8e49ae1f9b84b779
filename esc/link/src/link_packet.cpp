// PacketLink: AF_PACKET backend with a TPACKET_V2 receive ring. See esc/link_packet.hpp.
#include "esc/link_packet.hpp"

#include <arpa/inet.h>
#include <linux/filter.h>
#include <linux/if_ether.h>
#include <linux/if_packet.h>
#include <net/if.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "esc/wire/datagram.hpp"

namespace esc {

namespace {

constexpr uint16_t kEtherTypeEcat = wire::kEtherType;

// The socket filter (classic BPF) over the frame as the kernel hands it over, a VLAN tag already taken off
// into the slot header: EtherType 0x88A4, an 802.1Q tag left in place (a second one), or IPv4 with header
// length 5, protocol UDP and destination port 0x88A4 (what an ESC evaluates, ESC datasheet section I,
// UDP/IP).
constexpr sock_filter kFilter[] = {
    BPF_STMT(BPF_LD | BPF_H | BPF_ABS, 12),                           // 0: EtherType
    BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, kEtherTypeEcat, 8, 0),        // 1: -> accept
    BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, wire::kEtherTypeVlan, 7, 0),  // 2: -> accept
    BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, wire::kEtherTypeIpv4, 0, 7),  // 3: else -> reject
    BPF_STMT(BPF_LD | BPF_B | BPF_ABS, 14),                           // 4: IP version and header length
    BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, 0x45, 0, 5),                  // 5
    BPF_STMT(BPF_LD | BPF_B | BPF_ABS, 23),                           // 6: IP protocol
    BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, 0x11, 0, 3),                  // 7
    BPF_STMT(BPF_LD | BPF_H | BPF_ABS, 36),                           // 8: UDP destination port
    BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, wire::kUdpPortEcat, 0, 1),    // 9
    BPF_STMT(BPF_RET | BPF_K, 0xFFFF),                                // 10: accept
    BPF_STMT(BPF_RET | BPF_K, 0),                                     // 11: reject
};
// Ring geometry: 2 KiB slots (TPACKET2 header + sockaddr_ll + a 1518-byte frame fit), 8 slots per 16 KiB
// block, 16 blocks: 128 frames may wait before the kernel drops.
constexpr std::size_t kSlotSize = 2048;
constexpr std::size_t kBlockSize = 16384;
constexpr std::size_t kBlockCount = 16;

[[noreturn]] void throw_errno(const std::string& iface, const char* what, int err) {
    if (err == EPERM || err == EACCES)
        throw LinkError(LinkError::Kind::PermissionDenied,
                        "no permission to open a raw socket on '" + iface +
                            "': AF_PACKET needs CAP_NET_RAW (and CAP_NET_ADMIN for promiscuous mode); run as "
                            "root or `sudo setcap cap_net_raw,cap_net_admin+ep <program>`");
    if (err == ENODEV || err == ENXIO)
        throw LinkError(LinkError::Kind::NoSuchInterface, "network interface '" + iface + "' does not exist");
    if (err == ENETDOWN)
        throw LinkError(LinkError::Kind::InterfaceDown, "network interface '" + iface + "' is down");
    throw LinkError(LinkError::Kind::System,
                    std::string(what) + " on '" + iface + "': " + std::strerror(err));
}

}  // namespace

PacketLink::PacketLink(const std::string& iface) : iface_(iface) {
    check_interface(iface);
    ifindex_ = static_cast<int>(if_nametoindex(iface.c_str()));
    if (ifindex_ == 0) throw_errno(iface, "if_nametoindex", ENODEV);

    // Protocol 0 until bound: nothing is queued from other interfaces before bind().
    fd_ = ::socket(AF_PACKET, SOCK_RAW | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
    if (fd_ < 0) throw_errno(iface, "socket(AF_PACKET)", errno);
    auto fail = [this](const char* what) {
        const int err = errno;
        if (ring_ != nullptr) ::munmap(ring_, ring_size_);
        ring_ = nullptr;
        ::close(fd_);
        fd_ = -1;
        throw_errno(iface_, what, err);
    };

    int version = TPACKET_V2;
    if (::setsockopt(fd_, SOL_PACKET, PACKET_VERSION, &version, sizeof version) < 0) fail("PACKET_VERSION");
    int one = 1;
    // Best effort: kernels before 4.20 lack it; receive() also skips PACKET_OUTGOING slots.
    (void)::setsockopt(fd_, SOL_PACKET, PACKET_IGNORE_OUTGOING, &one, sizeof one);
    (void)::setsockopt(fd_, SOL_PACKET, PACKET_QDISC_BYPASS, &one, sizeof one);

    sock_fprog prog{};
    prog.len = static_cast<unsigned short>(sizeof kFilter / sizeof kFilter[0]);
    prog.filter = const_cast<sock_filter*>(kFilter);
    if (::setsockopt(fd_, SOL_SOCKET, SO_ATTACH_FILTER, &prog, sizeof prog) < 0) fail("SO_ATTACH_FILTER");

    tpacket_req req{};
    req.tp_block_size = kBlockSize;
    req.tp_block_nr = kBlockCount;
    req.tp_frame_size = kSlotSize;
    req.tp_frame_nr = static_cast<unsigned>(kBlockSize / kSlotSize * kBlockCount);
    if (::setsockopt(fd_, SOL_PACKET, PACKET_RX_RING, &req, sizeof req) < 0) fail("PACKET_RX_RING");
    ring_size_ = kBlockSize * kBlockCount;
    frame_size_ = kSlotSize;
    frame_count_ = req.tp_frame_nr;
    void* ring = ::mmap(nullptr, ring_size_, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, 0);
    if (ring == MAP_FAILED) fail("mmap(PACKET_RX_RING)");
    ring_ = static_cast<uint8_t*>(ring);

    sockaddr_ll addr{};
    addr.sll_family = AF_PACKET;
    addr.sll_protocol = htons(ETH_P_ALL);  // the filter chooses: VLAN-tagged and UDP frames too
    addr.sll_ifindex = ifindex_;
    if (::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) < 0) fail("bind");

    packet_mreq mreq{};
    mreq.mr_ifindex = ifindex_;
    mreq.mr_type = PACKET_MR_PROMISC;
    if (::setsockopt(fd_, SOL_PACKET, PACKET_ADD_MEMBERSHIP, &mreq, sizeof mreq) < 0)
        fail("PACKET_ADD_MEMBERSHIP(PROMISC)");
}

PacketLink::~PacketLink() {
    if (ring_ != nullptr) ::munmap(ring_, ring_size_);
    if (fd_ >= 0) ::close(fd_);
}

std::size_t PacketLink::receive(std::span<uint8_t> buf) {
    // Bounded: at most one pass over the ring (skipped slots are our own outgoing frames).
    for (std::size_t tries = 0; tries < frame_count_; ++tries) {
        auto* hdr = reinterpret_cast<tpacket2_hdr*>(ring_ + next_ * frame_size_);
        const uint32_t status = __atomic_load_n(&hdr->tp_status, __ATOMIC_ACQUIRE);
        if ((status & TP_STATUS_USER) == 0) return 0;
        const auto* sll = reinterpret_cast<const sockaddr_ll*>(reinterpret_cast<const uint8_t*>(hdr) +
                                                               TPACKET_ALIGN(sizeof(tpacket2_hdr)));
        std::size_t n = 0;
        if (sll->sll_pkttype != PACKET_OUTGOING && hdr->tp_mac + hdr->tp_snaplen <= frame_size_) {
            const uint8_t* data = reinterpret_cast<const uint8_t*>(hdr) + hdr->tp_mac;
            const std::size_t len = hdr->tp_snaplen;
            if ((status & TP_STATUS_VLAN_VALID) != 0 && len >= 12 && buf.size() >= 16) {
                // The tag the kernel took off goes back after the source MAC, unchanged.
                const uint16_t tpid =
                    (status & TP_STATUS_VLAN_TPID_VALID) != 0 ? hdr->tp_vlan_tpid : wire::kEtherTypeVlan;
                std::memcpy(buf.data(), data, 12);
                buf[12] = static_cast<uint8_t>(tpid >> 8);
                buf[13] = static_cast<uint8_t>(tpid);
                buf[14] = static_cast<uint8_t>(hdr->tp_vlan_tci >> 8);
                buf[15] = static_cast<uint8_t>(hdr->tp_vlan_tci);
                n = std::min<std::size_t>(len + 4, buf.size());
                std::memcpy(buf.data() + 16, data + 12, n - 16);
            } else {
                n = std::min<std::size_t>(len, buf.size());
                std::memcpy(buf.data(), data, n);
            }
            n = pad_to_minimum(buf, n);
            stamp_ns_ = static_cast<uint64_t>(hdr->tp_sec) * 1'000'000'000ull + hdr->tp_nsec;
        }
        __atomic_store_n(&hdr->tp_status, static_cast<uint32_t>(TP_STATUS_KERNEL), __ATOMIC_RELEASE);
        next_ = (next_ + 1) % frame_count_;
        if (n > 0) return n;
    }
    return 0;
}

bool PacketLink::send(std::span<const uint8_t> frame) {
    if (frame.empty()) return false;
    for (int attempt = 0; attempt < 2; ++attempt) {
        const ssize_t rc = ::send(fd_, frame.data(), frame.size(), MSG_DONTWAIT);
        if (rc == static_cast<ssize_t>(frame.size())) return true;
        if (rc < 0 && errno != EINTR && errno != EAGAIN && errno != ENOBUFS) return false;
    }
    return false;
}

}  // namespace esc
