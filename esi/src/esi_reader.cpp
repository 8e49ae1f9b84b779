// The ESI reader (ETG.2000 EtherCATInfo, see esi/esi_reader.hpp) on libxml2's tree API.
#include "esi/esi_reader.hpp"

#include <libxml/parser.h>
#include <libxml/tree.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>

#include "util/input_file.hpp"
#include "xml_tree.hpp"

namespace esi {

namespace {

using xml::child;
using xml::children;
using xml::is;
using xml::name_of;
using xml::Node;
using xml::text;
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

int line_of(Node n) {
    return n ? static_cast<int>(xmlGetLineNo(n)) : 0;
}

// The Name child in English (LcId 1033) if there is one, else the first.
std::string name_text(Node n, const char* tag = "Name") {
    Node first = nullptr;
    for (Node c : children(n, tag)) {
        if (attr(c, "LcId") == "1033") return text(c);
        if (!first) first = c;
    }
    return text(first);
}

struct DataType {
    std::string name, base;
    unsigned bits = 0;
    bool array = false;
    int64_t lbound = 0, elements = 0;
    std::optional<uint16_t> index;
    struct Sub {
        int subidx = -1;
        std::string name, type, access, write_restrictions, read_restrictions, pdo_mapping;
        unsigned bits = 0, offs = 0;
        bool backup = false, setting = false;
        int line = 0;
    };
    std::vector<Sub> subs;
    std::vector<std::pair<int64_t, std::string>> enums;  // EnumInfo
};
using TypeMap = std::map<std::string, DataType>;

// A type name the reader knows without a DataType: the basic types, STRING(n), ARRAY [..] OF BYTE.
bool basic_type(const std::string& t) {
    if (esi_basic_bits(t) > 0 || esi_coe_type(t) != 0) return true;
    return t.rfind("STRING", 0) == 0 || t.rfind("ARRAY", 0) == 0 || t.rfind("UNICODE_STRING", 0) == 0 ||
           t == "OCTET_STRING" || t == "VISIBLE_STRING" || t == "FLOAT" || t == "DOUBLE" || t == "BITARR8" ||
           t == "BITARR16" || t == "BITARR32";
}

// Resolves an entry's type: an enumerated type becomes its base type with the values, an alias (BaseType
// only) its base; marks a type that is neither basic nor defined.
void resolve_type(EsiEntry& e, const TypeMap& types) {
    e.declared_type = e.type;
    for (int depth = 0; depth < 8; ++depth) {
        auto it = types.find(e.type);
        if (it == types.end()) {
            e.type_known = basic_type(e.type);
            return;
        }
        const DataType& t = it->second;
        if (!t.enums.empty() && !t.base.empty()) {
            e.enumeration = t.enums;
            e.type = t.base;
            continue;
        }
        if (!t.array && t.subs.empty() && !t.base.empty() && t.base != e.type) {
            e.type = t.base;  // an alias
            continue;
        }
        e.type_known = true;  // defined: a basic type's own DataType, an array, a record
        return;
    }
}

struct Flags {
    std::string access, write_restrictions, read_restrictions, pdo;
    bool backup = false, setting = false;
};

void read_flags(Node flags, std::string& access, std::string& wr, std::string& rr, std::string& pdo,
                bool& backup, bool& setting) {
    if (!flags) return;
    if (Node a = child(flags, "Access")) {
        access = text(a);
        wr = attr(a, "WriteRestrictions");
        rr = attr(a, "ReadRestrictions");
    }
    if (Node p = child(flags, "PdoMapping")) {
        // ETG.2000 (EtherCATBase.xsd) allows T, R, TR, RT and the same in lower case.
        pdo = text(p);
        for (char& c : pdo)
            c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    }
    if (Node b = child(flags, "Backup")) backup = truthy(text(b));
    if (Node s = child(flags, "Setting")) setting = truthy(text(s));
}

// DefaultData/MinData/MaxData are hexBinary (the value's bytes, little endian); some vendor files write an
// ESI number there instead ("#x0003d090"): read as the number it is.
void read_data(Node d, std::vector<uint8_t>& data, std::optional<int64_t>& value) {
    const std::string t = text(d);
    if (t.size() > 2 && t[0] == '#' && (t[1] == 'x' || t[1] == 'X')) {
        if (auto v = parse_esi_number(t)) {
            value = *v;
            return;
        }
    }
    data = hex_bytes(t);
}

void read_info(Node info, EsiEntry& e) {
    if (!info) return;
    if (Node d = child(info, "DefaultData")) read_data(d, e.default_data, e.default_value);
    if (Node d = child(info, "DefaultString")) {
        // The text as written (not trimmed: a default may end in spaces).
        xmlChar* t = xmlNodeGetContent(d);
        std::string str = t ? reinterpret_cast<const char*>(t) : "";
        xmlFree(t);
        e.default_data.assign(str.begin(), str.end());
        e.default_is_string = true;
    }
    if (Node d = child(info, "MinData")) read_data(d, e.min_data, e.min);
    if (Node d = child(info, "MaxData")) read_data(d, e.max_data, e.max);
    if (Node d = child(info, "MinValue")) e.min = parse_esi_number(text(d));
    if (Node d = child(info, "MaxValue")) e.max = parse_esi_number(text(d));
    if (Node d = child(info, "DefaultValue")) e.default_value = parse_esi_number(text(d));
    if (Node u = child(info, "Unit"))
        if (auto v = parse_esi_number(text(u))) e.unit = static_cast<uint32_t>(*v);
}

// A limit or default of a signed type written as a hex number (`#xfe99` for an INT: -359, as Beckhoff writes
// MinValue) is that type's two's complement: a value above the type's maximum can mean nothing else.
void sign_extend_limits(EsiEntry& e) {
    static const std::map<std::string, unsigned> signed_bits = {
        {"SINT", 8}, {"INT", 16}, {"INT24", 24}, {"DINT", 32}};
    auto it = signed_bits.find(e.type);
    if (it == signed_bits.end()) return;
    const int64_t half = int64_t{1} << (it->second - 1);
    for (std::optional<int64_t>* v : {&e.min, &e.max, &e.default_value})
        if (*v && **v >= half && **v < 2 * half) **v -= 2 * half;
}

void read_types(Node dict, TypeMap& types) {
    for (Node dt : children(child(dict, "DataTypes"), "DataType")) {
        DataType t;
        t.name = text(dt, "Name");
        t.base = text(dt, "BaseType");
        t.bits = static_cast<unsigned>(number(text(dt, "BitSize")));
        if (Node i = child(dt, "Index"))
            if (auto v = parse_esi_number(text(i))) t.index = static_cast<uint16_t>(*v);
        if (Node ai = child(dt, "ArrayInfo")) {
            t.array = true;
            t.lbound = number(text(ai, "LBound"));
            t.elements = number(text(ai, "Elements"));
            if (t.elements < 0 || t.elements > 255) t.elements = 0;
            if (t.lbound < 0 || t.lbound > 255) t.lbound = 0;
        }
        for (Node en : children(dt, "EnumInfo"))
            t.enums.emplace_back(number(text(en, "Enum")), text(en, "Text"));
        for (Node si : children(dt, "SubItem")) {
            DataType::Sub sub;
            if (Node x = child(si, "SubIdx")) sub.subidx = static_cast<int>(number(text(x)));
            sub.name = text(si, "Name");
            sub.type = text(si, "Type");
            sub.bits = static_cast<unsigned>(number(text(si, "BitSize")));
            sub.offs = static_cast<unsigned>(number(text(si, "BitOffs")));
            sub.line = line_of(si);
            read_flags(child(si, "Flags"), sub.access, sub.write_restrictions, sub.read_restrictions,
                       sub.pdo_mapping, sub.backup, sub.setting);
            t.subs.push_back(sub);
        }
        types[t.name] = t;
    }
}

EsiEntry entry_from(const DataType::Sub& s, const Flags& of) {
    EsiEntry e;
    e.name = s.name;
    e.type = s.type;
    e.bit_size = static_cast<uint16_t>(s.bits);
    e.bit_offset = static_cast<uint16_t>(s.offs);
    // A SubItem without its own flags has the object's.
    e.access = s.access.empty() ? of.access : s.access;
    e.write_restrictions = s.access.empty() ? of.write_restrictions : s.write_restrictions;
    e.read_restrictions = s.access.empty() ? of.read_restrictions : s.read_restrictions;
    e.pdo_mapping = s.pdo_mapping;
    e.backup = s.backup || of.backup;
    e.setting = s.setting || of.setting;
    e.line = s.line;
    return e;
}

EsiObject read_object(Node ob, const TypeMap& types) {
    EsiObject o;
    Node index = child(ob, "Index");
    o.index = static_cast<uint16_t>(number(text(index)));
    o.depend_on_slot = truthy(attr(index, "DependOnSlot"));
    o.name = text(ob, "Name");
    o.type = text(ob, "Type");
    o.bit_size = static_cast<uint16_t>(number(text(ob, "BitSize")));
    o.line = line_of(ob);
    Flags of;
    read_flags(child(ob, "Flags"), of.access, of.write_restrictions, of.read_restrictions, of.pdo, of.backup,
               of.setting);
    Node info = child(ob, "Info");
    auto it = types.find(o.type);
    if (it == types.end() || it->second.subs.empty()) {
        EsiEntry e;
        e.name = o.name;
        e.type = o.type;
        e.bit_size = o.bit_size;
        e.access = of.access;
        e.write_restrictions = of.write_restrictions;
        e.read_restrictions = of.read_restrictions;
        e.pdo_mapping = of.pdo;
        e.backup = of.backup;
        e.setting = of.setting;
        e.line = o.line;
        read_info(info, e);
        resolve_type(e, types);
        sign_extend_limits(e);
        o.type = e.type;  // a VAR of an enumerated type: its base type
        o.entries.push_back(e);
        return o;
    }
    const DataType& t = it->second;
    o.type_index = t.index;
    // An array object: SubIndex 0 plus one SubItem whose type is an ArrayInfo type.
    bool array = false;
    for (const auto& s : t.subs) {
        auto at = types.find(s.type);
        if (s.subidx < 0 && at != types.end() && at->second.array) {
            array = true;
            const DataType& a = at->second;
            const auto el_bits =
                static_cast<uint16_t>(a.elements ? a.bits / static_cast<unsigned>(a.elements) : 0);
            for (int64_t k = 0; k < a.elements && a.lbound + k <= 255; ++k) {
                EsiEntry e = entry_from(s, of);
                e.subindex = static_cast<uint8_t>(a.lbound + k);
                char n[16];
                std::snprintf(n, sizeof n, "SubIndex %03u", static_cast<unsigned>(e.subindex));
                e.name = n;  // as configuration tools list array elements (Object/Info may rename them)
                e.type = a.base;
                e.bit_size = el_bits;
                e.bit_offset = static_cast<uint16_t>(s.offs + k * el_bits);
                resolve_type(e, types);
                o.entries.push_back(e);
            }
        } else {
            EsiEntry e = entry_from(s, of);
            e.subindex = static_cast<uint8_t>(s.subidx < 0 ? 0 : s.subidx);
            resolve_type(e, types);
            o.entries.push_back(e);
        }
    }
    o.object_code = array ? 8 : 9;
    // Object/Info/SubItem names the entry it describes (defaults, limits): by name where the name is
    // unique, else by position.
    auto infos = children(info, "SubItem");
    for (std::size_t i = 0; i < infos.size(); ++i) {
        const std::string n = text(infos[i], "Name");
        std::size_t target = i, matches = 0;
        for (std::size_t j = 0; j < o.entries.size(); ++j)
            if (o.entries[j].name == n) {
                target = j;
                ++matches;
            }
        if (matches != 1) target = i;
        if (target >= o.entries.size()) continue;
        // Array elements take the names the Info gives them ("SubIndex 001").
        if (array && matches == 0 && !n.empty() && target > 0) o.entries[target].name = n;
        read_info(child(infos[i], "Info"), o.entries[target]);
    }
    for (EsiEntry& e : o.entries)
        sign_extend_limits(e);
    return o;
}

void read_pdos(Node parent, const char* tag, bool rx, std::vector<EsiPdo>& out) {
    for (Node p : children(parent, tag)) {
        EsiPdo pdo;
        pdo.rx = rx;
        Node index = child(p, "Index");
        pdo.index = static_cast<uint16_t>(number(text(index)));
        pdo.depend_on_slot = truthy(attr(index, "DependOnSlot"));
        std::string sm = attr(p, "Sm");
        if (!sm.empty()) pdo.sm = static_cast<int>(number(sm, -1));
        pdo.fixed = truthy(attr(p, "Fixed"));
        pdo.mandatory = truthy(attr(p, "Mandatory"));
        pdo.is_virtual = truthy(attr(p, "Virtual"));
        pdo.overwritten_by_module = truthy(attr(p, "OverwrittenByModule"));
        pdo.name = name_text(p);
        pdo.line = line_of(p);
        for (Node x : children(p, "Exclude"))
            pdo.exclude.push_back(static_cast<uint16_t>(number(text(x))));
        for (Node e : children(p, "Entry")) {
            EsiPdoEntry pe;
            Node ei = child(e, "Index");
            pe.index = static_cast<uint16_t>(number(text(ei)));
            pe.depend_on_slot = truthy(attr(ei, "DependOnSlot"));
            pe.subindex = static_cast<uint8_t>(number(text(e, "SubIndex")));
            pe.bit_len = static_cast<uint8_t>(number(text(e, "BitLen")));
            pe.name = name_text(e);
            pe.data_type = text(e, "DataType");
            pe.line = line_of(e);
            pdo.entries.push_back(pe);
        }
        out.push_back(pdo);
    }
}

EsiDevice read_device(Node dev, const TypeMap& types_in, uint32_t vendor, const std::string& vendor_name,
                      const std::map<std::string, std::string>& group_names) {
    EsiDevice d;
    d.vendor_id = vendor;
    d.vendor_name = vendor_name;
    d.line = line_of(dev);
    if (xmlHasProp(dev, reinterpret_cast<const xmlChar*>("Physics"))) d.physics = attr(dev, "Physics");
    Node type = child(dev, "Type");
    d.type_name = text(type);
    d.has_product_code = !xml::trim(attr(type, "ProductCode")).empty();
    d.product_code = static_cast<uint32_t>(number(attr(type, "ProductCode")));
    d.revision = static_cast<uint32_t>(number(attr(type, "RevisionNo")));
    d.name = name_text(dev);
    d.group_type = text(dev, "GroupType");
    if (auto g = group_names.find(d.group_type); g != group_names.end()) d.group_name = g->second;
    Node info = child(dev, "Info");
    d.identification_reg134 = truthy(text(info, "IdentificationReg134"));
    if (Node ado = child(info, "IdentificationAdo"))
        if (auto v = parse_esi_number(text(ado)); v && *v > 0 && *v <= 0xFFFF)
            d.identification_ado = static_cast<uint16_t>(*v);
    if (Node ebus = child(child(info, "Electrical"), "EBusCurrent"))
        if (auto v = parse_esi_number(text(ebus)); v && *v >= INT16_MIN && *v <= INT16_MAX)
            d.ebus_current_ma = static_cast<int32_t>(*v);
    for (Node alt : children(child(child(info, "VendorSpecific"), "TwinCAT"), "AlternativeSmMapping")) {
        EsiPdoSet set;
        set.name = name_text(alt);
        set.is_default = truthy(attr(alt, "Default"));
        for (Node sm : children(alt, "Sm"))
            for (Node p : children(sm, "Pdo"))
                set.sms[static_cast<int>(number(attr(sm, "No")))].push_back(
                    static_cast<uint16_t>(number(text(p))));
        d.pdo_sets.push_back(std::move(set));
    }
    if (Node timeout = child(child(info, "Mailbox"), "Timeout")) {
        d.mailbox_request_timeout_ms = static_cast<uint32_t>(number(text(timeout, "RequestTimeout")));
        d.mailbox_response_timeout_ms = static_cast<uint32_t>(number(text(timeout, "ResponseTimeout")));
    }
    d.image16x14 = hex_bytes(text(dev, "ImageData16x14"));
    TypeMap types = types_in;
    for (Node prof : children(dev, "Profile")) {
        if (Node p = child(prof, "ProfileNo")) d.profile_no = static_cast<uint32_t>(number(text(p)));
        if (Node p = child(prof, "AddInfo")) d.profile_add_info = static_cast<uint32_t>(number(text(p)));
        for (Node m : children(child(prof, "DiagMessages"), "DiagMessage")) {
            const std::optional<int64_t> id = parse_esi_number(text(m, "TextId"));
            if (!id || *id < 0 || *id > 0xFFFF) {  // not a text id a 0x10F3 message can carry
                d.unsupported.push_back("Profile/DiagMessages/DiagMessage at line " +
                                        std::to_string(line_of(m)) + " with TextId '" +
                                        text(m, "TextId").substr(0, 24) + "' (not a 16-bit text id)");
                continue;
            }
            d.diag_messages.push_back({static_cast<uint16_t>(*id), name_text(m, "MessageText"),
                                       text(child(m, "Flags"), "DiagClass")});
        }
        if (child(prof, "DiagFile")) d.unsupported.push_back("Profile/DiagFile");
        Node dict = child(prof, "Dictionary");
        if (dict) d.has_dictionary = true;
        if (child(prof, "DictionaryFile")) d.unsupported.push_back("Profile/DictionaryFile");
        read_types(dict, types);
        for (Node ob : children(child(dict, "Objects"), "Object")) {
            EsiObject o = read_object(ob, types);
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
        sm.has_control = xmlHasProp(s, reinterpret_cast<const xmlChar*>("ControlByte")) != nullptr;
        // Enable is a HexDecValue (ETG.2000), the SII SyncM enable byte (ETG.2010: bit 0 enable; bits 1-3
        // fixed content, virtual, enable in OP only): "1", "#x01", "9" (enabled, in OP only) are all enabled.
        {
            const std::string en = attr(s, "Enable");
            const std::optional<int64_t> v = parse_esi_number(en);
            sm.enable = truthy(en) || (v && (*v & 1));
        }
        sm.watchdog = truthy(attr(s, "Watchdog"));
        sm.is_virtual = truthy(attr(s, "Virtual"));
        sm.type = text(s);
        sm.line = line_of(s);
        d.sms.push_back(sm);
    }
    if (child(dev, "Su")) d.unsupported.push_back("Su (sync units)");
    read_pdos(dev, "RxPdo", true, d.rxpdos);
    read_pdos(dev, "TxPdo", false, d.txpdos);
    if (Node mb = child(dev, "Mailbox")) {
        d.has_mailbox = true;
        d.mailbox_data_link_layer = truthy(attr(mb, "DataLinkLayer"));
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
            if (child(c, "InitCmd")) d.unsupported.push_back("Mailbox/CoE/InitCmd");
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
            m.desc = text(om, "Desc");
            m.line = line_of(om);
            m.assign_activate = static_cast<uint16_t>(number(text(om, "AssignActivate")));
            if (Node c0 = child(om, "CycleTimeSync0")) {
                m.cycle_time_sync0 = static_cast<uint32_t>(number(text(c0)));
                if (auto f = parse_esi_number(attr(c0, "Factor")))
                    m.cycle_time_sync0_factor = static_cast<int32_t>(*f);
            }
            m.shift_time_sync0 = static_cast<int32_t>(number(text(om, "ShiftTimeSync0")));
            if (Node c1 = child(om, "CycleTimeSync1")) {
                m.has_sync1 = true;
                m.cycle_time_sync1 = static_cast<uint32_t>(number(text(c1)));
                if (auto f = parse_esi_number(attr(c1, "Factor")))
                    m.cycle_time_sync1_factor = static_cast<int32_t>(*f);
            }
            if (Node s1 = child(om, "ShiftTimeSync1")) {
                m.has_sync1 = true;
                m.shift_time_sync1 = static_cast<int32_t>(number(text(s1)));
            }
            d.op_modes.push_back(m);
        }
    }
    if (Node slots = child(dev, "Slots")) {
        d.slot_pdo_increment = static_cast<uint32_t>(number(attr(slots, "SlotPdoIncrement")));
        d.slot_index_increment = static_cast<uint32_t>(number(attr(slots, "SlotIndexIncrement")));
        d.download_module_ident_list = truthy(attr(slots, "DownloadModuleIdentList"));
        for (Node sl : children(slots, "Slot")) {
            EsiSlot slot;
            slot.name = name_text(sl);
            slot.line = line_of(sl);
            slot.min_instances = static_cast<uint32_t>(number(attr(sl, "MinInstances")));
            slot.max_instances = static_cast<uint32_t>(number(attr(sl, "MaxInstances")));
            if (auto v = parse_esi_number(attr(sl, "SlotPdoIncrement")))
                slot.pdo_increment = static_cast<uint32_t>(*v);
            if (auto v = parse_esi_number(attr(sl, "SlotIndexIncrement")))
                slot.index_increment = static_cast<uint32_t>(*v);
            for (Node mi : children(sl, "ModuleIdent")) {
                const auto ident = static_cast<uint32_t>(number(text(mi)));
                slot.module_idents.push_back(ident);
                if (truthy(attr(mi, "Default")) && !slot.default_module) slot.default_module = ident;
            }
            for (Node mc : children(sl, "ModuleClass")) {
                EsiModuleClass c;
                c.class_name = text(mc, "Class");
                if (Node v = child(mc, "VendorId")) c.vendor_id = static_cast<uint32_t>(number(text(v)));
                c.name = name_text(mc);
                slot.module_classes.push_back(std::move(c));
            }
            // One entry per slot the element stands for (MaxInstances; 0 or absent: one), as many as the
            // module ident lists hold in all.
            const std::size_t count = std::max<std::size_t>(1, slot.max_instances);
            for (std::size_t k = 0; k < count && d.slots.size() < kMaxSlots; ++k) {
                slot.instance = static_cast<uint32_t>(k);
                d.slots.push_back(slot);
            }
        }
    }
    if (Node ee = child(dev, "Eeprom")) {
        d.has_eeprom = true;
        d.eeprom_line = line_of(ee);
        d.eeprom_bytes = static_cast<uint32_t>(number(text(ee, "ByteSize")));
        d.config_data = hex_bytes(text(ee, "ConfigData"));
        d.bootstrap = hex_bytes(text(ee, "BootStrap"));
        d.eeprom_data = hex_bytes(text(ee, "Data"));
        if (child(ee, "Category")) d.unsupported.push_back("Eeprom/Category");
    }
    return d;
}

EsiModule read_module(Node mod, const TypeMap& device_types) {
    EsiModule m;
    Node type = child(mod, "Type");
    m.ident = static_cast<uint32_t>(number(attr(type, "ModuleIdent")));
    m.type_name = text(type);
    m.module_class = attr(type, "ModuleClass");
    m.name = name_text(mod);
    m.line = line_of(mod);
    read_pdos(mod, "RxPdo", true, m.rxpdos);
    read_pdos(mod, "TxPdo", false, m.txpdos);
    TypeMap types = device_types;
    for (Node prof : children(mod, "Profile")) {
        Node dict = child(prof, "Dictionary");
        read_types(dict, types);
        for (Node ob : children(child(dict, "Objects"), "Object")) {
            EsiObject o = read_object(ob, types);
            m.objects[o.index] = std::move(o);
        }
    }
    return m;
}

// What a document must be: an ESI (EtherCATInfo with devices), or the file an InfoReference names, whose
// modules are read (an EtherCATModule file, ETG.2000 EtherCATModule.xsd: Vendor and Modules; or an
// EtherCATInfo, whose Descriptions/Modules are taken).
enum class DocKind { Esi, ModuleFile };

EsiFile read_doc(xmlDoc* doc, const std::string& source, DocKind kind) {
    std::unique_ptr<xmlDoc, void (*)(xmlDoc*)> guard(doc, xmlFreeDoc);
    Node root = xmlDocGetRootElement(doc);
    if (!root) throw InputError(source, 0, "no root element");
    if (kind == DocKind::ModuleFile && is(root, "EtherCATModule")) {
        EsiFile f;
        f.source = source;
        f.vendor_id = static_cast<uint32_t>(number(text(child(root, "Vendor"), "Id")));
        f.vendor_name = name_text(child(root, "Vendor"));
        TypeMap none;
        for (Node mod : children(child(root, "Modules"), "Module"))
            f.modules.push_back(read_module(mod, none));
        return f;
    }
    if (!is(root, "EtherCATInfo"))
        throw InputError(source, line_of(root),
                         "root element is " + name_of(root) + ", not EtherCATInfo" +
                             (kind == DocKind::ModuleFile ? " or EtherCATModule" : "") + ": not an ESI file");
    EsiFile f;
    f.source = source;
    f.vendor_id = static_cast<uint32_t>(number(text(child(root, "Vendor"), "Id")));
    f.vendor_name = name_text(child(root, "Vendor"));
    for (Node ref : children(root, "InfoReference")) {
        EsiInfoReference r;
        r.reference = text(ref);
        r.line = line_of(ref);
        f.info_references.push_back(std::move(r));
    }
    Node desc = child(root, "Descriptions");
    std::map<std::string, std::string> group_names;
    for (Node g : children(child(desc, "Groups"), "Group"))
        group_names[text(g, "Type")] = name_text(g);
    TypeMap none;
    for (Node dev : children(child(desc, "Devices"), "Device"))
        f.devices.push_back(read_device(dev, none, f.vendor_id, f.vendor_name, group_names));
    for (Node mod : children(child(desc, "Modules"), "Module"))
        f.modules.push_back(read_module(mod, none));
    if (kind == DocKind::ModuleFile) return f;
    if (f.devices.empty())
        throw InputError(source, line_of(desc ? desc : root), "no Device in Descriptions/Devices");
    return f;
}

}  // namespace

DeviceByIdentity find_device(const EsiFile& file, uint32_t product_code, std::optional<uint32_t> revision) {
    DeviceByIdentity out;
    for (const EsiDevice& d : file.devices) {
        if (d.product_code != product_code) continue;
        ++out.with_product;
        if (out.revision_matched) continue;
        if (revision && d.revision == *revision) {
            out.device = &d;
            out.revision_matched = true;
        } else if (out.device == nullptr || d.revision > out.device->revision) {
            out.device = &d;
        }
    }
    return out;
}

std::vector<const EsiDevice*> find_devices_by_type(const EsiFile& file, const std::string& type) {
    std::vector<const EsiDevice*> out;
    for (const EsiDevice& d : file.devices)
        if (d.type_name == type) out.push_back(&d);
    if (!out.empty()) return out;
    auto same = [](const std::string& a, const std::string& b) {
        return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
                   return std::toupper(static_cast<unsigned char>(x)) ==
                          std::toupper(static_cast<unsigned char>(y));
               });
    };
    for (const EsiDevice& d : file.devices)
        if (same(d.type_name, type)) out.push_back(&d);
    return out;
}

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
// What the parser saw that the reader refuses, or the first error it reported.
struct ParseState {
    bool doctype = false;
    int doctype_line = 0;
    bool error = false;
    int error_line = 0;
    std::string message;
};
thread_local ParseState* t_state = nullptr;

