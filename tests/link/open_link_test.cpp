#include <gtest/gtest.h>

#include "esc/link.hpp"
#include "slave/netif.hpp"

namespace {

using Kind = esc::LinkError::Kind;

Kind kind_of_open(const std::string& iface, const std::string& backend) {
    try {
        esc::open_link(iface, backend);
    } catch (const esc::LinkError& e) {
        return e.kind();
    }
    ADD_FAILURE() << "open_link(" << iface << ", " << backend << ") did not throw";
    return Kind::System;
}

TEST(OpenLink, UnknownBackendIsABadArgument) {
    EXPECT_EQ(kind_of_open("lo", "dpdk"), Kind::BadArgument);
}

TEST(OpenLink, MissingInterfaceIsReportedByBothBackends) {
    EXPECT_EQ(kind_of_open("nosuchif0", "pcap"), Kind::NoSuchInterface);
    EXPECT_EQ(kind_of_open("nosuchif0", "packet"), Kind::NoSuchInterface);
    EXPECT_EQ(kind_of_open("nosuchif0", ""), Kind::NoSuchInterface);
    EXPECT_EQ(kind_of_open("", "packet"), Kind::BadArgument);
    EXPECT_EQ(kind_of_open("a-name-far-too-long-for-linux", "packet"), Kind::BadArgument);
}

TEST(OpenLink, DefaultBackendIsOneOfTheTwo) {
    const std::string d = esc::default_link_backend();
    EXPECT_TRUE(d == "pcap" || d == "packet") << d;
}

TEST(VethPeerName, IncrementsATrailingNumberOrAppendsASuffix) {
    EXPECT_EQ(slave::veth_peer_name("ecat0"), "ecat1");
    EXPECT_EQ(slave::veth_peer_name("veth9"), "veth10");
    EXPECT_EQ(slave::veth_peer_name("slave"), "slave-m");
}

}  // namespace
