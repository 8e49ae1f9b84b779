#include "od/device_config.hpp"

#include <cerrno>
#include <charconv>
#include <cstring>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

#include "util/input_file.hpp"
#include "util/lex.hpp"

namespace od {
namespace {

struct Parser {
    std::string source;
    int line = 0;

    [[noreturn]] void fail(const std::string& msg) const { throw ConfigError(source, line, msg); }

    // Value text -> string (the one lexer's rule: one quoted word, or bare words; comment dropped).
    std::string value_string(std::string_view v) const {
        try {
            return util::value_text(v);
        } catch (const util::LexError& e) {
            fail(e.what());
        }
    }

    void check_rest(std::string_view rest) const {
        try {
            if (!util::split(rest).empty()) fail("unexpected text after the section header");
        } catch (const util::LexError& e) {
            fail(e.what());
        }
    }

    uint64_t value_uint(std::string_view key, std::string_view v, uint64_t max) const {
        const std::string s = value_string(v);
        uint64_t u = 0;
        if (util::parse_number<uint64_t>(s, u, 0, max) != util::NumberError::None)
            fail(util::number_message<uint64_t>(key, s, 0, max));
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

DeviceDescription parse_device_config(std::string_view text, const std::string& source,
                                      const DeviceDescription& base, const SyncManagerPlacer& place) {
    DeviceDescription d = base;
    Parser p{source, 0};
    std::string section = "identity";
    bool in_top_level = true;
    std::set<std::string> seen;
    std::istringstream in{std::string(text)};
    std::string raw;
    while (std::getline(in, raw)) {
        ++p.line;
        if (const std::string e = util::text_error(raw); !e.empty()) p.fail(e);
        std::string_view l = util::trim_blanks(raw);
        if (l.empty() || l.front() == '#' || l.front() == ';') continue;
        if (l.front() == '[') {
            const auto close = l.find(']');
            if (close == std::string_view::npos) p.fail("section header without ']'");
            p.check_rest(l.substr(close + 1));
            section = std::string(util::trim_blanks(l.substr(1, close - 1)));
            if (section.empty()) p.fail("empty section name");
            in_top_level = false;
            continue;
        }
        const auto eq = l.find_first_of("=:");
        if (eq == std::string_view::npos) p.fail("expected 'key = value'");
        const std::string key(util::trim_blanks(l.substr(0, eq)));
        const std::string_view value = util::trim_blanks(l.substr(eq + 1));
        if (key.empty()) p.fail("missing key before '='");

        const bool known_section = section == "identity" || section == "mailbox" ||
                                   section == "bootstrap_mailbox" || section == "eeprom";
        if (!known_section) continue;  // another program section

        Identity& id = d.identity;
        bool known = true;
        if (section == "identity") {
            if (key == "vendor_id")
                id.vendor_id = static_cast<uint32_t>(p.value_uint(key, value, 0xFFFFFFFF));
            else if (key == "product_code")
                id.product_code = static_cast<uint32_t>(p.value_uint(key, value, 0xFFFFFFFF));
            else if (key == "revision")
                id.revision = static_cast<uint32_t>(p.value_uint(key, value, 0xFFFFFFFF));
            else if (key == "serial_number")
                id.serial_number = static_cast<uint32_t>(p.value_uint(key, value, 0xFFFFFFFF));
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
                m.out_start = static_cast<uint16_t>(p.value_uint(key, value, 0xFFFF));
            else if (key == "out_size")
                m.out_size = static_cast<uint16_t>(p.value_uint(key, value, 0xFFFF));
            else if (key == "in_start")
                m.in_start = static_cast<uint16_t>(p.value_uint(key, value, 0xFFFF));
            else if (key == "in_size")
                m.in_size = static_cast<uint16_t>(p.value_uint(key, value, 0xFFFF));
            else
                known = false;
        } else {  // eeprom
            if (key == "bytes") {
                const auto b = p.value_uint(key, value, 32768);
                if (b < 128 || (b & (b - 1)) != 0) p.fail("eeprom bytes must be a power of two, 128...32768");
                d.eeprom_bytes = static_cast<uint16_t>(b);
            } else if (key == "station_alias")
                d.station_alias = static_cast<uint16_t>(p.value_uint(key, value, 0xFFFF));
            else if (key == "pdi_control")
                d.pdi_control = static_cast<uint8_t>(p.value_uint(key, value, 0xFF));
            else if (key == "esc_config")
                d.esc_config = static_cast<uint8_t>(p.value_uint(key, value, 0xFF));
            else if (key == "pdi_config")
                d.pdi_config = static_cast<uint16_t>(p.value_uint(key, value, 0xFFFF));
            else if (key == "sync_pulse_length")
                d.sync_pulse_length = static_cast<uint16_t>(p.value_uint(key, value, 0xFFFF));
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
        if (place) place(d);
    } catch (const std::out_of_range& e) {
        p.fail(e.what());
    }
    return d;
}

DeviceDescription load_device_config(const std::filesystem::path& path, const DeviceDescription& base,
                                     const SyncManagerPlacer& place) {
    std::string text;
    try {
        text = util::read_input_file(path, kMaxConfigBytes, "device configuration file");
    } catch (const util::InputFileError& e) {
        // e.what() is "PATH: why"; ConfigError puts the path in front again.
        std::string_view why = e.what();
        if (const std::string prefix = path.string() + ": "; why.rfind(prefix, 0) == 0)
            why.remove_prefix(prefix.size());
        throw ConfigError(path.string(), 0, std::string(why));
    }
    return parse_device_config(text, path.string(), base, place);
}

}  // namespace od
