#pragma once
// `ecatctl diag [slave]`: the diagnosis history 0x10F3 read over CoE SDO (cmd_diag.cpp).
#include <CLI/CLI.hpp>
#include <functional>

#include "master/master.hpp"

namespace ecatctl {

// Runs a function with a master on the link chosen by the global options; returns the exit code.
using MasterRunner = std::function<int(const std::function<int(master::Master&)>&)>;

// Adds the `diag` subcommand to app; its exit code goes to rc.
void add_diag_command(CLI::App& app, MasterRunner run, int& rc);

}  // namespace ecatctl
