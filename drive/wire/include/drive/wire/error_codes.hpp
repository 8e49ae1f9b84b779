#pragma once
// The drive's error codes (0x603F, emergency) with their names, error-register bits and reaction class
// (MAXPOS firmware specification §8.1, Table 8-141; codes per IEC 61800-7-201 / CiA 402): constexpr and
// od-free, so a master tool (ecatctl) names a code without linking the drive. Target `drive_wire`.
#include <cstdint>
#include <string_view>

namespace drive {

// Reaction classes of the MAXPOS firmware specification §8.1: d = power stage off at once; f = per fault
// reaction option code 0x605E; a = per abort connection option code 0x6007.
enum class Reaction : uint8_t { Disable, FaultReactionCode, AbortConnectionCode };

namespace error_code {
constexpr uint16_t None = 0x0000;
constexpr uint16_t Generic = 0x1000;
constexpr uint16_t Overcurrent = 0x2310;
constexpr uint16_t Overvoltage = 0x3210;
constexpr uint16_t Undervoltage = 0x3220;
constexpr uint16_t Overtemperature = 0x4210;
constexpr uint16_t HardwareDefect = 0x5280;
constexpr uint16_t HardwareMemory = 0x5580;
constexpr uint16_t InternalSoftware = 0x6100;
constexpr uint16_t SoftwareParameter = 0x6320;
constexpr uint16_t CurrentOffset = 0x7280;
constexpr uint16_t PositionSensor = 0x7320;
constexpr uint16_t PositionSensorBreach = 0x7380;
constexpr uint16_t PositionSensorResolution = 0x7381;
constexpr uint16_t PositionSensorIndex = 0x7382;
constexpr uint16_t HallSensor = 0x7388;
constexpr uint16_t HallSensorNotFound = 0x7389;
constexpr uint16_t HallAngleDetection = 0x738A;
constexpr uint16_t BissEncoder = 0x738B;
constexpr uint16_t MissingMainSensor = 0x7390;
constexpr uint16_t MissingCommutationSensor = 0x7391;
constexpr uint16_t EthercatStateMachine = 0x8180;
constexpr uint16_t TorqueFault = 0x8331;
constexpr uint16_t FollowingError = 0x8611;
constexpr uint16_t NegativeLimitSwitch = 0x8A80;
constexpr uint16_t PositiveLimitSwitch = 0x8A81;
constexpr uint16_t SoftwarePositionLimit = 0x8A82;
constexpr uint16_t MaxSpeed = 0x8A83;
constexpr uint16_t Sto = 0x8A88;
constexpr uint16_t SystemOverloaded = 0xFF01;
constexpr uint16_t Watchdog = 0xFF02;
constexpr uint16_t ControllerGain = 0xFF10;
constexpr uint16_t AutoTuningIdentification = 0xFF11;
}  // namespace error_code

struct ErrorInfo {
    uint16_t code;
    uint8_t error_register;  // 0x1001 bits this error sets
    Reaction reaction;
    std::string_view name;
};

// Error-register bits (MAXPOS firmware specification §7.2.2): b0 generic, b1 current, b2 voltage, b3
// temperature, b4 communication, b5 device profile, b7 motion. Where the overview table and the detail pages
// disagree the detail page wins; see docs/decisions/drive.md.
namespace error_register {
constexpr uint8_t kGeneric = 0x01, kCurrent = 0x02, kVoltage = 0x04, kTemperature = 0x08, kComm = 0x10,
                  kProfile = 0x20, kMotion = 0x80;
}  // namespace error_register
inline constexpr ErrorInfo kErrorTable[] = {
    {error_code::Generic, error_register::kGeneric, Reaction::Disable, "Generic error"},
    {error_code::Overcurrent, error_register::kCurrent, Reaction::Disable, "Overcurrent error"},
    {error_code::Overvoltage, error_register::kVoltage, Reaction::Disable, "Overvoltage error"},
    {error_code::Undervoltage, error_register::kVoltage, Reaction::Disable, "Undervoltage error"},
    {error_code::Overtemperature, error_register::kTemperature, Reaction::Disable, "Overtemperature error"},
    {error_code::HardwareDefect, error_register::kGeneric, Reaction::Disable, "Hardware defect error"},
    {error_code::HardwareMemory, error_register::kGeneric, Reaction::Disable, "Hardware memory error"},
    {error_code::InternalSoftware, error_register::kGeneric, Reaction::Disable, "Internal software error"},
    {error_code::SoftwareParameter, error_register::kGeneric, Reaction::FaultReactionCode,
     "Software parameter error"},
    {error_code::CurrentOffset, error_register::kCurrent, Reaction::Disable, "Current offset error"},
    {error_code::PositionSensor, error_register::kProfile, Reaction::Disable, "Position sensor error"},
    {error_code::PositionSensorBreach, error_register::kProfile, Reaction::Disable, "Position sensor breach"},
    {error_code::PositionSensorResolution, error_register::kProfile, Reaction::Disable,
     "Position sensor resolution error"},
    {error_code::PositionSensorIndex, error_register::kProfile, Reaction::Disable,
     "Position sensor index error"},
    {error_code::HallSensor, error_register::kProfile, Reaction::Disable, "Hall sensor error"},
    {error_code::HallSensorNotFound, error_register::kProfile, Reaction::Disable,
     "Hall sensor not found error"},
    {error_code::HallAngleDetection, error_register::kProfile, Reaction::FaultReactionCode,
     "Hall angle detection error"},
    {error_code::BissEncoder, error_register::kProfile, Reaction::FaultReactionCode, "BiSS encoder error"},
    {error_code::MissingMainSensor, error_register::kProfile, Reaction::Disable, "Missing main sensor error"},
    {error_code::MissingCommutationSensor, error_register::kProfile, Reaction::Disable,
     "Missing commutation sensor error"},
    {error_code::EthercatStateMachine, error_register::kComm, Reaction::AbortConnectionCode,
     "EtherCAT state machine error"},
    {error_code::TorqueFault, error_register::kProfile, Reaction::FaultReactionCode, "Torque fault"},
    {error_code::FollowingError, error_register::kMotion, Reaction::FaultReactionCode, "Following error"},
    {error_code::NegativeLimitSwitch, error_register::kMotion, Reaction::FaultReactionCode,
     "Negative limit switch error"},
    {error_code::PositiveLimitSwitch, error_register::kMotion, Reaction::FaultReactionCode,
     "Positive limit switch error"},
    {error_code::SoftwarePositionLimit, error_register::kMotion, Reaction::FaultReactionCode,
     "Software position limit error"},
    {error_code::MaxSpeed, error_register::kProfile, Reaction::FaultReactionCode, "Max speed error"},
    {error_code::Sto, error_register::kGeneric, Reaction::Disable, "STO error"},
    {error_code::SystemOverloaded, error_register::kGeneric, Reaction::Disable, "System overloaded error"},
    {error_code::Watchdog, error_register::kGeneric, Reaction::Disable, "Watchdog error"},
    {error_code::ControllerGain, error_register::kProfile, Reaction::FaultReactionCode,
     "Controller gain error"},
    {error_code::AutoTuningIdentification, error_register::kProfile, Reaction::Disable,
     "Auto-tuning identification error"},
};

// nullptr for a code not in the table.
constexpr const ErrorInfo* find_error_code(uint16_t code) {
    for (const ErrorInfo& e : kErrorTable)
        if (e.code == code) return &e;
    return nullptr;
}

}  // namespace drive
