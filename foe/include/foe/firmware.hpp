#pragma once
// The firmware-update side of the drive in one object: the two-slot store in <state dir>/firmware and the
// FoE server in front of it, configured from the device description. The glue that builds the slave
// (dictionary, SII, ecat::Stack) uses it like this:
//
//   foe::FirmwareUpdate fw(state_dir, desc);   // opens the store (recovers from an interrupted update)
//   fw.apply_to(desc.identity);                // revision (0x1018:03, SII) and 0x100A from the active image
//   ... build the dictionary and the SII from desc ...
//   stack.add_handler(fw.server());
//   // Application::on_restart() (Bootstrap -> Init): fw.restart(), then rebuild from the new identity.
#include <filesystem>
#include <optional>

#include "foe/server.hpp"
#include "foe/store.hpp"
#include "od/device.hpp"

namespace foe {

class FirmwareUpdate {
  public:
    FirmwareUpdate(const std::filesystem::path& state_dir, const od::DeviceDescription& description,
                   ServerConfig config);
    FirmwareUpdate(const std::filesystem::path& state_dir, const od::DeviceDescription& description)
        : FirmwareUpdate(state_dir, description, ServerConfig::from(description)) {}

    // Whether the store could be opened (the directory exists or was created).
    bool ok() const { return ok_; }
    const StoreError& error() const { return error_; }
    // Version of the image that boots, if one is stored.
    std::optional<uint32_t> active_version() const;
    // Sets revision and 0x100A text from the active image; leaves identity alone (false) if there is none.
    bool apply_to(od::Identity& identity) const;
    // Reopens the store (the device restarts: Bootstrap -> Init).
    void restart();

    FirmwareStore& store() { return store_; }
    FoeServer& server() { return server_; }

  private:
    static StoreConfig store_config(const std::filesystem::path& dir, const od::DeviceDescription& d);
    FirmwareStore store_;
    FoeServer server_;
    StoreError error_;
    bool ok_ = false;
};

}  // namespace foe
