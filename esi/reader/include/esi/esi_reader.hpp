#pragma once
// The ESI (ETG.2000 EtherCATInfo XML) reader: what a device description promises, read with libxml2 into
// plain structures. Independent of the slave's object model (od/): it reads any vendor's ESI file, so the
// conformance suite can be pointed at slaves that are not part of this project, and the tests compare our
// generated ESI with the object model it came from. Target `esi_reader`.
#include <cstdint>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace esi {

// A bad ESI file: "FILE:LINE: message", or "FILE: message" when no line is to blame (a file that cannot be
// read, a device spec that matches nothing). Every error the reader and the device loader (esi/device)
// throw is one of these; a program turns it into exit status 2.
class InputError : public std::runtime_error {
  public:
    InputError(const std::string& file, int line, const std::string& message)
        : std::runtime_error(text(file, line, message)), file_(file), line_(line) {}
    const std::string& file() const { return file_; }
    int line() const { return line_; }  // 1-based; 0 if not tied to a line

  private:
    static std::string text(const std::string& file, int line, const std::string& message) {
        std::string t = file;
        if (line > 0) {
            t += ':';
            t += std::to_string(line);
        }
        t += ": ";
        t += message;
        return t;
    }
    std::string file_;
    int line_ = 0;
};

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
    std::string read_restrictions;   // e.g. PreOP_SafeOP
    std::string pdo_mapping;         // "", R, T, RT, TR
    bool backup = false;
    bool setting = false;
    std::vector<uint8_t> default_data;        // little-endian bytes, empty if not given
    bool default_is_string = false;           // default_data came from DefaultString (text, not hex)
    std::vector<uint8_t> min_data, max_data;  // MinData/MaxData, little-endian bytes
    std::optional<int64_t> min, max, default_value;
    std::optional<uint32_t> unit;  // Info/Unit (ETG.1004 unit code)
    // The ESI type name as the object or SubItem wrote it (before an enumerated type was resolved to its
    // base), and whether it is a type the file defines or a basic type (false: an undefined type).
    std::string declared_type;
    bool type_known = true;
    int line = 0;  // of the SubItem (or Object) that declares the entry
};

struct EsiObject {
    uint16_t index = 0;
    std::string name;
    std::string type;
    uint16_t bit_size = 0;
    uint8_t object_code = 7;             // 7 VAR, 8 ARRAY, 9 RECORD
    std::optional<uint16_t> type_index;  // DataType/Index of a structured type, if the file gives it
    std::vector<EsiEntry> entries;       // VAR: one entry, subindex 0
    bool depend_on_slot = false;  // a module's object: Index DependOnSlot (the slot's increment is added)
    int line = 0;
    uint8_t max_subindex() const;
    const EsiEntry* entry(uint8_t sub) const;
};

struct EsiSm {
    uint16_t start = 0;
    uint16_t default_size = 0;
    std::optional<uint32_t> min_size, max_size;  // MinSize/MaxSize attributes, if given
    uint8_t control = 0;
    bool has_control = false;  // ControlByte given
    bool enable = false;
    bool watchdog = false;  // Watchdog attribute
    bool is_virtual = false;
    std::string type;  // MBoxOut, MBoxIn, Outputs, Inputs
    int line = 0;
};

struct EsiPdoEntry {
    uint16_t index = 0;
    uint8_t subindex = 0;
    uint8_t bit_len = 0;
    std::string name;
    std::string data_type;
    bool depend_on_slot = false;  // Index DependOnSlot
    int line = 0;
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
    bool is_virtual = false;      // Virtual attribute
    bool depend_on_slot = false;  // Index DependOnSlot
    // OverwrittenByModule (ETG.2000 PdoType): a module of the configuration may bring a PDO of this index,
    // which then takes this one's place.
    bool overwritten_by_module = false;
    int line = 0;
    unsigned bits() const;
};

struct EsiOpMode {
    std::string name;
    std::string desc;
    uint16_t assign_activate = 0;
    uint32_t cycle_time_sync0 = 0;
    std::optional<int32_t> cycle_time_sync0_factor;  // CycleTimeSync0 Factor
    int32_t shift_time_sync0 = 0;
    bool has_sync1 = false;  // CycleTimeSync1 or ShiftTimeSync1 given
    uint32_t cycle_time_sync1 = 0;
    std::optional<int32_t> cycle_time_sync1_factor;  // CycleTimeSync1 Factor
    int32_t shift_time_sync1 = 0;
    int line = 0;
};

