#pragma once
// What the SII image and the ESI file both say about the device, derived once from od::DeviceDescription and
// od::Dictionary: the default PDO mapping (the mapping objects, in the direction od::Object::direction gives,
// read through the assignment objects 0x1C1n), the
// SyncManager layout with the process-data sizes that mapping gives, the FMMU usage, the profile number
// (0x1000) and the EEPROM configuration words. build_sii() and build_esi() both render this, so the two
// files cannot disagree with each other or with the dictionary.
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "od/device.hpp"
#include "od/dictionary.hpp"

namespace esi {

// One entry of a default PDO mapping (the value of 0x16xx:n / 0x1Axx:n: index << 16 | sub << 8 | bits).
struct PdoEntryInfo {
    uint16_t index = 0;  // 0 = padding (gap) entry
    uint8_t subindex = 0;
    uint8_t bit_length = 0;
    std::string name;                  // the mapped entry's name (object name for a VAR); empty for padding
    od::DataType type{};               // the mapped entry's type (meaningless for padding)
    const od::Entry* entry = nullptr;  // the mapped entry, nullptr for padding or a dangling mapping
};

struct PdoInfo {
    uint16_t index = 0;                 // usually 0x1600.. (RxPDO) or 0x1A00.. (TxPDO), but any index
    bool rx = false;                    // true: RxPDO (master -> slave, outputs)
    std::string name;                   // the mapping object's name
    int sm = -1;                        // SyncManager that assigns it by default (0x1C1n), -1 = not assigned
    bool fixed = false;                 // mapping not writable in any state (PdoFixedContent / ESI Fixed)
    bool mandatory = false;             // od::PdoRule (PdoMandatory / ESI Mandatory)
    std::vector<uint16_t> exclude;      // od::PdoRule (ESI Exclude)
    std::vector<PdoEntryInfo> entries;  // the default mapping, in order
    uint32_t bit_size() const;
};

// A predefined PDO set (od::PdoSet) as the ESI lists it: AlternativeSmMapping with the SMs it assigns.
struct PdoSetInfo {
    std::string name;
    bool is_default = false;  // the set the default assignment (0x1C12/0x1C13) holds
    int rx_sm = -1;           // the outputs SyncManager (2), -1 if none
    int tx_sm = -1;           // the inputs SyncManager (3), -1 if none
    std::vector<uint16_t> rx, tx;
};

struct SmInfo {
    od::SmKind kind = od::SmKind::MBoxOut;
    uint16_t start = 0;
    uint16_t size = 0;  // mailbox: the mailbox size; process data: bytes of the default mapping
    uint8_t control = 0;
    bool enable = true;
    uint16_t min_size = 0;  // ESI MinSize/MaxSize (0: not declared)
    uint16_t max_size = 0;
};

// ESI Fmmu text / SII FMMU category byte.
enum class FmmuUse : uint8_t { Unused = 0x00, Outputs = 0x01, Inputs = 0x02, MBoxState = 0x03 };

// The device's ports (od::DeviceDescription::physics, ETG.2000 Device Physics: one character per port).
// A character that is not a port type (the reader refuses those: esi_device) counts as no port.
// ESC datasheet, register 0x0007 (port descriptor): 2 bits per port from port 0, 00 not implemented, 10 EBUS,
// 11 MII. 'Y' and 'H' are MII ports, 'K' an E-Bus port.
inline uint8_t physics_port_descriptor(std::string_view physics) {
    uint8_t d = 0;
    for (std::size_t p = 0; p < physics.size() && p < 4; ++p) {
        const char c = physics[p];
        const unsigned code = c == 'Y' || c == 'H' ? 0x3u : c == 'K' ? 0x2u : 0x0u;
        d = static_cast<uint8_t>(d | (code << (2 * p)));
    }
    return d;
}
// ETG.2010 SII General category bytes 16-17 (physical ports): 4 bits per port from port 0, 0 not used,
// 1 MII, 3 EBUS, 4 fast hot connect.
inline uint16_t physics_sii_ports(std::string_view physics) {
    uint16_t w = 0;
    for (std::size_t p = 0; p < physics.size() && p < 4; ++p) {
        const char c = physics[p];
        const unsigned code = c == 'Y' ? 0x1u : c == 'K' ? 0x3u : c == 'H' ? 0x4u : 0x0u;
        w = static_cast<uint16_t>(w | (code << (4 * p)));
    }
    return w;
}

// Properties of the stack itself rather than of one device, so not in od::DeviceDescription:
// Segmented SDO transfers (coe/src/sdo_server.cpp, both directions). ESI Mailbox/CoE SegmentedSdo.
constexpr bool kSegmentedSdo = true;
// SII General flags (ETG.2010, byte 11) as the description announces them: bit 2 mailbox data link layer
// (ecat/ serves the SM1 repeat request and drops a repeated request with the same non-zero counter for every
// device), bit 3 identification in AL status code 0x0134 on AL control bit 5 (ecat/src/stack.cpp), bit 4
// identification in the ESC register of bytes 18-19.
inline uint8_t general_flags(const od::DeviceDescription& d) {
    return static_cast<uint8_t>((d.mailbox_protocols != 0 && d.mailbox_data_link_layer ? 0x04 : 0) |
                                (d.identification_al_status ? 0x08 : 0) |
                                (d.identification_register != 0 ? 0x10 : 0));
}

struct DeviceModel {
    std::vector<PdoInfo>
        pdos;  // every mapping object of the dictionary, by index (Rx first: 0x16xx < 0x1Axx)
    // The order the ESI and the SII list the PDOs in (indices into pdos): the RxPDOs, then the TxPDOs; of
    // each direction by index, except that the places of the default-assigned ones hold them in their
    // assignment order (as a master lays out the process image of a device it cannot ask by CoE). A vendor
    // ESI that lists by index and assigns in that order (the usual case) is listed as it was written.
    std::vector<std::size_t> pdo_order;
    std::vector<SmInfo> sync_managers;
    std::vector<PdoSetInfo> pdo_sets;  // od::DeviceDescription::pdo_sets that name PDOs of the dictionary
    std::vector<FmmuUse> fmmus;
    // The description's profile (ESI ProfileNo/AddInfo) if it names one, else 0x1000 bits 0-15 (402 for a
    // drive; 0 if 0x1000 has no default) and bits 16-31 (CiA 402: 2 = servo).
    uint16_t profile_number = 0;
    uint16_t profile_add_info = 0;
    std::array<uint8_t, 14> config_data{};  // SII words 0-6 (ESI Eeprom/ConfigData)
    std::array<uint8_t, 8> bootstrap{};     // SII words 0x14-0x17 (ESI Eeprom/BootStrap)
    // Contradictions between the description and the dictionary (the dictionary wins in the output): a
    // default mapping that names a missing or unmappable entry, a process-data SyncManager whose declared
    // default_size differs from the size of its default mapping, ... Empty for a consistent device.
    std::vector<std::string> warnings;
};

DeviceModel derive_model(const od::DeviceDescription& description, const od::Dictionary& dictionary);

// The integral value of a declared number (default/min/max) as raw little-endian bits for an entry of the
// given type and bit length: reals become their IEEE-754 bits, integers are truncated two's complement.
std::optional<uint64_t> number_bits(const od::Number& n, od::DataType type, uint16_t bit_length);

// The device's 16x14 picture as a Windows bitmap (24 bits per pixel, bottom-up rows, 726 bytes): what the
// ESI carries as ImageData16x14 and a configuration tool shows in its tree. Drawn here, not loaded.
std::vector<uint8_t> device_image_bmp();

}  // namespace esi
