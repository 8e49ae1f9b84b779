// open_link(), check_interface(): the shared front door of the link backends.
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "esc/link.hpp"
#include "esc/link_packet.hpp"
#include "esc/link_pcap.hpp"

namespace esc {

void check_interface(const std::string& iface) {
    if (iface.empty()) throw LinkError(LinkError::Kind::BadArgument, "no network interface named");
    if (iface.size() >= IFNAMSIZ)
        throw LinkError(LinkError::Kind::BadArgument,
                        "interface name '" + iface + "' is longer than " + std::to_string(IFNAMSIZ - 1));
    if (if_nametoindex(iface.c_str()) == 0)
        throw LinkError(LinkError::Kind::NoSuchInterface,
                        "network interface '" + iface + "' does not exist (see `ip link`)");
    int s = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    if (s < 0) s = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    if (s < 0) throw LinkError(LinkError::Kind::System, std::string("socket(): ") + std::strerror(errno));
    ifreq ifr{};
    std::memcpy(ifr.ifr_name, iface.c_str(), iface.size());
    const int rc = ::ioctl(s, SIOCGIFFLAGS, &ifr);
    const int err = errno;
    ::close(s);
    if (rc < 0) {
        if (err == ENODEV)
            throw LinkError(LinkError::Kind::NoSuchInterface,
                            "network interface '" + iface + "' does not exist (see `ip link`)");
        throw LinkError(LinkError::Kind::System, "SIOCGIFFLAGS on '" + iface + "': " + std::strerror(err));
    }
    if ((ifr.ifr_flags & IFF_UP) == 0)
        throw LinkError(
            LinkError::Kind::InterfaceDown,
            "network interface '" + iface + "' is down; bring it up with `ip link set " + iface + " up`");
}

// Measured on a veth pair (docs/decisions/link.md): the AF_PACKET ring is the faster of the two.
const char* default_link_backend() {
    return kBackendPacket;
}

std::unique_ptr<Link> open_link(const std::string& iface, const std::string& backend) {
    const std::string name = backend.empty() ? std::string(default_link_backend()) : backend;
    if (name == kBackendPcap) return std::make_unique<PcapLink>(iface);
    if (name == kBackendPacket) return std::make_unique<PacketLink>(iface);
    throw LinkError(LinkError::Kind::BadArgument,
                    "unknown link backend '" + name + "' (expected 'pcap' or 'packet')");
}

}  // namespace esc
