#include "foe/firmware.hpp"

namespace foe {

StoreConfig FirmwareUpdate::store_config(const std::filesystem::path& dir, const od::DeviceDescription& d) {
    StoreConfig c;
    c.dir = dir / "firmware";
    c.identity = ImageIdentity::from(d.identity);
    if (!d.identity.device_name.empty()) c.device_name = d.identity.device_name;
    return c;
}

FirmwareUpdate::FirmwareUpdate(const std::filesystem::path& state_dir,
                               const od::DeviceDescription& description, ServerConfig config)
    : store_(store_config(state_dir, description)), server_(store_, std::move(config)) {
    ok_ = store_.open(&error_);
}

std::optional<uint32_t> FirmwareUpdate::active_version() const {
    if (!store_.active_image()) return std::nullopt;
    return store_.active_image()->header.version;
}

bool FirmwareUpdate::apply_to(od::Identity& identity) const {
    const auto v = active_version();
    if (!v) return false;
    apply_version(identity, *v);
    return true;
}

void FirmwareUpdate::restart() {
    server_.abort_transfer();
    ok_ = store_.open(&error_);
}

}  // namespace foe
