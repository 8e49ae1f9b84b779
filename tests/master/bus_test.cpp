// The DC topology and propagation-delay computation of the master (bus.hpp) against a model of a segment:
// a frame walked through a tree of ESCs with known processing, forwarding and cable delays, each ESC latching
// its port receive times on its own clock. The true arrival times are known, so the computed delays can be
// checked against them (exactly when the processing and forwarding delays are equal, as ETG.1020 assumes).
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "master/bus.hpp"

using namespace master;

namespace {

struct Node {
    int children[4] = {-1, -1, -1, -1};  // child node at each port (port 0 faces upstream)
    int64_t clock_offset = 0;            // the ESC's local clock = model time + offset
};

struct Model {
    std::vector<Node> nodes;
    int64_t processing = 320, forwarding = 320, cable = 10;
    // Filled by walk(): position order, true arrival time at each node's port 0, latched port times.
    std::vector<int> order;
    std::vector<int64_t> arrival;
    std::vector<std::array<uint32_t, 4>> latch;

    int64_t walk(int n, int64_t t_in) {
        order.push_back(n);
        arrival[static_cast<std::size_t>(n)] = t_in;
        auto& l = latch[static_cast<std::size_t>(n)];
        const int64_t off = nodes[static_cast<std::size_t>(n)].clock_offset;
        l[0] = static_cast<uint32_t>(t_in + off);
        int64_t t = t_in + processing;  // port 0 -> processing unit -> next port
        for (int p = next_port(0); p != 0; p = next_port(p)) {
            const int child = nodes[static_cast<std::size_t>(n)].children[p];
            if (child < 0) continue;  // closed: looped back inside the ESC
            const int64_t back = walk(child, t + cable) + cable;
            l[static_cast<std::size_t>(p)] = static_cast<uint32_t>(back + off);
            t = back + forwarding;
        }
        return t;
    }

