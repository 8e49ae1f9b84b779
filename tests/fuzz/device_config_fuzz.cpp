// (6) The device configuration parser (od/src/device_config.cpp, what `ecat-slave --config` reads): any
// text. A bad file is an od::ConfigError with a line; a good one must build a dictionary and an SII that
// parses back with the same identity (what the device then serves).
#include <string>
#include <string_view>

#include "esi/sii.hpp"
#include "fuzz_support.hpp"
#include "harnesses.hpp"
#include "od/device_config.hpp"
#include "od/drive_profile.hpp"

namespace fuzz::device_config {

int fuzz_one(const uint8_t* data, std::size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    od::DeviceDescription desc;
    try {
        desc = od::parse_device_config(text, "fuzz.conf");
    } catch (const od::ConfigError& e) {
        FUZZ_CHECK(e.what() != nullptr);
        return 0;
    }
    const od::Dictionary dict = od::make_drive_dictionary(desc);
    const std::vector<uint8_t> image = esi::build_sii(desc, dict);
    const esi::SiiInfo info = esi::parse_sii(image);
    FUZZ_CHECK(info.header_complete);
    FUZZ_CHECK(info.vendor_id == desc.identity.vendor_id);
    FUZZ_CHECK(info.product_code == desc.identity.product_code);
    return 0;
}

}  // namespace fuzz::device_config
