#pragma once
// SII EEPROM interface unit: the EEPROM image, the interface registers 0x0500-0x050F (read, write, reload
// commands on either side) and the load of SII words 0-7 at power-on / reload (ETG.1000.4 and ETG.2010 SII,
// ESC datasheet section I, SII EEPROM interface).
#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "esc/faults.hpp"
#include "esc_lock.hpp"
#include "memory.hpp"

namespace esc {

class SiiInterface {
  public:
    SiiInterface(Memory& m, const EscFaults& f);

    // The image (little-endian words).
    const std::vector<uint8_t>& image() const { return eeprom; }
    void set_image(const uint8_t* data, std::size_t n) { eeprom.assign(data, data + n); }
    void on_write(std::function<void(uint16_t, uint16_t)> cb) { on_write_ = std::move(cb); }

    // Loads SII words 0-7 into their registers (power-on) or reloads them (command 4).
    void load_words(bool power_on);
    // An ECAT write gave a command: it runs at the end of the frame.
    void request() { pending = true; }
    // Runs the command in 0x0502 bits 10:8 (at the end of the frame for ECAT, at once for the PDI).
    void execute();
    // End of an ECAT frame: runs the requested command if the frame was correct, else drops it.
    void end_of_frame(bool ok) {
        if (pending) run_pending(ok);
    }
    // Calls the write callback for the words written since the last flush, outside the lock.
    bool callbacks_pending() const { return write_count != 0; }
    void flush_callbacks(std::unique_lock<EscLock>& lock) {
        if (write_count != 0) flush(lock);
    }

  private:
    void run_pending(bool ok);
    void flush(std::unique_lock<EscLock>& lock);
    uint16_t word(uint64_t word) const;
    bool crc_ok() const;

    Memory& mem;
    const EscFaults& faults;
    std::vector<uint8_t> eeprom;
    std::function<void(uint16_t, uint16_t)> on_write_;
    struct EepromWrite {
        uint16_t address;
        uint16_t value;
    };
    std::array<EepromWrite, 4> writes{};
    uint8_t write_count = 0;
    bool pending = false;
};

}  // namespace esc
