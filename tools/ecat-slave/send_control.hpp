#pragma once
// The client of a running ecat-slave's control socket (--control PATH): `ecat-slave --control PATH --send
// LINE`. The project's own way to send a control command, needing no nc or socat. The server is
// tools/lib/device/src/control.cpp (and the segment's commands, docs/segment.md); this only sends and waits.
#include <chrono>
#include <iosfwd>
#include <string>
#include <vector>

namespace ecat_slave {

// Sends the lines in one datagram from a socket file of its own (beside the slave's, else in $TMPDIR), so the
// slave can answer, and prints the answer lines to out. Returns the exit code: 0 when every answer starts
// with "ok", 1 when one is an error (or no answer came within timeout), 2 when there is no such socket
// (message to err).
int send_control(const std::string& path, const std::vector<std::string>& lines, std::ostream& out,
                 std::ostream& err, std::chrono::milliseconds timeout = std::chrono::milliseconds(3000));

}  // namespace ecat_slave
