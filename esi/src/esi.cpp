#include "esi/esi.hpp"

#include <libxml/tree.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <stdexcept>

#include "esi/model.hpp"
#include "type_names.hpp"

namespace esi {
namespace {

using od::DataType;
using od::Entry;
using od::Object;
using od::ObjectCode;

const xmlChar* X(const char* s) {
    return reinterpret_cast<const xmlChar*>(s);
}

std::string hex(uint64_t v) {
    char b[24];
    std::snprintf(b, sizeof b, "#x%llx", static_cast<unsigned long long>(v));
    return b;
}

std::string hex32(uint32_t v) {
    char b[16];
    std::snprintf(b, sizeof b, "#x%08x", static_cast<unsigned>(v));
    return b;
}

std::string hex_index(uint16_t v) {
    char b[8];
    std::snprintf(b, sizeof b, "#x%04x", static_cast<unsigned>(v));
    return b;
}

// `digits` upper-case hex digits of v.
std::string hex_digits(uint32_t v, int digits) {
    std::string s;
    for (int shift = 4 * (digits - 1); shift >= 0; shift -= 4)
        s += "0123456789ABCDEF"[(v >> shift) & 0xF];
    return s;
}

std::string hex_bytes(const uint8_t* p, std::size_t n) {
    static const char* digits = "0123456789abcdef";
    std::string s;
    for (std::size_t i = 0; i < n; ++i) {
        s += digits[p[i] >> 4];
        s += digits[p[i] & 0xF];
    }
    return s;
}

// Text as XML 1.0 can carry it: valid UTF-8 sequences are kept, any other byte and the control characters
// XML 1.0 forbids (everything below 0x20 but tab, LF, CR) become '?'. Names come from the dictionary and
// the description, which are byte strings.
std::string xml_text(const std::string& in) {
    std::string out;
    out.reserve(in.size());
    for (std::size_t i = 0; i < in.size();) {
        const auto c = static_cast<unsigned char>(in[i]);
        if (c < 0x80) {
            out += (c < 0x20 && c != '\t' && c != '\n' && c != '\r') ? '?' : static_cast<char>(c);
            ++i;
            continue;
        }
        std::size_t n = 0;
        uint32_t cp = 0;
        if ((c & 0xE0) == 0xC0)
            n = 2, cp = c & 0x1F;
        else if ((c & 0xF0) == 0xE0)
            n = 3, cp = c & 0x0F;
        else if ((c & 0xF8) == 0xF0)
            n = 4, cp = c & 0x07;
        bool ok = n != 0 && i + n <= in.size();
        for (std::size_t k = 1; ok && k < n; ++k) {
            const auto cc = static_cast<unsigned char>(in[i + k]);
            ok = (cc & 0xC0) == 0x80;
            cp = (cp << 6) | (cc & 0x3F);
        }
        // Reject overlong forms, surrogates and code points past U+10FFFF.
        if (ok)
            ok = !((n == 2 && cp < 0x80) || (n == 3 && cp < 0x800) || (n == 4 && cp < 0x10000) ||
                   (cp >= 0xD800 && cp <= 0xDFFF) || cp > 0x10FFFF || cp == 0xFFFE || cp == 0xFFFF);
        if (ok) {
            out.append(in, i, n);
            i += n;
        } else {
            out += '?';
            ++i;
        }
    }
    return out;
}

// Builder helpers over libxml2's tree API (xmlNewTextChild escapes the content).
xmlNodePtr child(xmlNodePtr parent, const char* name, const std::string& text) {
    return xmlNewTextChild(parent, nullptr, X(name), X(xml_text(text).c_str()));
}
xmlNodePtr child(xmlNodePtr parent, const char* name) {
    return xmlNewChild(parent, nullptr, X(name), nullptr);
}
void attr(xmlNodePtr node, const char* name, const std::string& value) {
    xmlNewProp(node, X(name), X(xml_text(value).c_str()));
}
xmlNodePtr named(xmlNodePtr parent, const char* name, const std::string& text) {
    xmlNodePtr n = child(parent, name, text);
    attr(n, "LcId", "1033");
    return n;
}

// ---- Access flags ------------------------------------------------------------------------------------

// "PreOP", "SafeOP", "OP", "PreOP_SafeOP", ... for a subset of the three states; empty for all or none.
std::string restriction(uint16_t bits, uint16_t preop, uint16_t safeop, uint16_t op) {
    const bool p = bits & preop, s = bits & safeop, o = bits & op;
    if ((p && s && o) || (!p && !s && !o)) return {};
    if (p && s) return "PreOP_SafeOP";
    if (p && o) return "PreOP_OP";
    if (s && o) return "SafeOP_OP";
    if (p) return "PreOP";
    if (s) return "SafeOP";
    return "OP";
}

void access_flags(xmlNodePtr flags, const Entry& e, const char* category) {
    namespace a = od::access;
    const uint16_t r = e.access & a::ReadMask;
    const uint16_t w = e.access & a::WriteMask;
    const char* text = w == 0 ? "ro" : (r == 0 ? "wo" : "rw");
    xmlNodePtr acc = child(flags, "Access", text);
    const std::string rr = restriction(r, a::ReadPreOp, a::ReadSafeOp, a::ReadOp);
    const std::string wr = restriction(w, a::WritePreOp, a::WriteSafeOp, a::WriteOp);
    if (!rr.empty()) attr(acc, "ReadRestrictions", rr);
    if (!wr.empty()) attr(acc, "WriteRestrictions", wr);
    if (category != nullptr) child(flags, "Category", category);
    if (e.rx_mappable() || e.tx_mappable())
        child(flags, "PdoMapping", e.rx_mappable() && e.tx_mappable() ? "RT" : (e.rx_mappable() ? "R" : "T"));
}

void backup_flags(xmlNodePtr flags, const Entry& e) {
    if (e.access & od::access::Backup) child(flags, "Backup", "1");
    if (e.access & od::access::Settings) child(flags, "Setting", "1");
}

// ETG.1000.6: 0x1000 and 0x1018 are mandatory for every CoE device; everything else is optional here.
const char* object_category(uint16_t index) {
    return (index == 0x1000 || index == 0x1018) ? "m" : "o";
}

// ---- Values ------------------------------------------------------------------------------------------

std::string number_text(uint64_t bits, const Entry& e) {
    if (od::is_signed(e.type)) {
        const unsigned width = (e.bit_length == 0 || e.bit_length > 64) ? 64u : e.bit_length;
        int64_t v = static_cast<int64_t>(bits);
        if (width < 64 && (bits >> (width - 1)) & 1) v = static_cast<int64_t>(bits | (~uint64_t{0} << width));
        return std::to_string(v);
    }
    return hex(bits);
}

std::string le_hex(uint64_t bits, std::size_t bytes) {
    uint8_t b[8] = {};
    for (std::size_t i = 0; i < 8; ++i)
        b[i] = static_cast<uint8_t>(bits >> (8 * i));
    return hex_bytes(b, bytes > 8 ? 8 : bytes);
}

// Info content of one entry: default, limits, unit (ObjectInfoType).
void value_info(xmlNodePtr info, const Entry& e) {
    if (od::is_string(e.type)) {
        if (e.type == DataType::VisibleString) {
            if (!e.default_string.empty()) child(info, "DefaultString", e.default_string);
        } else if (!e.default_string.empty()) {
            child(info, "DefaultData",
                  hex_bytes(reinterpret_cast<const uint8_t*>(e.default_string.data()),
                            e.default_string.size()));
        }
    } else {
        const auto def = number_bits(e.default_value, e.type, e.bit_length);
        const auto min = number_bits(e.minimum, e.type, e.bit_length);
        const auto max = number_bits(e.maximum, e.type, e.bit_length);
        const std::size_t bytes = e.byte_size() == 0 ? 1 : e.byte_size();
        if ((min || max) && !od::is_real(e.type)) {
            if (min) child(info, "MinValue", number_text(*min, e));
            if (max) child(info, "MaxValue", number_text(*max, e));
            if (def) child(info, "DefaultValue", number_text(*def, e));
        } else {
            if (min) child(info, "MinData", le_hex(*min, bytes));
            if (max) child(info, "MaxData", le_hex(*max, bytes));
            if (def) child(info, "DefaultData", le_hex(*def, bytes));
        }
    }
    if (const auto u = unit_code(e.unit)) child(info, "Unit", hex(*u));
}

// ---- Data types --------------------------------------------------------------------------------------

// An enumerated entry's type: its base type with the named values (ETG.2000 DataType/EnumInfo).
struct EnumType {
    std::string base;
    uint32_t bits = 0;
    const std::vector<od::NamedValue>* values = nullptr;
};

struct TypeSet {
    std::map<std::string, uint32_t> base;   // name -> bit size (scalars and strings)
    std::map<std::string, EnumType> enums;  // "DT6060EN08" -> base type and values
    std::string use(const Entry& e) {
        const std::string n = esi_type_name(e.type, e.bit_length);
        if (e.type == DataType::OctetString) base["BYTE"] = 8;
        const uint32_t bits =
            od::is_string(e.type) ? e.bit_length : (e.bit_length ? e.bit_length : od::bit_size(e.type));
        base[n] = bits;
        if (e.enumeration.empty() || od::is_string(e.type)) return n;
        // Named as vendors name them: DT, the index (and subindex if not 0), EN, the bit size.
        std::string name = "DT" + hex_digits(e.index, 4) + (e.subindex ? hex_digits(e.subindex, 2) : "") +
                           "EN" + (bits < 10 ? "0" : "") + std::to_string(bits);
        enums[name] = EnumType{n, bits, &e.enumeration};
        return name;
    }
};

// An ARRAY object that can be described with ArrayInfo: subindices 1..n all present, one type, size and
// access for all elements.
bool uniform_array(const Object& o) {
    if (o.code != ObjectCode::Array || o.entries.size() < 2 || o.entries[0].subindex != 0) return false;
    const Entry& first = o.entries[1];
    for (std::size_t i = 1; i < o.entries.size(); ++i) {
        const Entry& e = o.entries[i];
        if (e.subindex != i || e.type != first.type || e.bit_length != first.bit_length ||
            (e.access & ~(od::access::Backup | od::access::Settings)) !=
                (first.access & ~(od::access::Backup | od::access::Settings)))
            return false;
    }
    return true;
}

std::string sub_name(unsigned sub) {
    char b[16];
    std::snprintf(b, sizeof b, "SubIndex %03u", sub);
    return b;
}

// An array's SubItem name: subindex 0 is named as the dictionary (and so SDO information) names it, the
// elements "SubIndex nnn" as configuration tools list them.
std::string array_item_name(const Entry& e) {
    return e.subindex == 0 && !e.name.empty() ? e.name : sub_name(e.subindex);
}

// Record-style SubItem names: the entry names, made unique (the XSD keys SubItems by Name).
std::vector<std::string> record_item_names(const Object& o) {
    std::vector<std::string> names;
    std::set<std::string> seen;
    for (const Entry& e : o.entries) {
        std::string n = e.name.empty() ? sub_name(e.subindex) : e.name;
        if (!seen.insert(n).second) n += " (" + sub_name(e.subindex) + ")";
        seen.insert(n);
        names.push_back(n);
    }
    return names;
}

// Bit offsets in the complete-access layout (as coe/ lays out a complete-access image): subindex 0 takes 16
// bits, byte-sized entries (and strings) start on a byte boundary, bit-sized ones are packed; gaps skipped.
std::vector<uint32_t> bit_offsets(const Object& o, uint32_t& total) {
    std::vector<uint32_t> offs;
    uint32_t off = 0;
    for (const Entry& e : o.entries) {
        if (e.subindex != 0 && (e.bit_length % 8 == 0 || od::is_string(e.type))) off = (off + 7u) & ~7u;
        offs.push_back(off);
        off += e.subindex == 0 ? std::max<uint32_t>(16u, e.bit_length) : e.bit_length;
    }
    total = off;
    return offs;
}

std::string dt_name(uint16_t index) {
    char b[16];
    std::snprintf(b, sizeof b, "DT%04X", static_cast<unsigned>(index));
    return b;
}

void sub_item(xmlNodePtr dt, const Entry* idx_entry, const std::string& name, const std::string& type,
              uint32_t bits, uint32_t offs, const Entry& flags_of) {
    xmlNodePtr si = child(dt, "SubItem");
    if (idx_entry != nullptr) child(si, "SubIdx", std::to_string(idx_entry->subindex));
    child(si, "Name", name);
    child(si, "Type", type);
    child(si, "BitSize", std::to_string(bits));
    child(si, "BitOffs", std::to_string(offs));
    xmlNodePtr flags = child(si, "Flags");
    access_flags(flags, flags_of, nullptr);
    backup_flags(flags, flags_of);
}

// Emits the DataType(s) of a structured object; returns its type name and bit size.
std::string structured_type(xmlNodePtr types, const Object& o, TypeSet& ts, uint32_t& bits) {
    const std::string name = dt_name(o.index);
    // An ARRAY without elements (an SM assignment of no PDO) is written as Beckhoff writes it: an ArrayInfo
    // of 0 elements of its element type.
    const bool empty_array =
        o.code == ObjectCode::Array && o.entries.size() == 1 && o.entries[0].subindex == 0;
    if (uniform_array(o) || empty_array) {
        const Entry& si0 = o.entries[0];
        Entry none;
        if (empty_array) {
            none.subindex = 1;
            none.type = o.type;
            none.bit_length = od::bit_size(o.type);
            none.access = si0.access;
        }
        const Entry& el = empty_array ? none : o.entries[1];
        const std::string base = ts.use(el);
        const std::string si0_type = ts.use(si0);
        const auto n = static_cast<uint32_t>(o.entries.size() - 1);
        const uint32_t arr_bits = n * el.bit_length;
        xmlNodePtr arr = child(types, "DataType");
        child(arr, "Name", name + "ARR");
        child(arr, "BaseType", base);
        child(arr, "BitSize", std::to_string(arr_bits));
        xmlNodePtr ai = child(arr, "ArrayInfo");
        child(ai, "LBound", "1");
        child(ai, "Elements", std::to_string(n));
        const uint32_t elements_offs = si0.bit_length < 16 ? 16 : si0.bit_length;
        bits = elements_offs + arr_bits;
        xmlNodePtr dt = child(types, "DataType");
        child(dt, "Name", name);
        child(dt, "BitSize", std::to_string(bits));
        sub_item(dt, &si0, array_item_name(si0), si0_type, si0.bit_length, 0, si0);
        sub_item(dt, nullptr, "Elements", name + "ARR", arr_bits, elements_offs, el);
        return name;
    }
    const auto names = record_item_names(o);
    const auto offs = bit_offsets(o, bits);
    std::vector<std::string> types_of;
    for (const Entry& e : o.entries)
        types_of.push_back(ts.use(e));
    xmlNodePtr dt = child(types, "DataType");
    child(dt, "Name", name);
    child(dt, "BitSize", std::to_string(bits));
    for (std::size_t i = 0; i < o.entries.size(); ++i)
        sub_item(dt, &o.entries[i], names[i], types_of[i], o.entries[i].bit_length, offs[i], o.entries[i]);
    return name;
}

void dictionary(xmlNodePtr profile, const od::Dictionary& dict) {
    xmlNodePtr dictionary = child(profile, "Dictionary");
    xmlNodePtr types = child(dictionary, "DataTypes");
    xmlNodePtr objects = child(dictionary, "Objects");
    TypeSet ts;
    // Structured types go into a separate list so the base types can be emitted first.
    xmlNodePtr structured = xmlNewNode(nullptr, X("Structured"));

    for (const Object& o : dict.objects()) {
        if (o.entries.empty()) continue;
        xmlNodePtr obj = child(objects, "Object");
        child(obj, "Index", hex_index(o.index));
        named(obj, "Name", o.name);
        if (o.code == ObjectCode::Var) {
            const Entry& e = o.entries[0];
            child(obj, "Type", ts.use(e));
            child(obj, "BitSize", std::to_string(e.bit_length));
            xmlNodePtr info = child(obj, "Info");
            value_info(info, e);
            if (info->children == nullptr) {
                xmlUnlinkNode(info);
                xmlFreeNode(info);
            }
            xmlNodePtr flags = child(obj, "Flags");
            access_flags(flags, e, object_category(o.index));
            backup_flags(flags, e);
            continue;
        }
        uint32_t bits = 0;
        child(obj, "Type", structured_type(structured, o, ts, bits));
        child(obj, "BitSize", std::to_string(bits));
        xmlNodePtr info = child(obj, "Info");
        const bool array = uniform_array(o);
        const auto names = record_item_names(o);
        for (std::size_t i = 0; i < o.entries.size(); ++i) {
            xmlNodePtr si = child(info, "SubItem");
            child(si, "Name", array ? array_item_name(o.entries[i]) : names[i]);
            value_info(child(si, "Info"), o.entries[i]);
        }
        xmlNodePtr flags = child(obj, "Flags");
        access_flags(flags, o.entries[0], object_category(o.index));
    }

    for (const auto& [name, bits] : ts.base) {
        xmlNodePtr dt = child(types, "DataType");
        child(dt, "Name", name);
        if (name.rfind("ARRAY ", 0) == 0) child(dt, "BaseType", "BYTE");
        child(dt, "BitSize", std::to_string(bits));
        if (name.rfind("ARRAY ", 0) == 0) {
            xmlNodePtr ai = child(dt, "ArrayInfo");
            child(ai, "LBound", "0");
            child(ai, "Elements", std::to_string(bits / 8));
        }
    }
    for (const auto& [name, t] : ts.enums) {
        xmlNodePtr dt = child(types, "DataType");
        child(dt, "Name", name);
        child(dt, "BaseType", t.base);
        child(dt, "BitSize", std::to_string(t.bits));
        for (const od::NamedValue& v : *t.values) {
            xmlNodePtr en = child(dt, "EnumInfo");
            named(en, "Text", v.text);
            child(en, "Enum", std::to_string(v.value));
        }
    }
    // Move the structured types behind the base and enumerated types.
    for (xmlNodePtr n = structured->children; n != nullptr;) {
        xmlNodePtr next = n->next;
        xmlUnlinkNode(n);
        xmlAddChild(types, n);
        n = next;
    }
    xmlFreeNode(structured);
}

// ---- Diagnosis texts (ETG.2000 DiagMessages, the ids 0x10F3 messages carry) ---------------------------

// Whatever texts the description holds (the drive core's for the MAXPOS, a vendor file's for a device read
// from its ESI), in their order; none, no element.
void diag_messages(xmlNodePtr profile, const std::vector<od::DiagMessageText>& texts) {
    if (texts.empty()) return;
    xmlNodePtr messages = child(profile, "DiagMessages");
    for (const od::DiagMessageText& t : texts) {
        xmlNodePtr m = child(messages, "DiagMessage");
        child(m, "TextId", hex_index(t.text_id));
        named(m, "MessageText", t.text);
        if (!t.diag_class.empty()) child(child(m, "Flags"), "DiagClass", t.diag_class);
    }
}

// ---- PDOs --------------------------------------------------------------------------------------------

void pdo(xmlNodePtr device, const PdoInfo& p) {
    xmlNodePtr n = child(device, p.rx ? "RxPdo" : "TxPdo");
    if (p.fixed) attr(n, "Fixed", "1");
    if (p.mandatory) attr(n, "Mandatory", "1");
    if (p.sm >= 0) attr(n, "Sm", std::to_string(p.sm));
    child(n, "Index", hex_index(p.index));
    named(n, "Name", p.name);
    for (uint16_t x : p.exclude)
        child(n, "Exclude", hex_index(x));
    for (const PdoEntryInfo& e : p.entries) {
        xmlNodePtr en = child(n, "Entry");
        child(en, "Index", hex_index(e.index));
        if (e.index != 0 || e.subindex != 0) child(en, "SubIndex", std::to_string(e.subindex));
        child(en, "BitLen", std::to_string(e.bit_length));
        if (e.index != 0) {
            named(en, "Name", e.name);
            if (e.entry != nullptr) child(en, "DataType", esi_type_name(e.type, e.bit_length));
        }
    }
}

// A module's PDO (Descriptions/Modules/Module), indices as the module declares them (before the slot's
// increments).
void module_pdo(xmlNodePtr module, const od::ModulePdo& p) {
    xmlNodePtr n = child(module, p.rx ? "RxPdo" : "TxPdo");
    if (p.fixed) attr(n, "Fixed", "1");
    if (p.mandatory) attr(n, "Mandatory", "1");
    if (p.sm >= 0) attr(n, "Sm", std::to_string(p.sm));
    xmlNodePtr index = child(n, "Index", hex_index(p.index));
    if (p.depend_on_slot) attr(index, "DependOnSlot", "true");
    named(n, "Name", p.name);
    for (const od::ModulePdoEntry& e : p.entries) {
        xmlNodePtr en = child(n, "Entry");
        xmlNodePtr ei = child(en, "Index", hex_index(e.index));
        if (e.depend_on_slot && e.index != 0) attr(ei, "DependOnSlot", "true");
        if (e.index != 0 || e.subindex != 0) child(en, "SubIndex", std::to_string(e.subindex));
        child(en, "BitLen", std::to_string(e.bit_length));
        if (e.index != 0) {
            named(en, "Name", e.name);
            if (!e.data_type.empty()) child(en, "DataType", e.data_type);
        }
    }
}

// The PDO indices the slots' default modules place (they are written with their module, not the device).
std::set<uint16_t> slot_pdos(const od::DeviceDescription& d) {
    std::set<uint16_t> out;
    for (std::size_t n = 0; n < d.slots.size(); ++n) {
        const od::Slot& slot = d.slots[n];
        if (slot.default_module == 0) continue;
        for (const od::Module& m : d.modules) {
            if (m.ident != slot.default_module) continue;
            for (const od::ModulePdo& p : m.pdos)
                out.insert(static_cast<uint16_t>(p.index + (p.depend_on_slot ? n * slot.pdo_increment : 0)));
            break;
        }
    }
    return out;
}

const char* sm_text(od::SmKind k) {
    switch (k) {
        case od::SmKind::MBoxOut:
            return "MBoxOut";
        case od::SmKind::MBoxIn:
            return "MBoxIn";
        case od::SmKind::Outputs:
            return "Outputs";
        case od::SmKind::Inputs:
            return "Inputs";
    }
    return "MBoxOut";
}

const char* fmmu_text(FmmuUse f) {
    switch (f) {
        case FmmuUse::Outputs:
            return "Outputs";
        case FmmuUse::Inputs:
            return "Inputs";
        case FmmuUse::MBoxState:
            return "MBoxState";
        case FmmuUse::Unused:
            break;
    }
    return "";
}

const char* boolean(bool b) {
    return b ? "true" : "false";
}

}  // namespace

std::string esi_type_name(od::DataType type, uint16_t bit_length) {
    switch (type) {
        case DataType::VisibleString:
            return "STRING(" + std::to_string(bit_length / 8) + ")";
        case DataType::UnicodeString:
            return "UNICODE_STRING(" + std::to_string(bit_length / 16) + ")";
        case DataType::OctetString:
            if (bit_length < 8) return "ARRAY [0..0] OF BYTE";
            return "ARRAY [0.." + std::to_string(bit_length / 8 - 1) + "] OF BYTE";
        default:
            break;
    }
    const uint16_t natural = od::bit_size(type);
    if (natural > 1 && bit_length != 0 && bit_length < natural) {
        // A compact mapping of an integer's low-order bytes: the integer type of that width.
        if (bit_length == 8) return od::is_signed(type) ? "SINT" : "USINT";
        if (bit_length == 16) return od::is_signed(type) ? "INT" : "UINT";
        if (bit_length == 32) return od::is_signed(type) ? "DINT" : "UDINT";
        return "BIT" + std::to_string(bit_length);
    }
    if (const char* n = detail::base_type_name(static_cast<uint16_t>(type))) return n;
    char b[16];
    std::snprintf(b, sizeof b, "DT%04X", static_cast<unsigned>(type));
    return b;
}

std::optional<uint32_t> unit_code(const std::string& unit) {
    struct U {
        const char* text;
        uint8_t prefix;
        uint8_t unit;
    };
    static const U table[] = {
        {"s", 0x00, 0x03},  {"ms", 0xFD, 0x03}, {"us", 0xFA, 0x03},  {"\xC2\xB5s", 0xFA, 0x03},
        {"ns", 0xF7, 0x03}, {"A", 0x00, 0x04},  {"mA", 0xFD, 0x04},  {"V", 0x00, 0x26},
        {"mV", 0xFD, 0x26}, {"Hz", 0x00, 0x20}, {"kHz", 0x03, 0x20},
    };
    for (const U& u : table)
        if (unit == u.text) return (uint32_t{u.prefix} << 24) | (uint32_t{u.unit} << 16);
    return std::nullopt;
}

std::string build_esi(const od::DeviceDescription& d, const od::Dictionary& dict,
                      std::span<const uint8_t> eeprom_image) {
    const DeviceModel m = derive_model(d, dict);
    std::unique_ptr<xmlDoc, decltype(&xmlFreeDoc)> doc(xmlNewDoc(X("1.0")), &xmlFreeDoc);
    xmlNodePtr root = xmlNewNode(nullptr, X("EtherCATInfo"));
    xmlDocSetRootElement(doc.get(), root);
    xmlNsPtr xsi = xmlNewNs(root, X("http://www.w3.org/2001/XMLSchema-instance"), X("xsi"));
    xmlNewNsProp(root, xsi, X("noNamespaceSchemaLocation"), X("EtherCATInfo.xsd"));
    attr(root, "Version", "1.14");

    const od::Identity& id = d.identity;
    xmlNodePtr vendor = child(root, "Vendor");
    child(vendor, "Id", hex32(id.vendor_id));
    named(vendor, "Name", id.vendor_name);

    xmlNodePtr descriptions = child(root, "Descriptions");
    xmlNodePtr group = child(child(descriptions, "Groups"), "Group");
    child(group, "Type", id.group_type);
    named(group, "Name", id.group_type);

    xmlNodePtr device = child(child(descriptions, "Devices"), "Device");
    attr(device, "Physics", d.physics);
    xmlNodePtr type = child(device, "Type", id.order_code.empty() ? id.device_name : id.order_code);
    attr(type, "ProductCode", hex32(id.product_code));
    attr(type, "RevisionNo", hex32(id.revision));
    named(device, "Name", id.device_name);
    xmlNodePtr info = child(device, "Info");
    if (d.ebus_current_ma != 0)
        child(child(info, "Electrical"), "EBusCurrent", std::to_string(d.ebus_current_ma));
    if (d.mailbox_request_timeout_ms != 0 || d.mailbox_response_timeout_ms != 0) {
        xmlNodePtr timeout = child(child(info, "Mailbox"), "Timeout");
        child(timeout, "RequestTimeout", std::to_string(d.mailbox_request_timeout_ms));
        child(timeout, "ResponseTimeout", std::to_string(d.mailbox_response_timeout_ms));
    }
    // One Info/Port per character of Physics (ETG.2000: MII, EBUS or NONE), as the SII General category's
    // physical ports say them.
    for (std::size_t port = 0; port < d.physics.size() && port < 4; ++port) {
        const char c = d.physics[port];
        child(child(info, "Port"), "Type", c == 'Y' || c == 'H' ? "MII" : c == 'K' ? "EBUS" : "NONE");
    }
    if (!m.pdo_sets.empty()) {
        // Where TwinCAT and the vendors' CiA 402 drives carry their predefined PDO sets.
        xmlNodePtr twincat = child(child(info, "VendorSpecific"), "TwinCAT");
        for (const PdoSetInfo& set : m.pdo_sets) {
            xmlNodePtr alt = child(twincat, "AlternativeSmMapping");
            if (set.is_default) attr(alt, "Default", "1");
            child(alt, "Name", set.name);
            for (const bool rx : {true, false}) {
                const int sm = rx ? set.rx_sm : set.tx_sm;
                const auto& pdos = rx ? set.rx : set.tx;
                if (sm < 0 || pdos.empty()) continue;
                xmlNodePtr n = child(alt, "Sm");
                attr(n, "No", std::to_string(sm));
                for (uint16_t p : pdos)
                    child(n, "Pdo", hex_index(p));
            }
        }
    }
    if (d.identification_register != 0)
        child(info, "IdentificationAdo", hex_index(d.identification_register));
    if (d.identification_al_status) child(info, "IdentificationReg134", "true");
    child(device, "GroupType", id.group_type);

    if (!dict.objects().empty() || !d.diag_messages.empty()) {  // a coupler has no dictionary
        xmlNodePtr profile = child(device, "Profile");
        if (m.profile_number != 0) {
            child(profile, "ProfileNo", std::to_string(m.profile_number));
            child(profile, "AddInfo", std::to_string(m.profile_add_info));
        }
        if (!dict.objects().empty()) dictionary(profile, dict);
        diag_messages(profile, d.diag_messages);
    }

    for (FmmuUse f : m.fmmus)
        child(device, "Fmmu", fmmu_text(f));
    for (const SmInfo& s : m.sync_managers) {
        xmlNodePtr sm = child(device, "Sm", sm_text(s.kind));
        if (s.min_size != 0 || s.max_size != 0) {
            attr(sm, "MinSize", std::to_string(s.min_size));
            attr(sm, "MaxSize", std::to_string(s.max_size));
        }
        if (s.size != 0) attr(sm, "DefaultSize", std::to_string(s.size));
        attr(sm, "StartAddress", hex_index(s.start));
        attr(sm, "ControlByte", hex(s.control));
        attr(sm, "Enable", s.enable ? "1" : "0");
    }
    const std::set<uint16_t> in_slots = slot_pdos(d);
    for (std::size_t k = 0; k < m.pdo_order.size(); ++k) {
        const PdoInfo& p = m.pdos[m.pdo_order[k]];
        if (!in_slots.count(p.index)) {
            pdo(device, p);
            continue;
        }
        // A module's PDO served before one of the device's own of its direction stands in a device PDO's
        // place (ETG.2000 OverwrittenByModule, as the vendor declared it): written as such a device PDO
        // without entries, so that a re-read puts the module's PDO in the same place of the assignment.
        const bool before_own = std::any_of(
            m.pdo_order.begin() + static_cast<std::ptrdiff_t>(k) + 1, m.pdo_order.end(),
            [&](std::size_t j) { return m.pdos[j].rx == p.rx && !in_slots.count(m.pdos[j].index); });
        if (!before_own) continue;
        xmlNodePtr n = child(device, p.rx ? "RxPdo" : "TxPdo");
        if (p.sm >= 0) attr(n, "Sm", std::to_string(p.sm));
        attr(n, "OverwrittenByModule", "true");
        child(n, "Index", hex_index(p.index));
        named(n, "Name", p.name);
    }

    if (d.mailbox_protocols != 0) {
        namespace mp = od::mailbox_protocol;
        namespace cd = od::coe_details;
        xmlNodePtr mbx = child(device, "Mailbox");
        if (d.mailbox_data_link_layer) attr(mbx, "DataLinkLayer", "true");
        if (d.mailbox_protocols & mp::AoE) child(mbx, "AoE");
        if (d.mailbox_protocols & mp::EoE) child(mbx, "EoE");
        if (d.mailbox_protocols & mp::CoE) {
            xmlNodePtr coe = child(mbx, "CoE");
            attr(coe, "SdoInfo", boolean(d.coe_details & cd::SdoInfo));
            attr(coe, "PdoAssign", boolean(d.coe_details & cd::PdoAssign));
            attr(coe, "PdoConfig", boolean(d.coe_details & cd::PdoConfig));
            attr(coe, "PdoUpload", boolean(d.coe_details & cd::PdoUpload));
            attr(coe, "CompleteAccess", boolean(d.coe_details & cd::CompleteAccess));
            if (m.profile_number == 402) attr(coe, "DS402Channels", "1");
            if (kSegmentedSdo) attr(coe, "SegmentedSdo", "true");
            if (dict.find(0x10F3) != nullptr) attr(coe, "DiagHistory", "true");
        }
        if (d.mailbox_protocols & mp::FoE) child(mbx, "FoE");
        if (d.mailbox_protocols & mp::SoE) child(mbx, "SoE");
        if (d.mailbox_protocols & mp::VoE) child(mbx, "VoE");
    }

    if (!d.dc_modes.empty()) {
        xmlNodePtr dc = child(device, "Dc");
        for (const od::DcOpMode& mode : d.dc_modes) {
            xmlNodePtr op = child(dc, "OpMode");
            child(op, "Name", mode.name);
            if (!mode.description.empty()) child(op, "Desc", mode.description);
            child(op, "AssignActivate", hex(mode.assign_activate));
            if (mode.assign_activate != 0) {
                xmlNodePtr c0 = child(op, "CycleTimeSync0", std::to_string(mode.cycle_time_sync0));
                attr(c0, "Factor", std::to_string(mode.cycle_time_sync0_factor));
                child(op, "ShiftTimeSync0", std::to_string(mode.shift_time_sync0));
                if (mode.cycle_time_sync1 != 0 || mode.cycle_time_sync1_factor != 0 ||
                    mode.shift_time_sync1 != 0) {
                    xmlNodePtr c1 = child(op, "CycleTimeSync1", std::to_string(mode.cycle_time_sync1));
                    if (mode.cycle_time_sync1_factor != 0)
                        attr(c1, "Factor", std::to_string(mode.cycle_time_sync1_factor));
                    child(op, "ShiftTimeSync1", std::to_string(mode.shift_time_sync1));
                }
            }
        }
    }

    if (!d.slots.empty()) {
        xmlNodePtr slots = child(device, "Slots");
        for (const od::Slot& slot : d.slots) {
            // The schema needs a ModuleIdent or a ModuleClass (SlotType: a choice of the two).
            if (slot.module_idents.empty() && slot.module_classes.empty()) continue;
            xmlNodePtr sl = child(slots, "Slot");
            attr(sl, "MinInstances", std::to_string(slot.min_instances));
            attr(sl, "MaxInstances", std::to_string(slot.max_instances));
            attr(sl, "SlotPdoIncrement", std::to_string(slot.pdo_increment));
            attr(sl, "SlotIndexIncrement", hex(slot.index_increment));
            if (!slot.name.empty()) named(sl, "Name", slot.name);
            for (uint32_t ident : slot.module_idents) {
                xmlNodePtr mi = child(sl, "ModuleIdent", hex32(ident));
                if (ident == slot.default_module) attr(mi, "Default", "1");
            }
            if (slot.module_idents.empty())
                for (const od::ModuleClass& c : slot.module_classes) {
                    xmlNodePtr mc = child(sl, "ModuleClass");
                    child(mc, "Class", c.class_name);
                    if (!c.any_vendor) child(mc, "VendorId", hex32(c.vendor_id));
                    if (!c.name.empty()) named(mc, "Name", c.name);
                }
        }
    }

    xmlNodePtr eeprom = child(device, "Eeprom");
    if (!eeprom_image.empty()) {
        child(eeprom, "Data", hex_bytes(eeprom_image.data(), eeprom_image.size()));
    } else {
        child(eeprom, "ByteSize", std::to_string(d.eeprom_bytes));
        child(eeprom, "ConfigData", hex_bytes(m.config_data.data(), m.config_data.size()));
        child(eeprom, "BootStrap", hex_bytes(m.bootstrap.data(), m.bootstrap.size()));
    }
    const std::vector<uint8_t> image = device_image_bmp();
    child(device, "ImageData16x14", hex_bytes(image.data(), image.size()));

    if (!d.modules.empty()) {
        xmlNodePtr modules = child(descriptions, "Modules");
        for (const od::Module& mod : d.modules) {
            xmlNodePtr mn = child(modules, "Module");
            xmlNodePtr t = child(mn, "Type", mod.type);
            attr(t, "ModuleIdent", hex32(mod.ident));
            if (!mod.module_class.empty()) attr(t, "ModuleClass", mod.module_class);
            named(mn, "Name", mod.name.empty() ? mod.type : mod.name);
            for (const bool rx : {true, false})
                for (const od::ModulePdo& p : mod.pdos)
                    if (p.rx == rx) module_pdo(mn, p);
        }
    }

    xmlChar* buf = nullptr;
    int size = 0;
    xmlDocDumpFormatMemoryEnc(doc.get(), &buf, &size, "UTF-8", 1);
    if (buf == nullptr) throw std::runtime_error("ESI: libxml2 could not serialise the document");
    std::string out(reinterpret_cast<const char*>(buf), static_cast<std::size_t>(size));
    xmlFree(buf);
    return out;
}

void write_esi(const std::filesystem::path& path, const od::DeviceDescription& d, const od::Dictionary& dict,
               std::span<const uint8_t> eeprom_image) {
    const std::string xml = build_esi(d, dict, eeprom_image);
    std::ofstream f(path, std::ios::binary | std::ios::trunc);
    f << xml;
    if (!f) throw std::runtime_error("cannot write " + path.string());
}

}  // namespace esi
