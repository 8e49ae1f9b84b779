#pragma once
// Checks ecat-slave's --config file before CLI11 reads it, so that every error names the file and the line:
// a file that is not text, a section header without ']', an unknown section, an unknown program option,
// and (through maxpos::parse_config) every error in the device sections.
#include <CLI/CLI.hpp>
#include <optional>
#include <string>

namespace ecat_slave {

// The --config FILE (or --config=FILE) given on the command line, if any.
std::optional<std::string> config_file_argument(int argc, char** argv);

// "" if the file is fine; else one message "FILE:LINE: what" (or "FILE: what" when no line is to blame).
std::string check_config_file(const CLI::App& app, const std::string& path);

}  // namespace ecat_slave
