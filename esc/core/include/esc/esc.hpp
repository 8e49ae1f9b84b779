#pragma once
// The emulated EtherCAT Slave Controller: register space 0x0000-0x0FFF plus process RAM, every datagram
// command with its working-counter rules, SyncManagers, FMMUs, the SII EEPROM interface, distributed clocks,
// watchdogs and event registers. Two faces, as on silicon:
//   - the ECAT side: process_frame(), called by the link loop for each received Ethernet frame;
//   - the PDI side: the Pdi interface (read/write with PDI side effects) plus the interrupt line irq().
// Nothing here knows about the mailbox protocols, the object dictionary or the drive.
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "esc/clock.hpp"
#include "esc/faults.hpp"
#include "esc/pdi.hpp"

namespace esc {

struct EscConfig {
    uint8_t type = 0x04;           // 0x0000 ESC type (0x04: "IP core" style emulated ESC)
    uint8_t revision = 0x01;       // 0x0001
    uint16_t build = 0x0001;       // 0x0002
    uint8_t fmmu_count = 8;        // 0x0004
    uint8_t sm_count = 8;          // 0x0005
    uint32_t process_ram_kib = 8;  // 0x0006; process RAM 0x1000 .. 0x1000 + kib*1024 - 1 (ET1100: 8 KiB)
    // 0x0007, 2 bits per port (00 not implemented, 01 not configured, 10 EBUS, 11 MII): which of the
    // ports 0-3 exist. 0x0F: ports 0 and 1 (MII), the IN/OUT pair of a drive; 0xFF: a four-port junction.
    uint8_t port_descriptor = 0x0F;
    uint16_t features = 0x01CC;  // 0x0008: DC available, 64-bit DC, ...
    EscFaults faults;            // testing aid: deliberate deviations (esc/faults.hpp), all off
    // The ESC's own oscillator against the Clock it is given: DC local time = Clock time * (1 + drift) +
    // offset before any correction by the DC control loop. Gives a master's drift compensation and offset
    // calculation something real to do on a segment of soft slaves. 0/0: the Clock itself.
    double clock_drift_ppm = 0.0;
    int64_t clock_offset_ns = 0;
    // true: every call takes the ESC's lock, for an owner that calls it from several threads. false: the
    // owner calls it from one thread only (frames, PDI and timers served in turn by one runtime, as
    // ecat-slave does), and the lock, taken several times per drive and cycle, is left out.
    bool thread_safe = true;
};

inline constexpr int kPortCount = 4;  // ports 0..3

// A frame's integrity as it travels along a segment (what a bad FCS does on a real line): the first ESC
// that receives a frame with crc_bad counts it as invalid at its port (0x0300 + 2p) and marks it; every
// later ESC counts a forwarded RX error at its port (0x0308 + p). Neither processes it.
struct FrameCheck {
    bool crc_bad = false;  // the frame's FCS is wrong (corrupted on the cable)
    bool marked = false;   // an earlier ESC detected it already
};

// Counters of what the ECAT side saw (also reflected in the error counter registers 0x0300-0x0313).
struct EscStats {
    uint64_t frames_processed = 0;
    uint64_t frames_ignored = 0;    // not EtherCAT (EtherType, UDP port) or not type 1
    uint64_t frames_malformed = 0;  // frame length errors (ESC datasheet section I, Table 57)
    // frames_malformed by reason (they add up to it). The EtherCAT header's Length is not evaluated.
    uint64_t malformed_no_header = 0;  // EtherCAT (0x88A4 or UDP) but no room for the 2-byte EtherCAT header
    uint64_t malformed_length = 0;     // more than 64 bytes of padding after the last datagram
    uint64_t malformed_datagram = 0;   // a datagram header or its data runs past the end of the frame
    uint64_t datagrams = 0;
    // receive(): frames destroyed (received at a closed or non-existent port, circulating a second time,
    // or not EtherCAT at the processing unit, which frames_ignored counts as well) and frames with a bad
    // FCS (FrameCheck::crc_bad), forwarded unprocessed.
    uint64_t frames_destroyed = 0;
    uint64_t frames_bad_fcs = 0;
};

// What a runtime that serves many ESCs needs to find the few with work without touching the others: the
// interrupt line of a hardware ESC to its controller, and when its timers next do something. The owner of
// the ESC gives it one (Esc::set_signals; a segment keeps them side by side for its ESCs) and reads it; the
// ESC keeps it up to date under its lock.
struct EscSignals {
    // Clock time before which tick() changes nothing (a SYNC0/SYNC1 pulse, a watchdog expiry, a watchdog
    // (re)start or a status bit to settle); never later than that, earlier only by a watchdog that a frame
    // re-triggered since. 0: not known (after a PDI access, an EEPROM load, or, while a SYNC pulse is
    // scheduled, a frame that wrote the watchdog, SII, FMMU, SM or DC registers, started the process-data
    // watchdog or reset the ESC): tick() to find out. Exact after every tick(), a link change and such a
    // frame while no SYNC pulse is scheduled.
    uint64_t due_ns = 0;
    // Set (never cleared by the ESC) when a frame or a tick raised an AL event the AL event mask lets
    // through (0x0220 & 0x0204: the PDI interrupt line rose or a new event joined it), or a master wrote an
    // EEPROM word: the PDI side has something new to look at. The owner clears it when it looked.
    uint8_t wake = 0;
    // Counts up (wrapping) whenever the registers may have changed other than through the PDI: a frame
    // passed the ESC (at any port), or a tick fired a SYNC pulse or changed a watchdog's state. A
    // controller that cannot use the interrupt line (an SM without its PDI interrupt) has to look at the
    // registers themselves; it finds nothing new in them before this changes.
    uint32_t activity = 0;
    // The clock due_ns counts (the ESC's Clock), set by set_signals().
    const Clock* clock = nullptr;
};

class Esc final : public Pdi {
  public:
    Esc(const EscConfig& config, const Clock& clock);
    ~Esc() override;
    Esc(const Esc&) = delete;
    Esc& operator=(const Esc&) = delete;

