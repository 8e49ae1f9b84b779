// Supervisor alone: error bookkeeping, fault reset, the cycle's checks and standstill (no Axis).
#include <gtest/gtest.h>

#include "drive/supervisor.hpp"
#include "recorder.hpp"

using namespace drive;
using namespace drive::test;

namespace {
const std::array<uint8_t, 5> kMfr{};
}

TEST(SupervisorPart, AnErrorIsRecordedOnceAndAsksForItsReaction) {
    Supervisor s;
    Recorder rec;
    const auto r = s.raise(error_code::FollowingError, 2, 2, kMfr, rec);
    EXPECT_TRUE(r.react);
    EXPECT_EQ(r.reaction, Reaction::FaultReactionCode);
    EXPECT_EQ(r.option, 2);
    EXPECT_TRUE(s.error_active(error_code::FollowingError));
    EXPECT_EQ(s.last_error(), error_code::FollowingError);
    EXPECT_EQ(s.error_register(),
              error_register::kMotion | error_register::kGeneric);             // CiA 301: generic too
    EXPECT_FALSE(s.raise(error_code::FollowingError, 2, 2, kMfr, rec).react);  // already active
    EXPECT_EQ(rec.raised.size(), 1u);
    const auto sto = s.raise(error_code::Sto, 2, 2, kMfr, rec);
    EXPECT_EQ(sto.reaction, Reaction::Disable);
    EXPECT_EQ(sto.option, 0);
    EXPECT_EQ(s.error_register(), error_register::kMotion | error_register::kGeneric);
}

TEST(SupervisorPart, FaultSignalOnlyIsAWarning) {
    Supervisor s;
    Recorder rec;
    EXPECT_FALSE(s.raise(error_code::FollowingError, -1, 2, kMfr, rec).react);       // 0x605E = -1
    EXPECT_FALSE(s.raise(error_code::EthercatStateMachine, 2, 1, kMfr, rec).react);  // 0x6007 = 1
    EXPECT_TRUE(s.warning());
    EXPECT_FALSE(s.error_active(error_code::FollowingError));
    EXPECT_TRUE(rec.raised.empty());
    s.acknowledge_warnings(rec);
    EXPECT_FALSE(s.warning());
    EXPECT_EQ(rec.cleared.size(), 2u);
}

TEST(SupervisorPart, FaultResetIsRefusedWhileTheCauseLasts) {
    Supervisor s;
    Recorder rec;
    s.raise(error_code::Sto, 0, 0, kMfr, rec);
    EXPECT_FALSE(s.reset({true, false, false}, rec));
    EXPECT_TRUE(s.error_active(error_code::Sto));
    EXPECT_TRUE(s.reset({}, rec));
    EXPECT_FALSE(s.error_active(error_code::Sto));
    EXPECT_EQ(s.error_register(), 0);
    EXPECT_EQ(s.last_error(), 0);
    ASSERT_EQ(rec.cleared.size(), 1u);
    EXPECT_EQ(rec.cleared[0], error_code::Sto);
}

TEST(SupervisorPart, CausesNameTheirErrors) {
    EXPECT_TRUE((Supervisor::Causes{true, false, false}).present(error_code::Sto));
    EXPECT_TRUE((Supervisor::Causes{false, true, false}).present(error_code::TorqueFault));
    EXPECT_TRUE((Supervisor::Causes{false, false, true}).present(error_code::MaxSpeed));
    EXPECT_FALSE((Supervisor::Causes{true, true, true}).present(error_code::FollowingError));
}

TEST(SupervisorPart, FollowingErrorNeedsTheTimeout) {
    Supervisor s;
    EXPECT_FALSE(s.following_error(true, 150, 100, 3, 1'000'000));
    EXPECT_FALSE(s.following_error(true, 150, 100, 3, 1'000'000));
    EXPECT_TRUE(s.following_error(true, 150, 100, 3, 1'000'000));
    EXPECT_FALSE(s.following_error(true, 50, 100, 3, 1'000'000));  // back within: the timer restarts
    EXPECT_FALSE(s.following_error(true, 150, 100, 3, 1'000'000));
    EXPECT_FALSE(s.following_error(false, 150, 100, 3, 1'000'000));         // not checked: restarts
    EXPECT_FALSE(s.following_error(true, 1e9, 0xFFFFFFFFu, 0, 1'000'000));  // window off
}

TEST(SupervisorPart, LimitsTakeTheDirectionOfMotion) {
    PositionFrame f;
    f.sw_min = -1000;
    f.sw_max = 1000;
    Supervisor::Motion m;
    m.neg_switch = true;
    m.v = 10;  // driving out of the switch
    EXPECT_EQ(Supervisor::limits(m, f).count, 0);
    m.v = -10;
    auto found = Supervisor::limits(m, f);
    ASSERT_EQ(found.count, 1);
    EXPECT_EQ(found.codes[0], error_code::NegativeLimitSwitch);
    m.neg_switch = false;
    m.actual = -1001;
    found = Supervisor::limits(m, f);
    ASSERT_EQ(found.count, 1);
    EXPECT_EQ(found.codes[0], error_code::SoftwarePositionLimit);
    m.check_actual = false;  // PPM clamps the target instead
    EXPECT_EQ(Supervisor::limits(m, f).count, 0);
    m.target_outside = true;
    EXPECT_EQ(Supervisor::limits(m, f).count, 1);
}

TEST(SupervisorPart, OverspeedAndStandstill) {
    const double rpm = 6.283185307179586 / 60.0;  // rad/s per rpm
    EXPECT_FALSE(Supervisor::overspeed(999 * rpm, 1000));
    EXPECT_TRUE(Supervisor::overspeed(-1001 * rpm, 1000));
    Supervisor s;
    s.standstill(5, 10, 2, 1'000'000);
    EXPECT_FALSE(s.still());
    s.standstill(5, 10, 2, 1'000'000);
    EXPECT_TRUE(s.still());
    s.standstill(50, 10, 2, 1'000'000);
    EXPECT_FALSE(s.still());
}
