#pragma once
// Network interface plumbing over rtnetlink (no `ip` binary needed): veth pairs, link up, moving an
// interface into another network namespace, and switching IPv6 off on an interface so the kernel sends no
// router/neighbour solicitations or MLD reports onto an EtherCAT segment.
// Errors throw esc::LinkError; a missing CAP_NET_ADMIN is reported as PermissionDenied.
#include <string>

#include "esc/link.hpp"

namespace slave {

bool interface_exists(const std::string& name);
// Creates the veth pair a <-> b (both down).
void create_veth(const std::string& a, const std::string& b);
// Deletes the interface (for a veth, both ends go). Does nothing if it does not exist.
void delete_interface(const std::string& name);
void set_interface_up(const std::string& name);
// Writes 1 to /proc/sys/net/ipv6/conf/<name>/disable_ipv6 (ignored when the kernel has no IPv6).
void disable_ipv6(const std::string& name);
// Moves the interface into the network namespace open at netns_fd (e.g. /run/netns/x or /proc/<pid>/ns/net).
void move_to_netns(const std::string& name, int netns_fd);

// A veth pair that exists as long as this object: created (after removing a stale pair of the same names
// left by a killed run), IPv6 off and up on both ends; deleted by the destructor.
// An existing pair is only taken as stale if no live VethPair owns it: each owner holds an flock on
// /run/softecat/veth-<netns inode>-<name>.lock, and a second owner gets LinkError(BadArgument, "in use").
class VethPair {
  public:
    VethPair(std::string slave_end, std::string master_end);
    ~VethPair();
    VethPair(const VethPair&) = delete;
    VethPair& operator=(const VethPair&) = delete;
    const std::string& slave_end() const { return slave_end_; }
    const std::string& master_end() const { return master_end_; }

  private:
    void create();
    void release_lock();
    std::string slave_end_;
    std::string master_end_;
    std::string lock_path_;
    int lock_fd_ = -1;
};

// The master-side name for a slave-side veth name: a trailing number is incremented (ecat0 -> ecat1),
// otherwise "-m" is appended (ecat -> ecat-m).
std::string veth_peer_name(const std::string& slave_end);

}  // namespace slave
