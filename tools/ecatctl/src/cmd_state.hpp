#pragma once
// `ecatctl state <slave> [STATE]`: show the AL state, or go to one with the set-up it needs (cmd_state.cpp).
#include <CLI/CLI.hpp>
#include <string>

#include "cmd_diag.hpp"  // MasterRunner
#include "master/master.hpp"

namespace ecatctl {

// Adds the `state` subcommand to app; its exit code goes to rc.
void add_state_command(CLI::App& app, MasterRunner run, int& rc);

// A state named on the command line in upper case ("preop" -> "PREOP"), and whether it is one of INIT,
// PREOP, BOOT, SAFEOP, OP.
std::string state_word(const std::string& text);
bool is_state_word(const std::string& text);
// Takes the slave to INIT|PREOP|BOOT|SAFEOP|OP with the set-up the state needs, as `state` does (prints
// errors; returns the exit code).
int go_to_state(master::Master& m, master::Address a, const std::string& target);

}  // namespace ecatctl
