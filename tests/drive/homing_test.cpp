// Homing mode (6): every method of 0x60E3 ends at the right place with the right status bits.
// Machine: 2000 inc/rev, index pulse at 0.25 rad = 79.58 inc + k x 2000 (raw increments).
#include "rig.hpp"

using namespace drive;
using namespace drive::test;

namespace {
constexpr double kIndex = 0.25 / 6.283185307179586 * 2000.0;  // 79.577 inc

struct Case {
    int8_t method;
    const char* machine;  // which fixture to build
    double expected_raw;  // where the axis ends (raw increments)
};

void build(Rig& r, const std::string& m) {
    Environment& e = r.ax.environment();
    if (m == "neg-limit") e.set_negative_limit(-3000);
    if (m == "pos-limit") e.set_positive_limit(3000);
    if (m == "home-ahead") e.set_home_switch(1000, 1500);
    if (m == "home-behind") e.set_home_switch(-1500, -1000);
    if (m == "home-here") e.set_home_switch(-500, 500);
    if (m == "stop-pos") e.set_mechanical_stops(Environment::kNone, 3000);
    if (m == "stop-neg") e.set_mechanical_stops(-3000, Environment::kNone);
}

std::string name_of(const ::testing::TestParamInfo<Case>& i) {
    // Appended piece by piece: GCC 12 at -O3 misjudges "literal" + std::string&& (the insert at position 0)
    // as an overlapping memcpy (-Werror=restrict, GCC bug 105651).
    std::string n = "M";
    if (i.param.method < 0) n += "minus";
    n += std::to_string(std::abs(i.param.method));
    n += '_';
    n += i.param.machine;
    for (auto& c : n)
        if (c == '-') c = '_';
    return n;
}

class HomingMethod : public ::testing::TestWithParam<Case> {};
}  // namespace

TEST_P(HomingMethod, EndsAtHomePositionWithAttainedBits) {
    const Case c = GetParam();
    Rig r;
    build(r, c.machine);
    r.run(1);
    Parameters& p = r.ax.params;
    p.homing_method = c.method;
    p.homing_speed_switch = 600;
    p.homing_speed_zero = 60;
    p.homing_acceleration = 10000;
    p.home_offset_move = 500;
    p.home_position = 10000;
    p.homing_current_threshold = 3000;  // above the running current at 600 rpm (1.4 A)
    r.ax.command.mode = mode::Homing;
    r.enable();
    EXPECT_EQ(r.sw() & (sw::Bit13 | sw::Bit12 | sw::TargetReached), sw::TargetReached);  // 001 not started
    r.cw(0x1F);
    EXPECT_EQ(r.sw() & (sw::Bit13 | sw::Bit12 | sw::TargetReached), 0);  // 000 in progress
    ASSERT_TRUE(r.until([&] { return (r.sw() & (sw::Bit12 | sw::Bit13)) != 0; }, 20000)) << "did not finish";
    r.run_ms(200);
    EXPECT_EQ(r.sw() & (sw::Bit13 | sw::Bit12 | sw::TargetReached), sw::Bit12 | sw::TargetReached);  // 011
    EXPECT_TRUE(r.sw() & sw::Referenced);
    EXPECT_NEAR(r.fb().position_actual, 10000, 3);
    EXPECT_EQ(r.fb().position_demand, 10000);
    EXPECT_NEAR(r.ax.raw_position_inc(), c.expected_raw, 3);
    EXPECT_EQ(r.ax.state(), State::OperationEnabled);
    EXPECT_TRUE(r.rec.raised.empty());  // limit switches do not raise errors while homing
}

INSTANTIATE_TEST_SUITE_P(
    AllMethods, HomingMethod,
    ::testing::Values(
        // 1: to the negative limit, back to its edge, on to the first index; offset positive.
        Case{1, "neg-limit", std::floor(kIndex - 2000 + 500)},
        Case{2, "pos-limit", std::floor(kIndex + 2000 - 500)},
        Case{7, "home-ahead", std::floor(kIndex + 500)},
        Case{7, "home-here", std::floor(kIndex - 2000 + 500)},
        Case{11, "home-behind", std::floor(kIndex + 500)}, Case{17, "neg-limit", -2500},
        Case{18, "pos-limit", 2500}, Case{23, "home-ahead", 1500}, Case{27, "home-behind", -500},
        Case{33, "none", std::floor(kIndex - 2000 + 500)}, Case{34, "none", std::floor(kIndex + 500)},
        Case{37, "none", 500},
        // Current threshold: into the stop, back until the current falls, on to the first index.
        Case{-1, "stop-pos", std::floor(kIndex + 2000 - 500)},
        Case{-2, "stop-neg", std::floor(kIndex - 2000 + 500)}, Case{-3, "stop-pos", 2500},
        Case{-4, "stop-neg", -2500}),
    name_of);

