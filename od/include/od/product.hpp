#pragma once
// A product: one kind of device a soft slave can be, as one value. The built-in MAXPOS drive is one; a device
// read from a vendor's ESI file (esi/device) or from an ENI's slave data is another. device::Device builds
// its firmware from a product; od/ itself declares no product.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "od/device.hpp"
#include "od/dictionary.hpp"

namespace od {

// The application behind the dictionary.
enum class Application : uint8_t {
    // Process data only: outputs are taken and visible, inputs follow the device's input model (an input
    // with the name and type of an output mirrors it, counters count) or what was set at run time.
    None,
    // The CiA 402 drive core (drive/), bound to the dictionary by object index: device control, the modes
    // 0x6502 announces, the objects that exist.
    Cia402Drive,
};

struct Product {
    // Names the product in messages: "the built-in MAXPOS", "ext/EL1008.xml, device EL1008 rev 0x00110000".
    std::string source;
    DeviceDescription description;
    // Builds the dictionary of a description. The description passed may differ from the one above in its
    // identity (serial number of a unit of a line, revision of the active firmware image); the dictionary's
    // identity objects (0x1008-0x100A, 0x1018) follow the one passed. Never empty.
    std::function<Dictionary(const DeviceDescription&)> make_dictionary;
    // The device's own EEPROM image (ESI Eeprom/Data), served byte for byte; empty: the SII is built from
    // the description and the dictionary (esi::build_sii).
    std::vector<uint8_t> eeprom;
    Application application = Application::None;
    // What the source declares that softecat does not emulate, one line per element, said once at start.
    std::vector<std::string> warnings;
};

}  // namespace od
