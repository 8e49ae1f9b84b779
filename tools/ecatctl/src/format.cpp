#include "format.hpp"

#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace ecatctl {

std::optional<ValueType> value_type_of(uint16_t coe_type) {
    switch (coe_type) {
        case 0x0001:  // BOOLEAN
        case 0x0005:
            return ValueType::U8;
        case 0x0002:
            return ValueType::I8;
        case 0x0003:
            return ValueType::I16;
        case 0x0004:
            return ValueType::I32;
        case 0x0006:
            return ValueType::U16;
        case 0x0007:
            return ValueType::U32;
        case 0x0008:
            return ValueType::F32;
        case 0x0011:
            return ValueType::F64;
        case 0x0015:
            return ValueType::I64;
        case 0x001B:
            return ValueType::U64;
        default:
            return std::nullopt;
    }
}

std::string end_state_text(std::string_view state, bool error, uint16_t code, std::string_view code_name,
                           std::string_view wanted) {
    const std::string not_wanted = ", not " + std::string(wanted);
    if (state.empty()) return "no AL status at the end (is the slave still there?)" + not_wanted;
    std::string text = "ended in " + std::string(state) + (error ? "+ERR" : "") + not_wanted;
    if (!error) return text;
    static const char* digits = "0123456789abcdef";
    std::string hex = "0x";
    for (int shift = 12; shift >= 0; shift -= 4)
        hex += digits[(code >> shift) & 0xF];
    return text + ", AL status code " + hex + " (" + std::string(code_name) + ")";
}

std::optional<uint64_t> parse_number(std::string_view text, uint64_t max) {
    int base = 10;
    if (text.size() > 2 && text[0] == '0' && (text[1] == 'x' || text[1] == 'X')) {
        base = 16;
        text.remove_prefix(2);
    } else if (text.size() > 2 && text[0] == '0' && (text[1] == 'b' || text[1] == 'B')) {
        base = 2;
        text.remove_prefix(2);
    }
    if (text.empty()) return std::nullopt;
    uint64_t v = 0;
    auto [p, ec] = std::from_chars(text.data(), text.data() + text.size(), v, base);
    if (ec != std::errc() || p != text.data() + text.size() || v > max) return std::nullopt;
    return v;
}

std::optional<ValueType> parse_type(std::string_view name) {
    if (name == "u8" || name == "uint8") return ValueType::U8;
    if (name == "u16" || name == "uint16") return ValueType::U16;
    if (name == "u32" || name == "uint32") return ValueType::U32;
    if (name == "u64" || name == "uint64") return ValueType::U64;
    if (name == "i8" || name == "int8") return ValueType::I8;
    if (name == "i16" || name == "int16") return ValueType::I16;
    if (name == "i32" || name == "int32") return ValueType::I32;
    if (name == "i64" || name == "int64") return ValueType::I64;
    if (name == "real32") return ValueType::F32;
    if (name == "real64") return ValueType::F64;
    return std::nullopt;
}

std::size_t type_size(ValueType t) {
    switch (t) {
        case ValueType::U8:
        case ValueType::I8:
            return 1;
        case ValueType::U16:
        case ValueType::I16:
            return 2;
        case ValueType::U32:
        case ValueType::I32:
        case ValueType::F32:
            return 4;
        case ValueType::U64:
        case ValueType::I64:
        case ValueType::F64:
            return 8;
    }
    return 0;
}

namespace {
bool is_signed(ValueType t) {
    return t == ValueType::I8 || t == ValueType::I16 || t == ValueType::I32 || t == ValueType::I64;
}
}  // namespace

std::string format_value(ValueType t, std::span<const uint8_t> data) {
    const std::size_t n = type_size(t);
    if (data.size() != n) return {};
    uint64_t u = 0;
    for (std::size_t i = 0; i < n; ++i)
        u |= static_cast<uint64_t>(data[i]) << (8 * i);
    char buf[64];
    if (t == ValueType::F32 || t == ValueType::F64) {
        double d = 0;
        if (t == ValueType::F32) {
            float f = 0;
            const auto bits = static_cast<uint32_t>(u);
            std::memcpy(&f, &bits, sizeof f);
            d = f;
            std::snprintf(buf, sizeof buf, "%.9g", d);
        } else {
            std::memcpy(&d, &u, sizeof d);
            std::snprintf(buf, sizeof buf, "%.17g", d);
        }
    } else if (is_signed(t)) {
        int64_t s = static_cast<int64_t>(u);
        if (n < 8 && (u >> (8 * n - 1)) & 1) s = static_cast<int64_t>(u | (~uint64_t{0} << (8 * n)));
        std::snprintf(buf, sizeof buf, "0x%0*llx (%lld)", static_cast<int>(2 * n),
                      static_cast<unsigned long long>(u), static_cast<long long>(s));
    } else {
        std::snprintf(buf, sizeof buf, "0x%0*llx (%llu)", static_cast<int>(2 * n),
                      static_cast<unsigned long long>(u), static_cast<unsigned long long>(u));
    }
    return buf;
}

std::optional<std::vector<uint8_t>> encode_value(ValueType t, std::string_view text) {
    const std::size_t n = type_size(t);
    if (t == ValueType::F32 || t == ValueType::F64) {
        std::string z(text);
        char* end = nullptr;
        errno = 0;
        const double d = std::strtod(z.c_str(), &end);
        if (z.empty() || end != z.c_str() + z.size() || errno == ERANGE) return std::nullopt;
        std::vector<uint8_t> out(n);
        if (t == ValueType::F32) {
            const auto f = static_cast<float>(d);
            std::memcpy(out.data(), &f, 4);
        } else {
            std::memcpy(out.data(), &d, 8);
        }
        return out;
    }
    const uint64_t umax = n == 8 ? ~uint64_t{0} : (uint64_t{1} << (8 * n)) - 1;
    uint64_t u = 0;
    if (!text.empty() && text[0] == '-') {
        if (!is_signed(t)) return std::nullopt;
        const uint64_t limit = uint64_t{1} << (8 * n - 1);  // |min|
        auto m = parse_number(text.substr(1), limit);
        if (!m) return std::nullopt;
        u = (0 - *m) & umax;
    } else {
        const uint64_t max = is_signed(t) ? (umax >> 1) : umax;
        auto v = parse_number(text, max);
        if (!v) return std::nullopt;
        u = *v;
    }
    std::vector<uint8_t> out(n);
    for (std::size_t i = 0; i < n; ++i)
        out[i] = static_cast<uint8_t>(u >> (8 * i));
    return out;
}

std::string hex_dump(uint32_t base, std::span<const uint8_t> data) {
    std::string s;
    char buf[16];
    for (std::size_t i = 0; i < data.size(); ++i) {
        if (i % 16 == 0) {
            if (i) s += '\n';
            std::snprintf(buf, sizeof buf, "0x%04x:", static_cast<unsigned>(base + i));
            s += buf;
        }
        std::snprintf(buf, sizeof buf, " %02x", data[i]);
        s += buf;
    }
    if (!data.empty()) s += '\n';
    return s;
}

}  // namespace ecatctl
