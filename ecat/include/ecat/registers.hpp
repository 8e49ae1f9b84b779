#pragma once
// ESC register addresses and bits the slave stack uses through the PDI (ethercat-protocol.md §3).
#include <cstdint>

namespace ecat::reg {

constexpr uint16_t kStationAlias = 0x0012;
constexpr uint16_t kAlControl = 0x0120;
constexpr uint16_t kAlStatus = 0x0130;
constexpr uint16_t kAlStatusCode = 0x0134;
constexpr uint16_t kPdiControl = 0x0140;
constexpr uint16_t kAlEventMask = 0x0204;
constexpr uint16_t kAlEventRequest = 0x0220;
constexpr uint16_t kWatchdogDivider = 0x0400;
constexpr uint16_t kWatchdogTimePd = 0x0420;
constexpr uint16_t kWatchdogStatusPd = 0x0440;
constexpr uint16_t kDcSystemTime = 0x0910;
constexpr uint16_t kDcSystemTimeOffset = 0x0920;
constexpr uint16_t kDcCyclicUnitControl = 0x0980;
constexpr uint16_t kDcActivation = 0x0981;
constexpr uint16_t kDcActivationStatus = 0x0984;
constexpr uint16_t kDcSync0Status = 0x098E;
constexpr uint16_t kDcSync1Status = 0x098F;
constexpr uint16_t kDcStartTime = 0x0990;  // read: system time of the next SYNC0 pulse
constexpr uint16_t kDcSync0CycleTime = 0x09A0;
constexpr uint16_t kDcSync1CycleTime = 0x09A4;
constexpr uint16_t kDcEcatBufferChangeTime = 0x09F0;  // local time (32 bit) of the last ECAT SM buffer change

// SyncManager n register block (8 bytes at 0x0800 + 8n).
constexpr uint16_t sm_base(unsigned n) {
    return static_cast<uint16_t>(0x0800 + 8 * n);
}
constexpr uint16_t kSmStart = 0;
constexpr uint16_t kSmLength = 2;
constexpr uint16_t kSmControl = 4;
constexpr uint16_t kSmStatus = 5;
constexpr uint16_t kSmActivate = 6;
constexpr uint16_t kSmPdiControl = 7;

// AL control / status bits (§6.1).
constexpr uint16_t kAlStateMask = 0x000F;
constexpr uint16_t kAlErrorFlag = 0x0010;  // control: error acknowledge; status: error indication
constexpr uint16_t kAlIdFlag = 0x0020;     // control: device identification request; status: ID loaded

// AL event request bits (§3.6).
constexpr uint32_t kEvAlControl = 1u << 0;
constexpr uint32_t kEvSync0 = 1u << 2;
constexpr uint32_t kEvSync1 = 1u << 3;
constexpr uint32_t kEvSmActivation = 1u << 4;
constexpr uint32_t kEvWatchdogPd = 1u << 6;
constexpr uint32_t ev_sm(unsigned n) {
    return 1u << (8 + n);
}

// SM control byte (§3.12).
constexpr uint8_t kSmModeMask = 0x03;
constexpr uint8_t kSmModeBuffered = 0x00;
constexpr uint8_t kSmModeMailbox = 0x02;
constexpr uint8_t kSmDirMask = 0x0C;
constexpr uint8_t kSmDirRead = 0x00;   // ECAT reads, PDI writes
constexpr uint8_t kSmDirWrite = 0x04;  // ECAT writes, PDI reads
constexpr uint8_t kSmWatchdogEnable = 0x40;
// SM status byte.
constexpr uint8_t kSmStatusIrqWrite = 0x01;
constexpr uint8_t kSmStatusIrqRead = 0x02;
constexpr uint8_t kSmStatusMailboxFull = 0x08;
// SM activate byte / PDI control byte.
constexpr uint8_t kSmEnable = 0x01;
constexpr uint8_t kSmRepeatRequest = 0x02;
constexpr uint8_t kSmPdiDeactivate = 0x01;
constexpr uint8_t kSmPdiRepeatAck = 0x02;

// DC activation 0x0981.
constexpr uint8_t kDcActCyclic = 0x01;
constexpr uint8_t kDcActSync0 = 0x02;
constexpr uint8_t kDcActSync1 = 0x04;

}  // namespace ecat::reg
