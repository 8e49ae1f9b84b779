// The one lexer of the line-oriented formats (see util/lex.hpp).
#include "util/lex.hpp"

#include <cmath>
#include <cstdio>

namespace util {

namespace {

bool blank(char c) {
    return c == ' ' || c == '\t' || c == '\r';
}

}  // namespace

std::string_view trim_blanks(std::string_view s) {
    while (!s.empty() && blank(s.front()))
        s.remove_prefix(1);
    while (!s.empty() && blank(s.back()))
        s.remove_suffix(1);
    return s;
}

std::string text_error(std::string_view l) {
    for (std::size_t i = 0; i < l.size(); ++i) {
        const auto c = static_cast<unsigned char>(l[i]);
        if ((c < 0x20 && c != '\t' && c != '\r') || c == 0x7F) {
            char code[8];
            std::snprintf(code, sizeof code, "0x%02X", c);
            return std::string("control character ") + code + " at column " + std::to_string(i + 1) +
                   " (not text)";
        }
        if (c < 0x80) continue;
        const int more = (c & 0xE0) == 0xC0 ? 1 : (c & 0xF0) == 0xE0 ? 2 : (c & 0xF8) == 0xF0 ? 3 : -1;
        bool ok = more > 0 && c != 0xC0 && c != 0xC1 && c <= 0xF4;
        const std::size_t at = i;
        for (int k = 0; ok && k < more; ++k)
            ok = ++i < l.size() && (static_cast<unsigned char>(l[i]) & 0xC0) == 0x80;
        if (!ok) return "invalid UTF-8 at column " + std::to_string(at + 1) + " (not text)";
    }
    return {};
}

std::vector<Word> split(std::string_view line) {
    if (std::string e = text_error(line); !e.empty()) throw LexError(e);
    std::vector<Word> out;
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && blank(line[i]))
            ++i;
        if (i == line.size()) break;
        if (line[i] == '#' || line[i] == ';') break;  // a comment: the rest of the line
        Word w;
        w.begin = i;
        while (i < line.size() && !blank(line[i])) {
            const char c = line[i];
            if (c == '"') {
                w.quoted = true;
                const std::size_t open = i++;
                for (;; ++i) {
                    if (i == line.size())
                        throw LexError("unterminated string (the quote at column " +
                                       std::to_string(open + 1) + " is not closed)");
                    if (line[i] == '"') break;
                    if (line[i] != '\\') {
                        w.text += line[i];
                        continue;
                    }
                    if (++i == line.size())
                        throw LexError("unterminated string (the quote at column " +
                                       std::to_string(open + 1) + " is not closed)");
                    switch (line[i]) {
                        case '"':
                        case '\\':
                            w.text += line[i];
                            break;
                        case 't':
                            w.text += '\t';
                            break;
                        case 'n':
                            w.text += '\n';
                            break;
                        default:
                            throw LexError(std::string("unknown escape \\") + line[i] + " at column " +
                                           std::to_string(i) + " (\\\" \\\\ \\t \\n)");
                    }
                }
                ++i;
            } else if (c == '\'') {
                w.quoted = true;
                const std::size_t close = line.find('\'', i + 1);
                if (close == std::string_view::npos)
                    throw LexError("unterminated string (the quote at column " + std::to_string(i + 1) +
                                   " is not closed)");
                w.text.append(line.substr(i + 1, close - i - 1));
                i = close + 1;
            } else {
                w.text += c;
                ++i;
            }
        }
        w.end = i;
        out.push_back(std::move(w));
    }
    return out;
}

std::string value_text(std::string_view rest) {
    std::vector<Word> w = split(rest);
    if (w.empty()) return {};
    if (w.size() == 1) return std::move(w[0].text);
    for (const Word& x : w)
        if (x.quoted)
            throw LexError("unexpected text after the string (quote the whole value: \"" +
                           std::string(rest.substr(w.front().begin, w.back().end - w.front().begin)) + "\")");
    return std::string(rest.substr(w.front().begin, w.back().end - w.front().begin));
}

std::optional<std::pair<std::string_view, std::string_view>> key_value(std::string_view word) {
    const std::size_t eq = word.find('=');
    if (eq == std::string_view::npos || eq == 0 || eq + 1 == word.size()) return std::nullopt;
    return std::make_pair(word.substr(0, eq), word.substr(eq + 1));
}

namespace detail {

NumberError floating(std::string_view s, double& out, double lo, double hi) {
    if (s.empty() || s[0] == '+') return NumberError::NotANumber;
    double v = 0;
    const auto r = std::from_chars(s.data(), s.data() + s.size(), v, std::chars_format::general);
    if (r.ec == std::errc::invalid_argument || r.ptr != s.data() + s.size()) return NumberError::NotANumber;
    if (r.ec == std::errc{} && !std::isfinite(v)) return NumberError::NotANumber;  // "inf", "nan"
    if (r.ec == std::errc::result_out_of_range || v < lo || v > hi) return NumberError::OutOfRange;
    out = v;
    return NumberError::None;
}

std::string range_text(long long lo, long long hi) {
    return std::to_string(lo) + ".." + std::to_string(hi);
}
std::string range_text(unsigned long long lo, unsigned long long hi) {
    return std::to_string(lo) + ".." + std::to_string(hi);
}
std::string range_text(double lo, double hi) {
    auto text = [](double v) {
        char b[32];
        std::snprintf(b, sizeof b, "%g", v);
        return std::string(b);
    };
    return text(lo) + ".." + text(hi);
}

}  // namespace detail

}  // namespace util
