// The ESI reader (ETG.2000 EtherCATInfo, see esi/esi_reader.hpp) on libxml2's tree API.
#include "esi/esi_reader.hpp"

#include <libxml/parser.h>
#include <libxml/tree.h>

#include <algorithm>
#include <cctype>
#include <memory>
#include <stdexcept>

#include "util/input_file.hpp"

namespace esi {

namespace {

using Node = xmlNode*;

std::string name_of(Node n) {
    return n && n->name ? reinterpret_cast<const char*>(n->name) : "";
}
bool is(Node n, const char* name) {
    return n && n->type == XML_ELEMENT_NODE && name_of(n) == name;
}
Node child(Node n, const char* name) {
    if (!n) return nullptr;
    for (Node c = n->children; c; c = c->next)
        if (is(c, name)) return c;
    return nullptr;
}
std::vector<Node> children(Node n, const char* name) {
    std::vector<Node> out;
    if (!n) return out;
    for (Node c = n->children; c; c = c->next)
        if (is(c, name)) out.push_back(c);
    return out;
}
std::string text(Node n) {
    if (!n) return "";
    xmlChar* t = xmlNodeGetContent(n);
    std::string s = t ? reinterpret_cast<const char*>(t) : "";
    xmlFree(t);
    auto b = s.find_first_not_of(" \t\r\n");
    auto e = s.find_last_not_of(" \t\r\n");
    return b == std::string::npos ? "" : s.substr(b, e - b + 1);
}
std::string text(Node n, const char* name) {
    return text(child(n, name));
}
std::string attr(Node n, const char* name) {
    if (!n) return "";
    xmlChar* v = xmlGetProp(n, reinterpret_cast<const xmlChar*>(name));
    std::string s = v ? reinterpret_cast<const char*>(v) : "";
    xmlFree(v);
    return s;
}
int64_t number(const std::string& s, int64_t fallback = 0) {
    return parse_esi_number(s).value_or(fallback);
}
bool truthy(const std::string& s) {
    return s == "1" || s == "true";
}
std::vector<uint8_t> hex_bytes(const std::string& s) {
    std::vector<uint8_t> out;
    for (std::size_t i = 0; i + 1 < s.size(); i += 2) {
        auto h = [](char c) -> int {
            if (c >= '0' && c <= '9') return c - '0';
            c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
            if (c >= 'a' && c <= 'f') return c - 'a' + 10;
            return -1;
        };
        int a = h(s[i]), b = h(s[i + 1]);
        if (a < 0 || b < 0) return {};
        out.push_back(static_cast<uint8_t>(a * 16 + b));
    }
    return out;
}

struct DataType {
    std::string name, base;
    unsigned bits = 0;
    bool array = false;
    int64_t lbound = 0, elements = 0;
    struct Sub {
        int subidx = -1;
        std::string name, type, access, write_restrictions, pdo_mapping;
        unsigned bits = 0, offs = 0;
        bool backup = false, setting = false;
    };
    std::vector<Sub> subs;
    std::vector<std::pair<int64_t, std::string>> enums;  // EnumInfo
};

// An entry of an enumerated type (a DataType with BaseType and EnumInfo) gets the base type and the values.
void resolve_enum(EsiEntry& e, const std::map<std::string, DataType>& types) {
    auto it = types.find(e.type);
    if (it == types.end() || it->second.enums.empty() || it->second.base.empty()) return;
    e.enumeration = it->second.enums;
    e.type = it->second.base;
}

void read_flags(Node flags, std::string& access, std::string& restrictions, std::string& pdo, bool& backup,
                bool& setting) {
    if (!flags) return;
    if (Node a = child(flags, "Access")) {
        access = text(a);
        restrictions = attr(a, "WriteRestrictions");
    }
    if (Node p = child(flags, "PdoMapping")) pdo = text(p);
    if (Node b = child(flags, "Backup")) backup = truthy(text(b));
    if (Node s = child(flags, "Setting")) setting = truthy(text(s));
}

void read_info(Node info, EsiEntry& e) {
    if (!info) return;
    if (Node d = child(info, "DefaultData")) e.default_data = hex_bytes(text(d));
    if (Node d = child(info, "DefaultString")) {
        std::string s = text(d);
        e.default_data.assign(s.begin(), s.end());
    }
    if (Node d = child(info, "MinValue")) e.min = parse_esi_number(text(d));
    if (Node d = child(info, "MaxValue")) e.max = parse_esi_number(text(d));
    if (Node d = child(info, "DefaultValue")) e.default_value = parse_esi_number(text(d));
}

EsiDevice read_device(Node dev, const std::map<std::string, DataType>& types_in, uint32_t vendor,
                      const std::string& vendor_name) {
    EsiDevice d;
    d.vendor_id = vendor;
    d.vendor_name = vendor_name;
    Node type = child(dev, "Type");
    d.type_name = text(type);
    d.product_code = static_cast<uint32_t>(number(attr(type, "ProductCode")));
    d.revision = static_cast<uint32_t>(number(attr(type, "RevisionNo")));
    d.name = text(dev, "Name");
    d.group_type = text(dev, "GroupType");
    d.identification_reg134 = truthy(text(child(dev, "Info"), "IdentificationReg134"));
    for (Node alt :
         children(child(child(child(dev, "Info"), "VendorSpecific"), "TwinCAT"), "AlternativeSmMapping")) {
        EsiPdoSet set;
        set.name = text(alt, "Name");
        set.is_default = truthy(attr(alt, "Default"));
        for (Node sm : children(alt, "Sm"))
            for (Node p : children(sm, "Pdo"))
                set.sms[static_cast<int>(number(attr(sm, "No")))].push_back(
                    static_cast<uint16_t>(number(text(p))));
        d.pdo_sets.push_back(std::move(set));
    }
    if (Node timeout = child(child(child(dev, "Info"), "Mailbox"), "Timeout")) {
        d.mailbox_request_timeout_ms = static_cast<uint32_t>(number(text(timeout, "RequestTimeout")));
        d.mailbox_response_timeout_ms = static_cast<uint32_t>(number(text(timeout, "ResponseTimeout")));
    }
    d.image16x14 = hex_bytes(text(dev, "ImageData16x14"));
    std::map<std::string, DataType> types = types_in;
    for (Node prof : children(dev, "Profile")) {
        if (Node p = child(prof, "ProfileNo")) d.profile_no = static_cast<uint32_t>(number(text(p)));
        for (Node m : children(child(prof, "DiagMessages"), "DiagMessage"))
            d.diag_messages[static_cast<uint16_t>(number(text(m, "TextId")))] = text(m, "MessageText");
        Node dict = child(prof, "Dictionary");
        for (Node dt : children(child(dict, "DataTypes"), "DataType")) {
            DataType t;
            t.name = text(dt, "Name");
            t.base = text(dt, "BaseType");
            t.bits = static_cast<unsigned>(number(text(dt, "BitSize")));
            if (Node ai = child(dt, "ArrayInfo")) {
                t.array = true;
                t.lbound = number(text(ai, "LBound"));
                t.elements = number(text(ai, "Elements"));
            }
            for (Node en : children(dt, "EnumInfo"))
                t.enums.emplace_back(number(text(en, "Enum")), text(en, "Text"));
            for (Node si : children(dt, "SubItem")) {
                DataType::Sub s;
                if (Node x = child(si, "SubIdx")) s.subidx = static_cast<int>(number(text(x)));
                s.name = text(si, "Name");
                s.type = text(si, "Type");
                s.bits = static_cast<unsigned>(number(text(si, "BitSize")));
                s.offs = static_cast<unsigned>(number(text(si, "BitOffs")));
                read_flags(child(si, "Flags"), s.access, s.write_restrictions, s.pdo_mapping, s.backup,
                           s.setting);
                t.subs.push_back(s);
            }
            types[t.name] = t;
        }
        for (Node ob : children(child(dict, "Objects"), "Object")) {
            EsiObject o;
            o.index = static_cast<uint16_t>(number(text(ob, "Index")));
            o.name = text(ob, "Name");
            o.type = text(ob, "Type");
            o.bit_size = static_cast<uint16_t>(number(text(ob, "BitSize")));
            std::string oaccess, orestr, opdo;
            bool obackup = false, osetting = false;
            read_flags(child(ob, "Flags"), oaccess, orestr, opdo, obackup, osetting);
            Node info = child(ob, "Info");
            auto it = types.find(o.type);
            if (it == types.end() || it->second.subs.empty()) {
                EsiEntry e;
                e.name = o.name;
                e.type = o.type;
                e.bit_size = o.bit_size;
                e.access = oaccess;
                e.write_restrictions = orestr;
                e.pdo_mapping = opdo;
                e.backup = obackup;
                e.setting = osetting;
                read_info(info, e);
                resolve_enum(e, types);
                o.type = e.type;  // a VAR of an enumerated type: its base type
                o.entries.push_back(e);
            } else {
                const DataType& t = it->second;
                // An array object: SubIndex 0 plus one SubItem whose type is an ArrayInfo type.
                bool array = false;
                for (const auto& s : t.subs) {
                    auto at = types.find(s.type);
                    if (s.subidx < 0 && at != types.end() && at->second.array) {
                        array = true;
                        for (int64_t k = 0; k < at->second.elements; ++k) {
                            EsiEntry e;
                            e.subindex = static_cast<uint8_t>(at->second.lbound + k);
                            e.name = s.name;
                            e.type = at->second.base;
                            e.bit_size = static_cast<uint16_t>(
                                at->second.elements
                                    ? at->second.bits / static_cast<unsigned>(at->second.elements)
                                    : 0);
                            e.bit_offset = static_cast<uint16_t>(s.offs + k * e.bit_size);
                            e.access = s.access;
                            e.write_restrictions = s.write_restrictions;
                            e.pdo_mapping = s.pdo_mapping;
                            e.backup = s.backup;
                            e.setting = s.setting;
                            o.entries.push_back(e);
                        }
                    } else {
                        EsiEntry e;
                        e.subindex = static_cast<uint8_t>(s.subidx < 0 ? 0 : s.subidx);
                        e.name = s.name;
                        e.type = s.type;
                        e.bit_size = static_cast<uint16_t>(s.bits);
                        e.bit_offset = static_cast<uint16_t>(s.offs);
                        e.access = s.access;
                        e.write_restrictions = s.write_restrictions;
                        e.pdo_mapping = s.pdo_mapping;
                        e.backup = s.backup;
                        e.setting = s.setting;
                        resolve_enum(e, types);
                        o.entries.push_back(e);
                    }
                }
                o.object_code = array ? 8 : 9;
                // Object/Info/SubItem i describes the i-th entry (defaults, limits).
                auto infos = children(info, "SubItem");
                for (std::size_t i = 0; i < infos.size() && i < o.entries.size(); ++i)
                    read_info(child(infos[i], "Info"), o.entries[i]);
            }
            d.objects[o.index] = std::move(o);
        }
    }
    for (Node f : children(dev, "Fmmu"))
        d.fmmus.push_back(text(f));
    for (Node s : children(dev, "Sm")) {
        EsiSm sm;
        sm.start = static_cast<uint16_t>(number(attr(s, "StartAddress")));
        sm.default_size = static_cast<uint16_t>(number(attr(s, "DefaultSize")));
        if (auto v = parse_esi_number(attr(s, "MinSize"))) sm.min_size = static_cast<uint32_t>(*v);
        if (auto v = parse_esi_number(attr(s, "MaxSize"))) sm.max_size = static_cast<uint32_t>(*v);
        sm.control = static_cast<uint8_t>(number(attr(s, "ControlByte")));
        sm.enable = truthy(attr(s, "Enable"));
        sm.type = text(s);
        d.sms.push_back(sm);
    }
    auto read_pdos = [&](const char* tag, std::vector<EsiPdo>& out) {
        for (Node p : children(dev, tag)) {
            EsiPdo pdo;
            pdo.rx = &out == &d.rxpdos;
            pdo.index = static_cast<uint16_t>(number(text(p, "Index")));
            std::string sm = attr(p, "Sm");
            if (!sm.empty()) pdo.sm = static_cast<int>(number(sm));
            pdo.fixed = truthy(attr(p, "Fixed"));
            pdo.mandatory = truthy(attr(p, "Mandatory"));
            pdo.name = text(p, "Name");
            for (Node x : children(p, "Exclude"))
                pdo.exclude.push_back(static_cast<uint16_t>(number(text(x))));
            for (Node e : children(p, "Entry")) {
                EsiPdoEntry pe;
                pe.index = static_cast<uint16_t>(number(text(e, "Index")));
                pe.subindex = static_cast<uint8_t>(number(text(e, "SubIndex")));
                pe.bit_len = static_cast<uint8_t>(number(text(e, "BitLen")));
                pe.name = text(e, "Name");
                pe.data_type = text(e, "DataType");
                pdo.entries.push_back(pe);
            }
            out.push_back(pdo);
        }
    };
    read_pdos("RxPdo", d.rxpdos);
    read_pdos("TxPdo", d.txpdos);
    if (Node mb = child(dev, "Mailbox")) {
        d.has_mailbox = true;
        if (Node c = child(mb, "CoE")) {
            d.coe.present = true;
            d.coe.sdo_info = truthy(attr(c, "SdoInfo"));
            d.coe.pdo_assign = truthy(attr(c, "PdoAssign"));
            d.coe.pdo_config = truthy(attr(c, "PdoConfig"));
            d.coe.pdo_upload = truthy(attr(c, "PdoUpload"));
            d.coe.complete_access = truthy(attr(c, "CompleteAccess"));
            std::string seg = attr(c, "SegmentedSdo");
            d.coe.segmented_sdo = seg.empty() || truthy(seg);
            for (xmlAttr* a = c->properties; a != nullptr; a = a->next) {
                const std::string v = attr(c, reinterpret_cast<const char*>(a->name));
                if (v == "true" || v == "false" || v == "1" || v == "0")
                    d.coe_attributes[reinterpret_cast<const char*>(a->name)] = truthy(v);
            }
        }
        d.foe = child(mb, "FoE") != nullptr;
        d.eoe = child(mb, "EoE") != nullptr;
        d.soe = child(mb, "SoE") != nullptr;
        d.aoe = child(mb, "AoE") != nullptr;
        d.voe = child(mb, "VoE") != nullptr;
    }
    if (Node dc = child(dev, "Dc")) {
        d.has_dc = true;
        for (Node om : children(dc, "OpMode")) {
            EsiOpMode m;
            m.name = text(om, "Name");
            m.assign_activate = static_cast<uint16_t>(number(text(om, "AssignActivate")));
            m.cycle_time_sync0 = static_cast<uint32_t>(number(text(om, "CycleTimeSync0")));
            m.shift_time_sync0 = static_cast<int32_t>(number(text(om, "ShiftTimeSync0")));
            d.op_modes.push_back(m);
        }
    }
    if (Node ee = child(dev, "Eeprom")) {
        d.eeprom_bytes = static_cast<uint32_t>(number(text(ee, "ByteSize")));
        d.config_data = hex_bytes(text(ee, "ConfigData"));
        d.bootstrap = hex_bytes(text(ee, "BootStrap"));
    }
    return d;
}

EsiFile read_doc(xmlDoc* doc) {
    std::unique_ptr<xmlDoc, void (*)(xmlDoc*)> guard(doc, xmlFreeDoc);
    if (!doc) throw std::runtime_error("not well-formed XML");
    Node root = xmlDocGetRootElement(doc);
    if (!is(root, "EtherCATInfo")) throw std::runtime_error("root element is not EtherCATInfo");
    EsiFile f;
    f.vendor_id = static_cast<uint32_t>(number(text(child(root, "Vendor"), "Id")));
    f.vendor_name = text(child(root, "Vendor"), "Name");
    Node desc = child(root, "Descriptions");
    std::map<std::string, DataType> none;
    for (Node dev : children(child(desc, "Devices"), "Device"))
        f.devices.push_back(read_device(dev, none, f.vendor_id, f.vendor_name));
    if (f.devices.empty()) throw std::runtime_error("no Device in Descriptions/Devices");
    return f;
}

}  // namespace

std::optional<int64_t> parse_esi_number(const std::string& t) {
    if (t.empty()) return std::nullopt;
    std::string s = t;
    bool neg = false;
    if (s[0] == '-') {
        neg = true;
        s = s.substr(1);
    }
    int base = 10;
    if (s.size() > 2 && (s.rfind("#x", 0) == 0 || s.rfind("0x", 0) == 0 || s.rfind("0X", 0) == 0)) {
        base = 16;
        s = s.substr(2);
    }
    if (s.empty()) return std::nullopt;
    uint64_t v = 0;
    for (char c : s) {
        int d;
        if (c >= '0' && c <= '9')
            d = c - '0';
        else if (base == 16 && std::isxdigit(static_cast<unsigned char>(c)))
            d = std::tolower(static_cast<unsigned char>(c)) - 'a' + 10;
        else
            return std::nullopt;
        v = v * static_cast<uint64_t>(base) + static_cast<uint64_t>(d);
    }
    return neg ? -static_cast<int64_t>(v) : static_cast<int64_t>(v);
}

unsigned esi_basic_bits(const std::string& t) {
    static const std::map<std::string, unsigned> m = {
        {"BOOL", 1},  {"BIT", 1},    {"SINT", 8},   {"USINT", 8},  {"BYTE", 8},   {"INT", 16},
        {"UINT", 16}, {"WORD", 16},  {"DINT", 32},  {"UDINT", 32}, {"DWORD", 32}, {"REAL", 32},
        {"LINT", 64}, {"ULINT", 64}, {"LWORD", 64}, {"LREAL", 64}, {"INT24", 24}, {"UINT24", 24}};
    if (auto it = m.find(t); it != m.end()) return it->second;
    if (t.size() > 3 && t.rfind("BIT", 0) == 0) return static_cast<unsigned>(number(t.substr(3)));
    if (t.rfind("STRING(", 0) == 0) return 8 * static_cast<unsigned>(number(t.substr(7, t.size() - 8)));
    return 0;
}

uint16_t esi_coe_type(const std::string& t) {
    static const std::map<std::string, uint16_t> m = {
        {"BOOL", 0x0001},  {"SINT", 0x0002},   {"INT", 0x0003},   {"DINT", 0x0004},  {"USINT", 0x0005},
        {"UINT", 0x0006},  {"UDINT", 0x0007},  {"REAL", 0x0008},  {"INT24", 0x0010}, {"LREAL", 0x0011},
        {"LINT", 0x0015},  {"UINT24", 0x0016}, {"ULINT", 0x001B}, {"BYTE", 0x001E},  {"WORD", 0x001F},
        {"DWORD", 0x0020}, {"BIT1", 0x0030},   {"BIT2", 0x0031},  {"BIT3", 0x0032},  {"BIT4", 0x0033},
        {"BIT5", 0x0034},  {"BIT6", 0x0035},   {"BIT7", 0x0036},  {"BIT8", 0x0037}};
    if (auto it = m.find(t); it != m.end()) return it->second;
    if (t.rfind("STRING(", 0) == 0) return 0x0009;
    return 0;
}

uint8_t EsiObject::max_subindex() const {
    uint8_t m = 0;
    for (const auto& e : entries)
        m = std::max(m, e.subindex);
    return m;
}

const EsiEntry* EsiObject::entry(uint8_t sub) const {
    for (const auto& e : entries)
        if (e.subindex == sub) return &e;
    return nullptr;
}

unsigned EsiPdo::bits() const {
    unsigned b = 0;
    for (const auto& e : entries)
        b += e.bit_len;
    return b;
}

const EsiObject* EsiDevice::object(uint16_t index) const {
    auto it = objects.find(index);
    return it == objects.end() ? nullptr : &it->second;
}

const EsiPdo* EsiDevice::pdo(uint16_t index) const {
    for (const auto* list : {&rxpdos, &txpdos})
        for (const EsiPdo& p : *list)
            if (p.index == index) return &p;
    return nullptr;
}

uint16_t EsiDevice::mailbox_protocols() const {
    uint16_t p = 0;
    if (aoe) p |= 0x01;
    if (eoe) p |= 0x02;
    if (coe.present) p |= 0x04;
    if (foe) p |= 0x08;
    if (soe) p |= 0x10;
    if (voe) p |= 0x20;
    return p;
}

namespace {

// Vendor XML is untrusted input (docs/robustness.md): parsed from memory (the file read through the one
// bounded reader), no network (XML_PARSE_NONET), no external DTD (no XML_PARSE_DTDLOAD), no entity
// substitution (no XML_PARSE_NOENT), libxml2's own limits on depth and entity amplification kept (no
// XML_PARSE_HUGE); a document with a DOCTYPE is refused altogether: ETG.2000 files carry none, and an
// entity reference left in the tree would still be expanded when its text is read.
EsiFile parse_esi(const std::string& xml, const std::string& name) {
    if (xml.size() > kMaxEsiBytes)
        throw std::runtime_error(name + ": larger than " + std::to_string(kMaxEsiBytes) +
                                 " bytes: not an ESI file");
    xmlDoc* doc = xmlReadMemory(xml.data(), static_cast<int>(xml.size()), name.c_str(), nullptr,
                                XML_PARSE_NONET | XML_PARSE_NOERROR | XML_PARSE_NOWARNING);
    if (doc != nullptr && (doc->intSubset != nullptr || doc->extSubset != nullptr)) {
        xmlFreeDoc(doc);
        throw std::runtime_error(name +
                                 ": a DOCTYPE (DTD or entity declarations) is not allowed in an ESI file");
    }
    if (doc == nullptr) throw std::runtime_error(name + ": not well-formed XML");
    return read_doc(doc);
}

}  // namespace

EsiFile read_esi_file(const std::string& path) {
    try {
        return parse_esi(util::read_input_file(path, kMaxEsiBytes, "ESI file"), path);
    } catch (const util::InputFileError& e) {
        throw std::runtime_error(e.what());
    }
}

EsiFile read_esi_text(const std::string& xml) {
    return parse_esi(xml, "esi.xml");
}

EsiDevice read_esi(const std::string& xml) {
    return read_esi_text(xml).devices.front();  // read_doc refuses a file without a device
}

}  // namespace esi
