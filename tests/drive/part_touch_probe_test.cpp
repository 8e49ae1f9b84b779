// TouchProbe alone: arming by 0x60B8, first-event and continuous latching, the source selection (no Axis).
#include <gtest/gtest.h>

#include "drive/touch_probe.hpp"

using namespace drive;

TEST(TouchProbePart, FirstEventLatchesOnceUntilReArmed) {
    TouchProbe tp;
    const uint16_t fn = 0x0031;  // enable, first event, TP1 input, both edges
    tp.configure(fn);
    EXPECT_EQ(tp.status(), 0x1);
    tp.latch(fn, true, 500);
    tp.latch(fn, true, 600);  // first event mode: ignored
    tp.latch(fn, false, 700);
    EXPECT_EQ(tp.status(), 0x7);
    EXPECT_EQ(tp.position_rising(), 500);
    EXPECT_EQ(tp.position_falling(), 700);
    EXPECT_EQ(tp.count_rising(), 1);
    tp.configure(0x0021);  // rising edge disabled: its stored bit clears
    EXPECT_EQ(tp.status(), 0x5);
    tp.configure(fn);  // enabled again: re-armed
    tp.latch(fn, true, 800);
    EXPECT_EQ(tp.position_rising(), 800);
}

TEST(TouchProbePart, ContinuousCountsEveryEdge) {
    TouchProbe tp;
    const uint16_t fn = 0x0013;  // enable, continuous, rising edge
    tp.configure(fn);
    for (int i = 0; i < 3; ++i)
        tp.latch(fn, true, 100 * i);
    tp.latch(fn, false, 999);  // falling edge not enabled
    EXPECT_EQ(tp.count_rising(), 3);
    EXPECT_EQ(tp.position_rising(), 200);
    EXPECT_EQ(tp.count_falling(), 0);
    tp.configure(0);
    EXPECT_EQ(tp.status(), 0);
    EXPECT_EQ(tp.count_rising(), 0);
}

TEST(TouchProbePart, SourceSelection) {
    EXPECT_EQ(TouchProbe::source_bit(0x0001, 0), 26);   // TP1 input function
    EXPECT_EQ(TouchProbe::source_bit(0x0009, 3), 34);   // 0x60D0:01 = 3: DigIN3
    EXPECT_EQ(TouchProbe::source_bit(0x0009, -3), 37);  // DigIN6
    EXPECT_EQ(TouchProbe::source_bit(0x0005, 0), -1);   // the index
    EXPECT_TRUE(TouchProbe::index_selected(0x0005, 0));
    EXPECT_TRUE(TouchProbe::index_selected(0x0009, 5));
    EXPECT_FALSE(TouchProbe::index_selected(0x0001, 5));
    EXPECT_TRUE(TouchProbe::armed(0x0001, false));
    EXPECT_FALSE(TouchProbe::armed(0x0001, true));  // not while homing
    EXPECT_FALSE(TouchProbe::armed(0x0000, false));
}

TEST(TouchProbePart, HomingClearsTheLatchesButKeepsTheEnable) {
    TouchProbe tp;
    tp.configure(0x0031);
    tp.latch(0x0031, true, 5);
    tp.clear_for_homing();
    EXPECT_EQ(tp.status(), 0x1);
    EXPECT_EQ(tp.position_rising(), 0);
    EXPECT_EQ(tp.count_rising(), 0);
}
