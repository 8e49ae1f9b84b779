#pragma once
// CRC-32 of IEEE 802.3 (reflected polynomial 0xEDB88320, initial value and final xor 0xFFFFFFFF), computed
// by zlib. Used by the firmware image format (foe/) and the parameter and state files (od/,
// tools/lib/device). crc32(b, crc32(a)) == crc32(a ++ b): the previous result continues the checksum over
// more bytes.
#include <cstdint>
#include <span>

namespace util {

uint32_t crc32(std::span<const uint8_t> data, uint32_t crc = 0);

}  // namespace util
