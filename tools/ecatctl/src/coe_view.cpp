#include "coe_view.hpp"

#include <cstdio>
#include <cstring>

#include "format.hpp"

namespace ecatctl {

using master::Error;

std::string_view esi_type_name(uint16_t t) {
    switch (t) {
        case dtype::Boolean:
            return "BOOL";
        case dtype::Integer8:
            return "SINT";
        case dtype::Integer16:
            return "INT";
        case dtype::Integer32:
            return "DINT";
        case dtype::Unsigned8:
            return "USINT";
        case dtype::Unsigned16:
            return "UINT";
        case dtype::Unsigned32:
            return "UDINT";
        case dtype::Real32:
            return "REAL";
        case dtype::VisibleString:
            return "STRING";
        case dtype::OctetString:
            return "OCTET_STRING";
        case dtype::UnicodeString:
            return "UNICODE_STRING";
        case dtype::Real64:
            return "LREAL";
        case dtype::Integer64:
            return "LINT";
        case dtype::Unsigned64:
            return "ULINT";
        default:
            return "";
    }
}

namespace {

std::optional<ValueType> value_type(uint16_t t, uint16_t bits) {
    switch (t) {
        case dtype::Integer8:
            return ValueType::I8;
        case dtype::Integer16:
            return ValueType::I16;
        case dtype::Integer32:
            return ValueType::I32;
        case dtype::Integer64:
            return ValueType::I64;
        case dtype::Boolean:
        case dtype::Unsigned8:
            return ValueType::U8;
        case dtype::Unsigned16:
            return ValueType::U16;
        case dtype::Unsigned32:
            return ValueType::U32;
        case dtype::Unsigned64:
            return ValueType::U64;
        case dtype::Real32:
            return ValueType::F32;
        case dtype::Real64:
            return ValueType::F64;
        default:
            break;
    }
    // Other unsigned types (UNSIGNED24, BIT2, ...): by size.
    if (t == dtype::VisibleString || t == dtype::OctetString || t == dtype::UnicodeString)
        return std::nullopt;
    if (bits <= 8) return ValueType::U8;
    if (bits <= 16) return ValueType::U16;
    if (bits <= 32) return ValueType::U32;
    if (bits <= 64) return ValueType::U64;
    return std::nullopt;
}

std::string hex_bytes(std::span<const uint8_t> data) {
    std::string s;
    char b[4];
    for (std::size_t i = 0; i < data.size(); ++i) {
        std::snprintf(b, sizeof b, i ? " %02x" : "%02x", data[i]);
        s += b;
    }
    return s;
}

}  // namespace

std::string format_typed(uint16_t data_type, uint16_t bit_length, std::span<const uint8_t> data) {
    if (data_type == dtype::VisibleString) {
        std::string s(data.begin(), data.end());
        if (auto nul = s.find('\0'); nul != std::string::npos) s.resize(nul);
        return s;
    }
    auto vt = value_type(data_type, bit_length);
    if (vt && data.size() <= type_size(*vt)) {
        std::vector<uint8_t> v(type_size(*vt), 0);
        std::memcpy(v.data(), data.data(), data.size());
        if (bit_length > 0 && bit_length < 8) v[0] = static_cast<uint8_t>(v[0] & ((1u << bit_length) - 1));
        // Signed types narrower than their container (INTEGER24, ...) are not sign-extended: rare in CoE.
        return format_value(*vt, v);
    }
    return hex_bytes(data);
}

void write_typed_json(util::JsonWriter& w, uint16_t data_type, uint16_t bit_length,
                      std::span<const uint8_t> data) {
    if (data_type == dtype::VisibleString) {
        std::string s(data.begin(), data.end());
        if (auto nul = s.find('\0'); nul != std::string::npos) s.resize(nul);
        w.value(s);
        return;
    }
    auto vt = value_type(data_type, bit_length);
    if (!vt || data.size() > type_size(*vt)) {
        w.value(hex_bytes(data));
        return;
    }
    uint8_t v[8] = {};
    std::memcpy(v, data.data(), data.size());
    if (bit_length > 0 && bit_length < 8) v[0] = static_cast<uint8_t>(v[0] & ((1u << bit_length) - 1));
    uint64_t u = 0;
    for (std::size_t i = type_size(*vt); i-- > 0;)
        u = (u << 8) | v[i];
    switch (*vt) {
        case ValueType::I8:
            w.value(static_cast<int8_t>(u));
            break;
        case ValueType::I16:
            w.value(static_cast<int16_t>(u));
            break;
        case ValueType::I32:
            w.value(static_cast<int32_t>(u));
            break;
        case ValueType::I64:
            w.value(static_cast<int64_t>(u));
            break;
        case ValueType::F32: {
            float f;
            std::memcpy(&f, v, sizeof f);
            w.value(static_cast<double>(f));
            break;
        }
        case ValueType::F64: {
            double d;
            std::memcpy(&d, v, sizeof d);
            w.value(d);
            break;
        }
        default:
            w.value(u);
    }
}

std::optional<std::vector<uint8_t>> encode_typed(uint16_t data_type, uint16_t bit_length,
                                                 const std::vector<std::string>& words) {
    if (data_type == dtype::VisibleString) {
        std::vector<uint8_t> out;
        for (const auto& w : words) {
            if (!out.empty()) out.push_back(' ');
            out.insert(out.end(), w.begin(), w.end());
        }
        return out;
    }
    auto vt = value_type(data_type, bit_length);
    if (!vt) return std::nullopt;
    std::vector<uint8_t> out;
    for (const auto& w : words) {
        auto b = encode_value(*vt, w);
        if (!b) return std::nullopt;
        out.insert(out.end(), b->begin(), b->end());
    }
    return out;
}

Error describe_entries(master::SdoClient& sdo, uint16_t index, uint8_t max_subindex,
                       std::vector<EntryView>& out) {
    out.clear();
    for (unsigned sub = 0; sub <= max_subindex; ++sub) {
        auto e = sdo.entry_description(index, static_cast<uint8_t>(sub), 0);
        if (!e) {
            if (e.error() == Error::SdoAbort) continue;  // a gap in the subindices
            return e.error();
        }
        out.push_back({static_cast<uint8_t>(sub), e->data_type, e->bit_length, e->access, e->name});
    }
    return Error::Ok;
}

std::vector<uint8_t> extract_bits(std::span<const uint8_t> image, std::size_t bit, std::size_t bits) {
    std::vector<uint8_t> v((bits + 7) / 8, 0);
    for (std::size_t i = 0; i < bits; ++i) {
        const std::size_t src = bit + i;
        if (src / 8 >= image.size()) break;
        if ((image[src / 8] >> (src % 8)) & 1) v[i / 8] = static_cast<uint8_t>(v[i / 8] | (1u << (i % 8)));
    }
    return v;
}

std::vector<CaPart> split_complete_access(const std::vector<EntryView>& entries, uint8_t from_sub,
                                          std::span<const uint8_t> image) {
    std::vector<CaPart> parts;
    std::size_t bit = 0;
    for (const auto& e : entries) {
        if (e.subindex < from_sub) continue;
        std::size_t bits = e.bit_length;
        if (e.subindex == 0) bits = 16;  // subindex 0 occupies 16 bits in a complete access
        if (bits % 8 == 0) bit = (bit + 7) / 8 * 8;
        if (bit + bits > image.size() * 8) break;
        CaPart p;
        p.entry = e;
        p.value = extract_bits(image, bit, e.subindex == 0 ? 8 : bits);
        parts.push_back(std::move(p));
        bit += bits;
    }
    return parts;
}

unsigned SyncView::bits() const {
    unsigned n = 0;
    for (const auto& p : pdos)
        for (const auto& e : p.entries)
            n += e.bit_length;
    return n;
}

namespace {

master::Result<uint64_t> read_uint(master::SdoClient& sdo, uint16_t index, uint8_t sub) {
    uint8_t b[8] = {};
    auto n = sdo.upload(index, sub, b);
    if (!n) return n.error();
    uint64_t v = 0;
    for (std::size_t i = 0; i < *n && i < 8; ++i)
        v |= static_cast<uint64_t>(b[i]) << (8 * i);
    return v;
}

}  // namespace

Error read_pdo_config(master::SdoClient& sdo, std::vector<SyncView>& out, bool names) {
    out.clear();
    // Which SMs carry process data: 0x1C00 (3 = outputs, 4 = inputs), else the usual SM2/SM3.
    std::vector<std::pair<uint8_t, bool>> sms;
    if (auto count = read_uint(sdo, 0x1C00, 0)) {
        for (unsigned i = 1; i <= *count && i <= 32; ++i) {
            auto t = read_uint(sdo, 0x1C00, static_cast<uint8_t>(i));
            if (!t) return t.error();
            if (*t == 3 || *t == 4) sms.emplace_back(static_cast<uint8_t>(i - 1), *t == 3);
        }
    } else if (count.error() == Error::SdoAbort) {
        sms = {{2, true}, {3, false}};
    } else {
        return count.error();
    }
    for (auto [sm, output] : sms) {
        SyncView sv;
        sv.sm = sm;
        sv.output = output;
        const auto assign = static_cast<uint16_t>(0x1C10 + sm);
        auto n = read_uint(sdo, assign, 0);
        if (!n) {
            if (n.error() == Error::SdoAbort) {
                out.push_back(std::move(sv));  // no assignment object: nothing assigned
                continue;
            }
            return n.error();
        }
        for (unsigned i = 1; i <= *n; ++i) {
            auto pdo = read_uint(sdo, assign, static_cast<uint8_t>(i));
            if (!pdo) return pdo.error();
            PdoView pv;
            pv.index = static_cast<uint16_t>(*pdo);
            if (names)
                if (auto od = sdo.object_description(pv.index)) pv.name = od->name;
            auto m = read_uint(sdo, pv.index, 0);
            if (!m) return m.error();
            for (unsigned k = 1; k <= *m; ++k) {
                auto raw = read_uint(sdo, pv.index, static_cast<uint8_t>(k));
                if (!raw) return raw.error();
                PdoEntryView ev;
                ev.index = static_cast<uint16_t>(*raw >> 16);
                ev.subindex = static_cast<uint8_t>(*raw >> 8);
                ev.bit_length = static_cast<uint8_t>(*raw);
                if (names && ev.index != 0) {
                    if (auto d = sdo.entry_description(ev.index, ev.subindex, 0)) {
                        ev.name = d->name;
                        ev.data_type = d->data_type;
                    }
                }
                pv.entries.push_back(std::move(ev));
            }
            sv.pdos.push_back(std::move(pv));
        }
        out.push_back(std::move(sv));
    }
    return Error::Ok;
}

}  // namespace ecatctl