TEST(Homing, WrongLimitSwitchEndsWithHomingError) {
    Rig r;
    r.ax.environment().set_positive_limit(2000);
    r.ax.params.homing_method = 7;  // searches positive for a home switch that is not there
    r.ax.params.homing_speed_switch = 600;
    r.ax.command.mode = mode::Homing;
    r.enable();
    r.cw(0x1F);
    ASSERT_TRUE(r.until([&] { return (r.sw() & sw::Bit13) != 0; }, 5000));
    EXPECT_FALSE(r.sw() & sw::Referenced);
    ASSERT_TRUE(r.until(
        [&] {
            return (r.sw() & (sw::Bit13 | sw::Bit12 | sw::TargetReached)) == (sw::Bit13 | sw::TargetReached);
        },
        2000));  // 101: error, velocity 0
}

TEST(Homing, IndexMethodWithoutIndexChannelFails) {
    Rig r;
    r.ax.params.encoder_type = 0;  // 2-channel encoder
    r.ax.params.homing_method = 34;
    r.ax.command.mode = mode::Homing;
    r.enable();
    r.cw(0x1F);
    r.run(5);
    EXPECT_TRUE(r.sw() & sw::Bit13);
}

TEST(Homing, HaltInterruptsWithStatus001) {
    Rig r;
    r.ax.params.homing_method = 34;
    r.ax.params.homing_speed_zero = 1;  // slow: the index is far
    r.ax.command.mode = mode::Homing;
    r.enable();
    r.cw(0x1F);
    r.run_ms(50);
    r.cw(0x11F);
    ASSERT_TRUE(r.until([&] { return (r.sw() & sw::TargetReached) != 0; }, 2000));
    EXPECT_EQ(r.sw() & (sw::Bit13 | sw::Bit12 | sw::TargetReached), sw::TargetReached);
    EXPECT_FALSE(r.sw() & sw::Referenced);
}

TEST(Homing, Method37WhileDisabledSetsThePositionWithoutMoving) {
    Rig r;
    r.ax.params.homing_method = 37;
    r.ax.params.home_position = -1234;
    r.ax.params.home_offset_move = 500;  // omitted while disabled
    r.ax.command.mode = mode::Homing;
    r.cw(0x06);
    r.cw(0x07);
    r.cw(0x17);  // bit 4 rising in Switched On
    EXPECT_EQ(r.fb().position_actual, -1234);
    EXPECT_TRUE(r.sw() & sw::Referenced);
    EXPECT_EQ(r.sw() & (sw::Bit13 | sw::Bit12 | sw::TargetReached), sw::Bit12 | sw::TargetReached);
    EXPECT_EQ(r.ax.plant().velocity(), 0.0);
}

TEST(Homing, TouchProbeIsOffDuringHoming) {
    Rig r;
    r.ax.params.homing_method = 34;
    r.ax.params.homing_speed_zero = 300;
    r.ax.command.mode = mode::Homing;
    r.ax.command.touch_probe_function = 0x0017;  // index source, continuous
    r.enable();
    r.cw(0x1F);
    ASSERT_TRUE(r.until([&] { return (r.sw() & sw::Bit12) != 0; }, 5000));
    EXPECT_EQ(r.fb().touch_probe_pos_count, 0);
    EXPECT_EQ(r.fb().touch_probe_status & 0x6, 0);
}

TEST(Homing, QuickStopInterruptsHoming) {
    Rig r;
    r.ax.params.homing_method = 34;
    r.ax.params.homing_speed_zero = 1;
    r.ax.command.mode = mode::Homing;
    r.enable();
    r.cw(0x1F);
    r.run_ms(30);
    r.cw(0x0B);
    r.run_ms(100);
    r.cw(0x0F);  // 16: back to Operation Enabled
    EXPECT_EQ(r.ax.state(), State::OperationEnabled);
    EXPECT_EQ(r.sw() & (sw::Bit13 | sw::Bit12 | sw::TargetReached), sw::TargetReached);  // 001
    r.run_ms(100);
    EXPECT_LT(std::abs(r.rpm()), 1.0);  // it does not resume on its own
}
