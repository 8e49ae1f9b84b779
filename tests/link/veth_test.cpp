// PcapLink and PacketLink on a real veth pair inside a network namespace the test creates. The namespace
// is anonymous (unshare on a helper thread) and dies with the last socket in it, taking the veth pair along,
// so nothing stays behind even when a test fails. Skipped when not root.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <linux/if_packet.h>
#include <net/if.h>
#include <poll.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <memory>
#include <vector>

#include "esc/link.hpp"
#include "esc/link_packet.hpp"
#include "esc/link_pcap.hpp"
#include "netns_util.hpp"
#include "slave/netif.hpp"

namespace {

using linktest::in_new_netns;

bool wait_readable(const esc::Link& link, int timeout_ms) {
    pollfd p{link.fd(), POLLIN, 0};
    return ::poll(&p, 1, timeout_ms) == 1 && (p.revents & POLLIN) != 0;
}

// Receives one frame, waiting up to timeout_ms; returns its length (0 if none came).
std::size_t receive_within(esc::Link& link, std::span<uint8_t> buf, int timeout_ms) {
    for (int i = 0; i < 4; ++i) {
        if (const std::size_t n = link.receive(buf)) return n;
        if (!wait_readable(link, timeout_ms / 4)) continue;
    }
    return link.receive(buf);
}

std::vector<uint8_t> ecat_frame(std::size_t total_len, uint8_t tag) {
    std::vector<uint8_t> f(total_len, 0);
    for (int i = 0; i < 6; ++i)
        f[static_cast<std::size_t>(i)] = 0xFF;  // broadcast
    for (int i = 6; i < 12; ++i)
        f[static_cast<std::size_t>(i)] = 0x01;  // as SOEM sends
    f[12] = 0x88;
    f[13] = 0xA4;
    if (total_len >= 16) {
        f[14] = 0x0E;  // one datagram of 2 data bytes: length 14, type 1
        f[15] = 0x10;
    }
    if (total_len > 17) f[17] = tag;  // datagram index
    return f;
}

struct Pair {
    std::unique_ptr<esc::Link> slave;   // the end under test
    std::unique_ptr<esc::Link> master;  // the other end (always a PacketLink)
};

// Creates veth "s0"/"m0" in a fresh namespace and opens the slave end with `backend`.
Pair make_pair(const std::string& backend) {
    Pair p;
    in_new_netns([&] {
        slave::create_veth("s0", "m0");
        slave::disable_ipv6("s0");
        slave::disable_ipv6("m0");
        slave::set_interface_up("s0");
        slave::set_interface_up("m0");
        p.slave = esc::open_link("s0", backend);
        p.master = std::make_unique<esc::PacketLink>("m0");
    });
    return p;
}

class VethLink : public ::testing::TestWithParam<std::string> {
  protected:
    void SetUp() override {
        if (!linktest::is_root()) GTEST_SKIP() << "needs root (CAP_NET_ADMIN, CAP_NET_RAW)";
    }
};

TEST_P(VethLink, EchoesFramesBothWaysRuntsPaddedAsOnAWire) {
    Pair p = make_pair(GetParam());
    std::array<uint8_t, esc::kMaxFrameSize> buf{};
    // Minimum (60) and full-size frames arrive at their length. A veth does not pad: a runt (29 bytes) is
    // returned padded with zeros to 60, as the sender's NIC would have put it on a wire.
    for (std::size_t len : {std::size_t{29}, std::size_t{60}, std::size_t{1514}}) {
        const auto f = ecat_frame(len, static_cast<uint8_t>(len));
        const std::size_t wire = std::max<std::size_t>(len, 60);
        buf.fill(0xEE);
        ASSERT_TRUE(p.master->send(f));
        ASSERT_EQ(receive_within(*p.slave, buf, 2000), wire);
        EXPECT_TRUE(std::equal(f.begin(), f.end(), buf.begin()));
        EXPECT_TRUE(std::all_of(buf.begin() + static_cast<long>(len), buf.begin() + static_cast<long>(wire),
                                [](uint8_t b) { return b == 0; }));
        buf[6] |= 0x02;  // what an ESC does to the source MAC
        ASSERT_TRUE(p.slave->send(std::span<const uint8_t>(buf.data(), wire)));
        std::array<uint8_t, esc::kMaxFrameSize> back{};
        ASSERT_EQ(receive_within(*p.master, back, 2000), wire);
        EXPECT_EQ(back[6], 0x03);
    }
}

// ESC datasheet section I, frame processing: VLAN-tagged frames are processed, the tag not modified. The
// kernel takes the tag off into the ring's metadata; the link puts it back.
TEST_P(VethLink, VlanTaggedFrameArrivesWithItsTag) {
    Pair p = make_pair(GetParam());
    auto f = ecat_frame(60, 0x42);
    const uint8_t tag[4] = {0x81, 0x00, 0xA0, 0x07};  // priority 5, VLAN 7
    f.insert(f.begin() + 12, tag, tag + 4);
    std::array<uint8_t, esc::kMaxFrameSize> buf{};
    ASSERT_TRUE(p.master->send(f));
    ASSERT_EQ(receive_within(*p.slave, buf, 2000), f.size());
    EXPECT_TRUE(std::equal(f.begin(), f.end(), buf.begin()));
}

// ESC datasheet section I, UDP/IP: EtherCAT in IPv4/UDP to port 0x88A4 reaches the ESC; other IP traffic not.
TEST_P(VethLink, EtherCatInUdpArrivesOtherIpDoesNot) {
    Pair p = make_pair(GetParam());
    auto udp = [](uint16_t port) {
        std::vector<uint8_t> f(12, 0xFF);
        for (int i = 6; i < 12; ++i)
            f[static_cast<std::size_t>(i)] = 0x01;
        const uint8_t rest[] = {0x08,
                                0x00,  // IPv4
                                0x45,
                                0,
                                0,
                                44,
                                0,
                                0,
                                0,
                                0,
                                64,
                                0x11,
                                0,
                                0,  // IP: UDP
                                10,
                                0,
                                0,
                                1,
                                10,
                                0,
                                0,
                                255,  // addresses
                                0x88,
                                0xA4,
                                static_cast<uint8_t>(port >> 8),  // UDP ports
                                static_cast<uint8_t>(port),
                                0,
                                24,
                                0x12,
                                0x34,  // length, checksum
                                0x0E,
                                0x10,
                                1,
                                0x33,
                                0,
                                0,
                                0x30,
                                0x01,
                                2,
                                0,
                                0,
                                0,
                                0,
                                0,
                                0,
                                0};
        f.insert(f.end(), rest, rest + sizeof rest);
        return f;
    };
    std::array<uint8_t, esc::kMaxFrameSize> buf{};
    ASSERT_TRUE(p.master->send(udp(0x0035)));  // DNS: not for an ESC
    ASSERT_TRUE(p.master->send(udp(0x88A4)));
    ASSERT_EQ(receive_within(*p.slave, buf, 2000), 60u);
    EXPECT_EQ(buf[36], 0x88);
    EXPECT_EQ(buf[37], 0xA4);
    EXPECT_EQ(buf[42 + 3], 0x33);  // the datagram index: the EtherCAT frame, not the DNS one
    EXPECT_EQ(receive_within(*p.slave, buf, 200), 0u);
}

TEST_P(VethLink, OwnRepliesNeverComeBackIn) {
    Pair p = make_pair(GetParam());
    std::array<uint8_t, esc::kMaxFrameSize> buf{};
    const auto f = ecat_frame(60, 7);
    ASSERT_TRUE(p.slave->send(f));
    std::array<uint8_t, esc::kMaxFrameSize> back{};
    ASSERT_EQ(receive_within(*p.master, back, 2000), 60u);
    // The master also never sees its own frame, and the slave sees nothing.
    EXPECT_EQ(receive_within(*p.slave, buf, 200), 0u);
    ASSERT_TRUE(p.master->send(f));
    ASSERT_EQ(receive_within(*p.slave, buf, 2000), 60u);
    EXPECT_EQ(receive_within(*p.master, back, 200), 0u);
}

// A plain AF_PACKET socket (through the qdisc, so packet taps see its frames as PACKET_OUTGOING), as a
// capture tool or a second program on the slave's interface would use.
int plain_packet_socket(const char* iface) {
    const int fd = ::socket(AF_PACKET, SOCK_RAW | SOCK_CLOEXEC, htons(0x88A4));
    if (fd < 0) throw std::runtime_error("socket(AF_PACKET)");
    sockaddr_ll addr{};
    addr.sll_family = AF_PACKET;
    addr.sll_protocol = htons(0x88A4);
    addr.sll_ifindex = static_cast<int>(if_nametoindex(iface));
    if (::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
        ::close(fd);
        throw std::runtime_error("bind");
    }
    return fd;
}

TEST_P(VethLink, FramesAnotherSocketSendsOutOfTheSameInterfaceAreNotReceived) {
    std::unique_ptr<esc::Link> slave, master;
    int other = -1;
    in_new_netns([&] {
        slave::create_veth("s0", "m0");
        slave::set_interface_up("s0");
        slave::set_interface_up("m0");
        slave = esc::open_link("s0", GetParam());
        master = std::make_unique<esc::PacketLink>("m0");
        other = plain_packet_socket("s0");
    });
    const auto f = ecat_frame(60, 9);
    ASSERT_EQ(::send(other, f.data(), f.size(), 0), 60);
    std::array<uint8_t, esc::kMaxFrameSize> buf{};
    ASSERT_EQ(receive_within(*master, buf, 2000), 60u) << "the frame went out on the wire";
    EXPECT_EQ(receive_within(*slave, buf, 200), 0u) << "an outgoing frame must not be taken as received";
    ::close(other);
}

TEST_P(VethLink, OnlyEtherCatFramesAreReceived) {
    Pair p = make_pair(GetParam());
    auto other = ecat_frame(60, 1);
    other[12] = 0x08;  // IPv4
    other[13] = 0x00;
    ASSERT_TRUE(p.master->send(other));
    const auto f = ecat_frame(60, 2);
    ASSERT_TRUE(p.master->send(f));
    std::array<uint8_t, esc::kMaxFrameSize> buf{};
    ASSERT_EQ(receive_within(*p.slave, buf, 2000), 60u);
    EXPECT_EQ(buf[12], 0x88);
    EXPECT_EQ(buf[17], 2);
    EXPECT_EQ(receive_within(*p.slave, buf, 200), 0u);
}

TEST_P(VethLink, UnicastToAnotherMacIsReceived) {
    Pair p = make_pair(GetParam());
    auto f = ecat_frame(60, 3);
    for (int i = 0; i < 6; ++i)
        f[static_cast<std::size_t>(i)] = 0x02;  // not our MAC, not broadcast
    ASSERT_TRUE(p.master->send(f));
    std::array<uint8_t, esc::kMaxFrameSize> buf{};
    EXPECT_EQ(receive_within(*p.slave, buf, 2000), 60u);
}

TEST_P(VethLink, DownAndMissingInterfacesAreClearErrors) {
    in_new_netns([&] {
        slave::create_veth("s0", "m0");
        try {
            esc::open_link("s0", GetParam());
            ADD_FAILURE() << "opening a down interface must fail";
        } catch (const esc::LinkError& e) {
            EXPECT_EQ(e.kind(), esc::LinkError::Kind::InterfaceDown) << e.what();
            EXPECT_NE(std::string(e.what()).find("ip link set s0 up"), std::string::npos) << e.what();
        }
        try {
            esc::open_link("s9", GetParam());
            ADD_FAILURE() << "opening a missing interface must fail";
        } catch (const esc::LinkError& e) {
            EXPECT_EQ(e.kind(), esc::LinkError::Kind::NoSuchInterface) << e.what();
        }
        slave::delete_interface("s0");
    });
}

uint64_t realtime_ns() {
    timespec ts{};
    ::clock_gettime(CLOCK_REALTIME, &ts);
    return static_cast<uint64_t>(ts.tv_sec) * 1'000'000'000ull + static_cast<uint64_t>(ts.tv_nsec);
}

// Each frame carries the time the kernel delivered it (PacketLink: the ring slot's stamp; PcapLink: the same
// through libpcap, CLOCK_REALTIME), not the time it was read: a frame read after the next was sent, 100 ms
// later, still has its own arrival.
TEST_P(VethLink, EachFrameCarriesItsArrivalNotTheTimeItWasRead) {
    Pair p = make_pair(GetParam());
    constexpr uint64_t kTruncation = 1000;  // a stamp in microseconds is up to that much earlier
    const uint64_t before_first = realtime_ns();
    ASSERT_TRUE(p.master->send(ecat_frame(60, 1)));
    ::usleep(100'000);
    const uint64_t before_second = realtime_ns();
    ASSERT_TRUE(p.master->send(ecat_frame(60, 2)));
    std::array<uint8_t, esc::kMaxFrameSize> buf{};
    uint64_t stamps[2] = {};
    for (uint8_t tag = 1; tag <= 2; ++tag) {
        ASSERT_EQ(receive_within(*p.slave, buf, 2000), 60u);
        ASSERT_EQ(buf[17], tag);
        stamps[tag - 1] = p.slave->rx_stamp_ns();
        const uint64_t read = realtime_ns();
        EXPECT_GE(stamps[tag - 1] + kTruncation, tag == 1 ? before_first : before_second)
            << "frame " << int{tag};
        EXPECT_LE(stamps[tag - 1], read) << "frame " << int{tag};
        EXPECT_LE(p.slave->stamp_now_ns() - read, 1'000'000'000ull)
            << "the stamps' time base is CLOCK_REALTIME";
    }
    EXPECT_LT(stamps[0], before_second) << "the first frame's stamp is its arrival, not when it was read";
}

INSTANTIATE_TEST_SUITE_P(Backends, VethLink, ::testing::Values(std::string("pcap"), std::string("packet")),
                         [](const ::testing::TestParamInfo<std::string>& param_info) {
                             return param_info.param;
                         });

class VethPairs : public ::testing::Test {
  protected:
    void SetUp() override {
        if (!linktest::is_root()) GTEST_SKIP() << "needs root (CAP_NET_ADMIN)";
    }
};

TEST_F(VethPairs, CreatesUpPairWithoutIpv6AndRemovesItAgain) {
    in_new_netns([] {
        {
            slave::VethPair pair("ecat0", "ecat1");
            EXPECT_TRUE(slave::interface_exists("ecat0"));
            EXPECT_TRUE(slave::interface_exists("ecat1"));
            EXPECT_NO_THROW(esc::check_interface("ecat0"));  // up
            EXPECT_NO_THROW(esc::check_interface("ecat1"));
            for (const char* name : {"ecat0", "ecat1"}) {
                const std::string path = std::string("/proc/sys/net/ipv6/conf/") + name + "/disable_ipv6";
                if (FILE* f = std::fopen(path.c_str(), "r")) {
                    EXPECT_EQ(std::fgetc(f), '1') << name;
                    std::fclose(f);
                }
            }
        }
        EXPECT_FALSE(slave::interface_exists("ecat0"));
        EXPECT_FALSE(slave::interface_exists("ecat1"));
    });
}

TEST_F(VethPairs, RemovesAStalePairLeftByAKilledRun) {
    in_new_netns([] {
        slave::create_veth("ecat0", "ecat1");  // as if a previous run was killed
        {
            slave::VethPair pair("ecat0", "ecat1");
            EXPECT_TRUE(slave::interface_exists("ecat0"));
        }
        EXPECT_FALSE(slave::interface_exists("ecat0"));
        EXPECT_FALSE(slave::interface_exists("ecat1"));
    });
}

TEST_F(VethPairs, APairOwnedByARunningSlaveIsNotTakenAsStale) {
    in_new_netns([] {
        slave::VethPair first("ecat0", "ecat1");
        try {
            slave::VethPair second("ecat0", "ecat1");
            ADD_FAILURE() << "a second owner must be refused";
        } catch (const esc::LinkError& e) {
            EXPECT_EQ(e.kind(), esc::LinkError::Kind::BadArgument);
            EXPECT_NE(std::string(e.what()).find("in use"), std::string::npos) << e.what();
        }
        EXPECT_TRUE(slave::interface_exists("ecat0")) << "the first owner's pair must survive";
    });
}

TEST_F(VethPairs, CreatingAnExistingPairFailsClearly) {
    in_new_netns([] {
        slave::create_veth("x0", "x1");
        EXPECT_THROW(slave::create_veth("x0", "x1"), esc::LinkError);
        slave::delete_interface("x0");
        EXPECT_FALSE(slave::interface_exists("x1"));
        EXPECT_NO_THROW(slave::delete_interface("x0"));  // already gone: nothing to do
    });
}

}  // namespace
