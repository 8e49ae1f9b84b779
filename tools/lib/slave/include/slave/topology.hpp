#pragma once
// The topology file of a segment of soft slaves (`ecat-slave --topology FILE`): which devices there are,
// where each is plugged in, their clocks and cables. One statement per line, in the one lexer's words
// (util/lex.hpp: blanks between words, "..." or '...' quoting, a word beginning with '#' starts a comment,
// numbers decimal or 0x... with range checks):
//
//   timing processing-ns=320 forwarding-ns=280 cable-ns=10
//   device NAME [config=FILE | esi=FILE [device=SPEC]] [at=PARENT:PORT] [port=P] [ports=2|4] [serial=N]
//   [drift-ppm=X] [offset-ns=N]
//          [cable-ns=N] [state-dir=DIR]
//   external DEVICE:PORT
//
// esi= serves the device an ESI file describes instead of the built-in drive; device= picks one device of a
// file with several (product code and revision "0x07d83052:0x00110000", or its Type name), as ecat-slave's
// --esi/--device do. config=, esi= and state-dir= are relative to the topology file's folder. at= defaults to
// the previous device's port 1 (a line); the first device is the root (its port 0 faces the master). port= is
// the device's own port facing upstream (default 0). ports=4 makes a four-port (junction-capable) ESC. A
// device given by esi= has the ports its ESI's Physics declares (ETG.2000: "YY" ports 0 and 1, "Y" port 0
// only, "YY K" ports 0, 1 and 3) unless ports= is written.
// `external` names the port that leads to --out-iface (default: port 1 of the last device).
//
// NAME: 1..64 characters of [A-Za-z0-9_.-], beginning with a letter or a digit, not a number, unique; it
// names the device's state directory <state-dir>/NAME. state-dir= values are unique too. At most
// kMaxDevices devices (the limit of --slaves as well); the file is at most kMaxTopologyBytes.
//
// Errors are reported as "FILE:LINE: message" (TopologyError), for an unknown key or statement, an
// unknown device, a port used twice or missing on the ESC, a loop, a bad number or a duplicate name.
#include <cstdint>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "esc/segment.hpp"

namespace slave {

// The most devices of one segment, from --slaves or a topology file (docs/segment.md, "Limits").
inline constexpr std::size_t kMaxDevices = 1000;
inline constexpr std::size_t kMaxNameLength = 64;
inline constexpr std::size_t kMaxTopologyBytes = 1 << 20;

class TopologyError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

struct TopologyDevice {
    std::string name;
    std::string config;       // device configuration file (resolved), empty: the built-in drive
    std::string esi;          // ESI file of the device (resolved), empty: not from an ESI
    std::string device_spec;  // device= of a file with several devices, empty: the only one
    int parent = -1;          // index of the upstream device, -1: the root (faces the master)
    int parent_port = 1;      // port of the parent this device is plugged into
    int port = 0;             // this device's own port facing upstream
    // The ESC's ports as its port descriptor 0x0007 (ESC datasheet: 2 bits per port, 00 not implemented):
    // ports 0 and 1 unless ports=4 (a junction, 0xFF) or, for esi=, its ESI's Physics says otherwise.
    uint8_t descriptor = 0x0F;
    bool ports_given = false;     // ports= was written
    bool ports_from_esi = false;  // descriptor is the ESI's Physics
    std::optional<uint32_t> serial;
    double drift_ppm = 0.0;
    int64_t offset_ns = 0;
    int64_t cable_ns = -1;  // the cable into this device; < 0: the timing's cable delay
    std::string state_dir;  // resolved; empty: <state-dir>/NAME
    int line = 0;           // where it is declared (for messages about it)

    uint8_t port_descriptor() const { return descriptor; }
    bool has_port(int p) const { return p >= 0 && p < 4 && ((descriptor >> (2 * p)) & 0x03) != 0; }
    // "0, 1" (the ports it has), for messages.
    std::string port_list() const;
};

struct Topology {
    std::string file;  // as given, for messages
    esc::SegmentTiming timing;
    std::vector<TopologyDevice> devices;
    int external_device = -1;  // -1: port 1 of the last device (when --out-iface is given)
    int external_port = 1;
    int external_line = 0;

    // Index of the device named `name`, or of the index written as a number; -1 if none.
    int find(std::string_view name_or_index) const;
    int find_name(std::string_view name) const;
    // "FILE:LINE: message" for a device's line.
    std::string where(int line) const;
};

// The port descriptor of a device given by esi= (its ESI's Physics, ETG.2000), asked for each such device
// without ports=; it throws (any std::exception) when the device cannot be served, which the parser reports
// at the device's line. Empty: such devices have ports 0 and 1 (MII).
using PortsOfEsi = std::function<uint8_t(const TopologyDevice&)>;

// Parses the text of a topology file. file names it in messages; base_dir resolves relative paths.
// Throws TopologyError.
Topology parse_topology(std::string_view text, const std::string& file, const std::string& base_dir,
                        const PortsOfEsi& ports_of_esi = {});
// Reads and parses a file. Throws TopologyError (also when the file cannot be read).
Topology load_topology(const std::string& file, const PortsOfEsi& ports_of_esi = {});
// The line of N drives that `--slaves N` means: drive1..driveN, serial numbers 1..N, each plugged into
// the previous one's port 1; state directories are left empty (the caller decides).
Topology line_topology(int count);

}  // namespace slave
