#include "identity.hpp"

#include "esi/esi_reader.hpp"
#include "maxpos/maxpos.hpp"
#include "od/device_config.hpp"

namespace fwimage {

namespace {

DeviceIdentity from(const od::Identity& id) {
    return {id.vendor_id, id.product_code, id.device_name};
}

}  // namespace

DeviceIdentity default_identity() {
    return from(maxpos::description().identity);
}

std::optional<DeviceIdentity> identity_from_config(const std::string& path, std::string& error) {
    try {
        return from(maxpos::load_config(path).identity);
    } catch (const std::exception& e) {
        error = e.what();
        return std::nullopt;
    }
}

std::optional<DeviceIdentity> identity_from_esi(const std::string& path, std::string& error) {
    // The one ESI reader: a regular file within esi::kMaxEsiBytes, checked before anything is read (a FIFO
    // does not hang the open, /dev/zero is not read), no DOCTYPE; its errors name the file and line.
    try {
        const esi::EsiFile f = esi::read_esi_file(path);
        if (f.devices.empty()) {
            error = path + ": no Descriptions/Devices/Device in it";
            return std::nullopt;
        }
        const esi::EsiDevice& d = f.devices.front();
        DeviceIdentity id{f.vendor_id, d.product_code, d.name};
        if (id.device_name.empty()) id.device_name = d.type_name;
        return id;
    } catch (const std::exception& e) {
        error = e.what();
        return std::nullopt;
    }
}

}  // namespace fwimage
