#pragma once
// What a master learns about the device besides the dictionary: identity, mailbox and SyncManager layout,
// supported protocols, DC modes. Declared once here; the SII image and the ESI file (esi/), the state
// machine's checks (ecat/) and object 0x1018 all read it.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "esc/wire/sii.hpp"

namespace od {

// Empty by default: each product states its own (maxpos::description(), an ESI's Vendor and Type).
struct Identity {
    uint32_t vendor_id = 0;     // ETG vendor id (0x1018:01)
    uint32_t product_code = 0;  // 0x1018:02
    uint32_t revision = 0;      // 0x1018:03
    uint32_t serial_number = 0;
    std::string vendor_name;
    std::string device_name;       // 0x1008
    std::string hardware_version;  // 0x1009
    std::string software_version;  // 0x100A
    std::string order_code;        // ESI Type text
    std::string group_type;        // ESI group
};

struct MailboxLayout {
    uint16_t out_start = 0x1000;  // SM0, master -> slave
    uint16_t out_size = 128;
    uint16_t in_start = 0x1080;  // SM1, slave -> master
    uint16_t in_size = 128;
};

// Mailbox protocol bits (SII word 0x1C, the ESI) and CoE details bits (SII General category): the SII
// vocabulary's (esc/wire/sii.hpp).
namespace mailbox_protocol = esc::sii::mailbox_protocol;
namespace coe_details = esc::sii::coe_details;

enum class SmKind : uint8_t { MBoxOut = 1, MBoxIn = 2, Outputs = 3, Inputs = 4 };

// The SyncManager control byte (ESC register 0x0804; ETG.1000.4, ESC datasheet section "SyncManager") each
// kind gets: mailbox out 0x26 (mailbox mode, ECAT writes, PDI interrupt), mailbox in 0x22 (mailbox mode, ECAT
// reads, PDI interrupt), outputs 0x64 (3-buffer mode, ECAT writes, PDI interrupt, watchdog trigger), inputs
// 0x20 (3-buffer mode, ECAT reads, PDI interrupt).
constexpr uint8_t default_sm_control(SmKind k) {
    switch (k) {
        case SmKind::MBoxOut:
            return 0x26;
        case SmKind::MBoxIn:
            return 0x22;
        case SmKind::Outputs:
            return 0x64;
        case SmKind::Inputs:
            return 0x20;
    }
    return 0;
}

struct SyncManagerDefault {
    SmKind kind = SmKind::MBoxOut;
    uint16_t start = 0;
    uint16_t default_size = 0;  // process-data SMs: size of the default mapping
    uint8_t control = 0;        // 0x0804 control byte
    bool enable = true;
    // Lengths the device accepts for this SyncManager (ESI Sm MinSize/MaxSize; 0: not declared). Mailbox:
    // the one mailbox size the state machine checks; process data: 0 .. the room left for the largest PDO
    // set.
    uint16_t min_size = 0;
    uint16_t max_size = 0;
};

// What the ESI says about one PDO besides its mapping (ETG.2000 RxPdo/TxPdo): Mandatory (the master must
// assign it to its SyncManager) and Exclude (PDOs that must not be assigned together with it). The SDO server
// refuses a 0x1C12/0x1C13 assignment that breaks these (coe::install_pdo_validators), so the ESI and the
// slave cannot disagree. Fixed, as the SII's PdoFixedContent flag and the written ESI state it: as the PDO
// element declares it where there is one (a vendor's ESI may declare a mapping object read-only in its
// dictionary and the PDO not Fixed; its devices' EEPROMs follow the element), else from the mapping object's
// access (not writable in any state).
struct PdoRule {
    uint16_t pdo = 0;  // 0x1600.. / 0x1A00..
    bool mandatory = false;
    std::vector<uint16_t> exclude;
    std::optional<bool> fixed;  // declared by a PDO element; unset: from the mapping object's access
};

// A predefined PDO set a configuration tool offers (ESI Info/VendorSpecific/TwinCAT/AlternativeSmMapping, as
// vendors' CiA 402 drives ship one per cyclic mode): the PDOs to assign to SM2 (0x1C12) and SM3 (0x1C13).
// The set the default assignment holds is the default one.
struct PdoSet {
    std::string name;
    std::vector<uint16_t> rx;  // 0x1600..
    std::vector<uint16_t> tx;  // 0x1A00..
};

// A DC operation mode (ESI Dc/OpMode, SII DC category, ETG.2000 / ETG.2010). (New fields go at the end:
// descriptions initialise the first ones by position.)
struct DcOpMode {
    std::string name;  // "SM-Synchron", "DC"
    std::string description;
    uint16_t assign_activate = 0;  // value for 0x0980/0x0981 (e.g. 0x0300: SYNC0 + cyclic unit)
    // SYNC0 cycle: the bus cycle times cycle_time_sync0_factor, or cycle_time_sync0 ns if that is not 0.
    int32_t cycle_time_sync0_factor = 1;
    int32_t shift_time_sync0 = 0;
    uint32_t cycle_time_sync0 = 0;
    // SYNC1 (AssignActivate bit 0x0400): its cycle as a multiple of the SYNC0 cycle (cycle_time_sync1_factor,
    // 0: not declared) or cycle_time_sync1 ns, and its shift after SYNC0 in ns.
    uint32_t cycle_time_sync1 = 0;
    int32_t cycle_time_sync1_factor = 0;
    int32_t shift_time_sync1 = 0;
    bool operator==(const DcOpMode&) const = default;
};

// A modular device's slots and the modules they take (ESI Slots, Descriptions/Modules; ETG.2000), kept so
// that the ESI written back offers the same choices. The dictionary and the PDOs hold the default
// configuration (each slot's default module placed); these say where it came from.
struct ModulePdoEntry {
    uint16_t index = 0;  // 0: padding; the module's base index (before the slot's increment)
    uint8_t subindex = 0;
    uint8_t bit_length = 0;
    std::string name;
    std::string data_type;        // ESI type name ("BOOL", "INT", ...), empty for padding
    bool depend_on_slot = false;  // the slot's index increment is added
};
struct ModulePdo {
    bool rx = false;
    uint16_t index = 0;  // base index (before the slot's PDO increment)
    bool depend_on_slot = false;
    std::string name;
    int sm = -1;
    bool fixed = false;
    bool mandatory = false;
    std::vector<ModulePdoEntry> entries;
};
struct Module {
    uint32_t ident = 0;        // ModuleIdent
    std::string type;          // Type text
    std::string module_class;  // Type ModuleClass ("": none)
    std::string name;
    std::vector<ModulePdo> pdos;
};
// A class of modules a slot takes (ETG.2000 Slot/ModuleClass): any module of that class, of that vendor.
struct ModuleClass {
    std::string class_name;
    bool any_vendor = true;  // false: only vendor_id's
    uint32_t vendor_id = 0;
    std::string name;
};
struct Slot {
    std::string name;
    uint32_t min_instances = 0, max_instances = 1;
    std::vector<uint32_t> module_idents;      // the modules it takes
    std::vector<ModuleClass> module_classes;  // or the classes of modules it takes
    uint32_t default_module = 0;              // 0: empty by default
    uint32_t pdo_increment = 0, index_increment = 0;
};

// A diagnosis text of the device (ETG.2000 Profile/DiagMessages/DiagMessage; ETG.1020 diagnosis history):
// a 0x10F3 message carries the text id, the master shows the text its ESI gives for it. A product that runs
// the drive core lists the drive's (drive/wire/diag_texts.hpp); a device read from a vendor's ESI keeps the
// vendor's, and --write-esi writes back whatever is here.
struct DiagMessageText {
    uint16_t text_id = 0;  // TextId
    std::string text;      // MessageText (the English one where a file gives several languages)
    // Flags/DiagClass: "error", "warning" or "information"; empty: the file declares none.
    std::string diag_class;
    // The emergency error code (0x603F, CiA 402) whose 0x10F3 message carries this text id when the device
    // raises it (coe::EventReporter); 0: none. Not part of the ESI (a vendor file's texts have 0): a message
    // without an error code gets its id by its text.
    uint16_t error_code = 0;
    bool operator==(const DiagMessageText&) const = default;
};

struct DeviceDescription {
    Identity identity;
    MailboxLayout standard_mailbox;
    MailboxLayout bootstrap_mailbox{0x1000, 1024, 0x1400, 1024};
    uint16_t mailbox_protocols = mailbox_protocol::CoE;
    uint8_t coe_details = coe_details::Sdo | coe_details::SdoInfo | coe_details::PdoAssign |
                          coe_details::PdoConfig | coe_details::CompleteAccess;
    uint8_t foe_details = 0;
    std::vector<SyncManagerDefault> sync_managers;  // SM0..SM3 in order (none: a device without mailbox and
                                                    // process data, as a coupler)
    // The FMMUs as declared (ESI Fmmu, SII FMMU category: 1 outputs, 2 inputs, 3 mailbox state, 0 unused);
    // empty: one for each process-data direction and one for the mailbox state, as the SMs need.
    std::vector<uint8_t> fmmus;
    std::vector<DcOpMode> dc_modes;
    uint16_t eeprom_bytes = 2048;
    uint8_t pdi_control = 0x05;  // SII word 0 low: SPI (as the MAXPOS's ESC) -- see docs/decisions.md
    uint8_t esc_config = 0x0C;   // SII word 0 high: DC SYNC out and latch in units on
    uint16_t pdi_config =
        0xCC00;  // SII word 1: 0x0151 = 0xCC, SYNC0/SYNC1 driven and mapped to AL event bits 2/3 (as EJ7211)
    uint16_t sync_pulse_length = 1000;  // SII word 2, 10 ns units
    uint16_t station_alias = 0;         // SII word 4
    uint16_t extended_pdi_config = 0;   // SII word 3 (ESI ConfigData bytes 6-7)
    uint16_t config_words_5_6[2] = {};  // SII words 5-6, reserved: kept as the ESI's ConfigData gives them
    // The device profile the ESI names (Profile/ProfileNo and AddInfo, ETG.2000), which a configuration tool
    // goes by; 0: the device type 0x1000 gives it (bits 0-15 the profile number, 16-31 additional
    // information, ETG.1000.6 / CiA 301). Vendor files whose 0x1000 disagrees keep both as written.
    uint16_t profile_number = 0;
    uint16_t profile_add_info = 0;
    std::vector<PdoRule> pdo_rules;  // Mandatory / Exclude of the PDOs (empty: none)
    std::vector<PdoSet> pdo_sets;    // predefined PDO sets (empty: none)
    // Mailbox timeouts a master should use with this device (ESI Info/Mailbox/Timeout, ms): how long the
    // slave may take to take a request out of SM0 and to answer it (0: not declared).
    uint32_t mailbox_request_timeout_ms = 0;
    uint32_t mailbox_response_timeout_ms = 0;
    // What the SII General category and the ESI say of the device besides its mailbox (ETG.2010 General
    // flags, ETG.2000 Mailbox/Info): the mailbox data link layer (ESI Mailbox DataLinkLayer, flag bit 2: the
    // slave serves the SM1 repeat and drops a repeated request), the device identification in AL status
    // code 0x0134 (Info/IdentificationReg134, bit 3), or in an ESC register (Info/IdentificationAdo, bit 4
    // and bytes 18-19; 0: none), and the E-Bus current (Info/Electrical/EBusCurrent, mA, bytes 12-13). The
    // stack itself serves the repeat and the identification in 0x0134 for every device; the description says
    // what the device announces, as its vendor's EEPROM does.
    bool mailbox_data_link_layer = true;
    bool identification_al_status = true;
    // The device's ports (ETG.2000 Device Physics): one character per port 0..3, 'Y' MII (100BASE-TX), 'K'
    // E-Bus (LVDS), 'H' MII with fast hot connect, ' ' (or past the end) none. The ESC's port descriptor
    // 0x0007 and the SII General category's physical ports follow it (esi/model.hpp).
    std::string physics = "YY";
    uint16_t identification_register = 0;
    int16_t ebus_current_ma = 0;
    // A modular device (empty: not modular). The PDOs of the slots' default modules are in the dictionary.
    std::vector<Slot> slots;
    std::vector<Module> modules;
    // The device's diagnosis texts (empty: none; the ESI then has no DiagMessages).
    std::vector<DiagMessageText> diag_messages;
};

}  // namespace od
