#pragma once
// The drive's error table (MAXPOS firmware specification §8.1, Table 8-141): code, error-register bits and
// reaction class.
#include <cstdint>
#include <optional>
#include <span>
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

// The whole table, in code order.
std::span<const ErrorInfo> error_table();
// nullptr for a code not in the table.
const ErrorInfo* find_error(uint16_t code);

}  // namespace drive
