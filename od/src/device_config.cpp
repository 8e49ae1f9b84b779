#include "od/device_config.hpp"

#include <cerrno>
#include <charconv>
#include <cstring>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

#include "od/drive_profile.hpp"

namespace od {
namespace {

std::string_view trim(std::string_view s) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == '\r'))
        s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r'))
        s.remove_suffix(1);
    return s;
}

struct Parser {
    std::string source;
    int line = 0;

    [[noreturn]] void fail(const std::string& msg) const { throw ConfigError(source, line, msg); }

    // Value text -> string (quotes removed, escapes resolved, trailing comment stripped).
    std::string value_string(std::string_view v) const {
        if (v.empty()) return {};
        if (v.front() == '"') {
            std::string out;
            std::size_t i = 1;
            for (; i < v.size() && v[i] != '"'; ++i) {
                if (v[i] == '\\') {
                    if (++i == v.size()) fail("unterminated string");
                    switch (v[i]) {
                        case '"':
                            out += '"';
                            break;
                        case '\\':
                            out += '\\';
                            break;
                        case 't':
                            out += '\t';
                            break;
                        case 'n':
                            out += '\n';
                            break;
                        default:
                            fail(std::string("unknown escape \\") + v[i]);
                    }
                } else {
                    out += v[i];
                }
            }
            if (i == v.size()) fail("unterminated string");
            check_rest(v.substr(i + 1));
            return out;
        }
        if (v.front() == '\'') {
            const auto end = v.find('\'', 1);
            if (end == std::string_view::npos) fail("unterminated string");
            check_rest(v.substr(end + 1));
            return std::string(v.substr(1, end - 1));
        }
        return std::string(strip_comment(v));
    }

    void check_rest(std::string_view rest) const {
        rest = trim(rest);
        if (!rest.empty() && rest.front() != '#' && rest.front() != ';')
            fail("unexpected text after the string");
    }

    static std::string_view strip_comment(std::string_view v) {
        for (std::size_t i = 0; i < v.size(); ++i)
            if ((v[i] == '#' || v[i] == ';') && (i == 0 || v[i - 1] == ' ' || v[i - 1] == '\t'))
                return trim(v.substr(0, i));
        return trim(v);
    }

    uint64_t value_uint(std::string_view v, uint64_t max) const {
        const std::string s = value_string(v);
        std::string_view d = s;
        int base = 10;
        if (d.size() > 2 && d[0] == '0' && (d[1] == 'x' || d[1] == 'X')) {
            base = 16;
            d.remove_prefix(2);
        }
        uint64_t u = 0;
        auto [p, ec] = std::from_chars(d.data(), d.data() + d.size(), u, base);
        if (d.empty() || ec == std::errc::invalid_argument || p != d.data() + d.size())
            fail("'" + s + "' is not an unsigned integer");
        if (ec == std::errc::result_out_of_range || u > max)
            fail("'" + s + "' is out of range (maximum " + std::to_string(max) + ")");
        return u;
    }
};

void check_mailbox(const Parser& p, const MailboxLayout& m, const char* what) {
    auto check = [&](uint32_t start, uint32_t size, const char* dir) {
        if (size < 16) p.fail(std::string(what) + " " + dir + " size must be at least 16 bytes");
        if (start < 0x1000 || start + size > 0x10000)
            p.fail(std::string(what) + " " + dir + " must lie in process RAM (0x1000...0xFFFF)");
    };
    check(m.out_start, m.out_size, "out");
    check(m.in_start, m.in_size, "in");
    const bool disjoint =
        uint32_t{m.out_start} + m.out_size <= m.in_start || uint32_t{m.in_start} + m.in_size <= m.out_start;
    if (!disjoint) p.fail(std::string(what) + " out and in areas overlap");
}

}  // namespace

