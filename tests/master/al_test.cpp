// AL state requests with the error-acknowledge handshake (ETG.1000.6 AL state machine).
#include <gtest/gtest.h>

#include "fake_bus.hpp"
#include "master/master.hpp"

using namespace master;

namespace {
MasterOptions fast_al() {
    MasterOptions o;
    o.timeout = std::chrono::milliseconds(5);
    o.al_timeout = std::chrono::milliseconds(50);
    return o;
}
}  // namespace

TEST(AlState, RequestReachesTheState) {
    fake::Bus bus(1);
    Master m(bus, fast_al());
    AlStatus st;
    ASSERT_EQ(m.request_state(Address::position(0), AlState::PreOp, &st), Error::Ok);
    EXPECT_EQ(st.state, 0x02);
    EXPECT_FALSE(st.error);
    EXPECT_EQ(bus.slaves[0].reg16(0x0120), 0x0002);
}

TEST(AlState, RefusalReturnsTheCodeAndIsAcknowledged) {
    fake::Bus bus(1);
    bus.slaves[0].refuse_state = 0x04;
    bus.slaves[0].refuse_code = 0x0011;
    Master m(bus, fast_al());
    AlStatus st;
    EXPECT_EQ(m.request_state(Address::position(0), AlState::SafeOp, &st), Error::AlRefused);
    EXPECT_TRUE(st.error);
    EXPECT_EQ(st.state, 0x01);
    EXPECT_EQ(st.code, 0x0011);
    // The master acknowledged: AL control = INIT | 0x10, and the slave cleared its error bit.
    EXPECT_EQ(bus.slaves[0].reg16(0x0120), 0x0011);
    auto now = m.al_status(Address::position(0));
    ASSERT_TRUE(now.ok());
    EXPECT_FALSE(now->error);
}

TEST(AlState, PendingErrorIsAcknowledgedBeforeTheNewRequest) {
    fake::Bus bus(1);
    fake::put16(&bus.slaves[0].mem[0x0130], 0x0012);  // PREOP + error
    fake::put16(&bus.slaves[0].mem[0x0134], 0x001B);
    Master m(bus, fast_al());
    ASSERT_EQ(m.request_state(Address::position(0), AlState::Init), Error::Ok);
    ASSERT_GE(bus.slaves[0].al_control_log.size(), 2u);
    EXPECT_EQ(bus.slaves[0].al_control_log[0], 0x0012);  // ack in the current state
    EXPECT_EQ(bus.slaves[0].al_control_log.back(), 0x0001);
}

TEST(AlState, RefusalOfOpKeepsSafeOpWithTheCode) {
    fake::Bus bus(1);
    fake::put16(&bus.slaves[0].mem[0x0130], 0x0004);
    bus.slaves[0].refuse_state = 0x08;
    bus.slaves[0].refuse_code = 0x001D;
    Master m(bus, fast_al());
    AlStatus st;
    EXPECT_EQ(m.request_state(Address::position(0), AlState::Op, &st), Error::AlRefused);
    EXPECT_EQ(st.state, 0x04);
    EXPECT_EQ(st.code, 0x001D);
    EXPECT_EQ(bus.slaves[0].reg16(0x0120), 0x0014);
}

TEST(AlState, SlaveThatNeverGetsThereTimesOut) {
    fake::Bus bus(1);
    bus.slaves[0].al_ignore = true;
    Master m(bus, fast_al());
    const auto t0 = std::chrono::steady_clock::now();
    EXPECT_EQ(m.request_state(Address::position(0), AlState::PreOp), Error::AlTimeout);
    EXPECT_GE(std::chrono::steady_clock::now() - t0, std::chrono::milliseconds(50));
}

TEST(AlState, StatusReadsStateErrorAndCode) {
    fake::Bus bus(1);
    fake::put16(&bus.slaves[0].mem[0x0130], 0x0034);
    fake::put16(&bus.slaves[0].mem[0x0134], 0x001B);
    Master m(bus, fast_al());
    auto st = m.al_status(Address::position(0));
    ASSERT_TRUE(st.ok());
    EXPECT_EQ(st->state, 0x04);
    EXPECT_TRUE(st->error);
    EXPECT_TRUE(st->id_loaded);
    EXPECT_EQ(st->code, 0x001B);
}

TEST(AlState, BroadcastRequestDrivesEverySlave) {
    fake::Bus bus(3);
    Master m(bus, fast_al());
    ASSERT_EQ(m.assign_station_addresses(3), Error::Ok);
    const uint16_t stations[] = {0x1001, 0x1002, 0x1003};
    ASSERT_EQ(m.request_state_all(AlState::PreOp, stations), Error::Ok);
    for (auto& s : bus.slaves)
        EXPECT_EQ(s.reg16(0x0130), 0x0002);
}
