#include "util/crc.hpp"

#include <zlib.h>

#include <algorithm>
#include <limits>

namespace util {

uint32_t crc32(std::span<const uint8_t> data, uint32_t crc) {
    uLong c = crc;
    const uint8_t* p = data.data();
    std::size_t left = data.size();
    while (left > 0) {  // zlib takes a uInt length: feed larger spans in pieces
        const std::size_t n = std::min<std::size_t>(left, std::numeric_limits<uInt>::max());
        c = ::crc32(c, p, static_cast<uInt>(n));
        p += n;
        left -= n;
    }
    return static_cast<uint32_t>(c);
}

}  // namespace util