DeviceDescription parse_device_config(std::string_view text, const std::string& source) {
    DeviceDescription d = default_drive_description();
    Parser p{source, 0};
    std::string section = "identity";
    bool in_top_level = true;
    std::set<std::string> seen;
    std::istringstream in{std::string(text)};
    std::string raw;
    while (std::getline(in, raw)) {
        ++p.line;
        std::string_view l = trim(raw);
        if (l.empty() || l.front() == '#' || l.front() == ';') continue;
        if (l.front() == '[') {
            const auto close = l.find(']');
            if (close == std::string_view::npos) p.fail("section header without ']'");
            p.check_rest(l.substr(close + 1));
            section = std::string(trim(l.substr(1, close - 1)));
            if (section.empty()) p.fail("empty section name");
            in_top_level = false;
            continue;
        }
        const auto eq = l.find_first_of("=:");
        if (eq == std::string_view::npos) p.fail("expected 'key = value'");
        const std::string key(trim(l.substr(0, eq)));
        const std::string_view value = trim(l.substr(eq + 1));
        if (key.empty()) p.fail("missing key before '='");

        const bool known_section = section == "identity" || section == "mailbox" ||
                                   section == "bootstrap_mailbox" || section == "eeprom";
        if (!known_section) continue;  // another program section

        Identity& id = d.identity;
        bool known = true;
        if (section == "identity") {
            if (key == "vendor_id")
                id.vendor_id = static_cast<uint32_t>(p.value_uint(value, 0xFFFFFFFF));
            else if (key == "product_code")
                id.product_code = static_cast<uint32_t>(p.value_uint(value, 0xFFFFFFFF));
            else if (key == "revision")
                id.revision = static_cast<uint32_t>(p.value_uint(value, 0xFFFFFFFF));
            else if (key == "serial_number")
                id.serial_number = static_cast<uint32_t>(p.value_uint(value, 0xFFFFFFFF));
            else if (key == "vendor_name")
                id.vendor_name = p.value_string(value);
            else if (key == "device_name")
                id.device_name = p.value_string(value);
            else if (key == "hardware_version")
                id.hardware_version = p.value_string(value);
            else if (key == "software_version")
                id.software_version = p.value_string(value);
            else if (key == "order_code")
                id.order_code = p.value_string(value);
            else if (key == "group_type")
                id.group_type = p.value_string(value);
            else
                known = false;
        } else if (section == "mailbox" || section == "bootstrap_mailbox") {
            MailboxLayout& m = section == "mailbox" ? d.standard_mailbox : d.bootstrap_mailbox;
            if (key == "out_start")
                m.out_start = static_cast<uint16_t>(p.value_uint(value, 0xFFFF));
            else if (key == "out_size")
                m.out_size = static_cast<uint16_t>(p.value_uint(value, 0xFFFF));
            else if (key == "in_start")
                m.in_start = static_cast<uint16_t>(p.value_uint(value, 0xFFFF));
            else if (key == "in_size")
                m.in_size = static_cast<uint16_t>(p.value_uint(value, 0xFFFF));
            else
                known = false;
        } else {  // eeprom
            if (key == "bytes") {
                const auto b = p.value_uint(value, 32768);
                if (b < 128 || (b & (b - 1)) != 0) p.fail("eeprom bytes must be a power of two, 128...32768");
                d.eeprom_bytes = static_cast<uint16_t>(b);
            } else if (key == "station_alias")
                d.station_alias = static_cast<uint16_t>(p.value_uint(value, 0xFFFF));
            else if (key == "pdi_control")
                d.pdi_control = static_cast<uint8_t>(p.value_uint(value, 0xFF));
            else if (key == "esc_config")
                d.esc_config = static_cast<uint8_t>(p.value_uint(value, 0xFF));
            else if (key == "pdi_config")
                d.pdi_config = static_cast<uint16_t>(p.value_uint(value, 0xFFFF));
            else if (key == "sync_pulse_length")
                d.sync_pulse_length = static_cast<uint16_t>(p.value_uint(value, 0xFFFF));
            else
                known = false;
        }
        if (!known) {
            if (in_top_level) continue;  // a program option before any section
            p.fail("unknown key '" + key + "' in [" + section + "]");
        }
        if (!seen.insert(section + "." + key).second)
            p.fail("duplicate key '" + key + "' in [" + section + "]");
    }
    p.line = 0;
    const Identity& id = d.identity;
    if (id.device_name.empty()) p.fail("identity device_name must not be empty");
    for (const std::string* s : {&id.vendor_name, &id.device_name, &id.hardware_version, &id.software_version,
                                 &id.order_code, &id.group_type})
        if (s->size() > 255) p.fail("identity strings are limited to 255 characters (SII string length)");
    check_mailbox(p, d.standard_mailbox, "mailbox");
    check_mailbox(p, d.bootstrap_mailbox, "bootstrap_mailbox");
    try {
        place_sync_managers(d);
    } catch (const std::out_of_range& e) {
        p.fail(e.what());
    }
    return d;
}

DeviceDescription load_device_config(const std::filesystem::path& path) {
    errno = 0;
    std::ifstream f(path, std::ios::binary);
    if (!f)
        throw ConfigError(path.string(), 0,
                          std::string("cannot open the device configuration file: ") +
                              std::strerror(errno ? errno : ENOENT));
    // Read in pieces up to the limit, never the whole of whatever the path names (a pipe or /dev/zero
    // would not end): a configuration is a few hundred bytes.
    std::string text;
    char piece[4096];
    while (f.read(piece, sizeof piece) || f.gcount() > 0) {
        text.append(piece, static_cast<std::size_t>(f.gcount()));
        if (text.size() > kMaxConfigBytes)
            throw ConfigError(
                path.string(), 0,
                "larger than " + std::to_string(kMaxConfigBytes) + " bytes: not a device configuration file");
    }
    return parse_device_config(text, path.string());
}

}  // namespace od