// SAX internalSubset: the DOCTYPE starts. Stops the parser before any declaration in it is read.
void on_doctype(void* ctx, const xmlChar*, const xmlChar*, const xmlChar*) {
    auto* c = static_cast<xmlParserCtxtPtr>(ctx);
    if (t_state && !t_state->doctype) {
        t_state->doctype = true;
        t_state->doctype_line = c->input ? c->input->line : 0;
    }
    xmlStopParser(c);
}

void on_error(void*, xmlErrorPtr e) {
    if (t_state == nullptr || t_state->error || e == nullptr || e->level < XML_ERR_ERROR) return;
    t_state->error = true;
    t_state->error_line = e->line;
    t_state->message = e->message ? e->message : "parse error";
    while (!t_state->message.empty() && (t_state->message.back() == '\n' || t_state->message.back() == ' '))
        t_state->message.pop_back();
}

EsiFile parse_esi(const std::string& xml, const std::string& name, DocKind kind = DocKind::Esi) {
    if (xml.size() > kMaxEsiBytes)
        throw InputError(name, 0, "larger than " + std::to_string(kMaxEsiBytes) + " bytes: not an ESI file");
    if (xml.empty()) throw InputError(name, 0, "empty file: not an ESI file");
    std::unique_ptr<xmlParserCtxt, void (*)(xmlParserCtxtPtr)> ctxt(xmlNewParserCtxt(), xmlFreeParserCtxt);
    if (!ctxt || !ctxt->sax) throw InputError(name, 0, "out of memory");
    ctxt->sax->internalSubset = on_doctype;
    ctxt->sax->serror = on_error;
    ParseState state;
    t_state = &state;
    xmlDoc* doc =
        xmlCtxtReadMemory(ctxt.get(), xml.data(), static_cast<int>(xml.size()), name.c_str(), nullptr,
                          XML_PARSE_NONET | XML_PARSE_NOERROR | XML_PARSE_NOWARNING | XML_PARSE_BIG_LINES);
    t_state = nullptr;
    if (state.doctype || (doc != nullptr && (doc->intSubset != nullptr || doc->extSubset != nullptr))) {
        if (doc) xmlFreeDoc(doc);
        throw InputError(name, state.doctype_line > 0 ? state.doctype_line : 1,
                         "a DOCTYPE (DTD or entity declarations) is not allowed in an ESI file");
    }
    if (doc == nullptr) {
        if (!state.error) {
            const xmlError* err = xmlCtxtGetLastError(ctxt.get());
            state.error_line = err ? err->line : 0;
            state.message = err && err->message ? err->message : "parse error";
            while (!state.message.empty() && (state.message.back() == '\n' || state.message.back() == ' '))
                state.message.pop_back();
        }
        throw InputError(name, state.error_line, "not well-formed XML: " + state.message);
    }
    return read_doc(doc, name, kind);
}

