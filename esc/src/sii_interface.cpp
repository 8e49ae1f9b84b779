// SII EEPROM interface unit (sii_interface.hpp): registers 0x0500-0x050F and the power-on / reload of SII
// words 0-7.
#include "sii_interface.hpp"

#include <algorithm>

#include "esc/wire/sii.hpp"
#include "util/le.hpp"

namespace esc {

namespace {

// The built-in SII image of a bare ESC: a valid header (PDI "on-chip bus", DC SYNC/latch units on, SYNC0/1
// mapped to the AL event register, 10 us pulses), identity zero, no categories, 2 KiB (16 Kbit).
std::vector<uint8_t> default_eeprom() {
    std::vector<uint8_t> img(2048, 0xFF);
    std::fill(img.begin(), img.begin() + 0x80, 0x00);
    auto put = [&](unsigned word, uint16_t v) { util::put16(&img[2 * word], v); };
    put(0x00, 0x0C80);  // 0x0140 PDI control 0x80, 0x0141 ESC config: SYNC out unit + latch in unit
    put(0x01, 0xCC00);  // 0x0150 0x00, 0x0151: SYNC0/SYNC1 outputs, mapped to AL event bits 2/3
    put(0x02, 0x03E8);  // SYNC pulse length 1000 x 10 ns
    put(0x07, esc::sii::crc8(img.data(), 14));
    put(0x3E, 0x000F);  // 16 Kbit - 1
    put(0x3F, 0x0001);  // version
    put(0x40, 0xFFFF);  // end of categories
    return img;
}

}  // namespace

SiiInterface::SiiInterface(Memory& m, const EscFaults& f) : mem(m), faults(f), eeprom(default_eeprom()) {}

void SiiInterface::run_pending(bool ok) {
    pending = false;
    if (ok) {
        execute();
    } else {
        mem.w16(reg::kSiiControl, static_cast<uint16_t>(mem.r16(reg::kSiiControl) & ~0x8000));
    }
}

void SiiInterface::flush(std::unique_lock<EscLock>& lock) {
    const std::array<EepromWrite, 4> w = writes;
    const uint8_t n = write_count;
    write_count = 0;
    auto cb = on_write_;
    lock.unlock();
    if (cb)
        for (uint8_t i = 0; i < n; ++i)
            cb(w[i].address, w[i].value);
}

uint16_t SiiInterface::word(uint64_t word) const {
    if (word >= eeprom.size()) return 0xFFFF;  // beyond the image (and no overflow below)
    const uint64_t b = word * 2;
    if (b + 1 >= eeprom.size() + 1) return 0xFFFF;  // beyond the image
    const uint8_t lo = eeprom[b];
    const uint8_t hi = b + 1 < eeprom.size() ? eeprom[b + 1] : 0xFF;
    return static_cast<uint16_t>(lo | (hi << 8));
}

bool SiiInterface::crc_ok() const {
    if (eeprom.size() < 16) return false;
    const uint16_t w7 = word(7);
    if (w7 == 0x88A4) return true;  // checksum check disabled (B1, debug value)
    return (w7 & 0xFF) == esc::sii::crc8(eeprom.data(), 14);
}

void SiiInterface::load_words(bool power_on) {
    const bool ok = crc_ok();
    uint16_t ctrl = mem.r16(reg::kSiiControl);
    const uint16_t dl = mem.r16(reg::kDlStatus);
    uint16_t ndl = dl;
    if (ok) {
        ctrl = static_cast<uint16_t>(ctrl & ~0x1800);
        const uint16_t w0 = word(0);
        mem.w8(reg::kPdiControl, static_cast<uint8_t>(w0));
        const uint8_t cfg_hi = static_cast<uint8_t>(w0 >> 8);
        // A reload keeps 0x0141 bits 1 and 4-7 (enhanced link detection).
        mem.w8(reg::kEscConfig,
               power_on ? cfg_hi : static_cast<uint8_t>((mem.r8(reg::kEscConfig) & 0xF2) | (cfg_hi & 0x0D)));
        mem.w16(reg::kPdiConfig, word(1));
        mem.w16(reg::kDcPulseLength, word(2));
        mem.w16(reg::kExtPdiConfig, word(3));
        if (power_on) mem.w16(reg::kStationAlias, word(4));
        ndl = static_cast<uint16_t>(ndl | 0x0001);
        ndl = static_cast<uint16_t>((mem.r8(reg::kEscConfig) & 0x02) ? (ndl | 0x0004) : (ndl & ~0x0004));
    } else {
        ctrl = static_cast<uint16_t>(ctrl | 0x1800);  // checksum error, device information not loaded
        ndl = static_cast<uint16_t>(ndl & ~0x0001);
    }
    mem.w16(reg::kSiiControl, ctrl);
    if (ndl != dl) {
        mem.w16(reg::kDlStatus, ndl);
        mem.set_ecat_event(ecev::kDlStatus);
    }
}

// Runs the command in 0x0502 bits 10:8 (after the whole frame for ECAT, at once for the PDI).
void SiiInterface::execute() {
    const uint16_t c = mem.r16(reg::kSiiControl);
    const unsigned cmd = (c >> 8) & 0x07;
    const uint32_t addr = mem.r32(reg::kSiiAddress);
    uint16_t err = 0;
    switch (cmd) {
        case 1:  // read: 4 words (8-byte read size, 0x0502 bit 6)
            // Word addresses count on past 0xFFFFFFFF (no wrap to word 0); words past the end of the EEPROM
            // read 0xFFFF (the idle bus). A start address past the end is not acknowledged by any EEPROM:
            // bit 13, as for a write there (decisions/esc.md).
            for (uint16_t i = 0; i < 4; ++i)
                mem.w16(
                    static_cast<uint16_t>(reg::kSiiData + 2 * i),
                    static_cast<uint16_t>(
                        word(static_cast<uint64_t>(addr) + i) ^
                        (static_cast<uint64_t>(addr) + i == 7 && faults.sii_checksum_wrong ? 0x00FF : 0)));
            if (static_cast<uint64_t>(addr) * 2 + 1 >= eeprom.size()) err = 0x2000;
            break;
        case 2:  // write one word
            if (!(c & 0x0001)) {
                err = 0x4000;  // write without write enable
            } else if (static_cast<uint64_t>(addr) * 2 + 1 >= eeprom.size()) {
                err = 0x2000;  // no acknowledge beyond the device
            } else {
                const uint16_t v = mem.r16(reg::kSiiData);
                util::put16(&eeprom[addr * 2], v);
                if (write_count < writes.size())
                    writes[write_count++] = EepromWrite{static_cast<uint16_t>(addr), v};
            }
            break;
        case 3:  // SOEM's EC_ECMD_RELOAD (0x0300): tolerated as reload
        case 4:
            load_words(false);
            break;
        default:
            err = 0x2000;  // invalid command
            break;
    }
    uint16_t nc = mem.r16(reg::kSiiControl);  // a reload may have changed bits 11/12
    nc = static_cast<uint16_t>((nc & ~(0x8000 | 0x6000 | 0x0701)) | err);
    mem.w16(reg::kSiiControl, nc);
}

}  // namespace esc
