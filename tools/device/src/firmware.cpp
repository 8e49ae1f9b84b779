// The soft drive as the runtime's firmware (see softdrive/firmware.hpp).
#include "softdrive/firmware.hpp"

#include <ostream>

namespace softdrive {

DeviceFirmware::DeviceFirmware(esc::Esc& esc, DeviceOptions options,
                               const std::filesystem::path& control_path)
    : device_(esc, std::move(options)) {
    if (!control_path.empty()) control_ = std::make_unique<ControlSocket>(control_path);
}

void DeviceFirmware::report(std::ostream& out) const {
    device_.stack().report(out);
    const DeviceStats& s = device_.stats();
    out << "device.builds " << s.builds << '\n'
        << "device.drive_cycles " << s.cycles << '\n'
        << "device.error_events " << s.emergencies << '\n'
        << "device.diagnosis_events " << s.diagnoses << '\n';
}

softslave::FirmwareFactory firmware_factory(DeviceOptions options, std::filesystem::path control_path) {
    return [options = std::move(options), control_path = std::move(control_path)](
               esc::Esc& esc, const softslave::SlaveOptions& slave) -> std::unique_ptr<softslave::Firmware> {
        DeviceOptions o = options;
        o.load_sii = slave.eeprom_file.empty();
        return std::make_unique<DeviceFirmware>(esc, std::move(o), control_path);
    };
}

softslave::EepromLoader eeprom_loader(DeviceOptions options) {
    return [options = std::move(options)](const softslave::SlaveOptions& slave) {
        if (!slave.eeprom_file.empty()) return softslave::load_eeprom_file(slave);
        return make_sii(options);
    };
}

}  // namespace softdrive
