// SII EEPROM interface (0x0500-0x050F) and the power-on / reload of SII words 0-7.
#include "esc_impl.hpp"

namespace esc {

uint16_t Esc::Impl::eeprom_word(uint64_t word) const {
    if (word >= eeprom.size()) return 0xFFFF;  // beyond the image (and no overflow below)
    const uint64_t b = word * 2;
    if (b + 1 >= eeprom.size() + 1) return 0xFFFF;  // beyond the image
    const uint8_t lo = eeprom[b];
    const uint8_t hi = b + 1 < eeprom.size() ? eeprom[b + 1] : 0xFF;
    return static_cast<uint16_t>(lo | (hi << 8));
}

bool Esc::Impl::eeprom_crc_ok() const {
    if (eeprom.size() < 16) return false;
    const uint16_t w7 = eeprom_word(7);
    if (w7 == 0x88A4) return true;  // checksum check disabled (B1, debug value)
    return (w7 & 0xFF) == sii_crc8(eeprom.data(), 14);
}

void Esc::Impl::load_eeprom_words(bool power_on) {
    const bool ok = eeprom_crc_ok();
    uint16_t ctrl = r16(reg::kSiiControl);
    const uint16_t dl = r16(reg::kDlStatus);
    uint16_t ndl = dl;
    if (ok) {
        ctrl = static_cast<uint16_t>(ctrl & ~0x1800);
        const uint16_t w0 = eeprom_word(0);
        w8(reg::kPdiControl, static_cast<uint8_t>(w0));
        const uint8_t cfg_hi = static_cast<uint8_t>(w0 >> 8);
        // A reload keeps 0x0141 bits 1 and 4-7 (enhanced link detection).
        w8(reg::kEscConfig,
           power_on ? cfg_hi : static_cast<uint8_t>((r8(reg::kEscConfig) & 0xF2) | (cfg_hi & 0x0D)));
        w16(reg::kPdiConfig, eeprom_word(1));
        w16(reg::kDcPulseLength, eeprom_word(2));
        w16(reg::kExtPdiConfig, eeprom_word(3));
        if (power_on) w16(reg::kStationAlias, eeprom_word(4));
        ndl = static_cast<uint16_t>(ndl | 0x0001);
        ndl = static_cast<uint16_t>((r8(reg::kEscConfig) & 0x02) ? (ndl | 0x0004) : (ndl & ~0x0004));
    } else {
        ctrl = static_cast<uint16_t>(ctrl | 0x1800);  // checksum error, device information not loaded
        ndl = static_cast<uint16_t>(ndl & ~0x0001);
    }
    w16(reg::kSiiControl, ctrl);
    if (ndl != dl) {
        w16(reg::kDlStatus, ndl);
        set_ecat_event(ecev::kDlStatus);
    }
}

// Runs the command in 0x0502 bits 10:8 (after the whole frame for ECAT, at once for the PDI).
void Esc::Impl::eeprom_execute(Side) {
    const uint16_t c = r16(reg::kSiiControl);
    const unsigned cmd = (c >> 8) & 0x07;
    const uint32_t addr = r32(reg::kSiiAddress);
    uint16_t err = 0;
    switch (cmd) {
        case 1:  // read: 4 words (8-byte read size, 0x0502 bit 6)
            // Word addresses count on past 0xFFFFFFFF (no wrap to word 0); words past the end of the EEPROM
            // read 0xFFFF (the idle bus). A start address past the end is not acknowledged by any EEPROM:
            // bit 13, as for a write there (decisions/esc.md).
            for (uint16_t i = 0; i < 4; ++i)
                w16(static_cast<uint16_t>(reg::kSiiData + 2 * i),
                    static_cast<uint16_t>(
                        eeprom_word(static_cast<uint64_t>(addr) + i) ^
                        (static_cast<uint64_t>(addr) + i == 7 && cfg.faults.sii_checksum_wrong ? 0x00FF
                                                                                               : 0)));
            if (static_cast<uint64_t>(addr) * 2 + 1 >= eeprom.size()) err = 0x2000;
            break;
        case 2:  // write one word
            if (!(c & 0x0001)) {
                err = 0x4000;  // write without write enable
            } else if (static_cast<uint64_t>(addr) * 2 + 1 >= eeprom.size()) {
                err = 0x2000;  // no acknowledge beyond the device
            } else {
                const uint16_t v = r16(reg::kSiiData);
                eeprom[addr * 2] = static_cast<uint8_t>(v);
                eeprom[addr * 2 + 1] = static_cast<uint8_t>(v >> 8);
                if (eeprom_write_count < eeprom_writes.size())
                    eeprom_writes[eeprom_write_count++] = EepromWrite{static_cast<uint16_t>(addr), v};
            }
            break;
        case 3:  // SOEM's EC_ECMD_RELOAD (0x0300): tolerated as reload
        case 4:
            load_eeprom_words(false);
            break;
        default:
            err = 0x2000;  // invalid command
            break;
    }
    uint16_t nc = r16(reg::kSiiControl);  // a reload may have changed bits 11/12
    nc = static_cast<uint16_t>((nc & ~(0x8000 | 0x6000 | 0x0701)) | err);
    w16(reg::kSiiControl, nc);
}

}  // namespace esc
