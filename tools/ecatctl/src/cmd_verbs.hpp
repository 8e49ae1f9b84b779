#pragma once
// The verbs IgH `ethercat` and SOEM `slaveinfo` users expect, each in its own file:
//   slaves [-v]   cmd_slaves.cpp   every slave, or with -v all that slaveinfo shows
//   pdos          cmd_pdos.cpp     the live PDO assignment and mapping read over CoE
//   cstruct       cmd_cstruct.cpp  the same as C arrays for IgH's ecrt_slave_config_pdos()
//   xml           cmd_xml.cpp      an ESI file built from the SII and SDO information
// Helpers they share (slave selection, the mailbox) are in verb_support.cpp.
#include <CLI/CLI.hpp>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "cmd_diag.hpp"  // MasterRunner
#include "coe_view.hpp"
#include "common.hpp"  // slave_label
#include "master/coe.hpp"
#include "master/mailbox.hpp"
#include "master/master.hpp"

namespace ecatctl {

void add_slaves_command(CLI::App& app, MasterRunner run, int& rc);
void add_pdos_command(CLI::App& app, MasterRunner run, int& rc);
void add_cstruct_command(CLI::App& app, MasterRunner run, int& rc);
void add_xml_command(CLI::App& app, MasterRunner run, int& rc);

// ---- verb_support.cpp ----------------------------------------------------------------------------

// "slave" positional argument and -s/--station, as every verb takes them.
struct SlaveArg {
    std::string slave = "0";
    bool station = false;
    void add_to(CLI::App* c);
    // The address, or nullopt after printing a usage error.
    std::optional<master::Address> address() const;
};

// A slave in INIT gets its mailbox SMs from its SII and goes to PREOP; one in PREOP or above keeps its SMs.
master::Error open_coe_mailbox(master::Master& m, master::Mailbox& mbx, master::Address a);

// The PDO assignment and mapping of slave a over CoE (mailbox opened by open_coe_mailbox), with names:
// kExitOk, or the exit code of the error it reported.
int read_slave_pdo_config(master::Master& m, master::Address a, std::vector<SyncView>& syncs);

// Prints "ecatctl: <what>: <error>" (SDO aborts with code and text) and returns the exit code.
int report_error(const master::SdoClient* sdo, master::Error e, const std::string& what);

// ---- typed values (sdo_typed.cpp) ----------------------------------------------------------------

// Prints an uploaded value by the type SDO information gives: one entry as its value (strings as text,
// integers "0x.. (n)", REAL32/REAL64 as numbers), a complete access as one "0xIIII:SS name = value" line per
// subindex. False (nothing printed) if the slave gives no description; the caller then prints by size.
bool print_described_upload(master::SdoClient& sdo, uint16_t index, uint8_t sub, bool complete_access,
                            std::span<const uint8_t> data);

// The same as JSON members of the object being written: "entries": [{subindex, name, type, bit_length,
// value}] (docs/ecatctl-json.md, "upload"); an empty list when the slave gives no description.
void write_described_upload_json(util::JsonWriter& w, master::SdoClient& sdo, uint16_t index, uint8_t sub,
                                 bool complete_access, std::span<const uint8_t> data);

// Prints the process image by PDO entry: "  0xIIII:SS name = value" for outputs, then inputs.
void print_pd_entries(const std::vector<SyncView>& syncs, std::span<const uint8_t> outputs,
                      std::span<const uint8_t> inputs);

}  // namespace ecatctl
