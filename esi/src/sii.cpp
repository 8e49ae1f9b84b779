// The SII EEPROM image built from the object model (ETG.2010, ETG.1000.6): the one part of the SII code
// that needs od/. Parsing and decoding an image is od-free (esi/sii_reader.hpp, target sii).
#include "esi/sii.hpp"

#include <algorithm>
#include <fstream>
#include <stdexcept>

#include "esc/wire/sii.hpp"
#include "esi/model.hpp"

namespace esi {
namespace {

// ---------------------------------------------------------------------------------------------------
// Building
// ---------------------------------------------------------------------------------------------------

// The strings category addresses its strings by one byte (ETG.2010: index 1-255, 0 none): a content that
// needs more distinct strings is compacted as one that does not fit the EEPROM is (build_sii).
struct TooManyStrings : std::length_error {
    TooManyStrings() : std::length_error("SII: more than 255 distinct strings") {}
};

class StringTable {
  public:
    // 1-based index of the string (0 for the empty string). Equal strings share one index.
    uint8_t add(const std::string& s) {
        if (s.empty()) return 0;
        const std::string v = s.substr(0, 255);  // one length byte
        for (std::size_t i = 0; i < strings_.size(); ++i)
            if (strings_[i] == v) return static_cast<uint8_t>(i + 1);
        if (strings_.size() >= 255) throw TooManyStrings();
        strings_.push_back(v);
        return static_cast<uint8_t>(strings_.size());
    }
    const std::vector<std::string>& strings() const { return strings_; }

