// Frame exchange, reply matching, retries, working counters, slave counting and station addresses.
#include <gtest/gtest.h>

#include "fake_bus.hpp"
#include "master/master.hpp"

using namespace master;

namespace {
MasterOptions fast_retrying() {
    MasterOptions o;
    o.timeout = std::chrono::milliseconds(5);
    o.retries = 2;
    return o;
}
}  // namespace

TEST(MasterExchange, SeveralDatagramsInOneFrameGetTheirOwnWorkingCounters) {
    fake::Bus bus(2);
    bus.slaves[1].mem[0x0F80] = 0x5A;
    Master m(bus, fast_retrying());
    uint8_t a[2] = {}, b[1] = {}, c[1] = {0x77};
    Datagram d[3] = {{Command::BRD, 0, 0x0000, a},
                     {Command::APRD, static_cast<uint16_t>(0u - 1u), 0x0F80, b},
                     {Command::APWR, 0, 0x0F81, c}};
    ASSERT_EQ(m.exchange(d), Error::Ok);
    EXPECT_EQ(bus.frames, 1u);
    EXPECT_EQ(d[0].wkc, 2);
    EXPECT_EQ(a[0], 0x04);
    EXPECT_EQ(d[1].wkc, 1);
    EXPECT_EQ(b[0], 0x5A);
    EXPECT_EQ(d[2].wkc, 1);
    EXPECT_EQ(bus.slaves[0].mem[0x0F81], 0x77);
    EXPECT_EQ(bus.slaves[1].mem[0x0F81], 0x00);
}

TEST(MasterExchange, LostReplyIsRetriedWithAFreshIndex) {
    fake::Bus bus(1);
    Master m(bus, fast_retrying());
    bus.drop_next = 1;
    auto n = m.count_slaves();
    ASSERT_TRUE(n.ok());
    EXPECT_EQ(*n, 1);
    ASSERT_EQ(bus.sent.size(), 2u);
    EXPECT_NE(bus.sent[0][15 + 2], bus.sent[1][15 + 2]);  // datagram index byte
    EXPECT_EQ(m.stats().timeouts, 1u);
}

TEST(MasterExchange, GivesUpAfterTheRetriesWithTimeout) {
    fake::Bus bus(1);
    Master m(bus, fast_retrying());
    bus.drop_next = 100;
    const auto t0 = std::chrono::steady_clock::now();
    EXPECT_EQ(m.count_slaves().error(), Error::Timeout);
    EXPECT_EQ(bus.frames, 3u);  // first attempt + 2 retries
    EXPECT_GE(std::chrono::steady_clock::now() - t0, std::chrono::milliseconds(15));
}

TEST(MasterExchange, StaleRepliesAndOwnUnprocessedFramesAreNotTakenForTheAnswer) {
    fake::Bus bus(1);
    bus.slaves[0].mem[0x0F80] = 1;
    Master m(bus, fast_retrying());
    ASSERT_EQ(m.read_reg<uint8_t>(Address::position(0), 0x0F80).value(), 1);
    bus.echo_stale = true;
    bus.echo_own = true;
    bus.slaves[0].mem[0x0F80] = 2;
    auto r = m.read_reg<uint8_t>(Address::position(0), 0x0F80);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(*r, 2);
    EXPECT_EQ(m.stats().frames_ignored, 2u);
    EXPECT_EQ(m.stats().timeouts, 0u);
}

TEST(MasterExchange, NoSlaveOnTheLoopMeansTimeout) {
    fake::Bus bus(0);  // frames come back untouched
    bus.echo_own = false;
    Master m(bus, fast_retrying());
    // The bus returns the unprocessed frame with the master's own source MAC: not a reply.
    EXPECT_EQ(m.count_slaves().error(), Error::Timeout);
}

TEST(MasterExchange, AcceptOwnSourceTakesAnUnchangedMacAsTheReply) {
    fake::Bus bus(0);  // frames come back untouched, with our source MAC
    bus.echo_own = false;
    MasterOptions o = fast_retrying();
    o.accept_own_source = true;  // as ecat-conform runs: a slave that leaves the MAC as sent is still heard
    Master m(bus, o);
    uint8_t b[2] = {};
    Datagram d{Command::BRD, 0, 0x0000, b};
    EXPECT_EQ(m.exchange(d), Error::Ok);
    EXPECT_EQ(d.wkc, 0);
    EXPECT_EQ(m.stats().timeouts, 0u);
}