// Slots/Slot: one place of a modular device and the modules it takes (ModuleIdent, the Default one).
// Slot/ModuleClass: the slot takes any module whose Type ModuleClass is this class (of this vendor, when
// given; a module's vendor is its file's).
struct EsiModuleClass {
    std::string class_name;             // Class
    std::optional<uint32_t> vendor_id;  // VendorId
    std::string name;                   // Name (the English one where a file gives several languages)
};

struct EsiSlot {
    std::string name;
    uint32_t min_instances = 0, max_instances = 0;
    std::vector<uint32_t> module_idents;
    std::vector<EsiModuleClass> module_classes;  // instead of module_idents (ETG.2000 SlotType is a choice)
    std::optional<uint32_t> default_module;      // ModuleIdent with Default="1"
    std::optional<uint32_t> pdo_increment, index_increment;  // SlotPdoIncrement / SlotIndexIncrement
    int line = 0;
    // A Slot element stands for up to MaxInstances slots in a row (ETG.2000 SlotType; a coupler's one
    // "Terminals" slot with MaxInstances 64 takes 64 modules): EsiDevice::slots holds one entry per slot,
    // `instance` counting the entries of one element from 0 (the ESI written back has the element once).
    uint32_t instance = 0;
};

// The most slots a device is given (ETG.5001.1: the module ident lists 0xF030/0xF050 have 254 entries).
constexpr std::size_t kMaxSlots = 254;

// Descriptions/Modules/Module: what a slot of a modular device can hold.
struct EsiModule {
    uint32_t ident = 0;  // Type ModuleIdent
    std::string type_name;
    std::string module_class;  // Type ModuleClass ("": none)
    std::string name;
    std::vector<EsiPdo> rxpdos, txpdos;
    std::map<uint16_t, EsiObject> objects;  // Profile/Dictionary/Objects (base indices)
    int line = 0;
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

// Profile/DiagMessages/DiagMessage (ETG.2000): a diagnosis text the device's 0x10F3 messages refer to by
// text id (ETG.1020).
struct EsiDiagMessage {
    uint16_t text_id = 0;
    std::string text;        // MessageText, the English one (LcId 1033) if there is one, else the first
    std::string diag_class;  // Flags/DiagClass ("error", "warning", "information"); empty if not given
};

struct EsiDevice {
    uint32_t vendor_id = 0;
    std::string vendor_name;
    uint32_t product_code = 0;
    uint32_t revision = 0;
    // Type/@ProductCode is optional in ETG.2000: a device without one has no EtherCAT slave controller (a
    // passive terminal of an E-Bus station: end, shield, potential feed terminals). Nothing of it is on the
    // wire, so it cannot be served (load_product refuses it, naming its line).
    bool has_product_code = true;
    std::string type_name;  // <Type> text (order number)
    std::vector<EsiPdoSet> pdo_sets;
    std::string name;  // Name with LcId 1033 (English) if given, else the first Name
    std::string group_type;
    std::string group_name;  // the Group's Name (LcId 1033 if given)
    std::optional<uint32_t> profile_no;
    std::optional<uint32_t> profile_add_info;
    bool has_dictionary = false;  // Profile/Dictionary present
    std::map<uint16_t, EsiObject> objects;
    std::vector<std::string> fmmus;
    std::vector<EsiSm> sms;
    std::vector<EsiSlot> slots;                                 // Slots/Slot, in order
    uint32_t slot_pdo_increment = 0, slot_index_increment = 0;  // Slots attributes (a Slot may override)
    // Slots DownloadModuleIdentList: the configuration tool writes the configured module ident list
    // (0xF030) to the device, which compares it with the modules it detected (0xF050; ETG.5001.1).
    bool download_module_ident_list = false;
    std::vector<std::string> unsupported;  // elements present that a reader of this structure ignores
    std::vector<EsiPdo> rxpdos, txpdos;
    bool has_mailbox = false;
    EsiCoe coe;
    std::map<std::string, bool> coe_attributes;  // every boolean attribute of Mailbox/CoE as written
    std::optional<uint32_t> mailbox_request_timeout_ms, mailbox_response_timeout_ms;  // Info/Mailbox/Timeout
    bool foe = false, eoe = false, soe = false, aoe = false, voe = false;
    bool mailbox_data_link_layer = false;
    bool has_dc = false;
    std::vector<EsiOpMode> op_modes;
    uint32_t eeprom_bytes = 0;
    std::vector<uint8_t> config_data;  // Eeprom/ConfigData (SII words 0..6)
    std::vector<uint8_t> bootstrap;    // Eeprom/BootStrap (SII words 0x14..0x17)
    std::vector<uint8_t> eeprom_data;  // Eeprom/Data: the whole EEPROM content, if the file gives it
    bool has_eeprom = false;
    int line = 0;  // of the Device element
    int eeprom_line = 0;
    bool identification_reg134 = false;
    // Info/IdentificationAdo: the ESC register that holds the device identification (a master reads it
    // there; SII General flag IdentPhyM and bytes 18-19).
    std::optional<uint16_t> identification_ado;
    std::optional<int32_t> ebus_current_ma;     // Info/Electrical/EBusCurrent (negative: the device feeds)
    std::optional<std::string> physics;         // the Physics attribute as written (blanks kept), if any
    std::vector<EsiDiagMessage> diag_messages;  // Profile/DiagMessages, in file order
    std::vector<uint8_t> image16x14;            // ImageData16x14, empty if none

