// drive-sim's plot: events found in the samples (homing done, faults, reset, limit switches) and the
// gnuplot script (panels on one time axis, demand under actual, mode and state strips, events marked, the
// script name in the title); rendered with gnuplot when it is installed.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "plot.hpp"

namespace {

using drivesim::Event;
using drivesim::Sample;

Sample at(double t, uint16_t sw, int8_t mode, uint32_t inputs = 0, uint16_t error = 0) {
    Sample s;
    s.t_ms = t;
    s.statusword = sw;
    s.mode = mode;
    s.inputs = inputs;
    s.error_code = error;
    return s;
}

std::size_t count(const std::string& text, const std::string& what) {
    std::size_t n = 0;
    for (std::size_t p = text.find(what); p != std::string::npos; p = text.find(what, p + 1))
        ++n;
    return n;
}

TEST(DriveSimPlot, Cia402StatesFromTheStatusword) {
    EXPECT_EQ(drivesim::cia402_state(0x0000), 0);
    EXPECT_EQ(drivesim::cia402_state(0x0250), 1);
    EXPECT_EQ(drivesim::cia402_state(0x0231), 2);
    EXPECT_EQ(drivesim::cia402_state(0x0233), 3);
    EXPECT_EQ(drivesim::cia402_state(0x0237), 4);
    EXPECT_EQ(drivesim::cia402_state(0x0217), 5);
    EXPECT_EQ(drivesim::cia402_state(0x021F), 6);
    EXPECT_EQ(drivesim::cia402_state(0x0218), 7);
}

TEST(DriveSimPlot, EventsAreHomingFaultsResetsAndSwitches) {
    const std::vector<Sample> s = {
        at(0, 0x0237, 6),
        at(1, 0x0237, 6, 0x1),          // negative limit switch reached
        at(2, 0x1637, 6, 0x1),          // homing attained (bit 12) with target reached
        at(3, 0x1637, 6, 0x0),          // switch released
        at(4, 0x0218, 8, 0x2, 0x8611),  // fault, positive limit on
        at(5, 0x0250, 8, 0x2),          // reset
        at(6, 0x0250, 8, 0x0),
    };
    const std::vector<Event> e = drivesim::find_events(s);
    std::vector<std::string> texts;
    for (const Event& x : e)
        texts.push_back(std::to_string(static_cast<int>(x.t_ms)) + " " + x.text);
    ASSERT_EQ(texts.size(), 7u) << ::testing::PrintToString(texts);
    EXPECT_EQ(texts[0], "1 negative limit switch on");
    EXPECT_EQ(texts[1], "2 homing done");
    EXPECT_EQ(texts[2], "3 negative limit switch off");
    EXPECT_EQ(texts[3].rfind("4 fault 0x8611", 0), 0u);
    EXPECT_EQ(texts[4], "4 positive limit switch on");
    EXPECT_EQ(texts[5], "5 fault reset");
    EXPECT_EQ(texts[6], "6 positive limit switch off");
    // Nothing happens, nothing marked: the same statusword in another mode is no homing event.
    EXPECT_TRUE(drivesim::find_events({at(0, 0x0237, 8), at(1, 0x1637, 8)}).empty());
}

TEST(DriveSimPlot, ScriptAlignsThePanelsAndMarksTheEvents) {
    const std::vector<Event> events = {{120, Event::Kind::Homing, "homing done"},
                                       {300, Event::Kind::Fault, "fault 0x8611 Following error"}};
    const std::string g =
        drivesim::gnuplot_script("run.csv", "run.png", "drive-sim: homing.txt (1000 us cycle)", 500, events);
    EXPECT_NE(g.find("set multiplot title 'drive-sim: homing.txt (1000 us cycle)'"), std::string::npos);
    // One left and right edge and one x range for every panel: the time axes line up.
    EXPECT_EQ(count(g, "set lmargin at screen"), 1u);
    EXPECT_EQ(count(g, "set rmargin at screen"), 1u);
    EXPECT_EQ(count(g, "set xrange [0:500]"), 1u);
    EXPECT_EQ(count(g, "\nplot "), 6u);
    EXPECT_EQ(count(g, "set tmargin at screen"), 6u);
    // Demand first, wide and light; the actual value on top of it, thin.
    const auto demand = g.find("title 'demand 0x6062'");
    const auto actual = g.find("title 'actual 0x6064'");
    ASSERT_NE(demand, std::string::npos);
    ASSERT_NE(actual, std::string::npos);
    EXPECT_LT(demand, actual);
    EXPECT_NE(g.find("using 1:3 with lines lw 7"), std::string::npos);
    // Mode and CiA 402 state strips.
    EXPECT_NE(g.find("using 1:(mrow($10)) with steps"), std::string::npos);
    EXPECT_NE(g.find("using 1:13 with steps"), std::string::npos);
    // Each event: a line in every panel (arrows stay for the whole multiplot), its name once on top.
    EXPECT_EQ(count(g, "set arrow from 120, graph 0 to 120, graph 1"), 1u);
    EXPECT_EQ(count(g, "set arrow from 300, graph 0"), 1u);
    EXPECT_NE(g.find("'homing done' at 120"), std::string::npos);
    EXPECT_NE(g.find("'fault 0x8611 Following error' at 300"), std::string::npos);
    EXPECT_LT(g.find("'homing done'"), g.find("unset label"));
    // Events at (nearly) the same time share one label instead of printing over each other.
    const std::string two = drivesim::gnuplot_script(
        "r.csv", "r.png", "t", 1000,
        {{620, Event::Kind::Limit, "positive limit switch on"}, {621, Event::Kind::Fault, "fault"}});
    EXPECT_NE(two.find("'positive limit switch on / fault' at 620"), std::string::npos);
    EXPECT_EQ(count(two, "set arrow from"), 2u);
    EXPECT_EQ(count(two, "set label "), 1u);
    // A quote in a name cannot end the gnuplot string early.
    const std::string q = drivesim::gnuplot_script("a'b.csv", "x.png", "it's", 1, {});
    EXPECT_NE(q.find("'a''b.csv'"), std::string::npos);
    EXPECT_NE(q.find("'it''s'"), std::string::npos);
}

TEST(DriveSimPlot, GnuplotRendersTheScript) {
    if (std::system("command -v gnuplot > /dev/null 2>&1") != 0) GTEST_SKIP() << "gnuplot not installed";
    const std::filesystem::path dir =
        std::filesystem::temp_directory_path() / ("drive-sim-plot-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    std::vector<Sample> s;
    for (int i = 0; i <= 100; ++i) {
        Sample x = at(i, i < 50 ? 0x0237 : 0x0218, 8, 0, i < 50 ? 0 : 0x8611);
        x.demand = i * 10;
        x.actual = i * 10 - 3;
        x.velocity_demand = 100;
        x.velocity = 100 - i % 3;
        x.current = static_cast<int16_t>(50 + i % 7);
        x.following_error = 3 - i % 2;
        s.push_back(x);
    }
    const std::string csv = (dir / "run.csv").string(), png = (dir / "run.png").string();
    ASSERT_TRUE(drivesim::write_csv(csv, s));
    std::ofstream(dir / "run.gp") << drivesim::gnuplot_script(csv, png, "test", 100,
                                                              drivesim::find_events(s));
    const std::string cmd =
        "gnuplot '" + (dir / "run.gp").string() + "' 2> '" + (dir / "err.txt").string() + "'";
    EXPECT_EQ(std::system(cmd.c_str()), 0);
    std::ifstream in(png, std::ios::binary);
    char magic[8] = {};
    in.read(magic, 8);
    EXPECT_EQ(std::string(magic + 1, 3), "PNG");
    std::ifstream err(dir / "err.txt");
    std::string warnings((std::istreambuf_iterator<char>(err)), std::istreambuf_iterator<char>());
    EXPECT_EQ(warnings, "") << "gnuplot complained";
    std::filesystem::remove_all(dir);
}

}  // namespace
