// Ports of the ESC (ESC datasheet section I, frame processing and loop control; ETG.1000.4 DL control 0x0101
// and DL status 0x0110): the order 0 -> 3 -> 1 -> 2 -> 0, loop back at closed ports, the circulating bit,
// loop settings, per-port receive-time latches, error counters, and the local clock's drift and offset.
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "esc_fixture.hpp"

using namespace esc_test;

namespace {

uint16_t dl_status(esc::Esc& e) {
    return e.read_reg<uint16_t>(0x0110);  // PDI read: does not clear the DL status event
}
uint16_t ecat_event(esc::Esc& e) {
    return e.read_reg<uint16_t>(0x0210);
}
uint16_t first_flags(const std::vector<uint8_t>& f) {
    return parse(f).at(0).flags;
}

// A line of ESCs wired port 1 -> next ESC's port 0, walked frame by frame as a segment would: each hop adds
// hop_ns to the Clock time at which the next port receives the frame.
struct Line {
    esc::ManualClock clk;
    std::vector<std::unique_ptr<esc::Esc>> escs;
    explicit Line(std::size_t n, uint8_t port_descriptor = 0x0F) {
        clk.set(kT0);
        esc::EscConfig c;
        c.port_descriptor = port_descriptor;
        for (std::size_t i = 0; i < n; ++i)
            escs.push_back(std::make_unique<esc::Esc>(c, clk));
        for (std::size_t i = 0; i + 1 < n; ++i)
            escs[i]->set_link(1, true);
    }
    // Returns true if the frame came back to the master (left ESC 0 through port 0).
    bool walk(std::vector<uint8_t>& f, uint64_t t, uint64_t hop_ns = 1000) {
        std::size_t k = 0;
        int port = 0;
        for (int guard = 0; guard < 1000; ++guard) {
            const int out = escs[k]->receive(f, port, t);
            t += hop_ns;
            if (out < 0) return false;
            if (out == 1 && k + 1 < escs.size()) {
                ++k;
                port = 0;
            } else if (out == 0 && k == 0) {
                return true;
            } else if (out == 0) {
                --k;
                port = 1;
            } else {
                return false;  // left through an unconnected port
            }
        }
        return false;
    }
    std::vector<Datagram> run(const std::vector<Datagram>& dgs, uint64_t t = kT0, uint64_t hop_ns = 1000) {
        auto f = build(dgs);
        EXPECT_TRUE(walk(f, t, hop_ns));
        return parse(f);
    }
};

using Ports = EscFixture<kT0>;

TEST_F(Ports, LoneEscHasPortZeroOnly) {
    EXPECT_TRUE(e->link(0));
    EXPECT_TRUE(e->port_open(0));
    for (int p = 1; p < 4; ++p) {
        EXPECT_FALSE(e->link(p)) << p;
        EXPECT_FALSE(e->port_open(p)) << p;
    }
    EXPECT_FALSE(e->link(-1));
    EXPECT_FALSE(e->port_open(4));
    // Link and communication on port 0, the loops of ports 1-3 closed, PDI watchdog, EEPROM loaded.
    EXPECT_EQ(dl_status(*e), 0x5613);
    // A frame received at port 0 is processed and leaves there again.
    auto f = build({dg_len(BRD, 0, 0x0000, 1)});
    EXPECT_EQ(e->receive(f, 0), 0);
    EXPECT_EQ(parse(f).at(0).wkc, 1);
}

TEST_F(Ports, FrameAtClosedOrMissingPortIsDestroyed) {
    const uint64_t before = e->stats().frames_destroyed;
    for (int p : {1, 2, 3, -1, 4, 100}) {
        auto f = build({dg_len(BRD, 0, 0x0000, 1)});
        const auto copy = f;
        EXPECT_EQ(e->receive(f, p), -1) << p;
        EXPECT_EQ(f, copy) << p;  // not processed
    }
    EXPECT_EQ(e->stats().frames_destroyed, before + 6);
    // set_link on a port the descriptor (0x0F: ports 0 and 1) does not implement changes nothing.
    e->set_link(2, true);
    EXPECT_FALSE(e->link(2));
    e->set_link(7, true);
    EXPECT_EQ(dl_status(*e), 0x5613);
}

TEST_F(Ports, LinkOnPortOneOpensIt) {
    (void)fprd(*e, 0x0110, 2);  // clears the DL status event
    EXPECT_EQ(ecat_event(*e) & 0x0004, 0);
    e->set_link(1, true);
    EXPECT_TRUE(e->port_open(1));
    // Links 0 and 1, communication on 0 and 1, loops 2 and 3 closed.
    EXPECT_EQ(dl_status(*e), 0x5A33);
    EXPECT_EQ(ecat_event(*e) & 0x0004, 0x0004);
    // Port 0 -> processing unit -> (3 closed) -> 1: leaves through port 1; back at 1 -> (2 closed) -> 0.
    auto f = build({dg_len(APRD, 0, 0x0000, 1)});
    EXPECT_EQ(e->receive(f, 0), 1);
    EXPECT_EQ(parse(f).at(0).adp, 1);
    EXPECT_EQ(e->receive(f, 1), 0);
    EXPECT_EQ(parse(f).at(0).adp, 1);   // not processed a second time
    EXPECT_FALSE(e->process_frame(f));  // a lone-ESC master would not get it back
    // Setting the same state again changes nothing.
    (void)fprd(*e, 0x0110, 2);
    e->set_link(1, true);
    EXPECT_EQ(ecat_event(*e) & 0x0004, 0);
}

TEST(PortsJunction, OrderIsZeroThreeOneTwo) {
    Line junction(1, 0xFF);  // one ESC with four ports
    esc::Esc& e = *junction.escs[0];
    for (int p = 1; p < 4; ++p)
        e.set_link(p, true);
    EXPECT_EQ(dl_status(e) & 0xFFF0, 0xAAF0);  // all links, all loops open, communication on all
    auto f = build({dg_len(APRD, 0, 0x0000, 1)});
    EXPECT_EQ(e.receive(f, 0), 3);
    EXPECT_EQ(e.receive(f, 3), 1);
    EXPECT_EQ(e.receive(f, 1), 2);
    EXPECT_EQ(e.receive(f, 2), 0);
    EXPECT_EQ(parse(f).at(0).adp, 1);  // the processing unit saw it once, behind port 0
    // Port 3 unplugged: 0 -> (3 loops back) -> 1.
    e.set_link(3, false);
    EXPECT_EQ(e.receive(f, 0), 1);
    EXPECT_EQ(e.receive(f, 2), 0);
    EXPECT_EQ(e.receive(f, 3), -1);  // closed
    // Only port 2 besides port 0: 0 -> 2 -> 0.
    e.set_link(1, false);
    EXPECT_EQ(e.receive(f, 0), 2);
    EXPECT_EQ(e.receive(f, 2), 0);
    // Lost-link counters of ports 1 and 3.
    EXPECT_EQ(e.read_reg<uint32_t>(0x0310), 0x01000100u);
}

// Random link changes, loop settings and entry ports on a junction: receive() returns -1 or a port whose loop
// is open, never processes a frame entering at a closed port, and DL status always matches
// link()/port_open().
TEST(PortsJunction, RandomLinksAndLoopSettingsKeepTheInvariants) {
    Line junction(1, 0xFF);  // one ESC with four ports
    esc::Esc& e = *junction.escs[0];
    esc::ManualClock& clk = junction.clk;
    set_station(e, 0x1001);
    uint32_t s = 12345;
    auto rnd = [&](uint32_t n) {
        s = s * 1103515245u + 12345u;
        return (s >> 8) % n;
    };
    for (int i = 0; i < 5000; ++i) {
        switch (rnd(4)) {
            case 0:
                e.set_link(static_cast<int>(rnd(4)), rnd(2) == 0);
                break;
            case 1:
                if (e.port_open(0)) fpwr(e, 0x0101, {static_cast<uint8_t>(rnd(256))});
                break;
            default:
                break;
        }
        const int port = static_cast<int>(rnd(6)) - 1;
        auto f = build({dg_len(BRD, 0, 0x0000, 1)});
        const bool open_before = port >= 0 && port < 4 && (dl_status(e) & (1u << (8 + 2 * port))) == 0;
        const int out = e.receive(f, port, clk.now_ns());
        if (!open_before) {
            EXPECT_EQ(out, -1) << i;
            EXPECT_EQ(parse(f).at(0).wkc, 0) << i;
        } else if (out >= 0) {
            EXPECT_EQ(dl_status(e) & (1u << (8 + 2 * out)), 0u) << i;  // leaves through an open loop
        }
        const uint16_t dl = dl_status(e);
        for (int p = 0; p < 4; ++p) {
            EXPECT_EQ(((dl >> (4 + p)) & 1u) != 0, e.link(p)) << i;
            EXPECT_EQ(((dl >> (9 + 2 * p)) & 1u) != 0, e.port_open(p)) << i;
        }
        if (!e.port_open(0) && rnd(8) == 0) {  // the master gets its way back
            e.set_link(0, true);
            run1(e, dg(BWR, 0, 0x0101, {0x00}));
        }
        clk.advance(1000);
    }
}

TEST(PortsLine, BroadcastCountsEveryEscAndAutoIncrementAddressesThem) {
    Line line(3);
    auto r = line.run({dg_len(BRD, 0, 0x0000, 1)});
    EXPECT_EQ(r.at(0).wkc, 3);
    EXPECT_EQ(r.at(0).adp, 3);
    for (uint16_t k = 0; k < 3; ++k) {
        auto w = line.run({dg(APWR, static_cast<uint16_t>(-k), 0x0010, le(0x1001 + k, 2))});
        EXPECT_EQ(w.at(0).wkc, 1) << k;
    }
    for (uint16_t k = 0; k < 3; ++k) {
        auto rd = line.run({dg_len(FPRD, static_cast<uint16_t>(0x1001 + k), 0x0110, 2)});
        ASSERT_EQ(rd.at(0).wkc, 1);
        // The last ESC has no link on port 1 (loop closed there), the others have both.
        EXPECT_EQ(rd.at(0).u16() & 0xFFF0, k < 2 ? 0x5A30 : 0x5610) << k;
    }
    // Cable between ESC 1 and 2 pulled: ESC 1's port 1 loses its link and loops back.
    line.escs[1]->set_link(1, false);
    line.escs[2]->set_link(0, false);
    EXPECT_EQ(line.run({dg_len(BRD, 0, 0x0000, 1)}).at(0).wkc, 2);
    EXPECT_EQ(line.escs[1]->read_reg<uint8_t>(0x0311), 1);
    EXPECT_EQ(line.escs[2]->read_reg<uint8_t>(0x0310), 1);
    line.escs[1]->set_link(1, true);
    line.escs[2]->set_link(0, true);
    EXPECT_EQ(line.run({dg_len(BRD, 0, 0x0000, 1)}).at(0).wkc, 3);
}

TEST(PortsLine, CirculatingFrameIsMarkedThenDestroyed) {
    // ESC whose port 0 lost its link while port 1 still has one (the master is gone behind port 0): a frame
    // coming in at port 1 loops back at 2, passes the processing unit at the closed port 0, loops back at 3
    // and leaves through port 1 again, marked as circulating.
    esc::ManualClock clk;
    clk.set(kT0);
    esc::Esc e(esc::EscConfig{}, clk);
    e.set_link(1, true);
    e.set_link(0, false);
    EXPECT_FALSE(e.port_open(0));
    auto f = build({dg_len(BRD, 0, 0x0000, 1)});
    EXPECT_EQ(first_flags(f) & 0x4000, 0);
    EXPECT_EQ(e.receive(f, 1), 1);
    EXPECT_EQ(first_flags(f) & 0x4000, 0x4000);
    EXPECT_EQ(parse(f).at(0).wkc, 1);  // processed on its way through
    const uint64_t destroyed = e.stats().frames_destroyed;
    EXPECT_EQ(e.read_reg<uint8_t>(0x030C), 0);
    EXPECT_EQ(e.receive(f, 1), -1);  // second pass with the bit set
    EXPECT_EQ(e.stats().frames_destroyed, destroyed + 1);
    EXPECT_EQ(e.read_reg<uint8_t>(0x030C), 1);  // a processing unit error (ESC datasheet section I, Table 57)
    EXPECT_EQ(parse(f).at(0).wkc, 1);           // not processed again
    // A frame received at port 0 never gets the bit (port 0 open).
    e.set_link(0, true);
    auto g = build({dg_len(BRD, 0, 0x0000, 1)});
    EXPECT_EQ(e.receive(g, 0), 1);
    EXPECT_EQ(first_flags(g) & 0x4000, 0);
}

TEST_F(Ports, LoopSettingsOpenAndClosed) {
    e->set_link(1, true);
    // 11 on port 1: always closed, even with a link.
    EXPECT_EQ(fpwr(*e, 0x0101, {0x0C}).wkc, 1);
    EXPECT_FALSE(e->port_open(1));
    EXPECT_TRUE(e->link(1));
    EXPECT_EQ(dl_status(*e) & 0x0F00, 0x0600);  // port 0 open + communication, port 1 closed
    auto f = build({dg_len(BRD, 0, 0x0000, 1)});
    EXPECT_EQ(e->receive(f, 0), 0);
    EXPECT_EQ(e->receive(f, 1), -1);  // received at a closed port
    // 10 on port 1: always open, even without a link (frames sent there are lost on the wire).
    e->set_link(1, false);
    EXPECT_EQ(fpwr(*e, 0x0101, {0x08}).wkc, 1);
    EXPECT_FALSE(e->port_open(1));              // no link
    EXPECT_EQ(dl_status(*e) & 0x0F00, 0x0200);  // loop 1 open, no communication there
    EXPECT_EQ(e->receive(f, 0), 1);
    // 11 on port 0 with port 1 open destroys everything the master sends.
    EXPECT_EQ(fpwr(*e, 0x0101, {0x0B}).wkc, 1);
    EXPECT_EQ(dl_status(*e) & 0x0F00, 0x0100);  // port 0 closed, port 1 open without a link
    auto g = build({dg_len(BRD, 0, 0x0000, 1)});
    EXPECT_FALSE(e->process_frame(g));
    EXPECT_EQ(parse(g).at(0).wkc, 0);
    // A frame looped back at a port 0 closed by the master gets no circulating bit.
    auto h = build({dg_len(BRD, 0, 0x0000, 1)});
    EXPECT_EQ(e->receive(h, 1), 1);
    EXPECT_EQ(first_flags(h) & 0x4000, 0);
    EXPECT_EQ(parse(h).at(0).wkc, 1);
}

TEST_F(Ports, PortZeroOpensWhenEveryPortIsClosed) {
    // Port 0 closed by the master and nothing else open: port 0's loop is open all the same.
    EXPECT_EQ(fpwr(*e, 0x0101, {0x03}).wkc, 1);
    EXPECT_EQ(dl_status(*e) & 0x0300, 0x0200);
    auto f = build({dg_len(BRD, 0, 0x0000, 1)});
    EXPECT_TRUE(e->process_frame(f));
    EXPECT_EQ(parse(f).at(0).wkc, 1);
    // Port 0 without a link and port 1 closed: still open (no communication), frames still answered.
    EXPECT_EQ(fpwr(*e, 0x0101, {0x00}).wkc, 1);
    e->set_link(0, false);
    EXPECT_EQ(dl_status(*e) & 0x0310, 0x0000);
    EXPECT_FALSE(e->port_open(0));
    auto g = build({dg_len(BRD, 0, 0x0000, 1)});
    EXPECT_TRUE(e->process_frame(g));
    // Once port 1 opens, port 0 (no link) closes.
    e->set_link(1, true);
    EXPECT_EQ(dl_status(*e) & 0x0F00, 0x0900);
    EXPECT_FALSE(e->process_frame(g));
}

TEST_F(Ports, AutoCloseReopensOnlyWhenDlControlIsWritten) {
    e->set_link(1, true);
    EXPECT_EQ(fpwr(*e, 0x0101, {0x04}).wkc, 1);  // port 1: auto close
    EXPECT_TRUE(e->port_open(1));
    e->set_link(1, false);
    EXPECT_FALSE(e->port_open(1));
    e->set_link(1, true);
    EXPECT_FALSE(e->port_open(1));              // link back, loop still closed
    EXPECT_EQ(dl_status(*e) & 0x0C20, 0x0420);  // link, loop closed, no communication
    EXPECT_EQ(fpwr(*e, 0x0101, {0x04}).wkc, 1);
    EXPECT_TRUE(e->port_open(1));
    // Written while the link is down: stays closed when the link comes back.
    e->set_link(1, false);
    EXPECT_EQ(fpwr(*e, 0x0101, {0x04}).wkc, 1);
    e->set_link(1, true);
    EXPECT_FALSE(e->port_open(1));
    // Fallback: a correct frame received at the waiting port opens it after the frame (which is destroyed);
    // one with a bad FCS does not.
    auto f = build({dg_len(BRD, 0, 0x0000, 1)});
    esc::FrameCheck bad;
    bad.crc_bad = true;
    EXPECT_EQ(e->receive(f, 1, 0, bad), -1);
    EXPECT_FALSE(e->port_open(1));
    EXPECT_EQ(e->receive(f, 1), -1);
    EXPECT_TRUE(e->port_open(1));
    EXPECT_EQ(e->receive(f, 1), 0);
    // Back to auto: open with the link.
    e->set_link(1, false);
    EXPECT_EQ(fpwr(*e, 0x0101, {0x00}).wkc, 1);
    e->set_link(1, true);
    EXPECT_TRUE(e->port_open(1));
}

TEST_F(Ports, AutoClosePortZeroReopensWithTheMastersNextFrame) {
    e->set_link(1, true);
    EXPECT_EQ(fpwr(*e, 0x0101, {0x01}).wkc, 1);  // port 0: auto close
    e->set_link(0, false);
    e->set_link(0, true);
    EXPECT_FALSE(e->port_open(0));  // waiting; port 1 is open so port 0 stays closed
    auto f = build({dg_len(BRD, 0, 0x0000, 1)});
    EXPECT_FALSE(e->process_frame(f));  // destroyed, but reopens the port
    EXPECT_EQ(parse(f).at(0).wkc, 0);
    EXPECT_TRUE(e->port_open(0));
    auto g = build({dg_len(BRD, 0, 0x0000, 1)});
    EXPECT_EQ(e->receive(g, 0), 1);
    EXPECT_EQ(parse(g).at(0).wkc, 1);
}

TEST_F(Ports, DlStatusPortBitsLeaveEepromAndWatchdogBitsAlone) {
    EXPECT_EQ(dl_status(*e) & 0x0003, 0x0003);
    e->set_link(1, true);
    e->set_link(1, false);
    EXPECT_EQ(dl_status(*e), 0x5613);
    // ESC reset (0x0040 sequence): DL control back to all auto, the physical link kept.
    e->set_link(1, true);
    EXPECT_EQ(fpwr(*e, 0x0101, {0x0C}).wkc, 1);
    for (uint8_t b : {0x52, 0x45, 0x53})
        run1(*e, dg(BWR, 0, 0x0040, {b}));
    EXPECT_EQ(e->read_reg<uint32_t>(0x0100), 0x00070001u);
    EXPECT_TRUE(e->port_open(1));
}

TEST_F(Ports, LostLinkCounterSaturatesAndClearsOnWrite) {
    for (int i = 0; i < 300; ++i) {
        e->set_link(1, true);
        e->set_link(1, false);
    }
    e->set_link(0, false);
    e->set_link(0, true);
    EXPECT_EQ(e->read_reg<uint8_t>(0x0311), 0xFF);
    EXPECT_EQ(e->read_reg<uint8_t>(0x0310), 1);
    EXPECT_EQ(fpwr(*e, 0x0310, {0, 0, 0, 0}).wkc, 1);
    EXPECT_EQ(fprd(*e, 0x0310, 4).u32(), 0u);
}

TEST(PortsLine, BadFcsCountedOnceThenAsForwardedError) {
    Line line(3);
    auto f = build({dg_len(BRD, 0, 0x0000, 1)});
    const auto copy = f;
    esc::FrameCheck check;
    check.crc_bad = true;
    // Corrupted on the cable into ESC 1: ESC 1 detects it at port 0, ESC 2 sees a marked frame; neither
    // processes it; it comes back through ESC 1's port 1 (marked) and ESC 0's port 1.
    EXPECT_EQ(line.escs[1]->receive(f, 0, kT0, check), 1);
    EXPECT_TRUE(check.marked);
    EXPECT_EQ(line.escs[2]->receive(f, 0, kT0, check), 0);
    EXPECT_EQ(line.escs[1]->receive(f, 1, kT0, check), 0);
    EXPECT_EQ(line.escs[0]->receive(f, 1, kT0, check), 0);
    EXPECT_EQ(f, copy);
    auto counters = [&](std::size_t k) { return line.escs[k]->read_reg<uint64_t>(0x0300); };
    EXPECT_EQ(counters(1), 0x0000000000000101ull);  // invalid frame + RX error, port 0
    EXPECT_EQ(counters(2), 0u);
    EXPECT_EQ(line.escs[2]->read_reg<uint8_t>(0x0308), 1);  // forwarded RX error, port 0
    EXPECT_EQ(line.escs[1]->read_reg<uint8_t>(0x0309), 1);  // forwarded RX error, port 1
    EXPECT_EQ(line.escs[0]->read_reg<uint8_t>(0x0309), 1);
    EXPECT_EQ(line.escs[1]->stats().frames_bad_fcs, 2u);
    // A good frame is processed as usual, and any write clears the counters.
    auto r = line.run({dg(BWR, 0, 0x0300, std::vector<uint8_t>(0x14, 0))});
    EXPECT_EQ(r.at(0).wkc, 3);
    for (std::size_t k = 0; k < 3; ++k) {
        EXPECT_EQ(counters(k), 0u) << k;
        EXPECT_EQ(line.escs[k]->read_reg<uint32_t>(0x0308), 0u) << k;
    }
}

TEST(PortsLine, ReceiveTimeLatchesPerPort) {
    Line line(3);
    // BWR 0x0900 at t: ESC k receives it at port 0 at t + k us, and back at port 1 at t + (4 - k) us.
    const uint64_t t = kT0 + 5'000'000;
    line.run({dg(BWR, 0, 0x0900, {0, 0, 0, 0})}, t, 1000);
    for (std::size_t k = 0; k < 3; ++k) {
        const uint64_t p0 = t + 1000 * k;
        EXPECT_EQ(line.escs[k]->read_reg<uint32_t>(0x0900), static_cast<uint32_t>(p0)) << k;
        EXPECT_EQ(line.escs[k]->read_reg<uint64_t>(0x0918), p0) << k;
        if (k < 2) {
            EXPECT_EQ(line.escs[k]->read_reg<uint32_t>(0x0904), static_cast<uint32_t>(t + 1000 * (4 - k)))
                << k;
        } else {
            EXPECT_EQ(line.escs[k]->read_reg<uint32_t>(0x0904), 0u);  // nothing received at port 1
        }
    }
    // A later frame does not move the latches (once per arming), the next arming does.
    line.run({dg_len(BRD, 0, 0x0000, 1)}, t + 1'000'000, 1000);
    EXPECT_EQ(line.escs[0]->read_reg<uint32_t>(0x0904), static_cast<uint32_t>(t + 4000));
    line.run({dg(BWR, 0, 0x0900, {0, 0, 0, 0})}, t + 2'000'000, 2000);
    EXPECT_EQ(line.escs[0]->read_reg<uint32_t>(0x0900), static_cast<uint32_t>(t + 2'000'000));
    EXPECT_EQ(line.escs[0]->read_reg<uint32_t>(0x0904), static_cast<uint32_t>(t + 2'008'000));
    EXPECT_EQ(line.escs[1]->read_reg<uint32_t>(0x0904), static_cast<uint32_t>(t + 2'006'000));
}

TEST(PortsClock, DriftAndOffsetShapeTheLocalTime) {
    esc::ManualClock clk;
    clk.set(kT0);
    esc::EscConfig c;
    c.clock_drift_ppm = 50.0;
    c.clock_offset_ns = -7'000;
    esc::Esc e(c, clk);
    EXPECT_EQ(e.local_time_ns(), kT0 + 50'000 - 7'000);  // 1 s * 50 ppm = 50 us
    clk.advance(1'000'000);
    EXPECT_EQ(e.local_time_ns(), kT0 + 1'000'000 + 50'050 - 7'000);
    // The receive-time latches are in local time.
    auto f = build({dg(BWR, 0, 0x0900, {0, 0, 0, 0})});
    EXPECT_EQ(e.receive(f, 0, kT0 + 2'000'000), 0);
    EXPECT_EQ(e.read_reg<uint64_t>(0x0918), kT0 + 2'000'000 + 50'100 - 7'000);
    // Another ESC on the same Clock without drift reads the Clock itself.
    esc::Esc plain(esc::EscConfig{}, clk);
    EXPECT_EQ(plain.local_time_ns(), kT0 + 1'000'000);
}

}  // namespace