    const EsiObject* object(uint16_t index) const;
    const EsiPdo* pdo(uint16_t index) const;  // an RxPdo or TxPdo
    // SII word 0x1C bits the Mailbox element announces (AoE 1, EoE 2, CoE 4, FoE 8, SoE 0x10, VoE 0x20).
    uint16_t mailbox_protocols() const;
};

// An InfoReference of the file (ETG.2000 EtherCATInfo/InfoReference: another file that belongs to the
// description; vendors of modular devices keep the modules the slots take in an EtherCATModule file named so,
// e.g. "Modules\Io.xml") and what became of it. read_esi_file reads it relative to the ESI's directory
// (docs/decisions/esi.md, "InfoReference").
struct EsiInfoReference {
    std::string reference;    // as written
    int line = 0;             // of the InfoReference element
    std::string resolved;     // the file read; empty if none was
    std::size_t modules = 0;  // modules taken from it (a module the file has itself is not replaced)
    std::string problem;      // why no module was taken; empty if the file was read
};

struct EsiFile {
    std::string source;  // the path (or name) messages give
    uint32_t vendor_id = 0;
    std::string vendor_name;
    std::vector<EsiDevice> devices;
    std::vector<EsiModule> modules;  // Descriptions/Modules, then those of the files InfoReference names
    std::vector<EsiInfoReference> info_references;
    const EsiModule* module(uint32_t ident) const;
};

// The largest ESI file read (vendor files with many devices run to a few MiB).
constexpr std::size_t kMaxEsiBytes = std::size_t{32} << 20;

// Reads the file; throws InputError ("FILE:LINE: message") if it is not an EtherCATInfo file (or not a
// regular file of at most kMaxEsiBytes, or a document with a DOCTYPE: vendor XML is untrusted, see
// esi_reader.cpp). Any encoding the XML declaration names that libxml2 knows (UTF-8, ISO-8859-1, ...) and a
// UTF-8 byte order mark are accepted; the strings read are UTF-8.
EsiFile read_esi_file(const std::string& path);
// `name` names the text in messages.
EsiFile read_esi_text(const std::string& xml, const std::string& name = "esi.xml");
// The first device of an ESI text (throws as read_esi_text does).
EsiDevice read_esi(const std::string& xml);

// The device of a file that a slave of this identity is (the SII's words 0x0A/0x0C, or 0x1018:02/:03;
// ETG.2000 Device/Type ProductCode and RevisionNo): the one with the product code and the revision; without a
// revision, or when no device of the product code has it, the one of the product code with the highest
// revision (revision_matched false: a later revision of a device describes the earlier ones' objects too, as
// far as any does). device is nullptr when no device has the product code; with_product counts those that do.
struct DeviceByIdentity {
    const EsiDevice* device = nullptr;
    bool revision_matched = false;
    std::size_t with_product = 0;
};
DeviceByIdentity find_device(const EsiFile& file, uint32_t product_code, std::optional<uint32_t> revision);
// The devices whose Type text is `type` (exactly; when none is, in any case), in file order.
std::vector<const EsiDevice*> find_devices_by_type(const EsiFile& file, const std::string& type);

// "#x1A00" / "0x1a00" / "6656" -> number; nullopt if not a number.
std::optional<int64_t> parse_esi_number(const std::string& text);
// Size in bits of a basic ESI type name (BOOL 1, USINT 8, ..., STRING(n) 8n), 0 if unknown.
unsigned esi_basic_bits(const std::string& type);
// CoE data type index (ETG.1000.6 basic data types: BOOL 0x0001, SINT 0x0002, ...), 0 if not basic.
uint16_t esi_coe_type(const std::string& type);

}  // namespace esi
