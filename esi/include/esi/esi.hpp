#pragma once
// The ESI XML file (ETG.2000, EtherCATInfo.xsd 1.14) of the device, generated from the object model with
// libxml2's tree API: vendor, group, device identity, the CiA 402 profile with the full dictionary
// (data types, objects, defaults, access, PDO mapping), FMMUs, SyncManagers, the default PDOs, mailbox
// protocols, DC op modes and the EEPROM configuration. The SII image (sii.hpp) is built from the same
// derived model (model.hpp), so the two always agree.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>

#include "od/device.hpp"
#include "od/dictionary.hpp"

namespace esi {

// eeprom_image: the device's own EEPROM content (od::Product::eeprom, ESI Eeprom/Data), written back as
// Eeprom/Data so that the file describes the SII the device serves; empty: Eeprom/ByteSize, ConfigData and
// BootStrap of the SII built from the description (esi::build_sii).
std::string build_esi(const od::DeviceDescription& description, const od::Dictionary& dictionary,
                      std::span<const uint8_t> eeprom_image = {});
void write_esi(const std::filesystem::path& path, const od::DeviceDescription& description,
               const od::Dictionary& dictionary, std::span<const uint8_t> eeprom_image = {});

// ESI names of the pieces the writer uses, exposed for tests and tools.
// Data type name of an entry: "UINT", "DINT", "STRING(6)", "ARRAY [0..3] OF BYTE", ...
std::string esi_type_name(od::DataType type, uint16_t bit_length);
// CiA 303-2 / ETG.1004 unit code (prefix << 24 | unit << 16) for an od unit string, if it is one of the
// SI units whose code the sources confirm ("s", "ms", "us", "ns", "A", "mA", "V", "mV", "Hz", "kHz").
std::optional<uint32_t> unit_code(const std::string& unit);

}  // namespace esi
