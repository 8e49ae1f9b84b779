// rtnetlink plumbing. See slave/netif.hpp.
#include "slave/netif.hpp"

#include <fcntl.h>
#include <linux/if_link.h>
#include <linux/netlink.h>
#include <linux/rtnetlink.h>
#include <linux/veth.h>
#include <net/if.h>
#include <sys/file.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>

namespace slave {

namespace {

using esc::LinkError;

// Builds one rtnetlink request in a fixed buffer.
class Request {
  public:
    Request(uint16_t type, uint16_t flags) {
        hdr()->nlmsg_len = NLMSG_LENGTH(0);
        hdr()->nlmsg_type = type;
        hdr()->nlmsg_flags = static_cast<uint16_t>(NLM_F_REQUEST | NLM_F_ACK | flags);
        hdr()->nlmsg_seq = 1;
    }
    nlmsghdr* hdr() { return reinterpret_cast<nlmsghdr*>(buf_); }
    // Appends raw bytes (a struct ifinfomsg), padded to 4 bytes.
    void append(const void* data, std::size_t len) {
        uint8_t* p = reserve(NLMSG_ALIGN(len));
        std::memcpy(p, data, len);
    }
    void attr(uint16_t type, const void* data, std::size_t len) {
        auto* a = reinterpret_cast<rtattr*>(reserve(RTA_SPACE(len)));
        a->rta_type = type;
        a->rta_len = static_cast<uint16_t>(RTA_LENGTH(len));
        std::memcpy(RTA_DATA(a), data, len);
    }
    void attr_str(uint16_t type, const std::string& s) { attr(type, s.c_str(), s.size() + 1); }
    std::size_t begin_nest(uint16_t type) {
        const std::size_t at = hdr()->nlmsg_len;
        auto* a = reinterpret_cast<rtattr*>(reserve(RTA_LENGTH(0)));
        a->rta_type = type;
        return at;
    }
    void end_nest(std::size_t at) {
        reinterpret_cast<rtattr*>(buf_ + at)->rta_len = static_cast<uint16_t>(hdr()->nlmsg_len - at);
    }

