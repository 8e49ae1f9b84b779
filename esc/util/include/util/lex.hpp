#pragma once
// One lexer for softecat's line-oriented formats: the control commands (tools/lib/device: control.cpp,
// line.cpp), the topology file (tools/lib/slave: topology.cpp) and the device configuration file
// (od/src/device_config.cpp, tools/ecat-slave/config_check.cpp). One rule for each of:
//
// - characters: a line is text: no NUL and no control character other than tab (and a CR, taken as a
//   blank: files written on Windows), bytes >= 0x80 form valid UTF-8;
// - words: separated by blanks (space, tab, CR);
// - quoting: "..." with the escapes \" \\ \t \n, '...' taken literally; quoted and bare parts that touch
//   form one word (config="my drive.conf" is the word config=my drive.conf);
// - comments: a word that begins with '#' or ';' outside quotes begins a comment to the end of the line
//   (a '#' inside a word, as in a#b, is part of the word);
// - numbers: decimal with a '-' only where the target range allows negative values, or hexadecimal 0x...
//   (never negative), parsed with std::from_chars into the target type, no leading '+' or blanks, nothing
//   after the digits; floating point in decimal or exponent form, finite; every number is checked against
//   its range lo..hi, and an error names the range the same way everywhere ("an integer 0..3").
#include <charconv>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

namespace util {

// A line that breaks the rules: unterminated quote, unknown escape, control character, bad UTF-8.
class LexError : public std::invalid_argument {
  public:
    using std::invalid_argument::invalid_argument;
};

struct Word {
    std::string text;       // quotes removed, escapes resolved
    std::size_t begin = 0;  // offset of the word's first character in the line
    std::size_t end = 0;    // offset just past its last character (closing quote included)
    bool quoted = false;    // a part of it was quoted (a quoted word is never a comment, nor a keyword)
    bool operator==(std::string_view s) const { return text == s; }
};

// "" if line is text by the character rule above, else what is wrong with it.
std::string text_error(std::string_view line);

// s without the blanks (space, tab, CR) at either end.
std::string_view trim_blanks(std::string_view s);

// The words of one line (comment dropped). Throws LexError.
std::vector<Word> split(std::string_view line);

// The value of a "key = value" line (the device configuration): the rest of the line after '=', as one
// quoted word, or bare words kept with the blanks between them ("bare words here"), comment dropped; "" for
// nothing. A quoted word with more words after it is an error. Throws LexError.
std::string value_text(std::string_view rest);

// KEY=VALUE split at the first '=' (both non-empty), or nothing.
std::optional<std::pair<std::string_view, std::string_view>> key_value(std::string_view word);

enum class NumberError { None, NotANumber, OutOfRange };

namespace detail {
template <class T>
NumberError integer(std::string_view s, T& out, T lo, T hi) {
    if (s.empty()) return NumberError::NotANumber;
    T v{};
    const char* first = s.data();
    const char* last = s.data() + s.size();
    std::from_chars_result r{};
    if (s.size() > 2 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
        if (s[2] == '-' || s[2] == '+') return NumberError::NotANumber;  // from_chars takes '-': not here
        r = std::from_chars(first + 2, last, v, 16);
    } else {
        if (s[0] == '-' && lo >= T{}) return NumberError::NotANumber;  // negative where the range allows it
        r = std::from_chars(first, last, v, 10);
    }
    if (r.ec == std::errc::invalid_argument || r.ptr != last) return NumberError::NotANumber;
    if (r.ec == std::errc::result_out_of_range || v < lo || v > hi) return NumberError::OutOfRange;
    out = v;
    return NumberError::None;
}
NumberError floating(std::string_view s, double& out, double lo, double hi);
std::string range_text(long long lo, long long hi);
std::string range_text(unsigned long long lo, unsigned long long hi);
std::string range_text(double lo, double hi);
}  // namespace detail

// s as a number of type T within lo..hi (see the rules above); out is untouched on an error.
template <class T>
requires(std::integral<T> && !std::same_as<T, bool>) NumberError
    parse_number(std::string_view s, T& out, T lo = std::numeric_limits<T>::min(),
                 T hi = std::numeric_limits<T>::max()) {
    return detail::integer(s, out, lo, hi);
}
inline NumberError parse_number(std::string_view s, double& out,
                                double lo = -std::numeric_limits<double>::max(),
                                double hi = std::numeric_limits<double>::max()) {
    return detail::floating(s, out, lo, hi);
}

// The number, or nothing (not a number, or out of lo..hi).
template <class T>
std::optional<T> number(std::string_view s, T lo = std::numeric_limits<T>::lowest(),
                        T hi = std::numeric_limits<T>::max()) {
    T v{};
    if (parse_number(s, v, lo, hi) != NumberError::None) return std::nullopt;
    return v;
}

// What is expected, in the one wording every format uses: "an integer 0..3", "-1000..1000".
template <class T>
std::string expected_number(T lo, T hi) {
    if constexpr (std::is_floating_point_v<T>)
        return detail::range_text(static_cast<double>(lo), static_cast<double>(hi));
    else if constexpr (std::is_signed_v<T>)
        return "an integer " + detail::range_text(static_cast<long long>(lo), static_cast<long long>(hi));
    else
        return "an integer " +
               detail::range_text(static_cast<unsigned long long>(lo), static_cast<unsigned long long>(hi));
}

// "bad number 's' for KEY (expected an integer 0..3)": what every format says of a number it refuses.
template <class T>
std::string number_message(std::string_view key, std::string_view s, T lo, T hi) {
    return "bad number '" + std::string(s) + "' for " + std::string(key) + " (expected " +
           expected_number(lo, hi) + ")";
}

}  // namespace util
