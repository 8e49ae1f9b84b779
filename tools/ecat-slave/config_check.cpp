#include "config_check.hpp"

#include <sstream>
#include <string_view>

#include "maxpos/maxpos.hpp"
#include "od/device_config.hpp"
#include "util/input_file.hpp"
#include "util/lex.hpp"

namespace ecat_slave {

namespace {

bool device_section(std::string_view name) {
    return name == "identity" || name == "mailbox" || name == "bootstrap_mailbox" || name == "eeprom";
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
    std::string text;
    try {  // a regular file within od::kMaxConfigBytes, checked before anything is read
        text = util::read_input_file(path, od::kMaxConfigBytes, "configuration file");
    } catch (const util::InputFileError& e) {
        return e.what();
    }
    std::istringstream in(text);
    std::string raw;
    int line = 0;
    std::string section;  // "" = before any section, or [default]: options of the program
    auto at = [&](const std::string& what) { return path + ":" + std::to_string(line) + ": " + what; };
    while (std::getline(in, raw)) {
        ++line;
        if (const std::string e = util::text_error(raw); !e.empty())
            return at(e + "; --config takes a text file");
        const std::string_view l = util::trim_blanks(raw);
        if (l.empty() || l.front() == '#' || l.front() == ';') continue;
        if (l.front() == '[') {
            const auto close = l.find(']');
            if (close == std::string_view::npos)
                return at("section header '" + std::string(l) + "' without ']'");
            section = std::string(util::trim_blanks(l.substr(1, close - 1)));
            if (section == "default") section.clear();
            if (!section.empty() && !device_section(section))
                return at("unknown section [" + section +
                          "] (sections: [identity], [mailbox], [bootstrap_mailbox], [eeprom]; options of "
                          "ecat-slave go before the first section or in [default])");
            continue;
        }
        if (!section.empty()) continue;  // a device section: maxpos::parse_config checks it below
        const auto eq = l.find('=');
        if (eq == std::string_view::npos) return at("expected 'option = value'");
        std::string key(util::trim_blanks(l.substr(0, eq)));
        std::string dashed = key;
        for (char& c : dashed)
            if (c == '_') c = '-';
        if (key == "config" || (app.get_option_no_throw("--" + key) == nullptr &&
                                app.get_option_no_throw("--" + dashed) == nullptr))
            return at("unknown option '" + key + "' (`ecat-slave --help` lists the options)");
    }
    try {
        (void)maxpos::parse_config(text, path);
    } catch (const od::ConfigError& e) {
        return e.what();
    }
    return {};
}

}  // namespace ecat_slave
