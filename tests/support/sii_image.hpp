#pragma once
// A small SII EEPROM image for tests of the master against plain emulated ESCs: the fixed header (ETG.2010)
// with an identity (vendor 0xFB, product 0x30010000, revision 0x01200000, the given serial number), a
// standard mailbox at 0x1000/0x1080 (128 bytes each, CoE), one STRINGS category and the end marker, in a
// 2 KiB EEPROM. esc_config goes to word 0's high byte (0x0141; bit 0 = device emulation).
#include <cstdint>
#include <vector>

#include "esc/wire/sii.hpp"
#include "util/le.hpp"

namespace test_support {

// Bytes up to and including the end marker.
inline constexpr std::size_t kSmallSiiImageEnd = (0x40 + 6) * 2;

inline std::vector<uint8_t> small_sii_image(uint8_t esc_config = 0x0C, uint32_t serial = 0x4321) {
    std::vector<uint16_t> w(0x40, 0);
    w[0] = static_cast<uint16_t>(0x05 | (esc_config << 8));
    w[8] = 0x00FB;
    w[10] = 0x0000;
    w[11] = 0x3001;
    w[12] = 0x0000;
    w[13] = 0x0120;
    w[14] = static_cast<uint16_t>(serial);
    w[15] = static_cast<uint16_t>(serial >> 16);
    w[0x18] = 0x1000;
    w[0x19] = 128;
    w[0x1A] = 0x1080;
    w[0x1B] = 128;
    w[0x1C] = 0x0004;
    w[0x3E] = 0x000F;
    w[0x3F] = 1;
    w.insert(w.end(), {10, 3, 0x4101, 0x4242, 0x0042, 0xFFFF});
    std::vector<uint8_t> b;
    for (uint16_t x : w)
        util::append16(b, x);
    b[14] = esc::sii::crc8(b.data(), 14);
    b.resize(2048, 0xFF);
    return b;
}

}  // namespace test_support