  private:
    std::vector<std::string> strings_;
};

struct Writer {
    std::vector<uint8_t> b;
    void u8(uint8_t v) { b.push_back(v); }
    void u16(uint16_t v) {
        b.push_back(static_cast<uint8_t>(v));
        b.push_back(static_cast<uint8_t>(v >> 8));
    }
    void u32(uint32_t v) {
        u16(static_cast<uint16_t>(v));
        u16(static_cast<uint16_t>(v >> 16));
    }
    void category(uint16_t type, const std::vector<uint8_t>& data) {
        std::vector<uint8_t> d = data;
        if (d.size() % 2) d.push_back(type == category::Fmmu ? 0xFF : 0x00);  // FMMU 0xFF = unused
        u16(type);
        u16(static_cast<uint16_t>(d.size() / 2));
        b.insert(b.end(), d.begin(), d.end());
    }
};

// The data type of an SII PDO entry (ETG.2010 TXPDO/RXPDO entry): the mapped entry's, or, where a PDO maps
// fewer bits than the entry has (a "compact" PDO mapping a 32-bit counter as 16 bits next to one that maps it
// whole), the standard type of the mapped length in the entry's family, so that type and bit length agree as
// the vendor's SII has them (its ESI's PDO entry DataType). 0 (none) for padding and lengths without a type.
uint8_t entry_type_code(const PdoEntryInfo& e) {
    if (e.entry == nullptr) return 0;
    const uint16_t bits = od::bit_size(e.type);
    if (bits == 0 || bits == e.bit_length) return static_cast<uint8_t>(e.type);
    const bool s = od::is_signed(e.type);
    od::DataType t{};
    switch (e.bit_length) {
        case 8:
            t = s ? od::DataType::Integer8 : od::DataType::Unsigned8;
            break;
        case 16:
            t = s ? od::DataType::Integer16 : od::DataType::Unsigned16;
            break;
        case 24:
            t = s ? od::DataType::Integer24 : od::DataType::Unsigned24;
            break;
        case 32:
            t = s ? od::DataType::Integer32 : od::DataType::Unsigned32;
            break;
        case 64:
            t = s ? od::DataType::Integer64 : od::DataType::Unsigned64;
            break;
        default:
            if (e.bit_length < 1 || e.bit_length > 7) return 0;
            t = static_cast<od::DataType>(static_cast<uint16_t>(od::DataType::Bit1) + e.bit_length - 1);
    }
    return static_cast<uint8_t>(t);
}

// What the SII leaves out when the full content does not fit the EEPROM, in this order
// (docs/decisions/esi.md): the categories a configuration tool needs stay (strings of the identity, General,
// FMMU, SyncM, DC, the PDOs of the default assignment); names that the ESI and the CoE dictionary carry
// anyway go first.
enum class Compaction {
    None,
    NoEntryNames,      // PDO entries without name strings (index 0: no string, ETG.2010)
    NoPdoNames,        // PDOs without name strings
    NoDcDescriptions,  // DC op modes without description strings (their names stay: a master selects by name)
    DefaultPdosOnly,   // only the default-assigned PDOs (a master without CoE can use no other)
    NoPdos,            // a CoE device: no PDO categories (a master reads 0x1C1n and the mappings by SDO)
    NameIsOrder,       // General's device name is the order number's string (the long name is left out)
};
constexpr Compaction kLastCompaction = Compaction::NameIsOrder;

// The content (header and categories, up to the End marker) at one compaction level.
std::vector<uint8_t> build_content(const od::DeviceDescription& d, const DeviceModel& m, Compaction level) {
    StringTable strings;
    // String 1 is the order number (ESI Type), as vendors write it: a master that names a slave by the first
    // string (SOEM's ecx_config_init: ecx_siistring(..., 1)) shows "EL2008", not its group "DigOut"; one
    // that follows the General category's indices finds order, name and group there.
    const std::string order = d.identity.order_code.empty() ? d.identity.device_name : d.identity.order_code;
    const uint8_t order_idx = strings.add(order);
    const uint8_t name_idx =
        level >= Compaction::NameIsOrder ? order_idx : strings.add(d.identity.device_name);
    const uint8_t group_idx = strings.add(d.identity.group_type);

    // ---- General ----
    std::vector<uint8_t> general(32, 0);
    general[0] = group_idx;
    general[1] = 0;  // no image
    general[2] = order_idx;
    general[3] = name_idx;
    if (d.mailbox_protocols & od::mailbox_protocol::CoE) general[5] = d.coe_details;
    if (d.mailbox_protocols & od::mailbox_protocol::FoE)
        general[6] = static_cast<uint8_t>(d.foe_details | 0x01);
    if (d.mailbox_protocols & od::mailbox_protocol::EoE) general[7] = 0x01;
    general[9] = m.profile_number == 402 ? 1 : 0;  // DS402 channels
    general[11] = general_flags(d);
    general[12] = static_cast<uint8_t>(static_cast<uint16_t>(d.ebus_current_ma));
    general[13] = static_cast<uint8_t>(static_cast<uint16_t>(d.ebus_current_ma) >> 8);
    general[14] = group_idx;
    const uint16_t ports = physics_sii_ports(d.physics);  // the ESI's Physics (ETG.2010 General 16-17)
    general[16] = static_cast<uint8_t>(ports);
    general[17] = static_cast<uint8_t>(ports >> 8);
    general[18] = static_cast<uint8_t>(d.identification_register);
    general[19] = static_cast<uint8_t>(d.identification_register >> 8);

    // ---- FMMU ----
    std::vector<uint8_t> fmmu;
    for (FmmuUse f : m.fmmus)
        fmmu.push_back(static_cast<uint8_t>(f));

    // ---- SyncM ----
    Writer syncm;
    for (const SmInfo& s : m.sync_managers) {
        syncm.u16(s.start);
        syncm.u16(s.size);
        syncm.u8(s.control);
        syncm.u8(0);
        syncm.u8(s.enable ? 0x01 : 0x00);
        syncm.u8(static_cast<uint8_t>(s.kind));
    }

    // ---- TxPDO / RxPDO ----
    Writer txpdo, rxpdo;
    for (std::size_t i : m.pdo_order) {
        const PdoInfo& p = m.pdos[i];
        if (level >= Compaction::DefaultPdosOnly && p.sm < 0) continue;
        if (level >= Compaction::NoPdos && (d.mailbox_protocols & od::mailbox_protocol::CoE)) continue;
        Writer& w = p.rx ? rxpdo : txpdo;
        w.u16(p.index);
        w.u8(static_cast<uint8_t>(p.entries.size()));
        w.u8(p.sm >= 0 ? static_cast<uint8_t>(p.sm) : 0xFF);
        w.u8(0);  // DC sync
        w.u8(level >= Compaction::NoPdoNames ? 0 : strings.add(p.name));
        uint16_t flags = 0;
        if (p.sm >= 0) flags |= pdo_flags::Default;
        if (p.fixed) flags |= pdo_flags::FixedContent;
        if (p.mandatory) flags |= pdo_flags::Mandatory;
        w.u16(flags);
        for (const PdoEntryInfo& e : p.entries) {
            w.u16(e.index);
            w.u8(e.subindex);
            w.u8(level >= Compaction::NoEntryNames ? 0 : strings.add(e.name));
            w.u8(entry_type_code(e));
            w.u8(e.bit_length);
            w.u16(0);
        }
    }

    // ---- DC ----
    Writer dc;
    for (const od::DcOpMode& mode : d.dc_modes) {
        dc.u32(mode.cycle_time_sync0);  // 0: set by the master
        dc.u32(static_cast<uint32_t>(mode.shift_time_sync0));
        dc.u32(static_cast<uint32_t>(mode.shift_time_sync1));
        dc.u16(static_cast<uint16_t>(mode.cycle_time_sync1_factor));
        dc.u16(mode.assign_activate);
        dc.u16(static_cast<uint16_t>(mode.cycle_time_sync0_factor));
        dc.u8(strings.add(mode.name));
        dc.u8(level >= Compaction::NoDcDescriptions ? 0 : strings.add(mode.description));
        dc.u32(0);
    }

    // ---- Strings (after every user has added its strings) ----
    std::vector<uint8_t> str;
    str.push_back(static_cast<uint8_t>(strings.strings().size()));
    for (const auto& s : strings.strings()) {
        str.push_back(static_cast<uint8_t>(s.size()));
        str.insert(str.end(), s.begin(), s.end());
    }

    // ---- Header ----
    Writer w;
    w.b.insert(w.b.end(), m.config_data.begin(), m.config_data.end());  // words 0-6
    w.u16(esc::sii::crc8(w.b.data(), 14));                              // word 7
    w.u32(d.identity.vendor_id);                                        // 0x08
    w.u32(d.identity.product_code);                                     // 0x0A
    w.u32(d.identity.revision);                                         // 0x0C
    w.u32(d.identity.serial_number);                                    // 0x0E
    for (int i = 0; i < 4; ++i)
        w.u16(0);                                                   // 0x10-0x13 delays, reserved
    w.b.insert(w.b.end(), m.bootstrap.begin(), m.bootstrap.end());  // 0x14-0x17
    w.u16(d.standard_mailbox.out_start);                            // 0x18
    w.u16(d.standard_mailbox.out_size);
    w.u16(d.standard_mailbox.in_start);
    w.u16(d.standard_mailbox.in_size);
    w.u16(d.mailbox_protocols);  // 0x1C
    while (w.b.size() < 0x3E * 2)
        w.u16(0);                                            // 0x1D-0x3D reserved
    w.u16(static_cast<uint16_t>(d.eeprom_bytes / 128 - 1));  // 0x3E: KiBit - 1
    w.u16(1);                                                // 0x3F: version

    w.category(category::Strings, str);
    w.category(category::General, general);
    if (!fmmu.empty()) w.category(category::Fmmu, fmmu);
    if (!syncm.b.empty()) w.category(category::SyncM, syncm.b);
    if (!txpdo.b.empty()) w.category(category::TxPdo, txpdo.b);
    if (!rxpdo.b.empty()) w.category(category::RxPdo, rxpdo.b);
    if (!dc.b.empty()) w.category(category::Dc, dc.b);
    w.u16(category::End);
    return std::move(w.b);
}

}  // namespace

std::vector<uint8_t> build_sii(const od::DeviceDescription& d, const od::Dictionary& dict) {
    if (d.eeprom_bytes < 128 || d.eeprom_bytes % 128 != 0)
        throw std::invalid_argument("SII: eeprom_bytes must be a positive multiple of 128 (1 KiBit)");
    const DeviceModel m = derive_model(d, dict);
    std::size_t full = 0;
    for (const Compaction level :
         {Compaction::None, Compaction::NoEntryNames, Compaction::NoPdoNames, Compaction::NoDcDescriptions,
          Compaction::DefaultPdosOnly, Compaction::NoPdos, Compaction::NameIsOrder}) {
        std::vector<uint8_t> image;
        try {
            image = build_content(d, m, level);
        } catch (const TooManyStrings&) {
            // A device whose PDO entries, PDOs and op modes name more than 255 strings (a measurement
            // module with hundreds of channel PDOs): the names go as the EEPROM's size would make them go.
            if (level == kLastCompaction) throw;
            continue;
        }
        if (full == 0) full = image.size();
        if (image.size() <= d.eeprom_bytes) {
            image.resize(d.eeprom_bytes, 0xFF);
            return image;
        }
        if (level == kLastCompaction)
            throw std::length_error("SII: content needs " + std::to_string(full) + " bytes (" +
                                    std::to_string(image.size()) + " at its most compact), the EEPROM has " +
                                    std::to_string(d.eeprom_bytes));
    }
    return {};  // not reached
}

void write_sii(const std::filesystem::path& path, const od::DeviceDescription& d,
               const od::Dictionary& dict) {
    const auto image = build_sii(d, dict);
    std::ofstream f(path, std::ios::binary | std::ios::trunc);
    f.write(reinterpret_cast<const char*>(image.data()), static_cast<std::streamsize>(image.size()));
    if (!f) throw std::runtime_error("cannot write " + path.string());
}

}  // namespace esi