std::string read_text(const std::string& path, const char* what) {
    try {
        return util::read_input_file(path, kMaxEsiBytes, what);
    } catch (const util::InputFileError& e) {
        std::string m = e.what();  // "PATH: what went wrong"
        if (m.rfind(path + ": ", 0) == 0) m.erase(0, path.size() + 2);
        throw InputError(path, 0, m);
    }
}

bool same_name(const std::string& a, const std::string& b) {
    return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
               return std::tolower(static_cast<unsigned char>(x)) ==
                      std::tolower(static_cast<unsigned char>(y));
           });
}

// The file an InfoReference names, for the ESI at `esi_path` (docs/decisions/esi.md, "InfoReference"): the
// reference with '\' read as a directory separator (the files are written on Windows), relative to the ESI's
// directory; if there is none, a file of the reference's last name in the ESI's directory; either matched
// without regard to case where the exact name is missing (Windows names are case-blind). Empty if none.
std::string resolve_reference(const std::string& esi_path, std::string ref, std::string& looked) {
    namespace fs = std::filesystem;
    std::replace(ref.begin(), ref.end(), '\\', '/');
    const fs::path base = fs::path(esi_path).parent_path();
    const fs::path given(ref);
    std::vector<fs::path> candidates{given.is_absolute() ? given : base / given};
    if (given.has_filename() && candidates.front() != base / given.filename())
        candidates.push_back(base / given.filename());
    for (const fs::path& c : candidates) {
        looked += (looked.empty() ? "" : ", ") + c.string();
        std::error_code ec;
        if (fs::is_regular_file(c, ec)) return c.string();
        const fs::path dir = c.parent_path().empty() ? fs::path(".") : c.parent_path();
        for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
            if (same_name(it->path().filename().string(), c.filename().string()) &&
                fs::is_regular_file(it->path(), ec))
                return it->path().string();
    }
    return {};
}

}  // namespace