  private:
    uint8_t* reserve(std::size_t len) {
        const std::size_t at = hdr()->nlmsg_len;  // always 4-byte aligned
        if (at + len > sizeof buf_) throw LinkError(LinkError::Kind::System, "netlink request too long");
        std::memset(buf_ + at, 0, len);
        hdr()->nlmsg_len = static_cast<uint32_t>(at + len);
        return buf_ + at;
    }
    alignas(nlmsghdr) uint8_t buf_[1024] = {};
};

[[noreturn]] void fail(const std::string& what, int err) {
    if (err == EPERM || err == EACCES)
        throw LinkError(LinkError::Kind::PermissionDenied,
                        what +
                            ": permission denied; creating and configuring interfaces needs CAP_NET_ADMIN "
                            "(run as root, or pass --iface with an existing interface)");
    if (err == ENODEV) throw LinkError(LinkError::Kind::NoSuchInterface, what + ": no such interface");
    throw LinkError(LinkError::Kind::System, what + ": " + std::strerror(err));
}

// Sends the request and waits for the kernel's acknowledgement. Returns 0 or a positive errno.
int transact(Request& req) {
    const int fd = ::socket(AF_NETLINK, SOCK_RAW | SOCK_CLOEXEC, NETLINK_ROUTE);
    if (fd < 0) return errno;
    sockaddr_nl kernel{};
    kernel.nl_family = AF_NETLINK;
    int result = 0;
    if (::sendto(fd, req.hdr(), req.hdr()->nlmsg_len, 0, reinterpret_cast<sockaddr*>(&kernel),
                 sizeof kernel) < 0) {
        result = errno;
    } else {
        alignas(nlmsghdr) uint8_t reply[8192];
        for (;;) {
            const ssize_t n = ::recv(fd, reply, sizeof reply, 0);
            if (n < 0) {
                if (errno == EINTR) continue;
                result = errno;
                break;
            }
            bool done = false;
            // NLMSG_OK/NLMSG_NEXT spelled out with unsigned sizes: the macros compare the u32 nlmsg_len with
            // an int length (clang's -Wsign-compare).
            std::size_t left = static_cast<std::size_t>(n);
            for (auto* h = reinterpret_cast<nlmsghdr*>(reply);
                 left >= sizeof(nlmsghdr) && h->nlmsg_len >= sizeof(nlmsghdr) && h->nlmsg_len <= left;) {
                if (h->nlmsg_type == NLMSG_ERROR) {
                    const auto* e = static_cast<const nlmsgerr*>(NLMSG_DATA(h));
                    result = -e->error;
                    done = true;
                    break;
                }
                if (h->nlmsg_type == NLMSG_DONE) {
                    done = true;
                    break;
                }
                const std::size_t step = std::min<std::size_t>(NLMSG_ALIGN(h->nlmsg_len), left);
                left -= step;
                h = reinterpret_cast<nlmsghdr*>(reinterpret_cast<uint8_t*>(h) + step);
            }
            if (done) break;
        }
    }
    ::close(fd);
    return result;
}

int index_of(const std::string& name) {
    const unsigned idx = if_nametoindex(name.c_str());
    if (idx == 0) fail("interface '" + name + "'", ENODEV);
    return static_cast<int>(idx);
}

void check_name(const std::string& name) {
    if (name.empty() || name.size() >= IFNAMSIZ)
        throw LinkError(LinkError::Kind::BadArgument, "interface name '" + name + "' must have 1 to " +
                                                          std::to_string(IFNAMSIZ - 1) + " characters");
    for (char c : name)
        if (c == '/' || c == ':' || std::isspace(static_cast<unsigned char>(c)))
            throw LinkError(LinkError::Kind::BadArgument,
                            "interface name '" + name + "' has an invalid character");
}

}  // namespace

bool interface_exists(const std::string& name) {
    return if_nametoindex(name.c_str()) != 0;
}

void create_veth(const std::string& a, const std::string& b) {
    check_name(a);
    check_name(b);
    Request req(RTM_NEWLINK, NLM_F_CREATE | NLM_F_EXCL);
    ifinfomsg ifi{};
    ifi.ifi_family = AF_UNSPEC;
    req.append(&ifi, sizeof ifi);
    req.attr_str(IFLA_IFNAME, a);
    const auto linkinfo = req.begin_nest(IFLA_LINKINFO);
    req.attr_str(IFLA_INFO_KIND, "veth");
    const auto data = req.begin_nest(IFLA_INFO_DATA);
    const auto peer = req.begin_nest(VETH_INFO_PEER);
    req.append(&ifi, sizeof ifi);
    req.attr_str(IFLA_IFNAME, b);
    req.end_nest(peer);
    req.end_nest(data);
    req.end_nest(linkinfo);
    if (const int err = transact(req)) fail("creating veth pair " + a + "/" + b, err);
}

void delete_interface(const std::string& name) {
    const unsigned idx = if_nametoindex(name.c_str());
    if (idx == 0) return;
    Request req(RTM_DELLINK, 0);
    ifinfomsg ifi{};
    ifi.ifi_family = AF_UNSPEC;
    ifi.ifi_index = static_cast<int>(idx);
    req.append(&ifi, sizeof ifi);
    const int err = transact(req);
    if (err != 0 && err != ENODEV) fail("deleting interface " + name, err);
}

void set_interface_up(const std::string& name) {
    Request req(RTM_NEWLINK, 0);
    ifinfomsg ifi{};
    ifi.ifi_family = AF_UNSPEC;
    ifi.ifi_index = index_of(name);
    ifi.ifi_flags = IFF_UP;
    ifi.ifi_change = IFF_UP;
    req.append(&ifi, sizeof ifi);
    if (const int err = transact(req)) fail("setting " + name + " up", err);
}

void move_to_netns(const std::string& name, int netns_fd) {
    Request req(RTM_NEWLINK, 0);
    ifinfomsg ifi{};
    ifi.ifi_family = AF_UNSPEC;
    ifi.ifi_index = index_of(name);
    req.append(&ifi, sizeof ifi);
    const uint32_t fd = static_cast<uint32_t>(netns_fd);
    req.attr(IFLA_NET_NS_FD, &fd, sizeof fd);
    if (const int err = transact(req)) fail("moving " + name + " to another network namespace", err);
}

void disable_ipv6(const std::string& name) {
    check_name(name);
    const std::string path = "/proc/sys/net/ipv6/conf/" + name + "/disable_ipv6";
    const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
    if (fd < 0) {
        if (errno == ENOENT) return;  // no IPv6 in this kernel / namespace: nothing to silence
        fail("disabling IPv6 on " + name, errno);
    }
    const ssize_t n = ::write(fd, "1", 1);
    const int err = errno;
    ::close(fd);
    if (n != 1) fail("disabling IPv6 on " + name, err);
}

std::string veth_peer_name(const std::string& slave_end) {
    std::size_t digits = slave_end.size();
    while (digits > 0 && std::isdigit(static_cast<unsigned char>(slave_end[digits - 1])))
        --digits;
    if (digits == slave_end.size() || slave_end.size() - digits > 9) return slave_end + "-m";
    const unsigned long n = std::stoul(slave_end.substr(digits));
    return slave_end.substr(0, digits) + std::to_string(n + 1);
}

namespace {

// Takes the ownership lock of a veth name in the current network namespace. Returns the fd (kept open for
// the lifetime of the pair), or -1 if no lock directory is writable (then ownership is not checked).
int lock_veth_name(const std::string& name, std::string& lock_path) {
    struct stat ns {};
    const unsigned long long ns_id = ::stat("/proc/thread-self/ns/net", &ns) == 0 ? ns.st_ino : 0;
    for (const char* dir : {"/run/softecat", "/tmp/softecat"}) {
        ::mkdir(dir, 0755);
        const std::string path = std::string(dir) + "/veth-" + std::to_string(ns_id) + "-" + name + ".lock";
        const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
        if (fd < 0) continue;
        if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
            ::close(fd);
            throw LinkError(LinkError::Kind::BadArgument,
                            "veth interface '" + name + "' is in use by another running ecat-slave (lock " +
                                path + "); choose another name with --veth-name");
        }
        lock_path = path;
        return fd;
    }
    return -1;
}

}  // namespace

