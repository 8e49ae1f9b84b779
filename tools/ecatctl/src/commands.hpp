#pragma once
// The ecatctl commands main.cpp wires, one file each, and the helpers they share (cli_support.cpp):
//   scan                     cmd_scan.cpp     sii read|write|decode  cmd_sii.cpp
//   reg read|write           cmd_reg.cpp      upload|download        cmd_sdo.cpp
//   pd [--all]               cmd_pd.cpp, cmd_pd_all.cpp
//                                  sdos                   cmd_sdos.cpp
//   foe read|write           cmd_foe.cpp      state                  cmd_state.cpp
//   diag                     cmd_diag.cpp     firmware-update        cmd_firmware.cpp
//   slaves, pdos, cstruct, xml (the IgH/SOEM-style verbs)          cmd_verbs.hpp
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "cmd_diag.hpp"  // MasterRunner
#include "common.hpp"
#include "master/coe.hpp"
#include "master/mailbox.hpp"
#include "master/master.hpp"
#include "master/session.hpp"

namespace ecatctl {

void add_scan_command(CLI::App& app, MasterRunner run, int& rc);
void add_reg_command(CLI::App& app, MasterRunner run, int& rc);
void add_sii_command(CLI::App& app, MasterRunner run, int& rc);
void add_sdo_commands(CLI::App& app, MasterRunner run, int& rc);  // upload, download
void add_pd_command(CLI::App& app, MasterRunner run, int& rc);
void add_sdos_command(CLI::App& app, MasterRunner run, int& rc);
void add_foe_command(CLI::App& app, MasterRunner run, int& rc);

// `pd --all` (cmd_pd_all.cpp): every slave on the line in one process-data session.
struct PdAllArgs {
    unsigned cycle_us = 1000;
    uint64_t count = 1000;
    bool dc = false;
    bool op = true;                // else SAFEOP
    std::vector<uint8_t> outputs;  // sent to every slave (from its first output byte)
    std::vector<std::pair<uint64_t, std::vector<uint8_t>>> steps;  // --step: cycles and output bytes
    bool keep = false;
    bool json = false;  // the outcome as JSON on stdout (docs/ecatctl-json.md, "pd --all")
};
int process_data_all(master::Master& m, const PdAllArgs& p);
// What both forms of pd share (cmd_pd.cpp): SAFEOP then (op) OP while cycling, a refusal reported with its
// AL status code; the --step cycles then `count` cycles with out_bytes; the cycle statistics line.
using PdStep = std::pair<uint64_t, std::vector<uint8_t>>;
int pd_to_state(master::ProcessDataSession& pd, bool op, std::chrono::microseconds period,
                const std::function<void()>& fill);
void pd_run(master::ProcessDataSession& pd, const std::vector<PdStep>& steps, uint64_t count,
            std::chrono::microseconds period, std::vector<uint8_t>& out_bytes,
            const std::function<void()>& fill);
void print_pd_cycles(const master::ProcessDataSession& pd, const master::CycleStats& before);

// ---- cli_support.cpp -----------------------------------------------------------------------------

// The AL status of the last refused state request, for fail() to report.
extern master::AlStatus g_refusal;
// "ecatctl: <what>: <error>" (a refused state request with its AL status code); returns the exit code.
int fail(master::Error e, const std::string& what);
// Why a process-data run failed at its end: "ended in SAFEOP+ERR, not OP, AL status code 0x001b (...)";
// st null or state 0: the slave gave no AL status.
std::string state_failure(const master::AlStatus* st, const std::string& wanted);
// The slave a command names; a bad one is reported as a usage error (exit kExitUsage) and gives nullopt.
std::optional<master::Address> named_slave(const std::string& text, bool station);
// The largest files the verbs read: an SII image (the EEPROM address space), a file written over FoE.
inline constexpr std::size_t kMaxSiiBytes = 65536;
inline constexpr std::size_t kMaxFileBytes = std::size_t{64} << 20;
// A file the command was given, read whole: a regular file of at most max_bytes (util::read_input_bytes; a
// FIFO, a device or a directory is refused). nullopt after "ecatctl: PATH: why" on stderr; what names the
// kind of file in that message.
std::optional<std::vector<uint8_t>> read_file(const std::string& path, std::size_t max_bytes,
                                              std::string_view what);
// A slave in INIT gets its mailbox SMs from its SII and is taken to PREOP; one already in PREOP or above
// keeps the SMs it has.
master::Error open_mailbox(master::Master& m, master::Mailbox& mbx, master::Address a);
// The end of a failed SDO transfer (abort code and text, mailbox error, or fail()).
int sdo_failed(const master::SdoClient& sdo, master::Error e, const std::string& what);

}  // namespace ecatctl