    std::vector<SlaveInfo> run() {
        order.clear();
        arrival.assign(nodes.size(), 0);
        latch.assign(nodes.size(), {});
        walk(0, 1'000);
        std::vector<SlaveInfo> s(order.size());
        for (std::size_t i = 0; i < order.size(); ++i) {
            const Node& node = nodes[static_cast<std::size_t>(order[i])];
            s[i].position = static_cast<uint16_t>(i);
            s[i].station = static_cast<uint16_t>(0x1001 + i);
            s[i].has_dc = true;
            // DL status: link + communication on port 0 and each used port; others loop closed.
            uint16_t dl = 0;
            for (int p = 0; p < 4; ++p) {
                const bool used = p == 0 || node.children[p] >= 0;
                if (used)
                    dl = static_cast<uint16_t>(dl | (1u << (4 + p)) | (1u << (9 + 2 * p)));
                else
                    dl = static_cast<uint16_t>(dl | (1u << (8 + 2 * p)));
            }
            s[i].dl_status = dl;
            s[i].active_ports = active_ports_from_dl_status(dl);
            s[i].port_time = latch[static_cast<std::size_t>(order[i])];
        }
        return s;
    }
    int64_t true_delay(std::size_t position) const {
        return arrival[static_cast<std::size_t>(order[position])] -
               arrival[static_cast<std::size_t>(order[0])];
    }
};

Model line(int n) {
    Model m;
    m.nodes.resize(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
        m.nodes[static_cast<std::size_t>(i)].clock_offset = 1'000'000'007LL * (i + 1) % 4'000'000'000LL;
        if (i + 1 < n) m.nodes[static_cast<std::size_t>(i)].children[1] = i + 1;
    }
    return m;
}

}  // namespace

TEST(BusDl, ActivePortsFromDlStatus) {
    // Port 0 communication, port 1 loop closed, port 2 loop open and communication, port 3 open, no comm.
    const uint16_t dl = (1u << 9) | (1u << 10) | (1u << 13);
    EXPECT_EQ(active_ports_from_dl_status(dl), 0x05);
    EXPECT_EQ(active_ports_from_dl_status(0), 0x00);
    EXPECT_EQ(next_port(0), 3);
    EXPECT_EQ(next_port(3), 1);
    EXPECT_EQ(next_port(1), 2);
    EXPECT_EQ(next_port(2), 0);
}

TEST(BusDc, LineDelaysIncreaseAndMatchTheWire) {
    Model m = line(5);
    auto s = m.run();
    ASSERT_EQ(compute_dc_topology(s), Error::Ok);
    EXPECT_EQ(reference_clock(s), 0);
    EXPECT_EQ(s[0].delay_ns, 0);
    EXPECT_EQ(s[0].parent, -1);
    for (std::size_t i = 1; i < s.size(); ++i) {
        EXPECT_EQ(s[i].parent, static_cast<int>(i) - 1);
        EXPECT_EQ(s[i].parent_port, 1);
        EXPECT_EQ(s[i].entry_port, 0);
        EXPECT_GT(s[i].delay_ns, s[i - 1].delay_ns);
        EXPECT_EQ(s[i].delay_ns, m.true_delay(i)) << "slave " << i;
    }
}

TEST(BusDc, UnequalProcessingAndForwardingStaysWithinHalfTheDifferencePerHop) {
    Model m = line(4);
    m.processing = 400;
    m.forwarding = 280;
    auto s = m.run();
    ASSERT_EQ(compute_dc_topology(s), Error::Ok);
    for (std::size_t i = 1; i < s.size(); ++i) {
        EXPECT_GT(s[i].delay_ns, s[i - 1].delay_ns);
        EXPECT_LE(std::llabs(s[i].delay_ns - m.true_delay(i)), static_cast<long long>(i) * 60) << i;
    }
}

TEST(BusDc, TreeWithAJunction) {
    // 0: junction with children at ports 3, 1 and 2; the child at port 1 has a child of its own.
    Model m;
    m.nodes.resize(6);
    m.nodes[0].children[3] = 1;
    m.nodes[0].children[1] = 2;
    m.nodes[2].children[1] = 3;
    m.nodes[0].children[2] = 4;
    m.nodes[4].children[1] = 5;
    for (std::size_t i = 0; i < m.nodes.size(); ++i)
        m.nodes[i].clock_offset = static_cast<int64_t>(i) * 123'456'789;
    auto s = m.run();
    ASSERT_EQ(s.size(), 6u);
    ASSERT_EQ(compute_dc_topology(s), Error::Ok);
    // Positions follow the processing order: 0, its port 3 child, its port 1 child and grandchild, port 2...
    const int parent[6] = {-1, 0, 0, 2, 0, 4};
    const int port[6] = {-1, 3, 1, 1, 2, 1};
    for (std::size_t i = 0; i < s.size(); ++i) {
        EXPECT_EQ(s[i].parent, parent[i]) << i;
        EXPECT_EQ(s[i].parent_port, port[i]) << i;
        EXPECT_EQ(s[i].delay_ns, m.true_delay(i)) << i;
    }
    // A later branch of the junction is further away than the earlier ones.
    EXPECT_GT(s[4].delay_ns, s[3].delay_ns);
    EXPECT_GT(s[3].delay_ns, s[2].delay_ns);
}

TEST(BusDc, MoreSlavesThanOpenPortsIsNoTree) {
    Model m = line(3);
    auto s = m.run();
    s[1].active_ports = 0x01;  // the middle one claims to be the end of the line
    EXPECT_EQ(compute_dc_topology(s), Error::InvalidArgument);
}

TEST(BusDc, SlavesBeforeTheFirstDcSlaveHaveNoDelay) {
    Model m = line(3);
    auto s = m.run();
    s[0].has_dc = false;
    ASSERT_EQ(compute_dc_topology(s), Error::Ok);
    EXPECT_EQ(reference_clock(s), 1);
    EXPECT_EQ(s[0].delay_ns, 0);
    EXPECT_EQ(s[1].delay_ns, 0);
    EXPECT_EQ(s[2].delay_ns, m.true_delay(2) - m.true_delay(1));
}
