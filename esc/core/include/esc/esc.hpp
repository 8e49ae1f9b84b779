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
    uint8_t type = 0x04;             // 0x0000 ESC type (0x04: "IP core" style emulated ESC)
    uint8_t revision = 0x01;         // 0x0001
    uint16_t build = 0x0001;         // 0x0002
    uint8_t fmmu_count = 8;          // 0x0004
    uint8_t sm_count = 8;            // 0x0005
    uint32_t process_ram_kib = 8;    // 0x0006; process RAM 0x1000 .. 0x1000 + kib*1024 - 1 (ET1100: 8 KiB)
    uint8_t port_descriptor = 0x0F;  // 0x0007: port0 MII, port1 EBUS... (single port used)
    uint16_t features = 0x01CC;      // 0x0008: DC available, 64-bit DC, ...
    EscFaults faults;                // testing aid: deliberate deviations (esc/faults.hpp), all off
};

// Counters of what the ECAT side saw (also reflected in the error counter registers 0x0300-0x0313).
struct EscStats {
    uint64_t frames_processed = 0;
    uint64_t frames_ignored = 0;    // not EtherCAT (wrong EtherType / type field)
    uint64_t frames_malformed = 0;  // length fields disagree with the frame, datagram past the end, ...
    // frames_malformed by reason (they add up to it):
    uint64_t malformed_no_header = 0;  // EtherType 0x88A4 but no room for the 2-byte EtherCAT header
    uint64_t malformed_length = 0;     // the EtherCAT header's length runs past the end of the frame
    uint64_t malformed_datagram = 0;   // a datagram header or its data runs past that length
    uint64_t datagrams = 0;
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
    // source MAC bit 1 set. rx_time_ns is the local time the frame's first bit arrived (DC receive-time
    // latch); pass 0 to use the clock's current time. Returns true if the frame is to be sent back out
    // (an EtherCAT frame, processed or not), false if it is to be dropped.
    bool process_frame(std::span<uint8_t> frame, uint64_t rx_time_ns = 0);

    // ---- PDI side ---------------------------------------------------------------------------------
    // An empty span is no access (no side effect, the PDI watchdog is not triggered).
    void read(uint16_t address, std::span<uint8_t> out) override;
    void write(uint16_t address, std::span<const uint8_t> in) override;
    // The PDI interrupt line: (AL event request 0x0220) & (AL event mask 0x0204) != 0.
    bool irq() const;

    // ---- Time -------------------------------------------------------------------------------------
    // Runs the time-driven parts (process-data and PDI watchdogs, SYNC0/SYNC1 generation) up to now.
    void tick();
    // Local time (ns) at which tick() has something to do next; UINT64_MAX if nothing is pending.
    uint64_t next_event_ns() const;
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

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace esc
