#pragma once
// CiA 402 device control (IEC 61800-7-201 §6.2.2; MAXPOS firmware specification §3.2, Tables 3-5..3-7):
// states, controlword commands, transitions 0..16 and the statusword state bits. Pure functions; the Axis
// executes the actions (ramps, standstill gating).
#include <cstdint>

namespace drive {

enum class State : uint8_t {
    NotReadyToSwitchOn,
    SwitchOnDisabled,
    ReadyToSwitchOn,
    SwitchedOn,
    OperationEnabled,
    QuickStopActive,
    FaultReactionActive,
    Fault,
};

enum class DeviceCommand : uint8_t {
    None,             // bit 7 held high, or nothing decodable
    Shutdown,         // 0xxx x110
    SwitchOn,         // 0xxx 0111 (also "disable operation" from Operation Enabled)
    EnableOperation,  // 0xxx 1111 (also "switch on + enable operation")
    DisableVoltage,   // 0xxx xx0x
    QuickStop,        // 0xxx x01x
    FaultReset,       // bit 7 0 -> 1
};

namespace cw {
constexpr uint16_t SwitchOn = 1u << 0;
constexpr uint16_t EnableVoltage = 1u << 1;
constexpr uint16_t QuickStop = 1u << 2;  // 0 = quick stop requested
constexpr uint16_t EnableOperation = 1u << 3;
constexpr uint16_t NewSetpoint = 1u << 4;  // PPM; HMM: homing operation start
constexpr uint16_t ChangeImmediately = 1u << 5;
constexpr uint16_t Relative = 1u << 6;
constexpr uint16_t FaultReset = 1u << 7;
constexpr uint16_t Halt = 1u << 8;
}  // namespace cw

namespace sw {
constexpr uint16_t ReadyToSwitchOn = 1u << 0;
constexpr uint16_t SwitchedOn = 1u << 1;
constexpr uint16_t OperationEnabled = 1u << 2;
constexpr uint16_t Fault = 1u << 3;
constexpr uint16_t VoltageEnabled = 1u << 4;
constexpr uint16_t QuickStop = 1u << 5;
constexpr uint16_t SwitchOnDisabled = 1u << 6;
constexpr uint16_t Warning = 1u << 7;
constexpr uint16_t Reserved8 =
    1u << 8;  // "reserved (1)" in the MAXPOS firmware specification: offset current measured (EPOS)
constexpr uint16_t Remote = 1u << 9;
constexpr uint16_t TargetReached = 1u << 10;
constexpr uint16_t InternalLimit = 1u << 11;
constexpr uint16_t Bit12 = 1u << 12;  // PPM set-point ack, PVM speed 0, HMM attained, CSx follows command
constexpr uint16_t Bit13 = 1u << 13;  // PPM/CSP following error, HMM homing error
constexpr uint16_t Referenced = 1u << 15;
}  // namespace sw

// Decode the low byte of the controlword. prev is the controlword of the previous cycle (for the bit-7 edge).
DeviceCommand decode(uint16_t controlword, uint16_t prev);

// Result of applying a command to a state: the target state and the CiA 402 transition number (-1 = none).
struct Transition {
    State to;
    int number;
};
// Transitions 2..12, 15, 16 (13/14 are driven by faults, 0/1 by start-up).
Transition next(State from, DeviceCommand c);

// Statusword bits 0..6 for a state (MAXPOS firmware specification Table 3-5). power_on only matters in Fault
// Reaction Active (x001 1111 while a ramp runs with the power stage on, x000 1111 once it is off).
uint16_t state_bits(State s, bool power_on = true);
const char* to_string(State s);

}  // namespace drive
