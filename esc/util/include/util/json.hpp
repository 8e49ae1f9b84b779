#pragma once
// JSON text (RFC 8259) written as it goes, for the programs' machine-readable outputs (ecatctl --json,
// ecat-conform --json). Strings are escaped as the RFC requires; bytes that are not UTF-8 (an SII string in
// ISO-8859-1, a slave's garbage) are taken as ISO-8859-1 and written as the characters they stand for, so the
// output is always valid UTF-8 and valid JSON. Numbers: integers exactly, reals as the shortest text that
// reads back as the same double (NaN and infinities, which JSON cannot carry, as null).
#include <cstdint>
#include <ostream>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace util {

// The quoted, escaped JSON string of s.
std::string json_string(std::string_view s);

class JsonWriter {
  public:
    explicit JsonWriter(std::ostream& out) : out_(out) {}
    JsonWriter(const JsonWriter&) = delete;
    JsonWriter& operator=(const JsonWriter&) = delete;

    JsonWriter& begin_object();
    JsonWriter& end_object();
    JsonWriter& begin_array();
    JsonWriter& end_array();
    // The name of the next member of the object being written.
    JsonWriter& key(std::string_view name);

    JsonWriter& value(std::string_view s);
    JsonWriter& value(const char* s) { return value(std::string_view(s)); }
    JsonWriter& value(const std::string& s) { return value(std::string_view(s)); }
    JsonWriter& value(bool b);
    // Any integer type, exactly.
    template <typename T>
    requires(std::is_integral_v<T> && !std::is_same_v<T, bool>) JsonWriter& value(T v) {
        if constexpr (std::is_signed_v<T>)
            return integer(static_cast<int64_t>(v));
        else
            return integer(static_cast<uint64_t>(v));
    }
    JsonWriter& value(double v);
    JsonWriter& null();
    // key(name).value(v) in one call.
    template <typename T>
    JsonWriter& member(std::string_view name, const T& v) {
        key(name);
        return value(v);
    }

  private:
    JsonWriter& integer(int64_t v);
    JsonWriter& integer(uint64_t v);
    void before_value();
    std::ostream& out_;
    // One entry per open container: true once it holds a member or element (the next one needs a comma).
    std::vector<bool> open_;
    bool after_key_ = false;
};

}  // namespace util
