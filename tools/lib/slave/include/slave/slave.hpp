#pragma once
// Everything the `ecat-slave` program does besides parsing its command line: open (or create) the
// interface, build the ESC, load the SII EEPROM image, start the firmware, run the event loop until
// SIGINT/SIGTERM, clean up. Options are plain data so other modules can add their own.
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "esc/esc.hpp"
#include "esc/segment.hpp"
#include "slave/firmware.hpp"
#include "slave/log.hpp"

namespace slave {

struct SlaveOptions;

// Produces the SII EEPROM image (little-endian words) the ESC serves. Replaceable: the default reads the
// binary file named by --eeprom; a generator from the object model can take its place.
using EepromLoader = std::function<std::vector<uint8_t>(const SlaveOptions&)>;
// Creates the firmware that runs behind the ESC's PDI; may return nullptr (ESC only, no state machine).
using FirmwareFactory = std::function<std::unique_ptr<Firmware>(esc::Esc&, const SlaveOptions&)>;

// A segment of devices (ecat-slave --slaves N / --topology): the esc::Segment with every device's ESC and
// the firmware of all of them in one (device::Line). run_slave() walks frames through segment().
class SegmentFirmware : public Firmware {
  public:
    virtual esc::Segment& segment() = 0;
};
// Sends a frame out of the segment's external port (on the --out-iface link); empty when there is none.
using ExternalSend = std::function<void(std::span<const uint8_t>)>;
// Builds the segment on the runtime's clock; the factory wires `send` to the external port, if given.
using SegmentFactory = std::function<std::unique_ptr<SegmentFirmware>(const esc::Clock&, const SlaveOptions&,
                                                                      ExternalSend send)>;

// Reads options.eeprom_file (empty name: returns an empty image). Throws std::runtime_error on an
// unreadable file or an image that is empty, of odd length or larger than 64 KiB words.
std::vector<uint8_t> load_eeprom_file(const SlaveOptions& options);

struct SlaveOptions {
    std::string iface;                // run on this interface; empty: create a veth pair
    std::string veth_name = "ecat0";  // slave end of the veth pair we create
    std::string veth_peer;            // master end; empty: veth_peer_name(veth_name) ("ecat1")
    std::string backend;              // "pcap" | "packet" | empty (esc::default_link_backend())
    std::string capture_file;         // record every frame in and out (.pcap)
    std::string eeprom_file;          // binary SII image
    bool eeprom_write_back = true;    // write the image back to eeprom_file at exit if the master changed it
    uint32_t ram_kib = 8;             // process RAM size (ESC register 0x0006)
    uint8_t port_descriptor = 0x0F;   // the ESC's ports (register 0x0007; a device's ESI Physics)
    bool verbose = false;             // print statistics (runtime, ESC, firmware report) at exit
    std::string stats_file;           // write the same statistics as "name value" lines here at exit
    int rt_priority = 0;              // > 0: SCHED_FIFO at this priority and all memory locked (mlockall)
    int cpu = -1;                     // >= 0: pin the slave to this CPU
    uint32_t spin_us = 0;             // wake this early before each timed event and busy-wait to it
    bool busy_poll = false;           // never sleep: poll the link and the clock in a loop
    esc::EscFaults esc_faults;        // testing aid (ecat-slave --fault): deliberate ESC deviations, none
    EepromLoader eeprom_loader = load_eeprom_file;
    FirmwareFactory firmware_factory;  // empty: no firmware
    // A segment of devices instead of one ESC with firmware_factory (eeprom_loader is then not used).
    SegmentFactory segment_factory;
    std::string out_iface;  // segment mode: the external port leads to this interface
    Log* log = nullptr;     // events of the runtime (carrier of out_iface); null: not logged
};

// Exit codes of run_slave() (and of ecat-slave).
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;  // failed while running
inline constexpr int kExitUsage = 2;    // bad options, missing interface, missing privileges

// Runs the slave until SIGINT/SIGTERM. Messages go to out (status) and err (errors).
int run_slave(const SlaveOptions& options, std::ostream& out, std::ostream& err);

}  // namespace slave
