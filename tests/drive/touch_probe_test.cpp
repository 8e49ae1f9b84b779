// Touch probe 0x60B8..0x60BB, 0x60D5/0x60D6: edges latched where they really happened between cycles.
#include "rig.hpp"

using namespace drive;
using namespace drive::test;

namespace {
// Moving axis in PVM at `rpm`.
void move(Rig& r, int32_t rpm) {
    r.ax.command.mode = mode::ProfileVelocity;
    r.ax.params.profile_acceleration = 50000;
    r.ax.command.target_velocity = rpm;
    r.enable();
    r.run_ms(100);
}
}  // namespace

TEST(TouchProbe, SwitchEdgesLatchedWithinOneIncrement) {
    Rig r;
    r.ax.params.input_function[3] = 26;  // DigIN4 = touch probe 1
    r.ax.environment().set_home_switch(5000.3, 9000.7, 4);
    r.ax.command.touch_probe_function = 0x0031;  // enable, first event, TP1 input, both edges
    move(r, 1500);                               // 50 inc per ms: many increments between two cycles
    EXPECT_EQ(r.fb().touch_probe_status, 0x1);
    ASSERT_TRUE(r.until([&] { return (r.fb().touch_probe_status & 0x6) == 0x6; }, 2000));
    EXPECT_NEAR(r.fb().touch_probe_pos, 5000, 1);
    EXPECT_NEAR(r.fb().touch_probe_neg, 9000, 1);
    EXPECT_EQ(r.fb().touch_probe_pos_count, 1);
    EXPECT_EQ(r.fb().touch_probe_neg_count, 1);
}

TEST(TouchProbe, TimedInputEdgeBetweenCyclesIsInterpolated) {
    Rig r;
    r.ax.params.input_function[3] = 26;
    r.ax.command.touch_probe_function = 0x0011;  // positive edge only
    move(r, 3000);                               // 100 inc/ms
    const int64_t edge = r.t + 437'000;          // 0.437 ms into the next cycle
    r.ax.environment().set_input(4, true, edge);
    // Sample the exact position at every plant step around the edge by running the cycle with a recorder.
    const double p0 = r.ax.raw_position_inc();
    r.run(1);
    const double p1 = r.ax.raw_position_inc();
    const double expected = p0 + (p1 - p0) * 0.437;  // constant speed within the cycle
    ASSERT_TRUE(r.fb().touch_probe_status & 0x2);
    EXPECT_NEAR(r.fb().touch_probe_pos, std::floor(expected), 1.0);
}

TEST(TouchProbe, FirstEventLatchesOnceContinuousCountsEveryEdge) {
    for (bool continuous : {false, true}) {
        Rig r;
        r.ax.params.input_function[3] = 26;
        r.ax.command.touch_probe_function = continuous ? 0x0013 : 0x0011;
        move(r, 1500);
        for (int k = 0; k < 4; ++k) {
            r.ax.environment().set_input(4, true, r.t + 200'000);
            r.run(5);
            r.ax.environment().set_input(4, false, r.t + 200'000);
            r.run(5);
        }
        EXPECT_EQ(r.fb().touch_probe_pos_count, continuous ? 4 : 1);
        EXPECT_EQ(r.fb().touch_probe_neg_count, 0);  // negative edge not enabled
        EXPECT_TRUE(r.fb().touch_probe_status & 0x2);
    }
}

TEST(TouchProbe, FirstEventRearmsWhenTheEdgeEnableIsToggled) {
    Rig r;
    r.ax.params.input_function[3] = 26;
    r.ax.command.touch_probe_function = 0x0011;
    move(r, 1500);
    r.ax.environment().set_input(4, true, r.t + 100'000);
    r.run(5);
    const int32_t first = r.fb().touch_probe_pos;
    r.ax.environment().set_input(4, false);
    r.ax.command.touch_probe_function = 0x0001;
    r.run(1);
    EXPECT_EQ(r.fb().touch_probe_status & 0x2, 0);
    r.ax.command.touch_probe_function = 0x0011;
    r.run(1);
    r.ax.environment().set_input(4, true, r.t + 100'000);
    r.run(5);
    EXPECT_TRUE(r.fb().touch_probe_status & 0x2);
    EXPECT_GT(r.fb().touch_probe_pos, first + 100);
}

TEST(TouchProbe, EncoderIndexAsSource) {
    Rig r;
    r.ax.command.touch_probe_function = 0x0017;  // enable, continuous, index, positive edge
    move(r, 600);
    r.run_ms(300);  // several index pulses (one per 2000 inc)
    ASSERT_TRUE(r.fb().touch_probe_status & 0x2);
    EXPECT_GE(r.fb().touch_probe_pos_count, 2);
    const int32_t v = r.fb().touch_probe_pos;
    EXPECT_EQ(((v - 79) % 2000 + 2000) % 2000, 0) << v;  // index at 79.58 inc + k x 2000
    EXPECT_EQ(r.fb().index_position, v);
}

TEST(TouchProbe, DisableClearsStatusAndCounters) {
    Rig r;
    r.ax.command.touch_probe_function = 0x0017;
    move(r, 600);
    r.run_ms(300);
    ASSERT_GT(r.fb().touch_probe_pos_count, 0);
    r.ax.command.touch_probe_function = 0;
    r.run(1);
    EXPECT_EQ(r.fb().touch_probe_status, 0);
    EXPECT_EQ(r.fb().touch_probe_pos_count, 0);
}
