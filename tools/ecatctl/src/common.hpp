#pragma once
#include <CLI/CLI.hpp>
// Helpers the ecatctl commands share (main.cpp, cmd_firmware.cpp).
#include <optional>
#include <string>
#include <vector>

#include "master/coe.hpp"
#include "master/master.hpp"

namespace ecatctl {

// The exit code for a master error (the kExit* codes of format.hpp).
int exit_code(master::Error e);

// The end of a failed SDO transfer: an SDO abort (code and text) or a mailbox error of sdo is reported here
// (kExitProtocol); any other error goes to the caller's fail(e, what).
int report_sdo_failure(const master::SdoClient& sdo, master::Error e, const std::string& what,
                       int (*fail)(master::Error, const std::string&));

// "slave 3" or "station 0x1001".
std::string slave_label(master::Address a);
// A slave named on the command line: a position, or a station address with --station.
std::optional<master::Address> parse_slave_address(const std::string& text, bool station);
// One line "ecatctl: what" on stderr; returns kExitUsage.
int usage_error(const std::string& what);
// One line "ecatctl: what: error" on stderr (with a hint when nothing answered); returns exit_code(e).
int report_error(master::Error e, const std::string& what);
// kExitOk if the slave named by a is on the line; else says so once ("there is no slave 5: 1 slave on the
// line") and returns kExitNoSlave (or the exit code of the error that kept us from knowing).
int check_slave_present(master::Master& m, master::Address a);

// The device name in the slave's SII General category (= object 0x1008); nullopt if there is none.
std::optional<std::string> sii_device_name(master::Master& m, master::Address a);
// "<prefix>: the device takes firmware as its device name (0x1008) or <name>_XXXXh_XXXXh_XXXXh_XXXXh.bin".
std::string foe_names_hint(const std::string& prefix);

// After `sii decode`: true (and one line on stderr naming what and the first problem) if the image is empty
// or its decoder found problems (bad checksum, truncated categories, no end marker...).
bool sii_problems(const std::string& what, const std::vector<uint8_t>& image);

// A command-line error in one line ("ecatctl: unknown command 'scna' (scan, reg, ...)" for a word that is no
// verb); returns kExitUsage.
int report_usage_error(const CLI::App& app, const CLI::ParseError& e, int argc, char** argv);

// The slave is named the same way in every verb: `-p N` / `--position N` (as in IgH's `ethercat`), a station
// address with `-s`/`--station`. Verbs that take the slave as their first argument (reg, state, upload,
// download, sdos, pd, diag) also take `-p N`: this moves it to the argument's place before parsing.
std::vector<std::string> position_option_as_argument(int argc, char** argv);

}  // namespace ecatctl