    // ---- ECAT side --------------------------------------------------------------------------------
    // Processes one whole Ethernet frame (destination MAC first, no FCS) in place, as the ESC's
    // processing unit does: datagrams executed in order, working counters incremented, ADP incremented,
    // source MAC bit 1 set. rx_time_ns is the Clock time the frame's first bit arrived (DC receive-time
    // latch); pass 0 to use the clock's current time. Returns true if the frame is to be sent back out
    // (an EtherCAT frame, processed or not), false if it is to be dropped: not EtherCAT (with DL control
    // 0x0100 bit 0 set), or a frame length error, which hardware sends on with a bad FCS that the master's
    // NIC discards (docs/decisions/esc.md, "Frame tolerance"). This is receive() at port 0 for
    // an ESC alone on its wire: true when the frame leaves through port 0 again.
    bool process_frame(std::span<uint8_t> frame, uint64_t rx_time_ns = 0);

    // Asks the memory system for the state a frame's pass through this ESC touches, without waiting for it
    // and without changing anything: a segment calls it for the ESCs a frame meets next while this one
    // processes it, so that the cache misses of a line's ESCs overlap instead of adding up (the walk of a
    // line whose state was evicted since the last cycle is mostly such misses). Two stages: the ESC's own
    // state (the registers of the cyclic datagrams, SyncManagers, FMMUs, DC, ports, counters; reads only
    // the pointer to it), then, deep, the process RAM its FMMUs map (reads the mappings: a step later).
    void prefetch(bool deep) const;

    // ---- PDI side ---------------------------------------------------------------------------------
    // An empty span is no access (no side effect, the PDI watchdog is not triggered).
    void read(uint16_t address, std::span<uint8_t> out) override;
    void write(uint16_t address, std::span<const uint8_t> in) override;
    // The PDI interrupt line: (AL event request 0x0220) & (AL event mask 0x0204) != 0.
    bool irq() const;

