#pragma once
// The ESC register map: every register address and bit the slave, the master, the tools and the tests use
// (ESC datasheet section II "register description"; ETG.1000.4 §6 for the DL registers, ETG.1000.6 §5.3 for
// AL control/status/event). One place for all of them: esc::reg.
#include <cstdint>

namespace esc::reg {

constexpr uint16_t kType = 0x0000;
constexpr uint16_t kStationAddress = 0x0010;
constexpr uint16_t kStationAlias = 0x0012;
constexpr uint16_t kRegWriteEnable = 0x0020;
constexpr uint16_t kRegWriteProtect = 0x0021;
constexpr uint16_t kEscWriteEnable = 0x0030;
constexpr uint16_t kEscWriteProtect = 0x0031;
constexpr uint16_t kEscResetEcat = 0x0040;
constexpr uint16_t kEscResetPdi = 0x0041;
constexpr uint16_t kDlControl = 0x0100;
constexpr uint16_t kDlStatus = 0x0110;
constexpr uint16_t kAlControl = 0x0120;
constexpr uint16_t kAlStatus = 0x0130;
constexpr uint16_t kAlStatusCode = 0x0134;
constexpr uint16_t kPdiControl = 0x0140;
constexpr uint16_t kEscConfig = 0x0141;
constexpr uint16_t kPdiConfig = 0x0150;
constexpr uint16_t kSyncLatchConfig = 0x0151;
constexpr uint16_t kExtPdiConfig = 0x0152;
constexpr uint16_t kEcatEventMask = 0x0200;
constexpr uint16_t kAlEventMask = 0x0204;
constexpr uint16_t kEcatEvent = 0x0210;
constexpr uint16_t kAlEvent = 0x0220;
constexpr uint16_t kInvalidFrameCounter = 0x0300;
constexpr uint16_t kProcessingUnitErrors = 0x030C;
constexpr uint16_t kWdDivider = 0x0400;
constexpr uint16_t kWdTimePdi = 0x0410;
constexpr uint16_t kWdTimePd = 0x0420;
constexpr uint16_t kWdStatusPd = 0x0440;
constexpr uint16_t kWdCounterPd = 0x0442;
constexpr uint16_t kWdCounterPdi = 0x0443;
constexpr uint16_t kSiiConfig = 0x0500;
constexpr uint16_t kSiiPdiAccess = 0x0501;
constexpr uint16_t kSiiControl = 0x0502;
constexpr uint16_t kSiiAddress = 0x0504;
constexpr uint16_t kSiiData = 0x0508;
constexpr uint16_t kFmmu = 0x0600;
constexpr uint16_t kSm = 0x0800;
constexpr uint16_t kDcRecvTime0 = 0x0900;
constexpr uint16_t kDcSystemTime = 0x0910;
constexpr uint16_t kDcRecvTimePu = 0x0918;
constexpr uint16_t kDcOffset = 0x0920;
constexpr uint16_t kDcDelay = 0x0928;
constexpr uint16_t kDcDiff = 0x092C;
constexpr uint16_t kDcSpeedStart = 0x0930;
constexpr uint16_t kDcSpeedDiff = 0x0932;
constexpr uint16_t kDcFilterDiff = 0x0934;
constexpr uint16_t kDcFilterSpeed = 0x0935;
constexpr uint16_t kDcCyclicControl = 0x0980;
constexpr uint16_t kDcActivation = 0x0981;
constexpr uint16_t kDcPulseLength = 0x0982;
constexpr uint16_t kDcActivationStatus = 0x0984;
constexpr uint16_t kDcSync0Status = 0x098E;
constexpr uint16_t kDcSync1Status = 0x098F;
constexpr uint16_t kDcStartTime = 0x0990;
constexpr uint16_t kDcNextSync1 = 0x0998;
constexpr uint16_t kDcSync0Cycle = 0x09A0;
constexpr uint16_t kDcSync1Cycle = 0x09A4;
constexpr uint16_t kDcLatch0Control = 0x09A8;
constexpr uint16_t kDcLatch1Control = 0x09A9;
constexpr uint16_t kDcLatch0Status = 0x09AE;
constexpr uint16_t kDcLatchTimes = 0x09B0;
constexpr uint16_t kDcEcatBufferChange = 0x09F0;
constexpr uint16_t kUserRam = 0x0F80;
constexpr uint32_t kRamBase = 0x1000;

// FMMU n (16 bytes at 0x0600 + 16n) and SyncManager n (8 bytes at 0x0800 + 8n) register blocks.
constexpr uint16_t fmmu_base(unsigned n) {
    return static_cast<uint16_t>(kFmmu + 16 * n);
}
constexpr uint16_t sm_base(unsigned n) {
    return static_cast<uint16_t>(kSm + 8 * n);
}
// Offsets inside one SyncManager block.
constexpr uint16_t kSmStart = 0;
constexpr uint16_t kSmLength = 2;
constexpr uint16_t kSmControl = 4;
constexpr uint16_t kSmStatus = 5;
constexpr uint16_t kSmActivate = 6;
constexpr uint16_t kSmPdiControl = 7;

// AL control / status bits (0x0120 / 0x0130).
constexpr uint16_t kAlStateMask = 0x000F;
constexpr uint16_t kAlErrorFlag = 0x0010;  // control: error acknowledge; status: error indication
constexpr uint16_t kAlIdFlag = 0x0020;     // control: device identification request; status: ID loaded

// SM control byte.
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

// SII EEPROM control/status 0x0502.
namespace sii {
constexpr uint16_t CtlWriteEnable = 0x0001;
constexpr uint16_t CtlReadSize8 = 0x0040;
constexpr uint16_t CmdRead = 0x0100;
constexpr uint16_t CmdWrite = 0x0200;
constexpr uint16_t CmdReload = 0x0400;
constexpr uint16_t CmdMask = 0x0700;
constexpr uint16_t ErrChecksum = 0x0800;
constexpr uint16_t ErrNotLoaded = 0x1000;
constexpr uint16_t ErrAck = 0x2000;
constexpr uint16_t ErrWriteEnable = 0x4000;
constexpr uint16_t ErrMask = 0x7800;
constexpr uint16_t Busy = 0x8000;
}  // namespace sii

}  // namespace esc::reg

namespace esc {

// AL event request bits (0x0220) and mask (0x0204).
namespace alev {
constexpr uint32_t kAlControl = 1u << 0;
constexpr uint32_t kDcLatch = 1u << 1;
constexpr uint32_t kSync0 = 1u << 2;
constexpr uint32_t kSync1 = 1u << 3;
constexpr uint32_t kSmActivation = 1u << 4;
constexpr uint32_t kEepromEmulation = 1u << 5;
constexpr uint32_t kWatchdogPd = 1u << 6;
constexpr uint32_t kSm0 = 1u << 8;
// SyncManager n event.
constexpr uint32_t sm(unsigned n) {
    return kSm0 << n;
}
}  // namespace alev

// ECAT event request bits (0x0210) and mask (0x0200).
namespace ecev {
constexpr uint16_t kDcLatch = 1u << 0;
constexpr uint16_t kDlStatus = 1u << 2;
constexpr uint16_t kAlStatus = 1u << 3;
constexpr uint16_t kSm0 = 1u << 4;
}  // namespace ecev

}  // namespace esc
