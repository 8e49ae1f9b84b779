// The MAXPOS drive as a master sees it, pinned: its ESI, its SII image and a dump of every object and entry
// of its dictionary, byte-compared against files captured from the tree before the MAXPOS declaration left
// od/ (issue 21: "the MAXPOS drive's ESI, SII and dictionary unchanged by the move"). The files are what
// `ecat-slave --write-esi` / `--write-sii` write for the built-in firmware (no --state-dir); CTest also
// compares the program's own output with them (tests/od/CMakeLists.txt). Nothing in them depends on the
// build: the ESI names no tool version and no date.
//
// A deliberate change of the MAXPOS regenerates them: SOFTECAT_UPDATE_GOLDEN=1 ./maxpos_golden_tests, then
// review the diff.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <variant>

#include "esi/esi.hpp"
#include "esi/sii.hpp"
#include "maxpos/maxpos.hpp"

namespace {

std::string hex(uint64_t v, int digits) {
    char b[24];
    std::snprintf(b, sizeof b, "0x%0*llX", digits, static_cast<unsigned long long>(v));
    return b;
}

std::string number(const od::Number& n) {
    if (const auto* i = std::get_if<int64_t>(&n)) return std::to_string(*i);
    if (const auto* u = std::get_if<uint64_t>(&n)) return std::to_string(*u);
    if (const auto* d = std::get_if<double>(&n)) {
        std::ostringstream s;
        s.precision(17);
        s << *d;
        return s.str();
    }
    return "-";
}

// Every object and entry with everything the model declares for it, one line each.
std::string dump(const od::Dictionary& dict) {
    std::ostringstream out;
    for (const od::Object& o : dict.objects()) {
        out << hex(o.index, 4) << " code=" << hex(static_cast<unsigned>(o.code), 2)
            << " type=" << od::to_string(o.type) << " \"" << o.name << "\"\n";
        for (const od::Entry& e : o.entries) {
            out << "  " << hex(e.index, 4) << ':' << hex(e.subindex, 2) << " \"" << e.name
                << "\" type=" << od::to_string(e.type) << " bits=" << e.bit_length
                << " access=" << hex(e.access, 4) << " default=" << number(e.default_value) << " string=\""
                << e.default_string << "\" min=" << number(e.minimum) << " max=" << number(e.maximum)
                << " unit=\"" << e.unit << "\"";
            for (const od::NamedValue& v : e.enumeration)
                out << " [" << v.value << "=" << v.text << "]";
            out << '\n';
        }
    }
    return out.str();
}

std::string read_file(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    std::ostringstream s;
    s << f.rdbuf();
    return s.str();
}

// Compares `actual` with the golden file `name`, or writes it in update mode.
void compare(const std::string& name, const std::string& actual) {
    const std::string path = std::string(GOLDEN_DIR) + "/" + name;
    if (const char* u = std::getenv("SOFTECAT_UPDATE_GOLDEN"); u && std::string(u) == "1") {
        std::ofstream(path, std::ios::binary) << actual;
        GTEST_SKIP() << "wrote " << path;
    }
    const std::string expected = read_file(path);
    ASSERT_FALSE(expected.empty()) << path << " missing";
    EXPECT_EQ(expected.size(), actual.size()) << name;
    std::size_t at = 0;
    while (at < expected.size() && at < actual.size() && expected[at] == actual[at])
        ++at;
    EXPECT_TRUE(expected == actual) << name << " differs first at byte " << at << ": expected \""
                                    << expected.substr(at, 80) << "\", got \"" << actual.substr(at, 80)
                                    << "\"";
}

od::DeviceDescription description() {
    return maxpos::description();
}

od::Dictionary dictionary(const od::DeviceDescription& d) {
    return maxpos::dictionary(d);
}

TEST(MaxposGolden, Esi) {
    const od::DeviceDescription d = description();
    compare("maxpos.esi.xml", esi::build_esi(d, dictionary(d)));
}

TEST(MaxposGolden, Sii) {
    const od::DeviceDescription d = description();
    const std::vector<uint8_t> sii = esi::build_sii(d, dictionary(d));
    compare("maxpos.sii", std::string(sii.begin(), sii.end()));
}

TEST(MaxposGolden, Dictionary) {
    const od::DeviceDescription d = description();
    compare("maxpos.dictionary.txt", dump(dictionary(d)));
}

// The dump sees a change of any field it prints (so the comparison above can fail).
TEST(MaxposGolden, DumpSeesEveryField) {
    const od::DeviceDescription d = description();
    const std::string base = dump(dictionary(d));
    od::DeviceDescription other = d;
    other.identity.serial_number = 7;
    EXPECT_NE(dump(dictionary(other)), base);
    od::Dictionary dict;
    od::Object o;
    o.index = 0x2000;
    o.entries.push_back(od::Entry{});
    o.entries[0].index = 0x2000;
    o.entries[0].bit_length = 8;
    dict.add(o);
    const std::string one = dump(dict);
    o.entries[0].unit = "mm";
    od::Dictionary dict2;
    dict2.add(o);
    EXPECT_NE(dump(dict2), one);
}

}  // namespace
