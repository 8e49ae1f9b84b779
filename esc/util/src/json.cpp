#include "util/json.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>

namespace util {

namespace {

// Length of the valid UTF-8 sequence starting at s[i] (1-4), 0 if the bytes there are not one.
std::size_t utf8_length(std::string_view s, std::size_t i) {
    const auto b = [&](std::size_t k) { return static_cast<unsigned char>(s[k]); };
    const unsigned char c = b(i);
    std::size_t n = 0;
    uint32_t cp = 0;
    if (c < 0x80) return 1;
    if (c >= 0xC2 && c <= 0xDF) {
        n = 2;
        cp = c & 0x1Fu;
    } else if (c >= 0xE0 && c <= 0xEF) {
        n = 3;
        cp = c & 0x0Fu;
    } else if (c >= 0xF0 && c <= 0xF4) {
        n = 4;
        cp = c & 0x07u;
    } else {
        return 0;
    }
    if (i + n > s.size()) return 0;
    for (std::size_t k = 1; k < n; ++k) {
        if ((b(i + k) & 0xC0) != 0x80) return 0;
        cp = (cp << 6) | (b(i + k) & 0x3Fu);
    }
    // Overlong forms, surrogates and code points past U+10FFFF are not UTF-8.
    if ((n == 3 && cp < 0x800) || (n == 4 && (cp < 0x10000 || cp > 0x10FFFF)) ||
        (cp >= 0xD800 && cp <= 0xDFFF))
        return 0;
    return n;
}

}  // namespace

std::string json_string(std::string_view s) {
    std::string o = "\"";
    for (std::size_t i = 0; i < s.size();) {
        const auto c = static_cast<unsigned char>(s[i]);
        if (c == '"' || c == '\\') {
            o += '\\';
            o += static_cast<char>(c);
            ++i;
        } else if (c < 0x20 || c == 0x7F) {
            char b[8];
            std::snprintf(b, sizeof b, "\\u%04x", c);
            o += b;
            ++i;
        } else if (const std::size_t n = utf8_length(s, i); n > 0) {
            o.append(s.substr(i, n));
            i += n;
        } else {
            // Not UTF-8: the byte as the ISO-8859-1 character it is (U+0080..U+00FF, two bytes in UTF-8).
            o += static_cast<char>(0xC0 | (c >> 6));
            o += static_cast<char>(0x80 | (c & 0x3F));
            ++i;
        }
    }
    o += '"';
    return o;
}

void JsonWriter::before_value() {
    if (after_key_) {
        after_key_ = false;
        return;
    }
    if (!open_.empty()) {
        if (open_.back()) out_ << ',';
        open_.back() = true;
    }
}

JsonWriter& JsonWriter::begin_object() {
    before_value();
    out_ << '{';
    open_.push_back(false);
    return *this;
}

JsonWriter& JsonWriter::end_object() {
    out_ << '}';
    open_.pop_back();
    if (open_.empty()) out_ << '\n';
    return *this;
}

JsonWriter& JsonWriter::begin_array() {
    before_value();
    out_ << '[';
    open_.push_back(false);
    return *this;
}

JsonWriter& JsonWriter::end_array() {
    out_ << ']';
    open_.pop_back();
    if (open_.empty()) out_ << '\n';
    return *this;
}

JsonWriter& JsonWriter::key(std::string_view name) {
    before_value();
    out_ << json_string(name) << ':';
    after_key_ = true;
    return *this;
}

JsonWriter& JsonWriter::value(std::string_view s) {
    before_value();
    out_ << json_string(s);
    return *this;
}

JsonWriter& JsonWriter::value(bool b) {
    before_value();
    out_ << (b ? "true" : "false");
    return *this;
}

JsonWriter& JsonWriter::integer(int64_t v) {
    before_value();
    out_ << v;
    return *this;
}

JsonWriter& JsonWriter::integer(uint64_t v) {
    before_value();
    out_ << v;
    return *this;
}

JsonWriter& JsonWriter::value(double v) {
    before_value();
    if (!std::isfinite(v)) {
        out_ << "null";
        return *this;
    }
    char b[32];
    const auto r = std::to_chars(b, b + sizeof b, v);  // the shortest text that reads back as v
    out_.write(b, r.ptr - b);
    return *this;
}

JsonWriter& JsonWriter::null() {
    before_value();
    out_ << "null";
    return *this;
}

}  // namespace util
