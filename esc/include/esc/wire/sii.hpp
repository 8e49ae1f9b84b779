#pragma once
// The SII EEPROM layout (ETG.1000.6 §5.4, ETG.2010): the word addresses of the fixed header (words
// 0x00-0x3F), the category header and codes that follow it, the PDO category flags and the CRC-8 over
// words 0-6 stored in word 7. The ESC reads this layout at EEPROM reload, so it lives with the ESC: the SII
// builder (esi/), the ESC's EEPROM interface, the object model, the master and the tools all take it from
// here.
#include <cstddef>
#include <cstdint>

namespace esc::sii {

// Word addresses of the fixed header.
namespace word {
constexpr uint16_t PdiControl = 0x0000;
constexpr uint16_t PdiConfig = 0x0001;
constexpr uint16_t SyncImpulseLength = 0x0002;
constexpr uint16_t PdiConfig2 = 0x0003;
constexpr uint16_t StationAlias = 0x0004;
constexpr uint16_t Checksum = 0x0007;  // low byte: CRC-8 of words 0-6
constexpr uint16_t VendorId = 0x0008;
constexpr uint16_t ProductCode = 0x000A;
constexpr uint16_t Revision = 0x000C;
constexpr uint16_t SerialNumber = 0x000E;
constexpr uint16_t BootMailboxOut = 0x0014;  // offset, size; then 0x0016 in: offset, size
constexpr uint16_t BootMailboxIn = 0x0016;
constexpr uint16_t StdMailboxOut = 0x0018;
constexpr uint16_t StdMailboxIn = 0x001A;
constexpr uint16_t MailboxProtocols = 0x001C;
constexpr uint16_t EepromSize = 0x003E;  // (KiBit - 1)
constexpr uint16_t Version = 0x003F;
constexpr uint16_t FirstCategory = 0x0040;
}  // namespace word

// Category header: type (word 0), length in words (word 1), then the data. 0xFFFF ends the list.
constexpr std::size_t kCategoryHeaderWords = 2;
namespace category {
constexpr uint16_t Nop = 0;
constexpr uint16_t Strings = 10;
constexpr uint16_t DataTypes = 20;
constexpr uint16_t General = 30;
constexpr uint16_t Fmmu = 40;
constexpr uint16_t SyncM = 41;
constexpr uint16_t FmmuX = 42;
constexpr uint16_t SyncUnit = 43;
constexpr uint16_t TxPdo = 50;
constexpr uint16_t RxPdo = 51;
constexpr uint16_t Dc = 60;
constexpr uint16_t End = 0xFFFF;
}  // namespace category

// PDO flags word (TxPDO/RxPDO category, bytes 6-7).
namespace pdo_flags {
constexpr uint16_t Mandatory = 0x0001;
constexpr uint16_t Default = 0x0002;  // assigned by default (ESI Sm attribute given)
constexpr uint16_t FixedContent = 0x0010;
constexpr uint16_t VirtualContent = 0x0020;
constexpr uint16_t OverwrittenByModule = 0x0800;
}  // namespace pdo_flags

constexpr uint16_t kChecksumDisabled = 0x88A4;  // word 7 value that disables the check (ESC datasheet, SII)
constexpr std::size_t kCrcBytes = 14;           // the CRC covers words 0-6

// CRC-8 of the SII header (polynomial 0x07, initial 0xFF, MSB first, no final xor) over the given bytes.
constexpr uint8_t crc8(const uint8_t* data, std::size_t size) {
    uint8_t crc = 0xFF;
    for (std::size_t i = 0; i < size; ++i) {
        crc ^= data[i];
        for (int b = 0; b < 8; ++b)
            crc = (crc & 0x80) ? static_cast<uint8_t>((crc << 1) ^ 0x07) : static_cast<uint8_t>(crc << 1);
    }
    return crc;
}

// Mailbox protocols word (word 0x1C) bits, also the ESI's Mailbox element (ETG.2010, ETG.2000).
namespace mailbox_protocol {
constexpr uint16_t AoE = 0x0001;
constexpr uint16_t EoE = 0x0002;
constexpr uint16_t CoE = 0x0004;
constexpr uint16_t FoE = 0x0008;
constexpr uint16_t SoE = 0x0010;
constexpr uint16_t VoE = 0x0020;
}  // namespace mailbox_protocol

// CoE details bits of the General category (ETG.2010).
namespace coe_details {
constexpr uint8_t Sdo = 0x01;
constexpr uint8_t SdoInfo = 0x02;
constexpr uint8_t PdoAssign = 0x04;
constexpr uint8_t PdoConfig = 0x08;
constexpr uint8_t PdoUpload = 0x10;
constexpr uint8_t CompleteAccess = 0x20;
}  // namespace coe_details

}  // namespace esc::sii
