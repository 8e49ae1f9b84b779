#pragma once
// A small ESI (EtherCATInfo XML, ETG.2000) reader that knows nothing of od/: it loads what a configuration
// tool takes from the file of one device, so tests (and tools) can compare an ESI with the object model it
// was generated from, or with a slave. Only the first Device of the file is read.
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace esi {

struct EsiPdoEntry {
    uint16_t index = 0;
    uint8_t subindex = 0;
    uint8_t bit_length = 0;
    std::string name;
    std::string data_type;
};

struct EsiPdo {
    bool rx = false;
    uint16_t index = 0;
    std::string name;
    int sm = -1;  // -1: no Sm attribute
    bool fixed = false;
    bool mandatory = false;
    std::vector<uint16_t> exclude;
    std::vector<EsiPdoEntry> entries;
};

struct EsiSm {
    std::string kind;  // MBoxOut, MBoxIn, Outputs, Inputs
    uint32_t start = 0;
    std::optional<uint32_t> default_size, min_size, max_size;
    uint32_t control = 0;
    bool enable = false;
};

struct EsiObject {
    uint16_t index = 0;
    std::string name;
    std::string type;
    uint32_t bit_size = 0;
    std::string access;  // Flags/Access of a VAR or of the object ("ro", "rw", "wo")
};

struct EsiDevice {
    uint32_t vendor_id = 0;
    std::string vendor_name;
    uint32_t product_code = 0;
    uint32_t revision = 0;
    std::string type;  // Device/Type text (order code)
    std::string name;
    std::optional<uint32_t> profile_number;
    std::vector<EsiObject> objects;
    std::map<uint16_t, std::string> diag_messages;  // TextId -> MessageText
    std::vector<EsiSm> sync_managers;
    std::vector<EsiPdo> pdos;         // RxPdo then TxPdo, in file order
    std::map<std::string, bool> coe;  // Mailbox/CoE attributes that are booleans (SdoInfo, SegmentedSdo, ...)
    bool foe = false;
    std::optional<uint32_t> mailbox_request_timeout_ms, mailbox_response_timeout_ms;
    std::vector<uint8_t> image16x14;   // ImageData16x14, empty if none
    std::vector<uint8_t> config_data;  // Eeprom/ConfigData
    uint32_t eeprom_bytes = 0;

    const EsiPdo* pdo(uint16_t index) const;
    const EsiObject* object(uint16_t index) const;
};

// Parses ESI text. Throws std::runtime_error if it is not XML, not EtherCATInfo, or has no device.
EsiDevice read_esi(const std::string& xml);

// "#x1A00" (ETG.2000 HexDecValue) or decimal; nullopt if neither.
std::optional<uint64_t> parse_hex_dec(const std::string& text);

}  // namespace esi
