#include "config_check.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string_view>

#include "od/device_config.hpp"

namespace ecat_slave {

namespace {

std::string_view trim(std::string_view s) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == '\r'))
        s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r'))
        s.remove_suffix(1);
    return s;
}

bool device_section(std::string_view name) {
    return name == "identity" || name == "mailbox" || name == "bootstrap_mailbox" || name == "eeprom";
}

// A line of text: no NUL and no other control character than tab and CR; bytes >= 0x80 must be UTF-8.
bool text_line(std::string_view l) {
    for (std::size_t i = 0; i < l.size(); ++i) {
        const auto c = static_cast<unsigned char>(l[i]);
        if (c < 0x20 && c != '\t' && c != '\r') return false;
        if (c == 0x7F) return false;
        if (c < 0x80) continue;
        const int more = (c & 0xE0) == 0xC0 ? 1 : (c & 0xF0) == 0xE0 ? 2 : (c & 0xF8) == 0xF0 ? 3 : -1;
        if (more < 0 || c == 0xC0 || c == 0xC1) return false;
        for (int k = 0; k < more; ++k)
            if (++i >= l.size() || (static_cast<unsigned char>(l[i]) & 0xC0) != 0x80) return false;
    }
    return true;
}

}  // namespace

std::optional<std::string> config_file_argument(int argc, char** argv) {
    std::optional<std::string> path;
    for (int i = 1; i < argc; ++i) {
        const std::string_view a = argv[i];
        if (a == "--") break;
        if (a == "--config" && i + 1 < argc)
            path = argv[++i];
        else if (a.rfind("--config=", 0) == 0)
            path = std::string(a.substr(9));
    }
    return path;
}

std::string check_config_file(const CLI::App& app, const std::string& path) {
    errno = 0;
    std::ifstream f(path, std::ios::binary);
    if (!f) return path + ": cannot open: " + std::strerror(errno ? errno : ENOENT);
    std::ostringstream all;
    all << f.rdbuf();
    const std::string text = all.str();
    std::istringstream in(text);
    std::string raw;
    int line = 0;
    std::string section;  // "" = before any section, or [default]: options of the program
    auto at = [&](const std::string& what) { return path + ":" + std::to_string(line) + ": " + what; };
    while (std::getline(in, raw)) {
        ++line;
        if (!text_line(raw))
            return at("not a text file (binary data on this line); --config takes a text file");
        const std::string_view l = trim(raw);
        if (l.empty() || l.front() == '#' || l.front() == ';') continue;
        if (l.front() == '[') {
            const auto close = l.find(']');
            if (close == std::string_view::npos)
                return at("section header '" + std::string(l) + "' without ']'");
            section = std::string(trim(l.substr(1, close - 1)));
            if (section == "default") section.clear();
            if (!section.empty() && !device_section(section))
                return at("unknown section [" + section +
                          "] (sections: [identity], [mailbox], [bootstrap_mailbox], [eeprom]; options of "
                          "ecat-slave go before the first section or in [default])");
            continue;
        }
        if (!section.empty()) continue;  // a device section: od::load_device_config checks it below
        const auto eq = l.find('=');
        if (eq == std::string_view::npos) return at("expected 'option = value'");
        std::string key(trim(l.substr(0, eq)));
        std::string dashed = key;
        for (char& c : dashed)
            if (c == '_') c = '-';
        if (key == "config" || (app.get_option_no_throw("--" + key) == nullptr &&
                                app.get_option_no_throw("--" + dashed) == nullptr))
            return at("unknown option '" + key + "' (`ecat-slave --help` lists the options)");
    }
    try {
        (void)od::parse_device_config(text, path);
    } catch (const od::ConfigError& e) {
        return e.what();
    }
    return {};
}

}  // namespace ecat_slave
