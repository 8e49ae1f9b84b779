// A device from its ESI file: esi::EsiDevice (od-free, esi_reader) -> od::Product. See
// esi/device/product.hpp and docs/decisions/esi.md.
#include "esi/device/product.hpp"

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>

#include "esc/wire/sii.hpp"
#include "esi/sii.hpp"
#include "esi/slots.hpp"
#include "util/strfmt.hpp"

namespace esi {
namespace {

using od::DataType;

using util::hex;
std::string where(uint16_t index, uint8_t sub) {
    return hex(index) + ":" + hex(sub, 2).substr(2);
}

// Messages of one load: errors throw, warnings are collected ("FILE:LINE: text").
struct Ctx {
    std::string file;
    std::vector<std::string> warnings;
    [[noreturn]] void fail(int line, const std::string& msg) const { throw InputError(file, line, msg); }
    void warn(int line, const std::string& msg) { warnings.push_back(InputError(file, line, msg).what()); }
};

std::string upper(std::string s) {
    for (char& c : s)
        c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    return s;
}

// The od type of an ESI type name (the reader resolved enums and aliases already) and its bit length;
// nullopt if the name is not one the object model can hold. declared_bits: the BitSize the file gives.
std::optional<std::pair<DataType, uint16_t>> od_type(const std::string& name, uint16_t declared_bits) {
    const std::string t = upper(name);
    static const std::map<std::string, DataType> scalars = {
        {"BOOL", DataType::Boolean},        {"BOOLEAN", DataType::Boolean},
        {"BIT", DataType::Boolean},         {"SINT", DataType::Integer8},
        {"INT", DataType::Integer16},       {"DINT", DataType::Integer32},
        {"LINT", DataType::Integer64},      {"INT24", DataType::Integer24},
        {"USINT", DataType::Unsigned8},     {"BYTE", DataType::Unsigned8},
        {"UINT", DataType::Unsigned16},     {"WORD", DataType::Unsigned16},
        {"UDINT", DataType::Unsigned32},    {"DWORD", DataType::Unsigned32},
        {"ULINT", DataType::Unsigned64},    {"LWORD", DataType::Unsigned64},
        {"UINT24", DataType::Unsigned24},   {"REAL", DataType::Real32},
        {"FLOAT", DataType::Real32},        {"LREAL", DataType::Real64},
        {"DOUBLE", DataType::Real64},       {"BITARR8", DataType::Unsigned8},
        {"BITARR16", DataType::Unsigned16}, {"BITARR32", DataType::Unsigned32}};
    if (auto it = scalars.find(t); it != scalars.end()) {
        // An unsigned type given fewer bits than its size: an enum on USINT with BitSize 3, as Beckhoff's
        // settings records declare their "DT0800EN03" entries. The entry is that many bits (a BITn), as its
        // SDO information describes it (ETG.1000.6 entry description: the bit length of the entry).
        const bool is_unsigned = it->second == DataType::Unsigned8 || it->second == DataType::Unsigned16;
        if (is_unsigned && declared_bits > 0 && declared_bits < 8)
            return std::make_pair(static_cast<DataType>(0x002F + declared_bits), declared_bits);
        return std::make_pair(it->second, od::bit_size(it->second));
    }
    if (t.size() == 4 && t.rfind("BIT", 0) == 0 && t[3] >= '1' && t[3] <= '8') {
        const auto n = static_cast<uint16_t>(t[3] - '0');
        return std::make_pair(static_cast<DataType>(0x002F + n), n);
    }
    if (t.rfind("STRING(", 0) == 0 && t.back() == ')') {
        const auto n = parse_esi_number(t.substr(7, t.size() - 8));
        if (!n || *n < 0 || *n > 4096) return std::nullopt;
        return std::make_pair(DataType::VisibleString, static_cast<uint16_t>(8 * *n));
    }
    if (t == "STRING" || t == "VISIBLE_STRING") return std::make_pair(DataType::VisibleString, declared_bits);
    if (t.rfind("UNICODE_STRING", 0) == 0) return std::make_pair(DataType::UnicodeString, declared_bits);
    if (t == "OCTET_STRING" || t.rfind("ARRAY", 0) == 0)
        return std::make_pair(DataType::OctetString, declared_bits);
    return std::nullopt;
}

// The od type of an entry: its (resolved) ESI type, or, for a type the file defines as an array (a VAR of
// an ArrayInfo type), an octet string of its size.
std::optional<std::pair<DataType, uint16_t>> entry_type(const EsiEntry& e) {
    if (auto t = od_type(e.type, e.bit_size)) return t;
    if (e.type_known && e.bit_size > 0) return std::make_pair(DataType::OctetString, e.bit_size);
    return std::nullopt;
}

uint16_t states(const std::string& restriction, uint16_t preop, uint16_t safeop, uint16_t op) {
    // "PreOP", "PreOP_SafeOP", "SafeOP_OP", "OP", ... (ETG.2000 AccessType)
    const std::string r = upper(restriction);
    uint16_t bits = 0;
    std::size_t pos = 0;
    while (pos <= r.size()) {
        const std::size_t end = std::min(r.find('_', pos), r.size());
        const std::string tok = r.substr(pos, end - pos);
        if (tok == "PREOP") bits |= preop;
        if (tok == "SAFEOP") bits |= safeop;
        if (tok == "OP") bits |= op;
        pos = end + 1;
    }
    return bits;
}

uint16_t access_bits(const EsiEntry& e) {
    namespace a = od::access;
    const std::string acc = upper(e.access.empty() ? "ro" : e.access);
    uint16_t bits = 0;
    if (acc != "WO") {
        const uint16_t r = e.read_restrictions.empty()
                               ? a::RO
                               : states(e.read_restrictions, a::ReadPreOp, a::ReadSafeOp, a::ReadOp);
        bits |= r ? r : a::RO;
    }
    if (acc == "RW" || acc == "WO") {
        const uint16_t w = e.write_restrictions.empty()
                               ? a::WO
                               : states(e.write_restrictions, a::WritePreOp, a::WriteSafeOp, a::WriteOp);
        bits |= w ? w : a::WO;
    }
    const std::string pdo = upper(e.pdo_mapping);
    if (pdo.find('R') != std::string::npos) bits |= a::RxPdo;
    if (pdo.find('T') != std::string::npos) bits |= a::TxPdo;
    if (e.backup) bits |= a::Backup;
    if (e.setting) bits |= a::Settings;
    return bits;
}

uint64_t load_le(const std::vector<uint8_t>& b, std::size_t n) {
    uint64_t v = 0;
    for (std::size_t i = 0; i < n && i < b.size() && i < 8; ++i)
        v |= uint64_t{b[i]} << (8 * i);
    return v;
}

// A raw value of `bits` bits as the od number of the type.
od::Number number_of(uint64_t raw, DataType type, uint16_t bits) {
    if (od::is_real(type)) {
        if (bits == 32) return static_cast<double>(std::bit_cast<float>(static_cast<uint32_t>(raw)));
        return std::bit_cast<double>(raw);
    }
    const unsigned w = bits == 0 || bits > 64 ? 64u : bits;
    const uint64_t mask = w == 64 ? ~uint64_t{0} : (uint64_t{1} << w) - 1;
    raw &= mask;
    if (od::is_signed(type)) {
        if (w < 64 && ((raw >> (w - 1)) & 1)) raw |= ~mask;
        return static_cast<int64_t>(raw);
    }
    return raw;
}

// Whether a declared integer fits the type; a value that does not is reduced to its low bits.
bool fits(int64_t v, DataType type, uint16_t bits) {
    if (bits >= 64 || od::is_real(type)) return true;
    if (od::is_signed(type)) {
        const int64_t lim = int64_t{1} << (bits - 1);
        return v >= -lim && v < lim;
    }
    return v >= 0 && static_cast<uint64_t>(v) < (uint64_t{1} << bits);
}

od::Number declared(const std::optional<int64_t>& value, const std::vector<uint8_t>& data, DataType type,
                    uint16_t bits, bool& bad) {
    if (value) {
        if (od::is_real(type)) return static_cast<double>(*value);
        if (!fits(*value, type, bits)) {
            bad = true;
            return number_of(static_cast<uint64_t>(*value), type, bits);
        }
        if (od::is_signed(type)) return *value;
        return static_cast<uint64_t>(*value);
    }
    if (!data.empty()) {
        const std::size_t bytes = (bits + 7u) / 8u;
        if (data.size() > bytes && bytes > 0) {
            for (std::size_t i = bytes; i < data.size(); ++i)
                if (data[i] != 0) bad = true;
        }
        const uint64_t raw = load_le(data, bytes);
        if (bits < 64 && !od::is_real(type) && (raw >> bits) != 0) bad = true;
        return number_of(raw, type, bits);
    }
    return std::monostate{};
}

bool outside(const od::Number& v, const od::Number& lo, const od::Number& hi) {
    auto as_d = [](const od::Number& n) -> std::optional<long double> {
        if (auto p = std::get_if<int64_t>(&n)) return static_cast<long double>(*p);
        if (auto p = std::get_if<uint64_t>(&n)) return static_cast<long double>(*p);
        if (auto p = std::get_if<double>(&n)) return static_cast<long double>(*p);
        return std::nullopt;
    };
    const auto x = as_d(v), l = as_d(lo), h = as_d(hi);
    if (!x) return false;
    return (l && *x < *l) || (h && *x > *h) || (l && h && *l > *h);
}

std::string trim_nul(const std::vector<uint8_t>& b) {
    std::string s(b.begin(), b.end());
    while (!s.empty() && s.back() == '\0')
        s.pop_back();
    return s;
}

// One ESI entry as an od entry. Throws (via ctx) for a type the object model cannot hold when `required`;
// returns nullopt (with a warning) otherwise.
std::optional<od::Entry> to_entry(const EsiEntry& e, uint16_t index, const std::string& object_name, Ctx& ctx,
                                  bool required) {
    const auto t = entry_type(e);
    if (!t) {
        const std::string msg =
            "object " + where(index, e.subindex) + " (" + object_name + "): data type '" + e.declared_type +
            "' is " + (e.type_known ? "not one the object model can hold" : "not defined in DataTypes");
        if (required) ctx.fail(e.line, msg);
        ctx.warn(e.line, msg + "; the object is left out");
        return std::nullopt;
    }
    od::Entry x;
    x.index = index;
    x.subindex = e.subindex;
    x.name = e.name;
    x.type = t->first;
    x.bit_length = t->second;
    if (od::is_string(x.type)) {
        if (x.bit_length == 0) x.bit_length = static_cast<uint16_t>(8 * e.default_data.size());
        if (x.bit_length == 0) {
            if (required) ctx.fail(e.line, "object " + where(index, e.subindex) + ": a string of no size");
            ctx.warn(e.line,
                     "object " + where(index, e.subindex) + ": a string of no size; the object is left out");
            return std::nullopt;
        }
    } else if (e.bit_size != 0 && e.bit_size != x.bit_length) {
        ctx.warn(e.line, "object " + where(index, e.subindex) + ": BitSize " + std::to_string(e.bit_size) +
                             " for type " + e.declared_type + " of " + std::to_string(x.bit_length) +
                             " bits; the type's size is used");
    }
    x.access = access_bits(e);
    for (const auto& [v, text] : e.enumeration)
        x.enumeration.push_back(od::NamedValue{v, text});
    if (od::is_string(x.type)) {
        std::string s = x.type == DataType::VisibleString
                            ? trim_nul(e.default_data)
                            : std::string(e.default_data.begin(), e.default_data.end());
        if (8 * s.size() > x.bit_length) {
            ctx.warn(e.line, "object " + where(index, e.subindex) +
                                 ": default longer than the type; cut to " +
                                 std::to_string(x.bit_length / 8) + " bytes");
            s.resize(x.bit_length / 8);
        }
        // An OCTET_STRING ("ARRAY [0..n] OF BYTE") has the fixed size its type gives: it uploads all n+1
        // bytes, zeros where the file gives no default (a device's byte array is not a text that ends early).
        // The diagnosis messages of 0x10F3 vary in length (ETG.1020) and stay as given.
        if (x.type == DataType::OctetString && index != 0x10F3) s.resize(x.bit_length / 8, '\0');
        x.default_string = s;
        return x;
    }
    bool bad = false;
    std::vector<uint8_t> data = e.default_data;
    std::optional<int64_t> value = e.default_value;
    if (e.default_is_string) {  // a DefaultString on a number: the number it spells
        value = parse_esi_number(std::string(data.begin(), data.end()));
        data.clear();
    }
    x.default_value = declared(value, data, x.type, x.bit_length, bad);
    if (bad)
        ctx.warn(e.line, "object " + where(index, e.subindex) + ": default does not fit " + e.declared_type +
                             "; its low bits are used");
    bool bad_limit = false;
    x.minimum = declared(e.min, e.min_data, x.type, x.bit_length, bad_limit);
    x.maximum = declared(e.max, e.max_data, x.type, x.bit_length, bad_limit);
    if (bad_limit || outside(x.default_value, x.minimum, x.maximum)) {
        ctx.warn(e.line, "object " + where(index, e.subindex) +
                             ": the limits do not fit the type or exclude the default; no limits are used");
        x.minimum = std::monostate{};
        x.maximum = std::monostate{};
    }
    if (const double* r = std::get_if<double>(&x.default_value); r && std::isnan(*r)) {
        ctx.warn(e.line, "object " + where(index, e.subindex) + ": default is not a number (NaN); 0 is used");
        x.default_value = 0.0;
    }
    if (x.type == DataType::Boolean) {
        // Writes of 0/1 only (od); a BOOL default of 0xFF (as some tools write TRUE) is true.
        if (auto p = std::get_if<uint64_t>(&x.default_value); p && *p > 1) x.default_value = uint64_t{1};
        x.minimum = std::monostate{};
        x.maximum = std::monostate{};
    }
    if (x.type >= DataType::Bit1 && x.type <= DataType::Bit8 &&
        std::holds_alternative<std::monostate>(x.maximum))
        x.maximum = uint64_t{(1u << x.bit_length) - 1};  // a write of more bits than the type has is refused
    return x;
}

struct Built {
    std::map<uint16_t, od::Object> objects;
    std::map<uint16_t, int> lines;  // declaring line of each object, for messages
};

od::ObjectCode code_of(uint8_t c) {
    return c == 8 ? od::ObjectCode::Array : (c == 9 ? od::ObjectCode::Record : od::ObjectCode::Var);
}

// An ESI object as an od object; nullopt (with a warning) if it cannot be held and is not required.
std::optional<od::Object> to_object(const EsiObject& eo, uint16_t index, Ctx& ctx, bool required) {
    od::Object o;
    o.index = index;
    o.code = code_of(eo.object_code);
    o.name = eo.name.empty() ? "Object " + hex(index) : eo.name;
    std::set<uint8_t> seen;
    for (const EsiEntry& ee : eo.entries) {
        if (!seen.insert(ee.subindex).second) {
            ctx.warn(ee.line,
                     "object " + where(index, ee.subindex) + ": subindex declared twice; the first is used");
            continue;
        }
        auto x = to_entry(ee, index, o.name, ctx, required);
        if (!x) return std::nullopt;
        if (o.code == od::ObjectCode::Var) x->subindex = 0;
        o.entries.push_back(std::move(*x));
    }
    if (o.entries.empty()) {
        if (required) ctx.fail(eo.line, "object " + hex(index) + " (" + o.name + ") has no entries");
        ctx.warn(eo.line, "object " + hex(index) + " (" + o.name + ") has no entries; it is left out");
        return std::nullopt;
    }
    std::sort(o.entries.begin(), o.entries.end(),
              [](const od::Entry& a, const od::Entry& b) { return a.subindex < b.subindex; });
    if (o.code == od::ObjectCode::Var) {
        o.type = o.entries[0].type;
        return o;
    }
    od::Entry& s0 = o.entries[0];
    if (s0.subindex == 0 && s0.type != DataType::Unsigned8) {
        ctx.warn(eo.line, "object " + hex(index) + ": subindex 0 of type " +
                              std::string(od::to_string(s0.type)) + "; served as UNSIGNED8 (ETG.1000.6)");
        s0.type = DataType::Unsigned8;
        s0.bit_length = 8;
        const uint64_t def = std::visit(
            [](auto v) -> uint64_t {
                if constexpr (std::is_same_v<decltype(v), std::monostate>)
                    return 0;
                else
                    return static_cast<uint64_t>(v);
            },
            s0.default_value);
        s0.default_value = def & 0xFF;
        s0.minimum = std::monostate{};
        s0.maximum = std::monostate{};
    }
    if (s0.subindex == 0 && std::holds_alternative<std::monostate>(s0.default_value))
        s0.default_value = uint64_t{o.entries.back().subindex};
    // An SM assignment object (ETG.1000.6 0x1C10-0x1C2F: an ARRAY of UNSIGNED16) that a file declares as a
    // record of UINT16 entries (a DT1C12 with SubItems and no ArrayInfo: a Bohigh drive) is the ARRAY the
    // standard makes it: a complete access and SDO information show it as every other device's, the entries
    // after the count bounded by subindex 0 (docs/decisions/coe.md, "Complete access").
    if (o.code == od::ObjectCode::Record && index >= 0x1C10 && index <= 0x1C2F && o.entries.size() >= 2 &&
        o.entries[0].subindex == 0 &&
        std::all_of(o.entries.begin() + 1, o.entries.end(),
                    [](const od::Entry& e) { return e.type == DataType::Unsigned16 && e.bit_length == 16; }))
        o.code = od::ObjectCode::Array;
    if (o.code == od::ObjectCode::Array) {
        // An od ARRAY holds elements of one type; otherwise it is served as a RECORD.
        for (std::size_t i = 2; i < o.entries.size(); ++i)
            if (o.entries[i].type != o.entries[1].type || o.entries[i].bit_length != o.entries[1].bit_length)
                o.code = od::ObjectCode::Record;
        // An SM assignment object without elements (0x1C12 of a device without outputs, 0x1C10 of a mailbox
        // SM: Beckhoff, Synapticon) stays the ARRAY of UINT16 ETG.1000.6 makes it; any other ARRAY without
        // elements has no element type to give and is a RECORD.
        if (o.entries.size() < 2 && !(index >= 0x1C10 && index <= 0x1C2F)) o.code = od::ObjectCode::Record;
    }
    if (o.code == od::ObjectCode::Array) {
        o.type = o.entries.size() < 2 ? DataType::Unsigned16 : o.entries[1].type;
    } else if (eo.type_index) {
        o.type = static_cast<DataType>(*eo.type_index);
    } else if (index == 0x1018) {
        o.type = DataType::Identity;
    } else if ((index >= 0x1600 && index <= 0x17FF) || (index >= 0x1A00 && index <= 0x1BFF)) {
        o.type = DataType::PdoMapping;
    } else if (index >= 0x1C32 && index <= 0x1C33) {
        o.type = DataType::SyncManagerParameter;
    } else {
        o.type = static_cast<DataType>(0);
    }
    return o;
}

uint64_t default_u(const od::Entry& e) {
    if (auto p = std::get_if<uint64_t>(&e.default_value)) return *p;
    if (auto p = std::get_if<int64_t>(&e.default_value)) return static_cast<uint64_t>(*p);
    return 0;
}

od::Entry u_entry(uint16_t index, uint8_t sub, DataType type, uint16_t access, uint64_t def,
                  std::string name) {
    od::Entry e;
    e.index = index;
    e.subindex = sub;
    e.name = std::move(name);
    e.type = type;
    e.bit_length = od::bit_size(type);
    e.access = access;
    e.default_value = def;
    return e;
}

std::string nth(unsigned n) {
    char b[16];
    std::snprintf(b, sizeof b, "SubIndex %03u", n);
    return b;
}

// The od type of a PDO entry whose object the file does not declare: its DataType, else by its length.
std::pair<DataType, uint16_t> pdo_entry_type(const EsiPdoEntry& pe, Ctx& ctx) {
    if (!pe.data_type.empty())
        if (auto t = od_type(pe.data_type, pe.bit_len);
            t && (od::is_string(t->first) || t->second == pe.bit_len))
            return *t;
    switch (pe.bit_len) {
        case 1:
            return {DataType::Boolean, 1};
        case 8:
            return {DataType::Unsigned8, 8};
        case 16:
            return {DataType::Unsigned16, 16};
        case 24:
            return {DataType::Unsigned24, 24};
        case 32:
            return {DataType::Unsigned32, 32};
        case 64:
            return {DataType::Unsigned64, 64};
        default:
            break;
    }
    if (pe.bit_len > 1 && pe.bit_len < 8) return {static_cast<DataType>(0x002F + pe.bit_len), pe.bit_len};
    if (pe.bit_len % 8 == 0 && pe.bit_len > 0) {
        ctx.warn(pe.line, "PDO entry " + where(pe.index, pe.subindex) + " of " + std::to_string(pe.bit_len) +
                              " bits and type '" + pe.data_type + "': held as an octet string");
        return {DataType::OctetString, pe.bit_len};
    }
    ctx.fail(pe.line, "PDO entry " + where(pe.index, pe.subindex) + " of " + std::to_string(pe.bit_len) +
                          " bits and type '" + pe.data_type + "': no type of that length");
}

// The entry a PDO entry implies where the dictionary does not declare it: its default the type's zero (a
// signed 0 for a signed type, as a declared entry's), a BITn entry limited to its bits (as to_entry does), so
// that the entry reads back the same from the ESI softecat writes for it.
od::Entry pdo_implied_entry(const EsiPdoEntry& pe, const std::pair<DataType, uint16_t>& t, uint16_t access) {
    od::Entry e = u_entry(pe.index, pe.subindex, t.first, access, 0, pe.name);
    e.bit_length = t.second;
    if (od::is_string(t.first)) {
        e.default_value = std::monostate{};
    } else {
        e.default_value = number_of(0, t.first, t.second);
        if (t.first >= DataType::Bit1 && t.first <= DataType::Bit8)
            e.maximum = uint64_t{(1u << t.second) - 1};
    }
    return e;
}

// The declared limits stay unless they exclude the (new) default.
void keep_limits_around_default(od::Entry& e) {
    if (outside(e.default_value, e.minimum, e.maximum)) {
        e.minimum = std::monostate{};
        e.maximum = std::monostate{};
    }
}

struct Pdo {
    const EsiPdo* esi = nullptr;
    uint16_t index = 0;
    std::vector<EsiPdoEntry> entries;  // indices with the slot's increment
    int sm = -1;
    std::string module;  // "" for the device's own PDOs
};

}  // namespace

std::vector<std::string> list_devices(const EsiFile& file) {
    std::vector<std::string> out;
    for (const EsiDevice& d : file.devices)
        out.push_back(d.type_name + " " + hex(d.product_code, 8) + ":" + hex(d.revision, 8) + " " + d.name +
                      (d.has_product_code ? "" : " (no ProductCode: no EtherCAT slave controller)"));
    return out;
}

const EsiDevice& select_device(const EsiFile& file, const std::string& spec_in) {
    auto listing = [&file] {
        std::string s;
        for (const std::string& l : list_devices(file))
            s += "\n  " + l;
        return s;
    };
    std::string spec = spec_in.substr(0, spec_in.find('@'));  // the module list is load_product's
    while (!spec.empty() && std::isspace(static_cast<unsigned char>(spec.back())))
        spec.pop_back();
    while (!spec.empty() && std::isspace(static_cast<unsigned char>(spec.front())))
        spec.erase(0, 1);
    if (spec.empty()) {
        if (file.devices.size() == 1) return file.devices.front();
        throw InputError(file.source, 0,
                         std::to_string(file.devices.size()) +
                             " devices in the file; choose one by 0xPRODUCT:0xREVISION or Type:" + listing());
    }
    std::vector<const EsiDevice*> found;
    const std::size_t colon = spec.find(':');
    const auto product = parse_esi_number(spec.substr(0, colon));
    const std::optional<int64_t> revision =
        colon == std::string::npos ? std::nullopt : parse_esi_number(spec.substr(colon + 1));
    const bool numeric = product && (colon == std::string::npos || revision);
    if (numeric) {
        // By identity: the revision given must be there; without one, the product code must have one.
        const DeviceByIdentity m =
            find_device(file, static_cast<uint32_t>(*product),
                        revision ? std::optional<uint32_t>(static_cast<uint32_t>(*revision)) : std::nullopt);
        if (revision ? m.revision_matched : m.with_product == 1) return *m.device;
        for (const EsiDevice& d : file.devices)
            if (d.product_code == static_cast<uint32_t>(*product) && !revision) found.push_back(&d);
    } else {
        found = find_devices_by_type(file, spec);
    }
    if (found.size() == 1) return *found.front();
    if (found.empty())
        throw InputError(file.source, 0, "no device matches '" + spec + "'; the file has:" + listing());
    std::string which;
    for (const EsiDevice* d : found)
        which +=
            "\n  " + d->type_name + " " + hex(d->product_code, 8) + ":" + hex(d->revision, 8) + " " + d->name;
    throw InputError(file.source, 0,
                     "'" + spec + "' matches " + std::to_string(found.size()) +
                         " devices; choose one by 0xPRODUCT:0xREVISION:" + which);
}

od::Product load_product(const std::string& path, const std::string& spec) {
    return load_product(read_esi_file(path), spec);
}

od::Product load_product(const EsiFile& file, const std::string& spec) {
    const EsiDevice& d = select_device(file, spec);
    const std::size_t at = spec.find('@');
    if (at == std::string::npos) return load_product(file, d);
    return load_product(file, d, parse_module_list(file, d, spec.substr(at + 1)));
}

od::Product load_product(const EsiFile& file, const EsiDevice& d) {
    return load_product(file, d, default_modules(d));
}

od::Product load_product(const EsiFile& file, const EsiDevice& d,
                         const std::vector<std::optional<uint32_t>>& modules) {
    Ctx ctx{file.source, {}};
    // ETG.2000 leaves Type/@ProductCode optional for a device without an ESC (a passive terminal: Beckhoff's
    // end, shield and potential feed terminals). A master never sees one on the wire (it has no registers,
    // no SII, no identity), so there is nothing to serve: refused, not served as product 0.
    if (!d.has_product_code)
        ctx.fail(d.line, "device " + d.type_name +
                             " has no ProductCode: a device without an EtherCAT slave controller (a passive "
                             "terminal) is not on the wire and cannot be served");
    od::Product product;
    product.source = file.source + ", device " + d.type_name + " rev " + hex(d.revision, 8);
    od::DeviceDescription desc;

    // ---- Identity ----
    od::Identity& id = desc.identity;
    id.vendor_id = d.vendor_id;
    id.product_code = d.product_code;
    id.revision = d.revision;
    id.serial_number = 0;
    id.vendor_name = d.vendor_name;
    id.device_name = d.name.empty() ? d.type_name : d.name;
    id.order_code = d.type_name;
    id.group_type = d.group_type;
    auto default_text = [&d](uint16_t index) -> std::string {
        const EsiObject* o = d.object(index);
        if (o == nullptr || o->entries.empty()) return {};
        // As the object serves it: a default longer than its STRING(n) is cut to n (to_entry).
        std::string s = trim_nul(o->entries[0].default_data);
        if (const auto t = entry_type(o->entries[0]);
            t && od::is_string(t->first) && t->second != 0 && s.size() > t->second / 8u)
            s.resize(t->second / 8u);
        return s;
    };
    id.hardware_version = default_text(0x1009);
    id.software_version = default_text(0x100A);

    // ---- SyncManagers ----
    for (const EsiSm& s : d.sms) {
        od::SyncManagerDefault sm;
        const std::string t = upper(s.type);
        if (t == "MBOXOUT") {
            sm.kind = od::SmKind::MBoxOut;
        } else if (t == "MBOXIN") {
            sm.kind = od::SmKind::MBoxIn;
        } else if ((t == "OUTPUTS" || t == "INPUTS") && s.has_control && (s.control & 0x03) != 0x02 &&
                   (((s.control >> 2) & 0x03) == 0x01) != (t == "OUTPUTS")) {
            // The text names one direction, the control byte the other (ESC datasheet 0x0804 bits 2-3: 00 the
            // master reads, 01 it writes): the ESC serves the buffer as the control byte says, and so do a
            // master that reads the SII and the PDOs the file assigns to it (SMC's EX250: SM1 "Outputs" with
            // #x0 carrying the TxPdo). Taken from the control byte, said once.
            const bool write = ((s.control >> 2) & 0x03) == 0x01;
            sm.kind = write ? od::SmKind::Outputs : od::SmKind::Inputs;
            ctx.warn(s.line, "Sm '" + s.type + "' with control byte " + hex(s.control, 2) + " (the master " +
                                 (write ? "writes" : "reads") + " it): taken as " +
                                 (write ? "Outputs" : "Inputs") + ", as the ESC serves it");
        } else if (t == "OUTPUTS") {
            sm.kind = od::SmKind::Outputs;
        } else if (t == "INPUTS") {
            sm.kind = od::SmKind::Inputs;
        } else {
            // ESC datasheet, 0x0804: bits 0-1 mode (2 = mailbox), bits 2-3 direction (1 = ECAT writes).
            const bool mailbox = (s.control & 0x03) == 0x02;
            const bool write = ((s.control >> 2) & 0x03) == 0x01;
            sm.kind = mailbox ? (write ? od::SmKind::MBoxOut : od::SmKind::MBoxIn)
                              : (write ? od::SmKind::Outputs : od::SmKind::Inputs);
            ctx.warn(s.line, "Sm '" + s.type + "': not MBoxOut, MBoxIn, Outputs or Inputs; taken as " +
                                 (mailbox ? (write ? "MBoxOut" : "MBoxIn") : (write ? "Outputs" : "Inputs")) +
                                 " from its control byte " + hex(s.control, 2));
        }
        sm.start = s.start;
        sm.default_size = s.default_size;
        sm.control = s.control;
        sm.enable = s.enable;
        sm.min_size = static_cast<uint16_t>(std::min<uint32_t>(s.min_size.value_or(0), 0xFFFF));
        sm.max_size = static_cast<uint16_t>(std::min<uint32_t>(s.max_size.value_or(0), 0xFFFF));
        if (s.is_virtual) ctx.warn(s.line, "Sm Virtual: served as an ordinary SyncManager");
        desc.sync_managers.push_back(sm);
    }
    const od::SyncManagerDefault* mbox_out = nullptr;
    const od::SyncManagerDefault* mbox_in = nullptr;
    for (const auto& sm : desc.sync_managers) {
        if (sm.kind == od::SmKind::MBoxOut && !mbox_out) mbox_out = &sm;
        if (sm.kind == od::SmKind::MBoxIn && !mbox_in) mbox_in = &sm;
    }
    auto mbox_size = [](const od::SyncManagerDefault& sm) -> uint16_t {
        return sm.default_size ? sm.default_size : (sm.max_size ? sm.max_size : 128);
    };
    if (mbox_out && mbox_in) {
        desc.standard_mailbox = {mbox_out->start, mbox_size(*mbox_out), mbox_in->start, mbox_size(*mbox_in)};
    } else {
        desc.standard_mailbox = {0, 0, 0, 0};
    }
    desc.bootstrap_mailbox = {0, 0, 0, 0};
    if (d.bootstrap.size() >= 8) {
        auto w = [&d](int i) {
            return static_cast<uint16_t>(d.bootstrap[2 * i] | d.bootstrap[2 * i + 1] << 8);
        };
        desc.bootstrap_mailbox = {w(0), w(1), w(2), w(3)};
    }

    // ---- Mailbox protocols ----
    desc.mailbox_protocols = d.mailbox_protocols();
    desc.coe_details = 0;
    desc.foe_details = 0;
    if (desc.mailbox_protocols != 0 && !(mbox_out && mbox_in)) {
        ctx.warn(d.line,
                 "a Mailbox is declared but no MBoxOut/MBoxIn SyncManager: the device has no mailbox");
        desc.mailbox_protocols = 0;
    }
    if (desc.mailbox_protocols & od::mailbox_protocol::CoE) {
        namespace cd = od::coe_details;
        desc.coe_details = cd::Sdo | (d.coe.sdo_info ? cd::SdoInfo : 0) |
                           (d.coe.pdo_assign ? cd::PdoAssign : 0) | (d.coe.pdo_config ? cd::PdoConfig : 0) |
                           (d.coe.pdo_upload ? cd::PdoUpload : 0) |
                           (d.coe.complete_access ? cd::CompleteAccess : 0);
    }
    struct Unemulated {
        bool present;
        const char* element;
        const char* what;
    };
    for (const Unemulated& u : {Unemulated{d.eoe, "Mailbox/EoE", "Ethernet over EtherCAT"},
                                Unemulated{d.soe, "Mailbox/SoE", "Servo drive profile over EtherCAT"},
                                Unemulated{d.aoe, "Mailbox/AoE", "ADS over EtherCAT"},
                                Unemulated{d.voe, "Mailbox/VoE", "Vendor specific protocol over EtherCAT"}})
        if (u.present && desc.mailbox_protocols != 0)
            ctx.warn(d.line, std::string(u.element) + ": " + u.what +
                                 " is declared; softecat does not emulate it (its requests get the mailbox "
                                 "error 'unsupported protocol')");
    for (const std::string& what : d.unsupported)
        ctx.warn(d.line, what + ": declared; softecat does not emulate it");
    // The files InfoReference names, whose modules the slots may take: one that was not read is said, with
    // why (the device is served without its modules).
    if (!d.slots.empty())
        for (const EsiInfoReference& r : file.info_references)
            if (!r.problem.empty())
                ctx.warn(r.line, "InfoReference '" + r.reference + "': " + r.problem +
                                     "; the modules it holds are not offered to the slots");

    // ---- FMMUs ----
    for (const std::string& f : d.fmmus) {
        const std::string t = upper(f);
        desc.fmmus.push_back(t == "OUTPUTS" ? 1 : t == "INPUTS" ? 2 : t == "MBOXSTATE" ? 3 : 0);
    }

    // ---- DC ----
    for (const EsiOpMode& m : d.op_modes) {
        od::DcOpMode mode;
        mode.name = m.name;
        mode.description = m.desc;
        mode.assign_activate = m.assign_activate;
        if (m.assign_activate != 0) {  // a mode without SYNC activation has no SYNC timing
            mode.cycle_time_sync0 = m.cycle_time_sync0;
            mode.cycle_time_sync0_factor = m.cycle_time_sync0_factor.value_or(1);
            mode.shift_time_sync0 = m.shift_time_sync0;
            mode.cycle_time_sync1 = m.cycle_time_sync1;
            mode.cycle_time_sync1_factor = m.cycle_time_sync1_factor.value_or(0);
            mode.shift_time_sync1 = m.shift_time_sync1;
        }
        desc.dc_modes.push_back(mode);
    }

    // ---- EEPROM ----
    // ConfigData gives the first bytes of SII words 0-7; vendors often give fewer than 14 (a digital
    // terminal's "0201": PDI control and ESC configuration only, device emulation on): each word it gives is
    // used, the others keep their defaults.
    const std::vector<uint8_t>& cd = !d.config_data.empty() ? d.config_data : d.eeprom_data;
    if (cd.size() >= 1) desc.pdi_control = cd[0];
    if (cd.size() >= 2) desc.esc_config = cd[1];
    if (cd.size() >= 4) desc.pdi_config = static_cast<uint16_t>(cd[2] | cd[3] << 8);
    if (cd.size() >= 6) desc.sync_pulse_length = static_cast<uint16_t>(cd[4] | cd[5] << 8);
    if (cd.size() >= 8) desc.extended_pdi_config = static_cast<uint16_t>(cd[6] | cd[7] << 8);
    if (cd.size() >= 10) desc.station_alias = static_cast<uint16_t>(cd[8] | cd[9] << 8);
    if (cd.size() >= 12) desc.config_words_5_6[0] = static_cast<uint16_t>(cd[10] | cd[11] << 8);
    if (cd.size() >= 14) desc.config_words_5_6[1] = static_cast<uint16_t>(cd[12] | cd[13] << 8);
    uint32_t bytes = d.eeprom_bytes;
    if (bytes == 0) bytes = d.eeprom_data.empty() ? 2048 : static_cast<uint32_t>(d.eeprom_data.size());
    if (bytes % 128 != 0 || bytes > 512 * 1024) {
        const uint32_t fixed = std::clamp<uint32_t>((bytes + 127) / 128 * 128, 128, 512 * 1024);
        ctx.warn(d.eeprom_line, "Eeprom size " + std::to_string(bytes) + " is not a whole number of KiBit; " +
                                    std::to_string(fixed) + " bytes are emulated");
        bytes = fixed;
    }
    desc.eeprom_bytes = static_cast<uint16_t>(std::min<uint32_t>(bytes, 0xFFFF) == bytes ? bytes : 0);
    if (bytes > 0xFFFF) {
        ctx.warn(d.eeprom_line, "Eeprom of " + std::to_string(bytes) + " bytes; 32768 bytes are emulated");
        desc.eeprom_bytes = 32768;
    }
    if (!d.eeprom_data.empty()) {
        product.eeprom = d.eeprom_data;
        const auto& b = d.eeprom_data;
        if (b.size() < 0x20) {
            ctx.fail(d.eeprom_line, "Eeprom/Data of " + std::to_string(b.size()) +
                                        " bytes: shorter than the SII header an ESC reads at start");
        }
        auto u32 = [&b](std::size_t w) {
            return static_cast<uint32_t>(b[2 * w] | b[2 * w + 1] << 8 | b[2 * w + 2] << 16 |
                                         static_cast<uint32_t>(b[2 * w + 3]) << 24);
        };
        if (u32(0x08) != d.vendor_id || u32(0x0A) != d.product_code || u32(0x0C) != d.revision)
            ctx.warn(d.eeprom_line, "Eeprom/Data names " + hex(u32(0x08), 8) + "/" + hex(u32(0x0A), 8) + "/" +
                                        hex(u32(0x0C), 8) + ", the device is " + hex(d.vendor_id, 8) + "/" +
                                        hex(d.product_code, 8) + "/" + hex(d.revision, 8) +
                                        "; the image is served as it is");
        if (esc::sii::crc8(b.data(), esc::sii::kCrcBytes) != b[14])
            ctx.warn(d.eeprom_line,
                     "Eeprom/Data: the CRC of words 0-6 is wrong; the image is served as it is");
    }
    desc.mailbox_request_timeout_ms = d.mailbox_request_timeout_ms.value_or(0);
    desc.mailbox_response_timeout_ms = d.mailbox_response_timeout_ms.value_or(0);
    desc.mailbox_data_link_layer = d.has_mailbox && d.mailbox_data_link_layer;
    desc.identification_al_status = d.identification_reg134;
    desc.identification_register = d.identification_ado.value_or(0);
    desc.ebus_current_ma = static_cast<int16_t>(d.ebus_current_ma.value_or(0));
    // Physics (ETG.2000 PhysicsType, pattern [Y,K,H, ]{0,4}): one character per port from port 0, Y MII, K
    // E-Bus, H MII with fast hot connect, a blank no port. The pattern's commas are the character class's
    // separators, not a port type; lowercase is not in it. Port 0 is where the master's frames come in (ESC
    // datasheet, frame processing), so a device without it could not be reached. Without the attribute (or
    // with it empty) the device has two MII ports (od::DeviceDescription's default), as before Physics was
    // read.
    if (d.physics && !d.physics->empty()) {
        const std::string& ph = *d.physics;
        if (ph.size() > 4 || ph.find_first_not_of("YKH ") != std::string::npos)
            ctx.fail(d.line, "Device Physics '" + ph +
                                 "': one character per port, at most 4: Y (MII), K (E-Bus), H or a blank "
                                 "(ETG.2000 PhysicsType)");
        if (ph[0] == ' ')
            ctx.fail(d.line, "Device Physics '" + ph +
                                 "': port 0 has no port type; the master's frames enter a device there");
        desc.physics = ph;
    }

    // ---- The PDOs: the device's own and those of the module of each slot (its default, or as chosen) ----
    std::vector<Pdo> pdos;
    for (const auto* list : {&d.rxpdos, &d.txpdos})
        for (const EsiPdo& p : *list)
            pdos.push_back(Pdo{&p, p.index, p.entries, p.sm, ""});
    std::map<uint16_t, std::pair<EsiObject, std::string>> module_objects;  // with the slot's increment
    std::string module_list;
    const std::vector<SlotModule> served = slot_modules(file, d, modules);
    for (const SlotModule& sm : served) {
        const std::size_t n = sm.slot;
        const EsiModule* m = sm.module;
        if (m == nullptr) {
            ctx.warn(sm.esi_slot->line, "slot " + std::to_string(n + 1) + ": module " + hex(sm.ident, 8) +
                                            " is not in Descriptions/Modules; the slot is left empty");
            continue;
        }
        module_list += (module_list.empty() ? "" : ", ") + std::to_string(n + 1) + ": " + m->type_name;
        for (const SlotPdo& p : sm.pdos)
            pdos.push_back(Pdo{p.esi, p.index, p.entries, p.esi->sm, m->type_name});
        for (const SlotObject& o : sm.objects) {
            if (module_objects.count(o.index) || d.object(o.index)) {
                ctx.warn(o.esi->line, "module " + m->type_name + " in slot " + std::to_string(n + 1) +
                                          ": object " + hex(o.index) + " exists already; the first is used");
                continue;
            }
            module_objects[o.index] = {*o.esi, m->type_name};
        }
    }
    // The slots and the modules they take, for the ESI written back.
    std::set<uint32_t> offered;
    for (std::size_t n = 0; n < d.slots.size(); ++n) {
        const EsiSlot& slot = d.slots[n];
        if (slot.instance != 0) {
            // A further slot of a Slot element with MaxInstances: written back once, as the element; a module
            // in it is in the configuration served, not in the ESI's default.
            if (n < modules.size() && modules[n])
                ctx.warn(slot.line, "slot " + std::to_string(n + 1) + " is instance " +
                                        std::to_string(slot.instance + 1) + " of a Slot with MaxInstances " +
                                        std::to_string(slot.max_instances) +
                                        ": an ESI written back (--write-esi) leaves it empty by default");
            continue;
        }
        od::Slot s;
        s.name = slot.name;
        s.min_instances = slot.min_instances;
        s.max_instances = slot.max_instances;
        s.module_idents = slot.module_idents;
        for (const EsiModuleClass& c : slot.module_classes)
            s.module_classes.push_back(
                od::ModuleClass{c.class_name, !c.vendor_id.has_value(), c.vendor_id.value_or(0), c.name});
        // The module served in the slot: the ESI written back serves the same device. A ModuleClass has no
        // Default (ETG.2000 SlotType), so a slot that names classes is written empty by default.
        s.default_module = n < modules.size() ? modules[n].value_or(0) : 0;
        if (s.default_module != 0 && slot.module_idents.empty())
            ctx.warn(slot.line, "slot " + std::to_string(n + 1) +
                                    " takes modules by ModuleClass, which marks no default: an ESI written "
                                    "back (--write-esi) leaves the slot empty by default");
        s.pdo_increment = slot.pdo_increment.value_or(d.slot_pdo_increment);
        s.index_increment = slot.index_increment.value_or(d.slot_index_increment);
        offered.insert(slot.module_idents.begin(), slot.module_idents.end());
        for (const EsiModule& m : file.modules)
            if (slot_takes(file, slot, m)) offered.insert(m.ident);
        desc.slots.push_back(std::move(s));
    }
    for (const EsiModule& m : file.modules) {
        if (!offered.count(m.ident)) continue;
        od::Module mod;
        mod.ident = m.ident;
        mod.type = m.type_name;
        mod.module_class = m.module_class;
        mod.name = m.name;
        for (const auto* list : {&m.rxpdos, &m.txpdos})
            for (const EsiPdo& p : *list) {
                od::ModulePdo mp;
                mp.rx = p.rx;
                mp.index = p.index;
                mp.depend_on_slot = p.depend_on_slot;
                mp.name = p.name;
                mp.sm = p.sm;
                mp.fixed = p.fixed;
                mp.mandatory = p.mandatory;
                for (const EsiPdoEntry& e : p.entries)
                    mp.entries.push_back(od::ModulePdoEntry{e.index, e.subindex, e.bit_len, e.name,
                                                            e.data_type, e.depend_on_slot});
                mod.pdos.push_back(std::move(mp));
            }
        desc.modules.push_back(std::move(mod));
    }
    // A configuration other than the default: another module (or none) in some slot than its default.
    auto idents = [](const std::vector<SlotModule>& v) {
        std::vector<std::pair<std::size_t, uint32_t>> out;
        for (const SlotModule& sm : v)
            out.emplace_back(sm.slot, sm.ident);
        return out;
    };
    const bool chosen = idents(served) != idents(default_slot_modules(file, d));
    if (!d.slots.empty())
        ctx.warn(d.line, std::string("Slots: ") + (chosen ? "the chosen" : "the default") +
                             " configuration (" + (module_list.empty() ? "no modules" : module_list) +
                             ") is served; another is chosen by the device spec (SPEC@MODULE,MODULE,...)");
    // A Virtual PDO (ETG.2000: for the configuration tool only, e.g. ESC register data such as the DC
    // activation) that has the index of a real one: the real one is the mapping object; the virtual one is
    // left out.
    for (auto it = pdos.begin(); it != pdos.end();) {
        const bool shadowed =
            it->esi->is_virtual && std::any_of(pdos.begin(), pdos.end(), [&](const Pdo& q) {
                return !q.esi->is_virtual && q.index == it->index && q.esi->rx == it->esi->rx;
            });
        if (!shadowed) {
            ++it;
            continue;
        }
        ctx.warn(it->esi->line,
                 "PDO " + hex(it->index) + " Virtual has the index of a PDO that is not: left out");
        it = pdos.erase(it);
    }
    // A device PDO flagged OverwrittenByModule (ETG.2000 PdoType) whose index a configured module's PDO has:
    // the module's PDO takes its place, in its position among the device's PDOs (the order of the default
    // assignment; an IO-Link master's port PDOs, replaced by the modules of its port slots). Without such a
    // module the device's own PDO stays.
    for (std::size_t i = 0; i < pdos.size(); ++i) {
        if (!pdos[i].module.empty() || !pdos[i].esi->overwritten_by_module) continue;
        const auto by = std::find_if(pdos.begin(), pdos.end(), [&](const Pdo& q) {
            return !q.module.empty() && q.index == pdos[i].index && q.esi->rx == pdos[i].esi->rx;
        });
        if (by == pdos.end()) continue;
        ctx.warn(pdos[i].esi->line, "PDO " + hex(pdos[i].index) +
                                        " OverwrittenByModule: the PDO of that index of module " +
                                        by->module + " is served in its place");
        const std::size_t j = static_cast<std::size_t>(by - pdos.begin());
        Pdo module_pdo = std::move(*by);
        pdos.erase(by);
        if (j < i) --i;
        pdos[i] = std::move(module_pdo);
    }
    for (std::size_t i = 0; i < pdos.size(); ++i)
        for (std::size_t j = 0; j < i; ++j)
            if (pdos[i].index == pdos[j].index)
                ctx.fail(pdos[i].esi->line, "PDO " + hex(pdos[i].index) + " is declared twice");
    for (const Pdo& p : pdos)
        if (p.esi->is_virtual)
            ctx.warn(p.esi->line, "PDO " + hex(p.index) + " Virtual: served as an ordinary PDO");

    // ---- The dictionary: the declared objects ----
    std::set<uint16_t> mapped;
    for (const Pdo& p : pdos)
        for (const EsiPdoEntry& e : p.entries)
            if (e.index != 0) mapped.insert(e.index);
    Built built;
    for (const auto& [index, eo] : d.objects)
        if (auto o = to_object(eo, index, ctx, mapped.count(index) != 0)) {
            built.objects[index] = std::move(*o);
            built.lines[index] = eo.line;
        }
    for (const auto& [index, mo] : module_objects)
        if (auto o = to_object(mo.first, index, ctx, mapped.count(index) != 0)) {
            built.objects[index] = std::move(*o);
            built.lines[index] = mo.first.line;
        }
    const bool declared_dictionary = !d.objects.empty();

    // ---- The objects the PDO entries map (a device without CoE declares none: process data needs them) ----
    // One mapped entry of PDO pdo_index: its object or entry added where the dictionary lacks it, made
    // mappable in the PDO's direction where it is not. `element`: mapped by an RxPdo/TxPdo element (a VAR
    // mapped with a subindex is then an error), else by a mapping object's default in the dictionary.
    auto map_entry = [&](const EsiPdoEntry& pe, bool rx, uint16_t pdo_index, const std::string& pdo_name,
                         bool element) {
        if (pe.index == 0) return;  // padding
        auto it = built.objects.find(pe.index);
        const uint16_t pdo_access =
            rx ? (od::access::RW | od::access::RxPdo) : (od::access::RO | od::access::TxPdo);
        if (it == built.objects.end()) {
            if (declared_dictionary)
                ctx.warn(pe.line, "PDO " + hex(pdo_index) + " maps " + where(pe.index, pe.subindex) +
                                      ", which the dictionary does not declare; the object is added");
            const auto t = pdo_entry_type(pe, ctx);
            od::Object o;
            o.index = pe.index;
            o.code = pe.subindex == 0 ? od::ObjectCode::Var : od::ObjectCode::Record;
            o.name = pe.subindex == 0 ? (pe.name.empty() ? pdo_name : pe.name) : pdo_name;
            od::Entry e = pdo_implied_entry(pe, t, pdo_access);
            o.type = o.code == od::ObjectCode::Var ? t.first : static_cast<DataType>(0);
            o.entries.push_back(std::move(e));
            built.objects[pe.index] = std::move(o);
            built.lines[pe.index] = pe.line;
            return;
        }
        od::Object& o = it->second;
        od::Entry* target = nullptr;
        for (od::Entry& e : o.entries)
            if (e.subindex == pe.subindex) target = &e;
        if (target == nullptr) {
            if (o.code == od::ObjectCode::Var) {
                const std::string msg = "PDO " + hex(pdo_index) + " maps " + where(pe.index, pe.subindex) +
                                        ", but " + hex(pe.index) + " (" + o.name +
                                        ") is a VAR with subindex 0 only";
                if (element) ctx.fail(pe.line, msg);
                ctx.warn(pe.line, msg);
                return;
            }
            if (declared_dictionary)
                ctx.warn(pe.line, "PDO " + hex(pdo_index) + " maps " + where(pe.index, pe.subindex) +
                                      ", which the dictionary does not declare; the entry is added");
            const auto t = pdo_entry_type(pe, ctx);
            od::Entry e = pdo_implied_entry(pe, t, pdo_access);
            if (o.code == od::ObjectCode::Array && (o.type != t.first)) o.code = od::ObjectCode::Record;
            o.entries.push_back(std::move(e));
            std::sort(o.entries.begin(), o.entries.end(),
                      [](const od::Entry& a, const od::Entry& b) { return a.subindex < b.subindex; });
            if (!o.entries.empty() && o.entries[0].subindex == 0 && !declared_dictionary)
                o.entries[0].default_value = uint64_t{o.entries.back().subindex};
            return;
        }
        const bool compact = pe.bit_len > 0 && pe.bit_len < target->bit_length &&
                             !od::is_real(target->type) && !od::is_string(target->type) &&
                             target->type != DataType::Boolean;
        if (compact && (target->pdo_bit_length == 0 || target->pdo_bit_length == pe.bit_len)) {
            // A compact PDO: the low-order bits of the entry, as the vendor's device maps it.
            target->pdo_bit_length = pe.bit_len;
        } else if (target->bit_length != pe.bit_len)
            ctx.warn(pe.line, "PDO " + hex(pdo_index) + " maps " + where(pe.index, pe.subindex) + " with " +
                                  std::to_string(pe.bit_len) + " bits; the object has " +
                                  std::to_string(target->bit_length));
        const uint16_t flag = rx ? od::access::RxPdo : od::access::TxPdo;
        if (!(target->access & flag)) {
            if (declared_dictionary)
                ctx.warn(pe.line, "PDO " + hex(pdo_index) + " maps " + where(pe.index, pe.subindex) +
                                      ", which the dictionary does not flag " + (rx ? "RxPDO" : "TxPDO") +
                                      " mappable; it is made mappable");
            target->access |= flag;
            // The elements of an ARRAY share one Flags (ETG.2000 ArrayInfo): all of them become
            // mappable, so that the object stays an array (and is written back as one).
            if (o.code == od::ObjectCode::Array)
                for (od::Entry& e : o.entries)
                    if (e.subindex != 0) e.access |= flag;
        }
    };
    for (const Pdo& p : pdos)
        for (const EsiPdoEntry& pe : p.entries)
            map_entry(pe, p.esi->rx, p.index, p.esi->name, true);
    // A Record of entries added from PDOs: subindex 0 (count) is added by od when missing.

    // ---- Mapping objects the dictionary declares without an RxPdo/TxPdo element: what their defaults map
    // is treated as a PDO element's entries are (they are PDOs a master may assign, and the ESI softecat
    // writes describes every mapping object with an element) ----
    {
        std::set<uint16_t> with_element;
        for (const Pdo& p : pdos)
            with_element.insert(p.index);
        struct Mapped {
            EsiPdoEntry pe;
            bool rx;
            uint16_t pdo;
            std::string name;
        };
        std::vector<Mapped> mapped_by_objects;
        for (const auto& [index, mo] : built.objects) {
            // Only the standard ranges tell a direction here: the file names no PDO for the object.
            const od::PdoDirection dir = od::standard_pdo_direction(index);
            const bool rx = dir == od::PdoDirection::Rx;
            if (dir == od::PdoDirection::None || od::is_assignment_index(index) ||
                with_element.count(index) || mo.entries.empty())
                continue;
            const uint64_t count = mo.entries[0].subindex == 0 ? default_u(mo.entries[0]) : 0;
            for (const od::Entry& slot : mo.entries) {
                if (slot.subindex == 0 || slot.subindex > count) continue;
                const auto word = static_cast<uint32_t>(default_u(slot));
                EsiPdoEntry pe;
                pe.index = static_cast<uint16_t>(word >> 16);
                pe.subindex = static_cast<uint8_t>(word >> 8);
                pe.bit_len = static_cast<uint8_t>(word);
                pe.line = built.lines[index];
                if (pe.index != 0 && pe.bit_len != 0) mapped_by_objects.push_back({pe, rx, index, mo.name});
            }
        }
        for (const Mapped& m : mapped_by_objects)
            map_entry(m.pe, m.rx, m.pdo, m.name, false);
    }

    // ---- The PDO mapping objects as the PDO elements declare them, at the PDO's index wherever it lies (the
    // direction is the element's: od::Object::direction) ----
    const bool coe = desc.mailbox_protocols & od::mailbox_protocol::CoE;
    // A PDO whose index is an object of another kind cannot be a mapping object too; a device that names its
    // PDOs so (EL1262 TxPdo 0x1C00, the AX5000's 0x1018) has no CoE, or does not show those PDOs as objects,
    // and its PDOs live in its SII and ESI only. Here the SyncManager objects (ETG.1000.6 0x1C10-0x1C4F,
    // the process data's own) and, with CoE, the objects every CoE device has, or an object the file declares
    // that cannot hold a mapping, keep their index; the PDO is left out with a warning
    // (docs/decisions/esi.md, "PDOs at any index").
    for (auto it = pdos.begin(); it != pdos.end();) {
        const uint16_t index = it->index;
        std::string taken;
        if (index >= 0x1C10 && index <= 0x1C4F) {
            taken = "a SyncManager object (ETG.1000.6)";
        } else if (coe && (index == 0x1000 || index == 0x1001 || index == 0x1008 || index == 0x1009 ||
                           index == 0x100A || index == 0x1018 || index == 0x1C00)) {
            taken = "an object every CoE device has (ETG.1000.6)";
        } else if (auto o = built.objects.find(index);
                   o != built.objects.end() && od::standard_pdo_direction(index) == od::PdoDirection::None) {
            const od::Object& x = o->second;
            bool mapping_shape = x.code != od::ObjectCode::Var && !x.entries.empty();
            for (const od::Entry& e : x.entries)
                if (e.subindex != 0 && e.type != DataType::Unsigned32) mapping_shape = false;
            if (!mapping_shape) taken = "object " + hex(index) + " (" + x.name + ")";
        }
        if (taken.empty()) {
            ++it;
            continue;
        }
        ctx.warn(it->esi->line, std::string(it->esi->rx ? "RxPdo " : "TxPdo ") + hex(index) +
                                    ": the index is " + taken + "; the PDO is not served");
        it = pdos.erase(it);
    }
    for (const Pdo& p : pdos) {
        const bool rx = p.esi->rx;
        const od::PdoDirection dir = rx ? od::PdoDirection::Rx : od::PdoDirection::Tx;
        std::vector<uint64_t> words;
        for (const EsiPdoEntry& e : p.entries)
            words.push_back(uint64_t{e.index} << 16 | uint64_t{e.subindex} << 8 | e.bit_len);
        const uint16_t access =
            p.esi->fixed || !coe || !d.coe.pdo_config ? od::access::RO : od::access::RW_PreOp;
        auto it = built.objects.find(p.index);
        if (it != built.objects.end()) {
            od::Object& o = it->second;
            bool fits = o.code != od::ObjectCode::Var && !o.entries.empty() && o.entries[0].subindex == 0;
            std::vector<uint64_t> had;
            if (fits) {
                const uint64_t count = default_u(o.entries[0]);
                for (uint64_t k = 1; k <= count; ++k) {
                    const od::Entry* e = o.entry(static_cast<uint8_t>(k));
                    had.push_back(e ? default_u(*e) : 0);
                }
                for (std::size_t k = 1; k <= words.size(); ++k) {
                    const od::Entry* e = o.entry(static_cast<uint8_t>(k));
                    if (e == nullptr || e->type != DataType::Unsigned32) fits = false;
                }
            }
            if (had != words)
                ctx.warn(p.esi->line, "PDO " + hex(p.index) +
                                          ": the dictionary's default mapping differs from the " +
                                          (rx ? "RxPdo" : "TxPdo") + " element; the element is served");
            if (fits) {
                o.direction = dir;
                o.entries[0].default_value = uint64_t{words.size()};
                for (od::Entry& e : o.entries) {
                    // Subindices past the count keep what the dictionary declares (nothing maps them).
                    if (e.subindex >= 1 && e.subindex <= words.size())
                        e.default_value = words[e.subindex - 1];
                    if (p.esi->fixed) e.access &= static_cast<uint16_t>(~od::access::WriteMask);
                    keep_limits_around_default(e);
                }
                continue;
            }
            ctx.warn(
                built.lines[p.index],
                "object " + hex(p.index) + " cannot hold the PDO's mapping; it is replaced by one that can");
        }
        od::Object o;
        o.index = p.index;
        o.code = od::ObjectCode::Record;
        o.type = DataType::PdoMapping;
        o.direction = dir;
        o.name = p.esi->name.empty() ? std::string(rx ? "RxPDO " : "TxPDO ") + hex(p.index) : p.esi->name;
        o.entries.push_back(u_entry(p.index, 0, DataType::Unsigned8, access, words.size(), "SubIndex 000"));
        for (std::size_t k = 0; k < words.size(); ++k)
            o.entries.push_back(u_entry(p.index, static_cast<uint8_t>(k + 1), DataType::Unsigned32, access,
                                        words[k], nth(static_cast<unsigned>(k + 1))));
        if (o.entries.size() == 1)  // an empty PDO: room for nothing, but a valid record
            o.entries.push_back(u_entry(p.index, 1, DataType::Unsigned32, access, 0, nth(1)));
        built.objects[p.index] = std::move(o);
        built.lines[p.index] = p.esi->line;
    }

    // ---- The module ident lists of a modular device (ETG.5001.1 Modular Device Profile) ----
    // 0xF050 Detected Module Ident List: the ident of the module served in each slot, 0 for an empty slot
    // (or a module the file lacks, which is served as empty), subindex 0 the number of slots. 0xF030
    // Configured Module Ident List: written by the master (Slots DownloadModuleIdentList), compared with
    // 0xF050 by the stack at Pre-Op -> Safe-Op (AL status 0x0070); it starts as the detected list, so a
    // master that does not download one is not refused. Where the dictionary lacks them and the file says
    // the master downloads the list, both are added.
    if (!d.slots.empty() && coe) {
        std::vector<uint64_t> detected(d.slots.size(), 0);
        for (const SlotModule& sm : served)
            if (sm.module != nullptr && sm.slot < detected.size()) detected[sm.slot] = sm.ident;
        // The further instances of a Slot with MaxInstances that hold no module, at the end, are not slots of
        // this configuration (a coupler lists the modules plugged, not the 64 it could take): left out.
        while (!detected.empty() && detected.back() == 0) {
            const EsiSlot& last = d.slots[detected.size() - 1];
            if (last.instance == 0 || last.instance < last.min_instances) break;
            detected.pop_back();
        }
        if (detected.size() > 254) ctx.fail(d.line, "Slots: more than 254 slots for the module ident lists");
        auto module_list_object = [&](uint16_t index, const char* name, uint16_t access) {
            auto it = built.objects.find(index);
            if (it != built.objects.end()) {
                od::Object& o = it->second;
                bool ok = o.code != od::ObjectCode::Var && !o.entries.empty() && o.entries[0].subindex == 0 &&
                          o.entries[0].type == DataType::Unsigned8;
                for (const od::Entry& e : o.entries)
                    if (e.subindex != 0 && e.type != DataType::Unsigned32) ok = false;
                if (ok) {
                    o.entries[0].default_value = uint64_t{detected.size()};
                    keep_limits_around_default(o.entries[0]);
                    for (std::size_t k = 1; k <= detected.size(); ++k) {
                        auto e = std::find_if(o.entries.begin(), o.entries.end(),
                                              [k](const od::Entry& x) { return x.subindex == k; });
                        if (e == o.entries.end()) {
                            // Room for every slot: the entries the dictionary lacks, with the access of its
                            // last one.
                            const uint16_t acc = o.entries.back().access;
                            o.entries.push_back(u_entry(index, static_cast<uint8_t>(k), DataType::Unsigned32,
                                                        acc, 0, nth(static_cast<unsigned>(k))));
                            e = o.entries.end() - 1;
                        }
                        e->default_value = detected[k - 1];
                        keep_limits_around_default(*e);
                    }
                    // Subindices past the slots list nothing.
                    for (od::Entry& e : o.entries)
                        if (e.subindex > detected.size()) e.default_value = uint64_t{0};
                    std::sort(o.entries.begin(), o.entries.end(),
                              [](const od::Entry& a, const od::Entry& b) { return a.subindex < b.subindex; });
                    return;
                }
                ctx.warn(built.lines[index], "object " + hex(index) + " (" + o.name +
                                                 ") cannot hold a module ident list (UINT8 count, UDINT " +
                                                 "idents); it is replaced");
            } else if (!d.download_module_ident_list) {
                return;
            }
            od::Object o;
            o.index = index;
            o.code = od::ObjectCode::Array;
            o.type = DataType::Unsigned32;
            o.name = name;
            o.entries.push_back(
                u_entry(index, 0, DataType::Unsigned8, access, detected.size(), "SubIndex 000"));
            for (std::size_t k = 0; k < detected.size(); ++k)
                o.entries.push_back(u_entry(index, static_cast<uint8_t>(k + 1), DataType::Unsigned32, access,
                                            detected[k], nth(static_cast<unsigned>(k + 1))));
            built.objects[index] = std::move(o);
            built.lines[index] = d.line;
        };
        module_list_object(0xF030, "Configured module ident list", od::access::RW_PreOp);
        module_list_object(0xF050, "Detected module ident list", od::access::RO);
    }

    // ---- PDO rules and sets ----
    for (const Pdo& p : pdos)
        desc.pdo_rules.push_back(od::PdoRule{p.index, p.esi->mandatory, p.esi->exclude, p.esi->fixed});

    // ---- The assignment objects 0x1C10 + n of the process-data SMs, defaults from the PDOs' Sm ----
    const bool assignable = coe && d.coe.pdo_assign;
    for (std::size_t n = 0; n < desc.sync_managers.size() && n < 32; ++n) {
        const od::SmKind kind = desc.sync_managers[n].kind;
        if (kind != od::SmKind::Outputs && kind != od::SmKind::Inputs) continue;
        const bool rx = kind == od::SmKind::Outputs;
        std::vector<uint16_t> assigned;
        std::size_t candidates = 0;
        for (const Pdo& p : pdos) {
            if (p.esi->rx != rx) continue;
            ++candidates;
            if (p.sm == static_cast<int>(n)) assigned.push_back(p.index);
        }
        const auto index = static_cast<uint16_t>(0x1C10 + n);
        const uint16_t access = assignable ? od::access::RW_PreOp : od::access::RO;
        auto it = built.objects.find(index);
        if (it != built.objects.end() && it->second.code != od::ObjectCode::Var &&
            !it->second.entries.empty() && it->second.entries[0].subindex == 0) {
            od::Object& o = it->second;
            std::vector<uint16_t> had;
            const uint64_t count = default_u(o.entries[0]);
            for (uint64_t k = 1; k <= count; ++k)
                if (const od::Entry* e = o.entry(static_cast<uint8_t>(k)))
                    had.push_back(static_cast<uint16_t>(default_u(*e)));
            if (had != assigned && count != 0)
                ctx.warn(built.lines[index], "object " + hex(index) +
                                                 ": the dictionary assigns other PDOs than the " +
                                                 "PDOs' Sm attributes; the Sm attributes are served");
            bool ok = true;
            for (std::size_t k = 1; k <= assigned.size(); ++k) {
                const od::Entry* e = o.entry(static_cast<uint8_t>(k));
                if (e == nullptr || e->type != DataType::Unsigned16) ok = false;
            }
            if (ok) {
                o.direction = rx ? od::PdoDirection::Rx : od::PdoDirection::Tx;
                o.entries[0].default_value = uint64_t{assigned.size()};
                for (od::Entry& e : o.entries) {
                    // Subindices past the count keep what the dictionary declares (nothing is assigned
                    // there).
                    if (e.subindex >= 1 && e.subindex <= assigned.size())
                        e.default_value = uint64_t{assigned[e.subindex - 1]};
                    keep_limits_around_default(e);
                }
                continue;
            }
            ctx.warn(built.lines[index],
                     "object " + hex(index) + " cannot hold the default assignment; it is replaced");
        }
        od::Object o;
        o.index = index;
        o.code = od::ObjectCode::Array;
        o.type = DataType::Unsigned16;
        o.direction = rx ? od::PdoDirection::Rx : od::PdoDirection::Tx;
        o.name = rx ? (n == 2 ? "RxPDO assign" : "SM" + std::to_string(n) + " RxPDO assign")
                    : (n == 3 ? "TxPDO assign" : "SM" + std::to_string(n) + " TxPDO assign");
        o.entries.push_back(u_entry(index, 0, DataType::Unsigned8, access, assigned.size(), "SubIndex 000"));
        const std::size_t room = std::max<std::size_t>({candidates, assigned.size(), 1});
        for (std::size_t k = 0; k < room && k < 254; ++k)
            o.entries.push_back(u_entry(index, static_cast<uint8_t>(k + 1), DataType::Unsigned16, access,
                                        k < assigned.size() ? assigned[k] : 0,
                                        nth(static_cast<unsigned>(k + 1))));
        built.objects[index] = std::move(o);
        built.lines[index] = d.line;
    }
    for (const Pdo& p : pdos)
        if (p.sm >= 0) {
            const auto n = static_cast<std::size_t>(p.sm);
            const od::SmKind want = p.esi->rx ? od::SmKind::Outputs : od::SmKind::Inputs;
            if (n >= desc.sync_managers.size() || desc.sync_managers[n].kind != want)
                ctx.warn(p.esi->line, "PDO " + hex(p.index) + ": Sm " + std::to_string(p.sm) + " is not an " +
                                          (p.esi->rx ? "Outputs" : "Inputs") +
                                          " SyncManager; it is not assigned");
        }
    // The objects every CoE device has (ETG.1000.6: 0x1000 and 0x1018 mandatory; 0x1008 as every vendor
    // has it), for a CoE device whose file does not declare them (files without a Profile/Dictionary):
    // a master that reads the identity by SDO finds what the SII says.
    // An object the file lacks, declared at the Device element's line.
    auto add_missing = [&built, &d](uint16_t index, od::ObjectCode code, DataType type, const char* name,
                                    std::vector<od::Entry> entries) {
        od::Object o;
        o.index = index;
        o.code = code;
        o.type = type;
        o.name = name;
        o.entries = std::move(entries);
        built.objects[index] = std::move(o);
        built.lines[index] = d.line;
    };
    if (coe && !built.objects.count(0x1000)) {
        const uint32_t type = d.profile_no.value_or(0) | d.profile_add_info.value_or(0) << 16;
        add_missing(0x1000, od::ObjectCode::Var, DataType::Unsigned32, "Device type",
                    {u_entry(0x1000, 0, DataType::Unsigned32, od::access::RO, type, "Device type")});
    }
    if (coe && !built.objects.count(0x1008) && !id.order_code.empty()) {
        od::Entry e = u_entry(0x1008, 0, DataType::VisibleString, od::access::RO, 0, "Device name");
        e.default_value = std::monostate{};
        e.default_string = id.order_code.substr(0, 255);
        e.bit_length = static_cast<uint16_t>(8 * e.default_string.size());
        add_missing(0x1008, od::ObjectCode::Var, DataType::VisibleString, "Device name", {std::move(e)});
    }
    if (coe && !built.objects.count(0x1018)) {
        std::vector<od::Entry> entries{
            u_entry(0x1018, 0, DataType::Unsigned8, od::access::RO, 4, "SubIndex 000")};
        const char* names[] = {"Vendor ID", "Product code", "Revision", "Serial number"};
        const uint32_t values[] = {id.vendor_id, id.product_code, id.revision, 0};
        for (uint8_t k = 0; k < 4; ++k)
            entries.push_back(u_entry(0x1018, static_cast<uint8_t>(k + 1), DataType::Unsigned32,
                                      od::access::RO, values[k], names[k]));
        add_missing(0x1018, od::ObjectCode::Record, DataType::Identity, "Identity", std::move(entries));
    }
    // 0x1C00 (SyncManager communication type) for a CoE device that does not declare it.
    if (coe && !built.objects.count(0x1C00) && !desc.sync_managers.empty()) {
        std::vector<od::Entry> entries{u_entry(0x1C00, 0, DataType::Unsigned8, od::access::RO,
                                               desc.sync_managers.size(), "SubIndex 000")};
        for (std::size_t n = 0; n < desc.sync_managers.size() && n < 32; ++n)
            entries.push_back(u_entry(0x1C00, static_cast<uint8_t>(n + 1), DataType::Unsigned8,
                                      od::access::RO, static_cast<uint64_t>(desc.sync_managers[n].kind),
                                      nth(static_cast<unsigned>(n + 1))));
        add_missing(0x1C00, od::ObjectCode::Array, DataType::Unsigned8, "Sync manager type",
                    std::move(entries));
    }

    // ---- Predefined PDO sets (AlternativeSmMapping) ----
    for (const EsiPdoSet& set : d.pdo_sets) {
        od::PdoSet s;
        s.name = set.name;
        for (const auto& [sm, list] : set.sms)
            for (uint16_t index : list) {
                // The direction of the SM the set assigns it to, else the PDO's own.
                bool rx = false;
                for (const Pdo& p : pdos)
                    if (p.index == index) rx = p.esi->rx;
                if (sm >= 0 && static_cast<std::size_t>(sm) < desc.sync_managers.size())
                    rx = desc.sync_managers[static_cast<std::size_t>(sm)].kind == od::SmKind::Outputs;
                (rx ? s.rx : s.tx).push_back(index);
            }
        desc.pdo_sets.push_back(std::move(s));
    }

    // ---- Diagnosis texts (Profile/DiagMessages): kept, so that --write-esi gives them back and the device's
    // 0x10F3 messages with one of these texts carry the vendor's text id ----
    for (const EsiDiagMessage& m : d.diag_messages)
        desc.diag_messages.push_back({m.text_id, m.text, m.diag_class, 0});

    // ---- Entry names unique within an object (as the ESI's SubItems must be, and SDO information lists
    // them) ----
    for (auto& [index, o] : built.objects) {
        if (o.code == od::ObjectCode::Var) continue;
        std::set<std::string> seen;
        for (od::Entry& e : o.entries) {
            if (e.name.empty()) e.name = nth(e.subindex);
            if (!seen.insert(e.name).second) {
                e.name += " (" + nth(e.subindex) + ")";
                seen.insert(e.name);
            }
        }
    }

    // ---- The dictionary, built once here so that every fault shows now, with its line ----
    std::vector<od::Object> objects;
    {
        od::Dictionary check;
        for (auto& [index, o] : built.objects) {
            try {
                check.add(o);
            } catch (const std::logic_error& e) {
                ctx.fail(built.lines[index], "object " + hex(index) + " (" + o.name + "): " + e.what());
            }
            objects.push_back(o);
        }
    }
    const od::Identity loaded = desc.identity;
    product.make_dictionary = [objects, loaded](const od::DeviceDescription& dd) {
        od::Dictionary dict;
        for (od::Object o : objects) {
            auto set_string = [&o](const std::string& s) {
                od::Entry& e = o.entries[0];
                if (!od::is_string(e.type)) return;
                e.default_string = s;
                e.bit_length = std::max<uint16_t>(
                    e.bit_length, static_cast<uint16_t>(8 * std::min<std::size_t>(s.size(), 4096)));
                if (e.default_string.size() > e.bit_length / 8u) e.default_string.resize(e.bit_length / 8u);
            };
            if (o.index == 0x1008 && dd.identity.device_name != loaded.device_name)
                set_string(dd.identity.device_name);
            if (o.index == 0x1009 && dd.identity.hardware_version != loaded.hardware_version)
                set_string(dd.identity.hardware_version);
            if (o.index == 0x100A && dd.identity.software_version != loaded.software_version)
                set_string(dd.identity.software_version);
            if (o.index == 0x1018 &&
                o.direction == od::PdoDirection::None)  // not a PDO named 0x1018 (AX5201)
                for (od::Entry& e : o.entries) {
                    if (e.type != DataType::Unsigned32) continue;
                    if (e.subindex == 1) e.default_value = uint64_t{dd.identity.vendor_id};
                    if (e.subindex == 2) e.default_value = uint64_t{dd.identity.product_code};
                    if (e.subindex == 3) e.default_value = uint64_t{dd.identity.revision};
                    if (e.subindex == 4) e.default_value = uint64_t{dd.identity.serial_number};
                    e.minimum = std::monostate{};
                    e.maximum = std::monostate{};
                }
            dict.add(std::move(o));
        }
        return dict;
    };

    // ---- The identity object agrees with the Type element ----
    if (const EsiObject* o = d.object(0x1018)) {
        auto val = [o](uint8_t sub) -> std::optional<uint64_t> {
            const EsiEntry* e = o->entry(sub);
            if (e == nullptr) return std::nullopt;
            if (e->default_value) return static_cast<uint64_t>(*e->default_value);
            if (e->default_data.empty()) return std::nullopt;
            return load_le(e->default_data, 4);
        };
        const uint32_t want[] = {d.vendor_id, d.product_code, d.revision};
        for (uint8_t sub = 1; sub <= 3; ++sub)
            if (auto v = val(sub); v && *v != want[sub - 1])
                ctx.warn(o->line, "object 0x1018:0" + std::to_string(sub) + " declares " +
                                      hex(static_cast<uint32_t>(*v), 8) + ", the Type element " +
                                      hex(want[sub - 1], 8) +
                                      "; 0x1018 follows the Type element (as the SII does)");
    }

    // ---- The application ----
    uint32_t device_type = 0;
    if (auto it = built.objects.find(0x1000); it != built.objects.end())
        device_type = static_cast<uint32_t>(default_u(it->second.entries[0]));
    // The profile is the one the ESI's ProfileNo names (0x1000 as the vendor wrote it may say otherwise: an
    // ESI with ProfileNo 402 and a device type 0x00000004 is still a CiA 402 drive); AddInfo, where not
    // given, is 0x1000's high word if 0x1000 names the same profile.
    if (d.profile_no && *d.profile_no != 0 && *d.profile_no <= 0xFFFF) {
        desc.profile_number = static_cast<uint16_t>(*d.profile_no);
        desc.profile_add_info = static_cast<uint16_t>(
            d.profile_add_info.value_or((device_type & 0xFFFF) == *d.profile_no ? device_type >> 16 : 0));
    }
    const bool profile402 = (d.profile_no && *d.profile_no == 402) || (device_type & 0xFFFF) == 402;
    if (profile402 && built.objects.count(0x6040) && built.objects.count(0x6041))
        product.application = od::Application::Cia402Drive;
    else if (profile402)
        ctx.warn(d.line,
                 "profile 402 without controlword 0x6040 and statusword 0x6041: served without the drive");

    // ---- An SII that fits: the declared EEPROM size, or the next one that holds what softecat writes ----
    product.description = desc;
    if (product.eeprom.empty()) {
        const od::Dictionary dict = product.make_dictionary(product.description);
        const uint16_t declared_bytes = product.description.eeprom_bytes;
        for (;;) {
            try {
                (void)build_sii(product.description, dict);
                break;
            } catch (const std::length_error& e) {
                // Too little EEPROM (a larger one helps), or more than the SII can say (255 strings): not.
                if (product.description.eeprom_bytes >= 32768)
                    ctx.fail(d.eeprom_line, std::string("no SII can be built for this device: ") + e.what());
                product.description.eeprom_bytes =
                    static_cast<uint16_t>(product.description.eeprom_bytes * 2);
            } catch (const std::invalid_argument& e) {
                ctx.fail(d.eeprom_line, std::string("Eeprom: ") + e.what());
            }
        }
        if (product.description.eeprom_bytes != declared_bytes)
            ctx.warn(d.eeprom_line, "Eeprom ByteSize " + std::to_string(declared_bytes) +
                                        " cannot hold the SII softecat writes for the device; " +
                                        std::to_string(product.description.eeprom_bytes) +
                                        " bytes are emulated");
    }
    product.warnings = std::move(ctx.warnings);
    return product;
}

}  // namespace esi
