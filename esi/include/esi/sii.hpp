#pragma once
// The SII EEPROM image (ETG.2010, ETG.1000.6) generated from the object model. Target `esi`; parsing and
// decoding any image is od-free and lives in esi/sii_reader.hpp (target `sii`), included here.
#include <cstdint>
#include <filesystem>
#include <vector>

#include "esi/sii_reader.hpp"
#include "od/device.hpp"
#include "od/dictionary.hpp"

namespace esi {

// Builds the image. Size = description.eeprom_bytes (the content is padded with 0xFF, as an erased
// EEPROM). Throws std::length_error if the content does not fit, std::invalid_argument if eeprom_bytes is
// not a whole number of KiBit between 1 and 4096 KiBit (word 0x3E could not express it).
std::vector<uint8_t> build_sii(const od::DeviceDescription& description, const od::Dictionary& dictionary);
void write_sii(const std::filesystem::path& path, const od::DeviceDescription& description,
               const od::Dictionary& dictionary);

}  // namespace esi
