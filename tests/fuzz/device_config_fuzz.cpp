// (6) The device configuration parser (od/src/device_config.cpp, what `ecat-slave --config` reads): any
// text. A bad file is an od::ConfigError with a line; a good one must build a dictionary and an SII that
// parses back with the same identity (what the device then serves), or be refused by the SII builder
// with std::length_error when its content does not fit the configured EEPROM.
#include <stdexcept>
#include <string>
#include <string_view>

#include "esi/sii.hpp"
#include "fuzz_support.hpp"
#include "harnesses.hpp"
#include "maxpos/maxpos.hpp"
#include "od/device_config.hpp"

namespace fuzz::device_config {

int fuzz_one(const uint8_t* data, std::size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    od::DeviceDescription desc;
    try {
        desc = maxpos::parse_config(text, "fuzz.conf");
    } catch (const od::ConfigError& e) {
        FUZZ_CHECK(e.what() != nullptr);
        return 0;
    }
    const od::Dictionary dict = maxpos::dictionary(desc);
    std::vector<uint8_t> image;
    try {
        image = esi::build_sii(desc, dict);
    } catch (const std::length_error&) {  // documented refusals of esi::build_sii
        // Strings and categories that do not fit the configured EEPROM size ([eeprom] bytes): the parser
        // accepts such a file, the SII builder refuses it and ecat-slave reports it (exit 1) before it
        // serves anything. Reported, not a crash (docs/robustness.md).
        return 0;
    } catch (const std::invalid_argument&) {  // [eeprom] bytes not a whole number of KiBit
        return 0;
    }
    const esi::SiiInfo info = esi::parse_sii(image);
    FUZZ_CHECK(info.header_complete);
    FUZZ_CHECK(info.vendor_id == desc.identity.vendor_id);
    FUZZ_CHECK(info.product_code == desc.identity.product_code);
    return 0;
}

}  // namespace fuzz::device_config