EsiFile read_esi_file(const std::string& path) {
    EsiFile f = parse_esi(read_text(path, "ESI file"), path);
    for (EsiInfoReference& r : f.info_references) {
        if (r.reference.empty()) {
            r.problem = "names no file";
            continue;
        }
        std::string looked;
        const std::string file = resolve_reference(path, r.reference, looked);
        if (file.empty()) {
            r.problem = "no such file (looked for " + looked + ")";
            continue;
        }
        try {
            const EsiFile other = parse_esi(read_text(file, "InfoReference file"), file, DocKind::ModuleFile);
            r.resolved = file;
            for (const EsiModule& m : other.modules)
                if (f.module(m.ident) == nullptr) {
                    f.modules.push_back(m);
                    ++r.modules;
                }
            if (other.modules.empty()) r.problem = file + " has no Module";
        } catch (const InputError& e) {
            // The device itself is described without it: said, and served without the modules.
            r.problem = std::string("not read: ") + e.what();
        }
    }
    return f;
}

EsiFile read_esi_text(const std::string& xml, const std::string& name) {
    return parse_esi(xml, name);
}

const EsiModule* EsiFile::module(uint32_t ident) const {
    for (const EsiModule& m : modules)
        if (m.ident == ident) return &m;
    return nullptr;
}

EsiDevice read_esi(const std::string& xml) {
    return read_esi_text(xml).devices.front();  // read_doc refuses a file without a device
}

}  // namespace esi