VethPair::VethPair(std::string slave_end, std::string master_end)
    : slave_end_(std::move(slave_end)), master_end_(std::move(master_end)) {
    check_name(slave_end_);
    check_name(master_end_);
    if (slave_end_ == master_end_)
        throw LinkError(LinkError::Kind::BadArgument, "the two ends of a veth pair need different names");
    lock_fd_ = lock_veth_name(slave_end_, lock_path_);
    try {
        create();
    } catch (...) {
        release_lock();
        throw;
    }
}

void VethPair::release_lock() {
    if (lock_fd_ < 0) return;
    ::unlink(lock_path_.c_str());
    ::close(lock_fd_);
    lock_fd_ = -1;
}

void VethPair::create() {
    // A killed earlier run may have left the pair (or one name) behind.
    delete_interface(slave_end_);
    delete_interface(master_end_);
    create_veth(slave_end_, master_end_);
    try {
        disable_ipv6(slave_end_);
        disable_ipv6(master_end_);
        set_interface_up(slave_end_);
        set_interface_up(master_end_);
    } catch (...) {
        delete_interface(slave_end_);
        throw;
    }
}

VethPair::~VethPair() {
    try {
        delete_interface(slave_end_);
    } catch (...) {
        // Nothing sensible to do in a destructor; the next run removes a stale pair.
    }
    release_lock();
}

}  // namespace slave
