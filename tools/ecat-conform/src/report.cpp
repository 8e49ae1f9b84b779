// Report writers.
#include "report.hpp"

#include <cstdio>
#include <map>

#include "util/json.hpp"

namespace conform {

Totals totals(const std::vector<TestResult>& results) {
    Totals t;
    for (const auto& r : results) {
        switch (r.outcome.status) {
            case Status::Pass:
                ++t.passed;
                break;
            case Status::Fail:
                ++t.failed;
                break;
            case Status::Skip:
                ++t.skipped;
                break;
            case Status::Warn:
                ++t.warned;
                break;
        }
    }
    return t;
}

const char* status_name(Status s) {
    switch (s) {
        case Status::Pass:
            return "PASS";
        case Status::Fail:
            return "FAIL";
        case Status::Skip:
            return "SKIP";
        case Status::Warn:
            return "WARN";
    }
    return "?";
}

std::string xml_escape(const std::string& s) {
    std::string o;
    for (unsigned char c : s) {
        switch (c) {
            case '&':
                o += "&amp;";
                break;
            case '<':
                o += "&lt;";
                break;
            case '>':
                o += "&gt;";
                break;
            case '"':
                o += "&quot;";
                break;
            case '\'':
                o += "&apos;";
                break;
            default:
                // Control characters are not allowed in XML 1.0 (except tab, newline, CR).
                if (c < 0x20 && c != '\t' && c != '\n' && c != '\r')
                    o += '?';
                else
                    o += static_cast<char>(c);
        }
    }
    return o;
}

namespace {
const char* colour_of(Status s) {
    switch (s) {
        case Status::Pass:
            return "\033[32m";
        case Status::Fail:
            return "\033[31;1m";
        case Status::Skip:
            return "\033[90m";
        case Status::Warn:
            return "\033[33m";
    }
    return "";
}
std::string detail(const Outcome& o) {
    std::string s = o.message;
    if (!o.observed.empty() || !o.expected.empty()) {
        if (!s.empty()) s += ": ";
        s += "observed " + (o.observed.empty() ? std::string("-") : o.observed);
        if (!o.expected.empty()) s += ", expected " + o.expected;
    }
    return s;
}
}  // namespace

std::string printable(const std::string& s) {
    std::string o;
    char b[8];
    for (unsigned char c : s) {
        if (c == '\\') {
            o += "\\\\";
        } else if (c < 0x20 || c >= 0x7F) {
            std::snprintf(b, sizeof b, "\\x%02x", c);
            o += b;
        } else {
            o += static_cast<char>(c);
        }
    }
    return o;
}

void write_text_header(std::ostream& out, const RunInfo& info) {
    out << "ecat-conform on " << printable(info.iface) << ": " << printable(info.device) << "\n";
}

void write_text_result(std::ostream& out, const TestResult& r, std::string& group, bool colour,
                       bool verbose) {
    const TestCase& t = *r.test;
    const std::string key = r.slave < 0 ? t.group : "slave " + std::to_string(r.slave) + ", " + t.group;
    if (key != group) {
        group = key;
        out << "\n"
            << (colour ? "\033[1m" : "") << "== " << group_title(t.group) << " ("
            << (r.slave < 0 ? "" : "slave " + std::to_string(r.slave) + ", ") << t.group << ")"
            << (colour ? "\033[0m" : "") << "\n";
    }
    const Status s = r.outcome.status;
    out << "  " << (colour ? colour_of(s) : "") << status_name(s) << (colour ? "\033[0m" : "") << "  " << t.id
        << "  " << t.title << "\n";
    if (s == Status::Fail || s == Status::Warn) {
        out << "        " << printable(detail(r.outcome)) << "\n";
        out << "        clause: " << t.clause << "\n";
    } else if (s == Status::Skip || verbose) {
        std::string d = detail(r.outcome);
        if (!d.empty()) out << "        " << printable(d) << "\n";
    }
}

void write_text_footer(std::ostream& out, const std::vector<TestResult>& results, const RunInfo& info) {
    for (const auto& n : info.notes)
        out << "\nnote: " << printable(n) << "\n";
    Totals t = totals(results);
    char b[64];
    std::snprintf(b, sizeof b, "%.1f s", static_cast<double>(info.duration.count()) / 1000.0);
    out << "\n" << results.size() << " tests in " << b;
    if (t.warned) out << ", " << t.warned << " warning(s)";
    out << "\n";
    out << t.passed << " passed, " << t.failed << " failed, " << t.skipped << " skipped\n";
}

void write_text(std::ostream& out, const std::vector<TestResult>& results, const RunInfo& info, bool colour,
                bool verbose) {
    write_text_header(out, info);
    std::string group;
    for (const auto& r : results)
        write_text_result(out, r, group, colour, verbose);
    write_text_footer(out, results, info);
}

void write_junit(std::ostream& out, const std::vector<TestResult>& results, const RunInfo& info) {
    std::map<std::string, std::vector<const TestResult*>> by_group;
    std::vector<std::string> order;
    for (const auto& r : results) {
        const std::string g =
            r.slave < 0 ? r.test->group : "slave" + std::to_string(r.slave) + "." + r.test->group;
        if (!by_group.count(g)) order.push_back(g);
        by_group[g].push_back(&r);
    }
    Totals all = totals(results);
    char secs[32];
    out << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
    std::snprintf(secs, sizeof secs, "%.3f", static_cast<double>(info.duration.count()) / 1000.0);
    out << "<testsuites name=\"ecat-conform\" tests=\"" << results.size() << "\" failures=\"" << all.failed
        << "\" skipped=\"" << all.skipped << "\" time=\"" << secs << "\">\n";
    for (const auto& g : order) {
        const auto& rs = by_group[g];
        unsigned f = 0, s = 0;
        double time = 0;
        for (const auto* r : rs) {
            f += r->outcome.status == Status::Fail;
            s += r->outcome.status == Status::Skip;
            time += static_cast<double>(r->duration.count()) / 1e6;
        }
        std::snprintf(secs, sizeof secs, "%.3f", time);
        out << "  <testsuite name=\"" << xml_escape(g) << "\" tests=\"" << rs.size() << "\" failures=\"" << f
            << "\" errors=\"0\" skipped=\"" << s << "\" time=\"" << secs << "\">\n";
        for (const auto* r : rs) {
            std::snprintf(secs, sizeof secs, "%.3f", static_cast<double>(r->duration.count()) / 1e6);
            out << "    <testcase classname=\"ecat-conform." << xml_escape(g) << "\" name=\""
                << xml_escape(r->test->id) << "\" time=\"" << secs << "\">\n";
            const std::string d = detail(r->outcome);
            switch (r->outcome.status) {
                case Status::Fail:
                    out << "      <failure message=\"" << xml_escape(d) << "\" type=\""
                        << xml_escape(r->test->clause) << "\">"
                        << xml_escape(r->test->title + "\n" + d + "\nclause: " + r->test->clause)
                        << "</failure>\n";
                    break;
                case Status::Skip:
                    out << "      <skipped message=\"" << xml_escape(d) << "\"/>\n";
                    break;
                case Status::Warn:
                    out << "      <system-out>"
                        << xml_escape("WARNING: " + d + "\nclause: " + r->test->clause) << "</system-out>\n";
                    break;
                case Status::Pass:
                    if (!d.empty()) out << "      <system-out>" << xml_escape(d) << "</system-out>\n";
                    break;
            }
            out << "    </testcase>\n";
        }
        out << "  </testsuite>\n";
    }
    out << "</testsuites>\n";
}

void write_json(std::ostream& out, const std::vector<TestResult>& results, const RunInfo& info) {
    const Totals t = totals(results);
    util::JsonWriter w(out);
    w.begin_object()
        .member("tool", "ecat-conform")
        .member("iface", info.iface)
        .member("device", info.device)
        .member("duration_ms", info.duration.count())
        .member("passed", t.passed)
        .member("failed", t.failed)
        .member("skipped", t.skipped)
        .member("warnings", t.warned);
    w.key("notes").begin_array();
    for (const auto& n : info.notes)
        w.value(n);
    w.end_array();
    w.key("results").begin_array();
    for (const auto& r : results) {
        w.begin_object();
        if (r.slave >= 0) w.member("slave", r.slave);
        w.member("id", r.test->id)
            .member("group", r.test->group)
            .member("status", status_name(r.outcome.status))
            .member("severity", r.test->severity == Severity::Error ? "error" : "warning")
            .member("title", r.test->title)
            .member("clause", r.test->clause)
            .member("message", r.outcome.message)
            .member("observed", r.outcome.observed)
            .member("expected", r.outcome.expected)
            .member("duration_us", r.duration.count())
            .end_object();
    }
    w.end_array().end_object();
}

void write_list(std::ostream& out, const Catalogue& c, bool markdown) {
    if (markdown) {
        out << "| id | title | clause | severity | applies when |\n|---|---|---|---|---|\n";
        for (const auto& t : c)
            out << "| `" << t.id << "` | " << t.title << " | " << t.clause << " | "
                << (t.severity == Severity::Error ? "error" : "warning") << " | "
                << (t.applies.empty() ? "always" : t.applies) << " |\n";
        return;
    }
    std::string group;
    for (const auto& t : c) {
        if (t.group != group) {
            group = t.group;
            out << "\n== " << group_title(group) << " (" << group << ")\n";
        }
        out << "  " << t.id << "  [" << (t.severity == Severity::Error ? "error" : "warning") << "]  "
            << t.title << "\n      clause: " << t.clause
            << (t.applies.empty() ? "" : "; applies: " + t.applies) << "\n";
    }
    out << "\n" << c.size() << " tests\n";
}

}  // namespace conform
