#pragma once
// Report writers: the readable text report (grouped, colour on a terminal only), JUnit XML and JSON.
#include <chrono>
#include <ostream>
#include <string>
#include <vector>

#include "conform.hpp"

namespace conform {

struct RunInfo {
    std::string iface;
    std::string device;  // identity as read
    std::chrono::milliseconds duration{0};
    std::vector<std::string> notes;
};

struct Totals {
    unsigned passed = 0, failed = 0, skipped = 0, warned = 0;
};
Totals totals(const std::vector<TestResult>& results);

const char* status_name(Status s);
// One test's line (and detail lines for failures/warnings, or with verbose for all).
void write_text(std::ostream& out, const std::vector<TestResult>& results, const RunInfo& info, bool colour,
                bool verbose);
// The same in three parts, for a report written line by line as the tests run: the header, each result
// (with the group heading when the group changes; `group` carries it from one call to the next), the end.
void write_text_header(std::ostream& out, const RunInfo& info);
void write_text_result(std::ostream& out, const TestResult& r, std::string& group, bool colour, bool verbose);
void write_text_footer(std::ostream& out, const std::vector<TestResult>& results, const RunInfo& info);
// Slave strings in the text report: control and non-ASCII bytes as \xNN.
std::string printable(const std::string& s);
void write_junit(std::ostream& out, const std::vector<TestResult>& results, const RunInfo& info);
void write_json(std::ostream& out, const std::vector<TestResult>& results, const RunInfo& info);
// The catalogue as a table (--list); markdown for docs/conformance.md.
void write_list(std::ostream& out, const Catalogue& c, bool markdown);

std::string xml_escape(const std::string& s);

}  // namespace conform
