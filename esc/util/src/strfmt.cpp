#include "util/strfmt.hpp"

#include <cstdarg>
#include <cstdio>

namespace util {

std::string strprintf(const char* fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    va_list ap2;
    va_copy(ap2, ap);
    const int n = std::vsnprintf(nullptr, 0, fmt, ap);
    va_end(ap);
    std::string out(n > 0 ? static_cast<std::size_t>(n) : 0, '\0');
    if (n > 0) std::vsnprintf(out.data(), out.size() + 1, fmt, ap2);
    va_end(ap2);
    return out;
}

std::string hex(unsigned long long v, int digits) {
    return strprintf("0x%0*llX", digits, v);
}

}  // namespace util
