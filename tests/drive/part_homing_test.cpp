// Homing alone: the phase machine of the 0x60E3 methods on a profile, fed edges and ticks (no Axis).
#include <gtest/gtest.h>

#include "drive/homing.hpp"
#include "recorder.hpp"

using namespace drive;
using namespace drive::test;

namespace {

struct HomingRig {
    Homing home;
    Profile profile;
    Parameters p;
    Recorder rec;
    Homing::Motion motion{1000.0, 100.0, 1e5};
    Homing::Inputs in;
    static constexpr double kH = 0.0004;

    HomingRig() {
        p.home_offset_move = 0;
        p.home_position = 0;
        in.resolution = 2000;
    }
    void tick() { home.tick(profile, motion, in, p, rec, kH); }
    // Ticks until `done` or `max` ticks; false if it never happened.
    template <class F>
    bool until(F done, int max = 100000) {
        for (int i = 0; i < max; ++i) {
            if (done()) return true;
            tick();
        }
        return done();
    }
};

}  // namespace

TEST(HomingPart, UnknownMethodOrMissingIndexIsAHomingError) {
    HomingRig r;
    r.p.homing_method = 99;
    r.home.start(r.p, 0, 0, r.rec);
    EXPECT_EQ(r.home.status(), HomingStatus::Error);
    EXPECT_FALSE(r.home.referenced());
    r.p.homing_method = 33;  // index method
    r.p.encoder_type = 0;    // encoder without index
    r.home.start(r.p, 0, 0, r.rec);
    EXPECT_EQ(r.home.status(), HomingStatus::Error);
}

TEST(HomingPart, ActualPositionMethodSetsTheShift) {
    HomingRig r;
    r.p.homing_method = 37;
    r.p.home_position = 1000;
    r.profile.reset(250);
    r.home.start(r.p, 0, 250, r.rec);
    EXPECT_TRUE(r.home.running());
    ASSERT_TRUE(r.until([&] { return r.home.status() == HomingStatus::Done; }));
    EXPECT_TRUE(r.home.referenced());
    EXPECT_EQ(r.home.shift(), 750);
    r.home.invalidate();
    EXPECT_FALSE(r.home.referenced());
    EXPECT_EQ(r.home.shift(), 0);
}

TEST(HomingPart, SetHereWithoutMotion) {
    HomingRig r;
    r.home.set_here(500, 20, r.rec);
    EXPECT_EQ(r.home.status(), HomingStatus::Done);
    EXPECT_EQ(r.home.shift(), 480);
}

TEST(HomingPart, LimitSwitchMethodSearchesBacksOffAndTakesTheFallingEdge) {
    HomingRig r;
    r.p.homing_method = 17;  // negative limit switch, no index
    r.p.home_position = 0;
    r.home.start(r.p, 0, 0, r.rec);
    ASSERT_EQ(r.home.phase(), HomingPhase::Search);
    r.tick();
    EXPECT_LT(r.profile.velocity(), 0);                // searching in the negative direction
    r.home.edge(1, true, r.profile.velocity(), -50);   // not the awaited switch
    r.home.edge(0, false, r.profile.velocity(), -50);  // not the awaited edge
    r.tick();
    EXPECT_EQ(r.home.phase(), HomingPhase::Search);
    r.home.edge(0, true, r.profile.velocity(), -100);
    r.tick();
    EXPECT_EQ(r.home.phase(), HomingPhase::Backoff);
    r.home.edge(0, false, r.profile.velocity(), -95);  // still moving negative: an overshoot, not the edge
    r.tick();
    EXPECT_EQ(r.home.phase(), HomingPhase::Backoff);
    ASSERT_TRUE(r.until([&] { return r.profile.velocity() > 0; }));
    r.home.edge(0, false, r.profile.velocity(), -90.5);
    r.tick();
    EXPECT_EQ(r.home.phase(), HomingPhase::Offset);
    ASSERT_TRUE(r.until([&] { return r.home.status() == HomingStatus::Done; }));
    EXPECT_EQ(r.home.shift(), 91);  // the reference floor(-90.5) = -91 becomes 0
    EXPECT_EQ(r.profile.position(), -91);
}

TEST(HomingPart, TheWrongLimitSwitchEndsTheSearchWithAnError) {
    HomingRig r;
    r.p.homing_method = 17;
    r.home.start(r.p, 0, 0, r.rec);
    r.in.functions = 1ull << 1;  // positive limit switch
    r.tick();
    EXPECT_EQ(r.home.status(), HomingStatus::Error);
}

TEST(HomingPart, HaltAndInterruption) {
    HomingRig r;
    r.p.homing_method = 17;
    r.home.start(r.p, 0, 0, r.rec);
    r.in.halted = true;
    r.tick();  // at rest: the halt completes at once
    EXPECT_EQ(r.home.status(), HomingStatus::Interrupted);
    r.in.halted = false;
    r.home.start(r.p, 0, 0, r.rec);
    r.home.error();
    EXPECT_EQ(r.home.status(), HomingStatus::Error);
    r.home.entered();
    EXPECT_EQ(r.home.status(), HomingStatus::Idle);
    r.home.start(r.p, 0, 0, r.rec);
    r.home.interrupt();
    EXPECT_EQ(r.home.status(), HomingStatus::Interrupted);
    EXPECT_EQ(r.home.phase(), HomingPhase::Search);
}
