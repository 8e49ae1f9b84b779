#pragma once
// What a master wrote into the SII EEPROM (e.g. a station alias in word 4 and the checksum in word 7), kept
// in the state directory so it survives a restart, as the EEPROM chip of a hardware drive does. The image the
// device serves is the one built from the model with these words on top.
//
// File "<state>/sii-writes.bin" (little-endian), replaced atomically (temp file, fsync, rename, fsync dir):
//   0 char[8] "SECATSII"   8 u32 number of words n   12 n x (u16 word address, u16 value)   then u32 CRC-32
//   (IEEE) of everything before it.
#include <cstdint>
#include <filesystem>
#include <map>
#include <span>
#include <string>
#include <vector>

namespace device {

class EepromWrites {
  public:
    static constexpr const char* kFileName = "sii-writes.bin";

    explicit EepromWrites(std::filesystem::path state_dir);

    // Reads the file. No file: empty, "". A bad file: empty and the reason (the file stays until the next
    // save replaces it).
    std::string load();
    // Removes sii-writes.bin.tmp if an interrupted save left it behind (called once at the start of the
    // device, never while a save may run). Returns whether there was one.
    bool remove_stale_temp() const;
    // Writes the file now (atomically); "" or the error text.
    std::string save();

    // A master wrote `value` into word `address` (ESC on_eeprom_write callback).
    void record(uint16_t address, uint16_t value) { words_[address] = value; }
    // Puts the recorded words onto an image (words outside it are left out).
    void apply(std::vector<uint8_t>& image) const;
    bool empty() const { return words_.empty(); }
    std::size_t size() const { return words_.size(); }
    const std::filesystem::path& file() const { return file_; }

  private:
    std::filesystem::path dir_;
    std::filesystem::path file_;
    std::map<uint16_t, uint16_t> words_;
};

// Where an SII image disagrees with what the object model says (checksum of words 0-6 in word 7, identity
// words 8-15 against 0x1018 vendor id, product code, revision, serial number), one sentence per difference;
// empty if none. An image too short to hold the identity says so.
std::vector<std::string> sii_drift(std::span<const uint8_t> image, uint32_t vendor_id, uint32_t product_code,
                                   uint32_t revision, uint32_t serial_number);

}  // namespace device
