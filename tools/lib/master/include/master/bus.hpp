#pragma once
// The whole line at once, as SOEM's and IgH's bring-up do it: count the slaves, give them station addresses
// 0x1001.., read each one's identity (SII), AL state, DL status and port descriptor; then distributed clocks
// for all of them (ESC datasheet section I, "Distributed Clocks": propagation delay measurement and offset
// compensation; ETG.1020 "Distributed Clocks"): one BWR to 0x0900 latches every port's receive time in every
// slave, the topology (which slave hangs at which port of which) follows from the positions, the ports with
// communication (DL status 0x0110) and the processing order 0 -> 3 -> 1 -> 2, and the propagation delay of
// each slave from the reference clock (the first DC slave) follows from the receive times; the delays go to
// 0x0928 and the offsets that make every system time agree with the reference clock's to 0x0920.
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "master/master.hpp"

namespace master {

struct SlaveInfo {
    uint16_t position = 0;
    uint16_t station = 0;
    // Identity from the SII header (ETG.2010 words 0x08..0x0F).
    uint32_t vendor_id = 0, product_code = 0, revision = 0, serial = 0;
    AlStatus al;
    uint16_t dl_status = 0;       // 0x0110
    uint8_t port_descriptor = 0;  // 0x0007
    bool has_dc = false;          // ESC features 0x0008 bit 2
    // Ports with the loop open and communication established (DL status bits 8+2p clear, 9+2p set).
    uint8_t active_ports = 0;
    Error error = Error::Ok;  // the first error while reading this slave's state or identity (scan goes on)

    // ---- distributed clocks (configure_dc) -------------------------------------------------------
    std::array<uint32_t, 4> port_time{};  // receive times 0x0900/0x0904/0x0908/0x090C (local, 32 bit)
    uint64_t rx_time_pu = 0;              // 0x0918: the same frame at the processing unit (local, 64 bit)
    int entry_port = 0;                   // the port the frame came in (the earliest receive time)
    int parent = -1;                      // position of the slave upstream, -1 for the first one
    int parent_port = -1;                 // the port of `parent` this slave is plugged into
    int64_t delay_ns = 0;                 // propagation delay from the reference clock (0x0928)
    int64_t offset_ns = 0;                // system time offset written (0x0920)
};

// Active ports from a DL status word.
uint8_t active_ports_from_dl_status(uint16_t dl_status);
// The port a frame leaves by after `port` in the processing order 0 -> 3 -> 1 -> 2 -> 0.
int next_port(int port);

struct BusOptions {
    uint16_t first_station = 0x1001;
    bool identity = true;  // read vendor, product, revision and serial from each slave's SII
};

// Count, station addresses, identity, AL status, DL status, port descriptor and DC feature of every slave.
// Error::Timeout if nothing answers; an empty vector if the count is 0. A slave whose AL status or SII cannot
// be read keeps the error in SlaveInfo::error and the scan goes on.
Result<std::vector<SlaveInfo>> scan_bus(Master& m, const BusOptions& options = {});
// Re-reads DL status (active ports) of each slave of a scan (after a cable came back, for example).
Error read_ports(Master& m, std::span<SlaveInfo> slaves);

// From active_ports and port_time of every slave (in position order): entry port, parent, parent port and
// the propagation delay of each slave from the first DC slave. Pure: no frames. Error::InvalidArgument if
// the ports do not describe a tree in that order (more slaves than open ports lead to).
Error compute_dc_topology(std::span<SlaveInfo> slaves);
// Index of the reference clock (the first slave with DC), -1 if none.
int reference_clock(std::span<const SlaveInfo> slaves);

struct DcMeasureOptions {
    // Static drift compensation (ETG.1020): this many FRMW of the reference clock's system time after the
    // offsets are written, so the slaves' control loops settle before SYNC0 starts. 0: none.
    unsigned drift_frames = 0;
};

// The measurement alone: BWR 0x0900, the receive times (0x0900..0x090C) and 0x0918 of every DC slave,
// compute_dc_topology(). Writes nothing else (what `ecatctl scan` shows).
Error measure_dc(Master& m, std::span<SlaveInfo> slaves);
// The wire part: BWR 0x0900, the receive times and 0x0918 of every DC slave, compute_dc_topology(), then
// 0x0928 (delay) and 0x0920 (offset) of every DC slave, the filters reset (0x0930). The reference clock's
// system time becomes the master's clock (ns since 2000); the others follow it.
Error configure_dc(Master& m, std::span<SlaveInfo> slaves, const DcMeasureOptions& options = {});

// EtherCAT system time of the master's own clock: ns since 2000-01-01 (ESC datasheet section I, DC).
uint64_t master_system_time();

}  // namespace master
