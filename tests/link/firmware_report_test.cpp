// slave::Firmware::report(): the hook through which run_slave() prints the firmware's statistics at
// exit (--verbose, SlaveOptions::stats_file); FirmwareAdapter forwards it when the target has one.
#include <gtest/gtest.h>

#include <cstdint>
#include <ostream>
#include <sstream>

#include "slave/firmware.hpp"

namespace {

struct WithReport {
    void poll(uint64_t) {}
    uint64_t next_deadline_ns() const { return 0; }
    void report(std::ostream& out) const { out << "stack.cycles " << cycles << '\n'; }
    uint64_t cycles = 42;
};

struct WithoutReport {
    void poll(uint64_t) {}
    uint64_t next_deadline_ns() const { return 0; }
};

TEST(FirmwareReport, AdapterForwardsReportOfItsTarget) {
    WithReport target;
    slave::FirmwareAdapter<WithReport> adapter(target);
    const slave::Firmware& fw = adapter;
    std::ostringstream out;
    fw.report(out);
    EXPECT_EQ(out.str(), "stack.cycles 42\n");
    target.cycles = 7;
    out.str("");
    fw.report(out);
    EXPECT_EQ(out.str(), "stack.cycles 7\n");
}

TEST(FirmwareReport, TargetWithoutReportPrintsNothing) {
    WithoutReport target;
    slave::FirmwareAdapter<WithoutReport> adapter(target);
    std::ostringstream out;
    static_cast<const slave::Firmware&>(adapter).report(out);
    EXPECT_TRUE(out.str().empty());
}

}  // namespace