    // ---- Time -------------------------------------------------------------------------------------
    // Runs the time-driven parts (process-data and PDI watchdogs, SYNC0/SYNC1 generation) up to now.
    void tick();
    // Clock time (ns) at which tick() has something to do next; UINT64_MAX if nothing is pending.
    uint64_t next_event_ns() const;
    // The same with the Clock's current time given (now_clock = clock().now_ns(), read once by a caller that
    // serves many ESCs on one clock, e.g. a segment).
    void tick(uint64_t now_clock);
    uint64_t next_event_ns(uint64_t now_clock) const;
    const Clock& clock() const;
    // Where the ESC keeps its EscSignals; null: a place of its own. Sets due_ns (as at the clock's now) and
    // wake to the interrupt line's level.
    void set_signals(EscSignals* signals);
    // Local clock of this ESC (DC local time, 0x0900 base), in ns.
    uint64_t local_time_ns() const;

    // ---- EEPROM -----------------------------------------------------------------------------------
    // Installs the SII EEPROM content (little-endian words) and loads words 0-7 as at power-on
    // (PDI control, ESC configuration, alias, ...). Sets "EEPROM loaded" in DL status.
    void load_eeprom(std::span<const uint8_t> image);
    std::span<const uint8_t> eeprom() const;
    // Called after a master wrote one EEPROM word, so the owner can persist the image.
    void on_eeprom_write(std::function<void(uint16_t word_address, uint16_t value)> callback);

    EscStats stats() const;

    // ---- Ports (ESC datasheet section I, "Frame processing" / "Loop control"; ETG.1000.4 DL control and
    // DL status) ------------------------------------------------------------------------------------
    // A frame received at `port` at Clock time rx_clock_ns (0: now) travels through the ESC in the fixed
    // order 0 -> 3 -> 1 -> 2 -> 0, the EtherCAT processing unit sitting behind the receive side of port 0.
    // A port that is closed (no link with loop "auto", or DL control 0x0101 "closed"/"auto close" after a
    // link loss) loops the frame back internally to its own receive side. receive() runs the frame through
    // the processing unit where it passes it and returns the next port that is open, i.e. where the frame
    // leaves the ESC; that can be `port` itself (all others closed). Returns -1 if the frame is destroyed:
    // received at a closed or non-existent port, or circulating a second time (the circulating bit of the
    // first datagram set on its way through the processing unit while port 0 is closed, ETG.1000.4), or not
    // EtherCAT with the forwarding rule set. A frame length error leaves marked in `check` (crc_bad, marked),
    // as hardware aborts it with a bad FCS; without a FrameCheck it is destroyed.
    // Receive-time latches: a write to 0x0900 arms them; port 0 (0x0900) latches that frame's arrival at
    // port 0, ports 1-3 (0x0904/0x0908/0x090C) the arrival of the next frame received at that port.
    int receive(std::span<uint8_t> frame, int port, uint64_t rx_clock_ns = 0);
    int receive(std::span<uint8_t> frame, int port, uint64_t rx_clock_ns, FrameCheck& check);
    // Physical link of a port (cable plugged, the peer powered). A change updates DL status 0x0110, raises
    // the DL status event; a loss counts in the lost-link counter 0x0310 + port. No effect on a port the
    // port descriptor does not implement. After construction port 0 has a link, ports 1-3 have none.
    void set_link(int port, bool up);
    bool link(int port) const;
    // A frame sent towards `port` leaves the ESC there (the port exists, has a link and its loop is open).
    bool port_open(int port) const;
    // The port descriptor (0x0007: 2 bits per port, 00 = not implemented), read without a PDI access (the
    // wiring of a segment asks it; a PDI read would trigger the PDI watchdog).
    uint8_t port_descriptor() const;

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace esc
