#pragma once
// Parsing and decoding an SII EEPROM image (ETG.2010, ETG.1000.6), od-free: works on any image, ours or
// one read from a real device. Target `sii`; the builder that renders the object model is esi/sii.hpp.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "esc/wire/sii.hpp"

namespace esi {

// Category codes, PDO flags, the checksum-disabled word and the first category word are the SII wire
// vocabulary (esc/wire/sii.hpp, the ESC reads that layout); these names are kept for the reader's users.
namespace sii = esc::sii;
namespace category = sii::category;
namespace pdo_flags = sii::pdo_flags;
constexpr uint16_t kSiiChecksumDisabled = sii::kChecksumDisabled;
constexpr std::size_t kSiiFirstCategoryWord = sii::word::FirstCategory;

// Mailbox protocol bits (SII word 0x1C, the ESI) and CoE details bits (SII General category): the SII
// vocabulary's (esc/wire/sii.hpp).
namespace mailbox_protocol = sii::mailbox_protocol;
namespace coe_details = sii::coe_details;

// A mailbox's two sync managers as the SII header words 0x14-0x1B give them.
struct SiiMailbox {
    uint16_t out_start = 0;  // SM0, master -> slave
    uint16_t out_size = 0;
    uint16_t in_start = 0;  // SM1, slave -> master
    uint16_t in_size = 0;
};

// ---- Parsed content -------------------------------------------------------------------------------
struct SiiGeneral {
    uint8_t group_idx = 0, image_idx = 0, order_idx = 0, name_idx = 0;
    std::string group, image, order, name;  // resolved through the STRINGS category
    uint8_t coe_details = 0, foe_details = 0, eoe_details = 0, soe_channels = 0, ds402_channels = 0;
    uint8_t sysman_class = 0, flags = 0;
    int16_t ebus_current_ma = 0;
    uint8_t group_idx_duplicate = 0;
    uint16_t physical_ports = 0;
    uint16_t physical_memory_address = 0;
};

struct SiiSyncManager {
    uint16_t start = 0;
    uint16_t length = 0;
    uint8_t control = 0;
    uint8_t status = 0;
    uint8_t enable = 0;  // bit0 enable, bit1 fixed content, bit2 virtual, bit3 OP only
    uint8_t type = 0;    // 0 unused, 1 MBoxOut, 2 MBoxIn, 3 Outputs, 4 Inputs
};

struct SiiPdoEntry {
    uint16_t index = 0;
    uint8_t subindex = 0;
    uint8_t name_idx = 0;
    std::string name;
    uint8_t data_type = 0;  // CoE data type code
    uint8_t bit_length = 0;
    uint16_t flags = 0;
};

struct SiiPdo {
    uint16_t index = 0;
    uint8_t sm = 0xFF;  // 0xFF: not assigned by default
    uint8_t dc_sync = 0;
    uint8_t name_idx = 0;
    std::string name;
    uint16_t flags = 0;
    std::vector<SiiPdoEntry> entries;
};

struct SiiDcMode {
    uint32_t sync0_cycle_time = 0;
    int32_t sync0_shift_time = 0;
    int32_t sync1_shift_time = 0;
    int16_t sync1_cycle_factor = 0;
    uint16_t assign_activate = 0;
    int16_t sync0_cycle_factor = 0;
    uint8_t name_idx = 0, description_idx = 0;
    std::string name, description;
};

struct SiiCategory {
    uint16_t type = 0;
    std::size_t word_offset = 0;  // of the category header
    uint16_t word_length = 0;     // data words as declared
    bool truncated = false;       // the declared length runs past the end of the image
};

struct SiiInfo {
    std::size_t image_bytes = 0;
    bool header_complete = false;  // the image holds all 64 header words
    // Words 0-7
    uint8_t pdi_control = 0, esc_config = 0;
    uint16_t pdi_config = 0, sync_pulse_length = 0, extended_pdi_config = 0, station_alias = 0;
    uint16_t checksum_word = 0;
    uint8_t crc_computed = 0;
    bool crc_ok = false;        // word 7 low byte == CRC-8 of words 0-6 (or the check is disabled)
    bool crc_disabled = false;  // word 7 == 0x88A4
    // Words 8-0x3F
    uint32_t vendor_id = 0, product_code = 0, revision = 0, serial_number = 0;
    SiiMailbox bootstrap_mailbox{};
    SiiMailbox standard_mailbox{};
    uint16_t mailbox_protocols = 0;
    uint16_t eeprom_size_word = 0;  // word 0x3E: KiBit - 1
    uint16_t version = 0;
    std::size_t eeprom_bytes() const { return (std::size_t{eeprom_size_word} + 1) * 128; }
    // Categories
    std::vector<std::string> strings;  // strings[0] is string index 1
    std::optional<SiiGeneral> general;
    std::vector<uint8_t> fmmus;
    std::vector<SiiSyncManager> sync_managers;
    std::vector<SiiPdo> tx_pdos, rx_pdos;
    std::vector<SiiDcMode> dc_modes;
    std::vector<SiiCategory> categories;  // every category header found, in order (End not included)
    bool end_found = false;
    std::vector<std::string>
        problems;  // what is wrong with the image (bad CRC, truncation, bad lengths, ...)

    // 1-based string index; "" for 0 or an index past the table.
    std::string string_at(uint8_t index) const;
};

// Never throws on bad input and never reads outside the span.
SiiInfo parse_sii(std::span<const uint8_t> image);
// Readable text of any image: header, every category (unknown ones as hex), and the problems found.
std::string decode_sii(std::span<const uint8_t> image);

}  // namespace esi
