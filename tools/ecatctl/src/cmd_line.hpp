#pragma once
// `ecatctl crc`, `states`, `alias`, `graph`: verbs over the whole line (cmd_line.cpp).
#include <CLI/CLI.hpp>

#include "cmd_diag.hpp"  // MasterRunner

namespace ecatctl {

void add_line_commands(CLI::App& app, MasterRunner run, int& rc);

}  // namespace ecatctl
