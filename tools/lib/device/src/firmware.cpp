// The soft drive as the runtime's firmware (see device/firmware.hpp).
#include "device/firmware.hpp"

#include <ostream>
#include <string>
#include <vector>

namespace device {

DeviceFirmware::DeviceFirmware(esc::Esc& esc, DeviceOptions options,
                               const std::filesystem::path& control_path, gid_t control_group)
    : device_(esc, std::move(options)) {
    if (!control_path.empty()) control_ = std::make_unique<ControlSocket>(control_path, control_group);
}

void DeviceFirmware::report(std::ostream& out) const {
    report_device(out, device_);
}

void report_device(std::ostream& out, const Device& device) {
    ecat::print_stats(out, device.stack_stats());  // every firmware instance of the run, not the last only
    const DeviceStats& s = device.stats();
    out << "device.builds " << s.builds << '\n'
        << "device.drive_cycles " << s.cycles << '\n'
        << "device.error_events " << s.emergencies << '\n'
        << "device.diagnosis_events " << s.diagnoses << '\n';
}

slave::FirmwareFactory firmware_factory(DeviceOptions options, std::filesystem::path control_path,
                                        gid_t control_group) {
    return [options = std::move(options), control_path = std::move(control_path), control_group](
               esc::Esc& esc, const slave::SlaveOptions& slave) -> std::unique_ptr<slave::Firmware> {
        DeviceOptions o = options;
        o.load_sii = slave.eeprom_file.empty();
        return std::make_unique<DeviceFirmware>(esc, std::move(o), control_path, control_group);
    };
}

slave::EepromLoader eeprom_loader(DeviceOptions options) {
    return [options = std::move(options)](const slave::SlaveOptions& slave) {
        if (!slave.eeprom_file.empty()) {
            std::vector<uint8_t> image = slave::load_eeprom_file(slave);
            // A user's image may say something else than the device answers over CoE (0x1018): warn.
            if (options.events != nullptr) {
                const od::Identity id = make_description(options).identity;
                for (const std::string& d :
                     sii_drift(image, id.vendor_id, id.product_code, id.revision, id.serial_number))
                    options.events->warn("--eeprom " + slave.eeprom_file + ": " + d);
            }
            return image;
        }
        return make_sii(options);
    };
}

}  // namespace device
