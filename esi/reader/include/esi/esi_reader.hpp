#pragma once
// The ESI (ETG.2000 EtherCATInfo XML) reader: what a device description promises, read with libxml2 into
// plain structures. Independent of the slave's object model (od/): it reads any vendor's ESI file, so the
// conformance suite can be pointed at slaves that are not part of this project, and the tests compare our
// generated ESI with the object model it came from. Target `esi_reader`.
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace esi {

struct EsiEntry {
    uint8_t subindex = 0;
    std::string name;
    std::string type;  // ESI type name (UINT, DINT, STRING(6), ...); an enumerated type's base type
    // An enumerated type's named values (DataType/EnumInfo: Enum, Text); empty otherwise.
    std::vector<std::pair<int64_t, std::string>> enumeration;
    uint16_t bit_size = 0;
    uint16_t bit_offset = 0;
    std::string access;              // ro, rw, wo
    std::string write_restrictions;  // e.g. PreOP
    std::string pdo_mapping;         // "", R, T, RT, TR
    bool backup = false;
    bool setting = false;
    std::vector<uint8_t> default_data;  // little-endian bytes, empty if not given
    std::optional<int64_t> min, max, default_value;
};

struct EsiObject {
    uint16_t index = 0;
    std::string name;
    std::string type;
    uint16_t bit_size = 0;
    uint8_t object_code = 7;        // 7 VAR, 8 ARRAY, 9 RECORD
    std::vector<EsiEntry> entries;  // VAR: one entry, subindex 0
    uint8_t max_subindex() const;
    const EsiEntry* entry(uint8_t sub) const;
};

struct EsiSm {
    uint16_t start = 0;
    uint16_t default_size = 0;
    std::optional<uint32_t> min_size, max_size;  // MinSize/MaxSize attributes, if given
    uint8_t control = 0;
    bool enable = false;
    std::string type;  // MBoxOut, MBoxIn, Outputs, Inputs
};

struct EsiPdoEntry {
    uint16_t index = 0;
    uint8_t subindex = 0;
    uint8_t bit_len = 0;
    std::string name;
    std::string data_type;
};

struct EsiPdo {
    bool rx = false;  // RxPdo (outputs) or TxPdo
    uint16_t index = 0;
    int sm = -1;  // Sm attribute: assigned by default to this SM, -1 none
    bool fixed = false;
    bool mandatory = false;
    std::string name;
    std::vector<uint16_t> exclude;
    std::vector<EsiPdoEntry> entries;
    unsigned bits() const;
};

struct EsiOpMode {
    std::string name;
    uint16_t assign_activate = 0;
    uint32_t cycle_time_sync0 = 0;
    int32_t shift_time_sync0 = 0;
};

struct EsiCoe {
    bool present = false;
    bool sdo_info = false, pdo_assign = false, pdo_config = false, pdo_upload = false,
         complete_access = false;
    bool segmented_sdo = true;
};

// Info/VendorSpecific/TwinCAT/AlternativeSmMapping: a predefined PDO set.
struct EsiPdoSet {
    std::string name;
    bool is_default = false;
    std::map<int, std::vector<uint16_t>> sms;  // SyncManager number -> PDOs
};

struct EsiDevice {
    uint32_t vendor_id = 0;
    std::string vendor_name;
    uint32_t product_code = 0;
    uint32_t revision = 0;
    std::string type_name;  // <Type> text (order number)
    std::vector<EsiPdoSet> pdo_sets;
    std::string name;
    std::string group_type;
    std::optional<uint32_t> profile_no;
    std::map<uint16_t, EsiObject> objects;
    std::vector<std::string> fmmus;
    std::vector<EsiSm> sms;
    std::vector<EsiPdo> rxpdos, txpdos;
    bool has_mailbox = false;
    EsiCoe coe;
    std::map<std::string, bool> coe_attributes;  // every boolean attribute of Mailbox/CoE as written
    std::optional<uint32_t> mailbox_request_timeout_ms, mailbox_response_timeout_ms;  // Info/Mailbox/Timeout
    bool foe = false, eoe = false, soe = false, aoe = false, voe = false;
    bool has_dc = false;
    std::vector<EsiOpMode> op_modes;
    uint32_t eeprom_bytes = 0;
    std::vector<uint8_t> config_data;  // Eeprom/ConfigData (SII words 0..6)
    std::vector<uint8_t> bootstrap;    // Eeprom/BootStrap (SII words 0x14..0x17)
    bool identification_reg134 = false;
    std::map<uint16_t, std::string> diag_messages;  // Profile/DiagMessages: TextId -> MessageText
    std::vector<uint8_t> image16x14;                // ImageData16x14, empty if none

    const EsiObject* object(uint16_t index) const;
    const EsiPdo* pdo(uint16_t index) const;  // an RxPdo or TxPdo
    // SII word 0x1C bits the Mailbox element announces (AoE 1, EoE 2, CoE 4, FoE 8, SoE 0x10, VoE 0x20).
    uint16_t mailbox_protocols() const;
};

struct EsiFile {
    uint32_t vendor_id = 0;
    std::string vendor_name;
    std::vector<EsiDevice> devices;
};

// The largest ESI file read (vendor files with many devices run to a few MiB).
constexpr std::size_t kMaxEsiBytes = std::size_t{32} << 20;

// Reads the file; throws std::runtime_error with a readable message if it is not an EtherCATInfo file
// (or not a regular file of at most kMaxEsiBytes, or a document with a DOCTYPE: vendor XML is untrusted,
// see esi_reader.cpp).
EsiFile read_esi_file(const std::string& path);
EsiFile read_esi_text(const std::string& xml);
// The first device of an ESI text (throws as read_esi_text does).
EsiDevice read_esi(const std::string& xml);

// "#x1A00" / "0x1a00" / "6656" -> number; nullopt if not a number.
std::optional<int64_t> parse_esi_number(const std::string& text);
// Size in bits of a basic ESI type name (BOOL 1, USINT 8, ..., STRING(n) 8n), 0 if unknown.
unsigned esi_basic_bits(const std::string& type);
// CoE data type index (ETG.1000.6 basic data types: BOOL 0x0001, SINT 0x0002, ...), 0 if not basic.
uint16_t esi_coe_type(const std::string& type);

}  // namespace esi
