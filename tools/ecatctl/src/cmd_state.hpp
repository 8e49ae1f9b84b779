#pragma once
// `ecatctl state <slave> [STATE]`: show the AL state, or go to one with the set-up it needs (cmd_state.cpp).
#include <CLI/CLI.hpp>

#include "cmd_diag.hpp"  // MasterRunner

namespace ecatctl {

// Adds the `state` subcommand to app; its exit code goes to rc.
void add_state_command(CLI::App& app, MasterRunner run, int& rc);

}  // namespace ecatctl