TEST(MasterExchange, RejectsEmptyAndOversizedRequests) {
    fake::Bus bus(1);
    Master m(bus, fast_retrying());
    EXPECT_EQ(m.exchange(std::span<Datagram>()), Error::InvalidArgument);
    std::vector<uint8_t> big(kMaxDatagramData + 1);
    EXPECT_EQ(m.read(Address::position(0), 0x1000, big), Error::InvalidArgument);
    EXPECT_EQ(bus.frames, 0u);
}

TEST(MasterBus, CountsSlavesAndAssignsStationAddresses) {
    fake::Bus bus(3);
    Master m(bus, fast_retrying());
    auto n = m.count_slaves();
    ASSERT_TRUE(n.ok());
    ASSERT_EQ(*n, 3);
    ASSERT_EQ(m.assign_station_addresses(*n), Error::Ok);
    for (uint16_t i = 0; i < 3; ++i)
        EXPECT_EQ(bus.slaves[i].reg16(0x0010), 0x1001 + i);
    // Now reachable by station address.
    bus.slaves[2].mem[0x0F90] = 0xAB;
    EXPECT_EQ(m.read_reg<uint8_t>(Address::station(0x1003), 0x0F90).value(), 0xAB);
    ASSERT_EQ(m.write_reg<uint16_t>(Address::station(0x1002), 0x0F92, 0xBEEF), Error::Ok);
    EXPECT_EQ(bus.slaves[1].reg16(0x0F92), 0xBEEF);
    EXPECT_EQ(bus.slaves[0].reg16(0x0F92), 0);
}

TEST(MasterBus, AbsentSlaveGivesWorkingCounterError) {
    fake::Bus bus(1);
    Master m(bus, fast_retrying());
    ASSERT_EQ(m.assign_station_addresses(1), Error::Ok);
    EXPECT_EQ(m.read_reg<uint16_t>(Address::station(0x2000), 0x0000).error(), Error::WorkingCounter);
    EXPECT_EQ(m.read_reg<uint16_t>(Address::position(1), 0x0000).error(), Error::WorkingCounter);
    EXPECT_EQ(m.assign_station_addresses(2), Error::WorkingCounter);
}

TEST(MasterBus, BroadcastWriteReportsHowManySlavesTookIt) {
    fake::Bus bus(4);
    Master m(bus, fast_retrying());
    const uint8_t v[2] = {0x34, 0x12};
    auto w = m.broadcast_write(0x0F80, v);
    ASSERT_TRUE(w.ok());
    EXPECT_EQ(*w, 4);
    for (auto& s : bus.slaves)
        EXPECT_EQ(s.reg16(0x0F80), 0x1234);
}

TEST(MasterNames, StatesAndCodes) {
    EXPECT_EQ(to_string(AlState::SafeOp), "SAFEOP");
    EXPECT_EQ(al_state_name(0x12), "PREOP");
    EXPECT_EQ(al_state_name(0x05), "UNKNOWN");
    EXPECT_EQ(al_status_code_name(0x0016), "Invalid mailbox configuration (PreOp)");
    EXPECT_EQ(al_status_code_name(0x9000), "Vendor specific");
    EXPECT_EQ(to_string(Error::Timeout), "no slave answered (timeout)");
}

// busy_poll waits for replies without sleeping; matching, retries and the timeout work as before.
TEST(MasterExchange, BusyPollMatchesRetriesAndTimesOutLikeTheDefault) {
    fake::Bus bus(1);
    MasterOptions o = fast_retrying();
    o.busy_poll = true;
    Master m(bus, o);
    bus.drop_next = 1;
    auto n = m.count_slaves();
    ASSERT_TRUE(n.ok());
    EXPECT_EQ(*n, 1);
    EXPECT_EQ(m.stats().timeouts, 1u);
    bus.drop_next = 100;
    EXPECT_EQ(m.count_slaves().error(), Error::Timeout);
    EXPECT_EQ(m.stats().timeouts, 4u);
}
