#pragma once
// The device a firmware image is built for: vendor id, product code and device name (the FoE file name's
// prefix), from the drive's defaults (od/), from a device configuration file (ecat-slave --config) or from an
// ESI file (the Vendor Id, and the first Device's Type ProductCode and Name).
#include <cstdint>
#include <optional>
#include <string>

namespace fwimage {

struct DeviceIdentity {
    uint32_t vendor_id = 0;
    uint32_t product_code = 0;
    std::string device_name;
};

// The soft drive's own identity (maxpos::description()).
DeviceIdentity default_identity();
// From ecat-slave's --config file; on error, error says why (with the file and line) and nullopt.
std::optional<DeviceIdentity> identity_from_config(const std::string& path, std::string& error);
// From an ESI XML file; on error, error says why and nullopt.
std::optional<DeviceIdentity> identity_from_esi(const std::string& path, std::string& error);

}  // namespace fwimage
