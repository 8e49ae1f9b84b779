#pragma once
// The EtherCAT mailbox vocabulary (ETG.1000.4 §5.6, ETG.1000.6 §5.6): the 6-byte mailbox header, the
// mailbox types and the error codes of a mailbox error reply (type 0). Slave and master both take them
// from here.
#include <cstddef>
#include <cstdint>

namespace ecat {

// Mailbox types (header byte 5, bits 3:0).
enum class MailboxType : uint8_t {
    Error = 0x0,
    AoE = 0x1,
    EoE = 0x2,
    CoE = 0x3,
    FoE = 0x4,
    SoE = 0x5,
    VoE = 0xF
};

// Mailbox error codes (mailbox type 0 reply, ETG.1000.4).
enum class MailboxError : uint16_t {
    Syntax = 0x0001,
    UnsupportedProtocol = 0x0002,
    InvalidChannel = 0x0003,
    ServiceNotSupported = 0x0004,
    InvalidHeader = 0x0005,
    SizeTooShort = 0x0006,
    NoMoreMemory = 0x0007,
    InvalidSize = 0x0008,
    ServiceInWork = 0x0009,
};

// Mailbox header: bytes 0-1 length of the data after the header, 2-3 address, byte 4 bits 5:0 channel and
// 7:6 priority, byte 5 bits 3:0 type and 6:4 counter (1..7; 0 = not counted).
constexpr std::size_t kMailboxHeaderSize = 6;
namespace mbx {
constexpr std::size_t kLength = 0;
constexpr std::size_t kAddress = 2;
constexpr std::size_t kChannelPriority = 4;
constexpr std::size_t kTypeCounter = 5;
constexpr uint8_t kChannelMask = 0x3F;
constexpr uint8_t kTypeMask = 0x0F;
constexpr unsigned kCounterShift = 4;
constexpr uint8_t kCounterMask = 0x07;  // after the shift
constexpr uint8_t type_of(uint8_t byte5) {
    return byte5 & kTypeMask;
}
constexpr uint8_t counter_of(uint8_t byte5) {
    return (byte5 >> kCounterShift) & kCounterMask;
}
constexpr uint8_t type_counter(MailboxType type, uint8_t counter) {
    return static_cast<uint8_t>((static_cast<uint8_t>(type) & kTypeMask) |
                                ((counter & kCounterMask) << kCounterShift));
}
// The next counter after c: 1..7, never 0.
constexpr uint8_t next_counter(uint8_t c) {
    return static_cast<uint8_t>(c % 7 + 1);
}
}  // namespace mbx

}  // namespace ecat
