// PositionFrame: the reported frame (home shift, modulo range, software limits) on its own.
#include <gtest/gtest.h>

#include <cmath>

#include "drive/frame.hpp"

using namespace drive;

TEST(PositionFramePart, ShiftWithoutRange) {
    PositionFrame f;
    f.shift = 100;
    EXPECT_FALSE(f.range_on());
    EXPECT_EQ(f.report(600), 600);
    EXPECT_EQ(f.to_raw(500, 0), 400);
    EXPECT_TRUE(std::isinf(f.raw_min()));
    f.sw_min = -100;
    f.sw_max = 100;
    EXPECT_EQ(f.raw_min(), -200);
    EXPECT_EQ(f.raw_max(), 0);
    EXPECT_TRUE(f.outside_limits(101));
    EXPECT_FALSE(f.outside_limits(-100));
}

TEST(PositionFramePart, ModuloRangeWrapsAndTakesTheShortWay) {
    PositionFrame f;
    f.range_min = 0;
    f.range_max = 999;
    ASSERT_TRUE(f.range_on());
    EXPECT_EQ(f.report(1000), 0);
    EXPECT_EQ(f.report(-1), 999);
    EXPECT_EQ(f.unwrap(10, 990), 1010);  // forward over the wrap, not back 980
    EXPECT_EQ(f.unwrap(980, 1010), 980);
    EXPECT_EQ(f.to_raw(10, 990), 1010);
}
