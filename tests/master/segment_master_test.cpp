// The master on a line (and a tree) of emulated ESCs wired into an esc::Segment in process: bring-up of the
// whole line (count, station addresses, identities), DC propagation delays and offsets measured over it, one
// LRW process-data session over every slave, and a pulled cable seen as a working-counter error the session
// recovers from. The ESCs run with device emulation (AL status follows AL control), so no firmware is
// needed; every device has its own SII image (serial number = position + 1) and its own clock offset.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <vector>

#include "esc/clock.hpp"
#include "esc/esc.hpp"
#include "esc/segment.hpp"
#include "esc/wire/sii.hpp"
#include "master/bus.hpp"
#include "master/master.hpp"
#include "master/session.hpp"
#include "support/alloc_counter.hpp"
#include "support/fixed_link.hpp"
#include "support/master_bring_up.hpp"
#include "support/sii_image.hpp"
#include "support/wire_link.hpp"
#include "util/le.hpp"

using namespace master;

namespace {

constexpr uint32_t kVendor = 0x000000FB;  // test_support::small_sii_image's identity
constexpr uint32_t kProduct = 0x30010000;

// A segment of ESCs and a master whose link walks every frame through it.
struct Line {
    esc::ManualClock clock;
    std::vector<std::unique_ptr<esc::Esc>> escs;
    esc::Segment seg;
    test_support::WireLink link{[this](std::vector<uint8_t>& f) {
        clock.advance(50'000);  // time passes between frames
        return seg.walk(f, clock.now_ns()).kind == esc::Segment::Result::Kind::Reply;
    }};
    Master m{link, test_support::in_process_master_options()};

    Line() { clock.set(5'000'000'000); }
    int add(uint8_t port_descriptor = 0x0F) {
        esc::EscConfig cfg;
        cfg.port_descriptor = port_descriptor;
        // Every device's local clock is somewhere else, as after power-on.
        cfg.clock_offset_ns = static_cast<int64_t>(escs.size() + 1) * 1'234'567'891;
        escs.push_back(std::make_unique<esc::Esc>(cfg, clock));
        escs.back()->load_eeprom(test_support::small_sii_image(0x0D, static_cast<uint32_t>(escs.size())));
        return seg.add(*escs.back());
    }
    void line(int n) {
        for (int k = 0; k < n; ++k) {
            add();
            if (k > 0) seg.connect(k - 1, 1, k, 0);
        }
    }
    // The line scanned and one process-data session over all of it, every slave with `layout` (null, after
    // a failed assertion, if the scan failed).
    std::vector<SlaveInfo> bus;
    std::unique_ptr<ProcessDataSession> session(const ProcessDataLayout& layout) {
        auto scanned = scan_bus(m, {.first_station = 0x1001, .identity = false});
        EXPECT_TRUE(scanned.ok()) << to_string(scanned.error());
        if (!scanned) return nullptr;
        bus = *scanned;
        std::vector<Address> a;
        for (const SlaveInfo& s : bus)
            a.push_back(Address::station(s.station));
        auto pd = std::make_unique<ProcessDataSession>(m, a);
        for (std::size_t k = 0; k < pd->size(); ++k)
            pd->set_layout(k, layout);
        return pd;
    }
    // The ESC at a master position (processing order).
    esc::Esc& at(std::size_t position) { return seg.esc(seg.order()[position]); }
};

// The layout of a small drive: 4 output bytes in SM2, 6 input bytes in SM3.
ProcessDataLayout small_layout() {
    ProcessDataLayout l;
    l.add(2, true, 0x1100, 4, 0x64).add(3, false, 0x1180, 6, 0x20);
    return l;
}

// A larger drive: 12 output bytes, 20 input bytes (a hundred of them need more than one frame).
ProcessDataLayout big_layout() {
    ProcessDataLayout l;
    l.add(2, true, 0x1100, 12, 0x64).add(3, false, 0x1180, 20, 0x20);
    return l;
}

void set_layouts(ProcessDataSession& pd, const ProcessDataLayout& layout) {
    for (std::size_t k = 0; k < pd.size(); ++k)
        pd.set_layout(k, layout);
}

std::vector<Address> stations(const std::vector<SlaveInfo>& bus) {
    std::vector<Address> a;
    for (const SlaveInfo& s : bus)
        a.push_back(Address::station(s.station));
    return a;
}

}  // namespace

TEST(MasterOnSegment, BringUpCountsAddressesAndIdentifiesEverySlave) {
    for (int n : {1, 7, 100}) {
        Line l;
        l.line(n);
        auto bus = scan_bus(l.m);
        ASSERT_TRUE(bus.ok()) << to_string(bus.error());
        ASSERT_EQ(bus->size(), static_cast<std::size_t>(n));
        for (std::size_t i = 0; i < bus->size(); ++i) {
            const SlaveInfo& s = (*bus)[i];
            EXPECT_EQ(s.error, Error::Ok);
            EXPECT_EQ(s.position, i);
            EXPECT_EQ(s.station, 0x1001 + i);
            EXPECT_EQ(l.at(i).read_reg<uint16_t>(0x0010), 0x1001 + i);
            EXPECT_EQ(s.vendor_id, kVendor);
            EXPECT_EQ(s.product_code, kProduct);
            EXPECT_EQ(s.serial, i + 1) << "position " << i;
            EXPECT_EQ(s.al.state, static_cast<uint8_t>(AlState::Init));
            EXPECT_TRUE(s.has_dc);
            // Port 0 towards the master always; port 1 onwards except at the end of the line.
            EXPECT_EQ(s.active_ports, i + 1 < bus->size() ? 0x03 : 0x01) << "position " << i;
        }
    }
}

TEST(MasterOnSegment, DcDelaysIncreaseAlongTheLineAndSystemTimesAgree) {
    Line l;
    l.line(6);
    auto bus = scan_bus(l.m);
    ASSERT_TRUE(bus.ok());
    ASSERT_EQ(configure_dc(l.m, *bus), Error::Ok);
    EXPECT_EQ(reference_clock(*bus), 0);
    EXPECT_EQ((*bus)[0].delay_ns, 0);
    for (std::size_t i = 1; i < bus->size(); ++i) {
        const SlaveInfo& s = (*bus)[i];
        EXPECT_EQ(s.parent, static_cast<int>(i) - 1);
        EXPECT_EQ(s.parent_port, 1);
        EXPECT_GT(s.delay_ns, (*bus)[i - 1].delay_ns) << "position " << i;
        // Written to the slave.
        EXPECT_EQ(l.at(i).read_reg<uint32_t>(esc::reg::kDcDelay), static_cast<uint32_t>(s.delay_ns));
    }
    // Each step is about one hop: processing or forwarding plus a cable (SegmentTiming), within a factor 2.
    const auto& t = l.seg.timing();
    const int64_t hop = (t.processing_delay_ns + t.forwarding_delay_ns) / 2 + t.cable_delay_ns;
    for (std::size_t i = 1; i < bus->size(); ++i) {
        const int64_t step = (*bus)[i].delay_ns - (*bus)[i - 1].delay_ns;
        EXPECT_GT(step, hop / 2);
        EXPECT_LT(step, hop * 2);
    }
    // One frame reads every system time as it passes: slave i sees it delay_i later than the reference, and
    // an ECAT read gives its system time less its delay (0x0928): all read the same time if the offsets
    // made the clocks agree.
    std::vector<std::array<uint8_t, 8>> times(bus->size());
    std::vector<Datagram> d;
    for (std::size_t i = 0; i < bus->size(); ++i)
        d.push_back(Datagram{Command::FPRD, (*bus)[i].station, reg::DcSystemTime, times[i]});
    ASSERT_EQ(l.m.exchange(d), Error::Ok);
    const int64_t ref = static_cast<int64_t>(util::get64(times[0].data()));
    for (std::size_t i = 1; i < bus->size(); ++i) {
        const int64_t sys = static_cast<int64_t>(util::get64(times[i].data()));
        EXPECT_LT(std::llabs(sys - ref), 100) << "position " << i;
    }
}

TEST(MasterOnSegment, DcDelaysInATree) {
    // A junction (4 ports) at position 0: a drive at port 3, a line of two at port 1, one more at port 2.
    Line l;
    const int j = l.add(0xFF);
    const int a = l.add(), b = l.add(), c = l.add(), d = l.add();
    l.seg.connect(j, 3, a, 0);
    l.seg.connect(j, 1, b, 0);
    l.seg.connect(b, 1, c, 0);
    l.seg.connect(j, 2, d, 0);
    auto bus = scan_bus(l.m);
    ASSERT_TRUE(bus.ok());
    ASSERT_EQ(bus->size(), 5u);
    EXPECT_EQ((*bus)[0].active_ports, 0x0F);
    ASSERT_EQ(configure_dc(l.m, *bus), Error::Ok);
    const int parent[5] = {-1, 0, 0, 2, 0};
    const int port[5] = {-1, 3, 1, 1, 2};
    for (std::size_t i = 0; i < bus->size(); ++i) {
        EXPECT_EQ((*bus)[i].parent, parent[i]) << i;
        EXPECT_EQ((*bus)[i].parent_port, port[i]) << i;
    }
    // Along each branch the delay grows; a later branch of the junction starts after the earlier ones.
    EXPECT_GT((*bus)[1].delay_ns, 0);
    EXPECT_GT((*bus)[2].delay_ns, (*bus)[1].delay_ns);
    EXPECT_GT((*bus)[3].delay_ns, (*bus)[2].delay_ns);
    EXPECT_GT((*bus)[4].delay_ns, (*bus)[3].delay_ns);
}

TEST(MasterOnSegment, OneLrwOverEverySlaveWithTheSumOfTheirWorkingCounters) {
    Line l;
    l.line(5);
    auto session = l.session(small_layout());
    ASSERT_TRUE(session);
    ProcessDataSession& pd = *session;
    ASSERT_EQ(pd.configure(), Error::Ok);
    EXPECT_EQ(pd.expected_wkc(), 5 * 3);
    EXPECT_EQ(pd.outputs().size(), 5u * 4);
    EXPECT_EQ(pd.inputs().size(), 5u * 6);
    ASSERT_EQ(pd.request_state(AlState::SafeOp, std::chrono::microseconds(100)), Error::Ok);
    ASSERT_EQ(pd.request_state(AlState::Op, std::chrono::microseconds(100)), Error::Ok);
    // Each slave's firmware side puts its own inputs into SM3; the master puts its own outputs in SM2.
    for (std::size_t k = 0; k < 5; ++k) {
        std::vector<uint8_t> in(6, static_cast<uint8_t>(0x40 + k));
        l.at(k).write(0x1180, in);
        auto o = pd.outputs(k);
        std::fill(o.begin(), o.end(), static_cast<uint8_t>(0x10 + k));
    }
    ASSERT_EQ(pd.cycle(), Error::Ok);
    ASSERT_EQ(pd.cycle(), Error::Ok);
    EXPECT_EQ(pd.last_wkc(), 15);
    EXPECT_EQ(pd.frames_per_cycle(), 1u);
    for (std::size_t k = 0; k < 5; ++k) {
        for (uint8_t b : pd.inputs(k))
            EXPECT_EQ(b, 0x40 + k) << "slave " << k;
        uint8_t out[4] = {};
        l.at(k).read(0x1100, out);
        for (uint8_t b : out)
            EXPECT_EQ(b, 0x10 + k) << "slave " << k;
    }
}

TEST(MasterOnSegment, ImageLargerThanOneFrameIsSplitAndStillAddsUp) {
    Line l;
    l.line(100);
    auto session = l.session(big_layout());
    ASSERT_TRUE(session);
    ProcessDataSession& pd = *session;
    ASSERT_EQ(pd.configure(), Error::Ok);
    EXPECT_GT(pd.frames_per_cycle(), 1u);
    EXPECT_EQ(pd.expected_wkc(), 300);
    EXPECT_EQ(pd.cycle(), Error::Ok);
    EXPECT_EQ(pd.last_wkc(), 300);
}

TEST(MasterOnSegment, DcSessionStartsSync0EverywhereAtTheSameTime) {
    Line l;
    l.line(4);
    auto session = l.session(small_layout());
    ASSERT_TRUE(session);
    ProcessDataSession& pd = *session;
    DcConfig dc;
    dc.enable = true;
    dc.cycle_ns = 1'000'000;
    ASSERT_EQ(pd.configure(dc), Error::Ok);
    ASSERT_EQ(pd.dc_slaves().size(), 4u);
    const uint64_t start = l.at(0).read_reg<uint64_t>(esc::reg::kDcStartTime);
    EXPECT_EQ(start % dc.cycle_ns, 0u);
    for (std::size_t k = 0; k < 4; ++k) {
        EXPECT_EQ(l.at(k).read_reg<uint64_t>(esc::reg::kDcStartTime), start) << k;
        EXPECT_EQ(l.at(k).read_reg<uint16_t>(esc::reg::kDcCyclicControl), dc.assign_activate) << k;
        if (k > 0) {
            EXPECT_GT(pd.dc_slaves()[k].delay_ns, pd.dc_slaves()[k - 1].delay_ns);
        }
    }
    ASSERT_EQ(pd.cycle(), Error::Ok);
    EXPECT_EQ(pd.last_wkc(), 12);
    EXPECT_NE(pd.reference_time(), 0u);  // the FRMW of the reference clock rode along
}

TEST(MasterOnSegment, PulledCableGivesAWorkingCounterErrorAndRecovers) {
    Line l;
    l.line(5);
    auto session = l.session(small_layout());
    ASSERT_TRUE(session);
    ProcessDataSession& pd = *session;
    ASSERT_EQ(pd.configure(), Error::Ok);
    ASSERT_EQ(pd.request_state(AlState::Op, std::chrono::microseconds(100)), Error::Ok);
    ASSERT_EQ(pd.cycle(), Error::Ok);
    // The cable between positions 2 and 3: the line ends at 2, slaves 3 and 4 are gone.
    l.seg.set_cable(l.seg.order()[2], 1, false);
    EXPECT_EQ(pd.cycle(), Error::WorkingCounter);
    EXPECT_EQ(pd.last_wkc(), 9);
    EXPECT_EQ(pd.stats().wkc_errors, 1u);
    std::vector<AlStatus> st(5);
    ASSERT_EQ(pd.read_states(st), Error::Ok);
    for (std::size_t k = 0; k < 5; ++k)
        EXPECT_EQ(st[k].state, k < 3 ? static_cast<uint8_t>(AlState::Op) : 0) << k;
    EXPECT_EQ(l.m.count_slaves().value(), 3);
    // Plugged again: every slave answers, still in OP with its configuration.
    l.seg.set_cable(l.seg.order()[2], 1, true);
    EXPECT_EQ(pd.cycle(), Error::Ok);
    EXPECT_EQ(pd.last_wkc(), 15);
    ASSERT_EQ(pd.read_states(st), Error::Ok);
    for (std::size_t k = 0; k < 5; ++k)
        EXPECT_EQ(st[k].state, static_cast<uint8_t>(AlState::Op)) << k;
    EXPECT_EQ(pd.stats().wkc_errors, 1u);
}

TEST(MasterOnSegment, CyclesOverAHundredSlavesWithDcAllocateNothing) {
    Line l;
    l.line(100);
    test_support::FixedLink link([&](std::span<uint8_t> f) {
        l.clock.advance(20'000);
        return l.seg.walk(f, l.clock.now_ns()).kind == esc::Segment::Result::Kind::Reply;
    });
    Master m(link, test_support::in_process_master_options());
    auto bus = scan_bus(m, {.first_station = 0x1001, .identity = false});
    ASSERT_TRUE(bus.ok());
    ProcessDataSession pd(m, stations(*bus));
    set_layouts(pd, big_layout());
    DcConfig dc;
    dc.enable = true;
    ASSERT_EQ(pd.configure(dc), Error::Ok);
    ASSERT_GT(pd.frames_per_cycle(), 1u);
    ASSERT_EQ(pd.cycle(), Error::Ok);
    const alloc_counter::Scope counting;
    for (int i = 0; i < 100; ++i) {
        pd.outputs()[0] = static_cast<uint8_t>(i);
        ASSERT_EQ(pd.cycle(), Error::Ok);
    }
    EXPECT_EQ(counting.count(), 0u) << "allocations per cycle of a 100-slave session";
}
