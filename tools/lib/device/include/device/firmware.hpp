#pragma once
// The soft drive as the slave runtime's firmware: a Device (plus an optional control socket) behind the
// slave::Firmware interface, and the factory/loader that plug it into slave::SlaveOptions.
#include <cstdint>
#include <filesystem>
#include <memory>

#include "device/control.hpp"
#include "device/device.hpp"
#include "slave/firmware.hpp"
#include "slave/slave.hpp"

namespace device {

class DeviceFirmware final : public slave::Firmware {
  public:
    // control_path: where to create the control socket; empty: none. control_group: who else may use it.
    DeviceFirmware(esc::Esc& esc, DeviceOptions options, const std::filesystem::path& control_path = {},
                   gid_t control_group = ControlSocket::kNoGroup);

    void poll(uint64_t now_ns) override { device_.poll(now_ns); }
    uint64_t next_deadline_ns() const override { return device_.next_deadline_ns(); }
    int control_fd() const override { return control_ ? control_->fd() : -1; }
    void on_control(uint64_t now_ns) override {
        if (control_) control_->service(device_, now_ns);
    }

    // The stack's statistics (ecat::print_stats) and the device's, as "name value" lines.
    void report(std::ostream& out) const override;

    Device& device() { return device_; }

  private:
    Device device_;
    std::unique_ptr<ControlSocket> control_;
};

// What DeviceFirmware::report() writes for a device ("name value" lines).
void report_device(std::ostream& out, const Device& device);

// SlaveOptions::firmware_factory for the soft drive. options.load_sii is set from whether the slave
// serves a user's image (SlaveOptions::eeprom_file).
slave::FirmwareFactory firmware_factory(DeviceOptions options, std::filesystem::path control_path = {},
                                        gid_t control_group = ControlSocket::kNoGroup);
// SlaveOptions::eeprom_loader: the user's --eeprom file if one is given, else the SII built from the model.
slave::EepromLoader eeprom_loader(DeviceOptions options);

}  // namespace device
