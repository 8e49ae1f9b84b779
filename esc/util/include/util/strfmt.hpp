#pragma once
// printf-style formatting into a std::string of the length the text needs (libstdc++ 12 has no std::format).
// For messages, which carry paths and names of any length: a fixed char array cuts them.
#include <string>

namespace util {

// The text std::printf(fmt, ...) would print, whole; "" if fmt is invalid for the arguments.
std::string strprintf(const char* fmt, ...) __attribute__((format(printf, 1, 2)));

// "0x" and v in upper-case hex digits, at least `digits` of them: 0x1C12, 0x0007, 0x00000002.
std::string hex(unsigned long long v, int digits = 4);

}  // namespace util