// DL control 0x0100 bit 0, the forwarding rule: 1 (reset value) destroys non-EtherCAT frames, 0 forwards
// them unchanged, through the port after the processing unit.
TEST_F(Ports, ForwardingRuleDestroysOrForwardsNonEtherCatFrames) {
    auto ip = build({dg_len(BRD, 0, 0x0000, 1)});
    ip[12] = 0x08;  // EtherType 0x0800
    ip[13] = 0x00;
    auto f = ip;
    EXPECT_EQ(e->receive(f, 0), -1) << "destroyed by default";
    EXPECT_EQ(fpwr(*e, 0x0100, {0x00}).wkc, 1);
    f = ip;
    EXPECT_EQ(e->receive(f, 0), 0) << "forwarded: a lone ESC sends it back";
    EXPECT_EQ(f, ip) << "unchanged, source MAC included";
    e->set_link(1, true);
    f = ip;
    EXPECT_EQ(e->receive(f, 0), 1) << "on to the next device";
    EXPECT_EQ(f, ip);
    EXPECT_EQ(fpwr(*e, 0x0100, {0x01}).wkc, 1);
    f = ip;
    EXPECT_EQ(e->receive(f, 0), -1);
}

// A frame length error counts in the processing unit error counter 0x030C only, whatever port it came in at
// (ESC datasheet section I, Table 57), also when it reaches the processing unit through a port 0 the master
// closed; the frame leaves marked bad: the next ESC counts a forwarded error.
TEST_F(Ports, LengthErrorCountsInTheProcessingUnitOnly) {
    auto bad = build({dg_len(BRD, 0, 0x0000, 1)});
    bad[16 + 6] = 0xFF;  // datagram length 0xFF: beyond the frame
    auto f = bad;
    esc::FrameCheck check;
    EXPECT_EQ(e->receive(f, 0, 0, check), 0);
    EXPECT_TRUE(check.crc_bad);
    EXPECT_TRUE(check.marked);
    EXPECT_EQ(e->read_reg<uint8_t>(0x0300), 0);
    EXPECT_EQ(e->read_reg<uint8_t>(0x030C), 1);
    f = bad;
    EXPECT_EQ(e->receive(f, 0), -1);  // without a FrameCheck to carry the marking, nobody receives it
    EXPECT_EQ(e->read_reg<uint8_t>(0x030C), 2);
    e->set_link(1, true);
    EXPECT_EQ(fpwr(*e, 0x0101, {0x0B}).wkc, 1);  // port 0 closed, port 1 open
    f = bad;
    esc::FrameCheck c1;
    (void)e->receive(f, 1, 0, c1);
    EXPECT_EQ(e->read_reg<uint8_t>(0x0302), 0);
    EXPECT_EQ(e->read_reg<uint8_t>(0x030C), 3);
}
