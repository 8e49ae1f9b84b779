#include "drive/errors.hpp"

#include <algorithm>

namespace drive {
namespace {
// Error-register bits (MAXPOS firmware specification §7.2.2): b0 generic, b1 current, b2 voltage, b3
// temperature, b4 communication, b5 device profile, b7 motion. Where the overview table and the detail pages
// disagree the detail page wins; see docs/decisions/drive.md.
constexpr uint8_t kGeneric = 0x01, kCurrent = 0x02, kVoltage = 0x04, kTemperature = 0x08, kComm = 0x10,
                  kProfile = 0x20, kMotion = 0x80;
using R = Reaction;
constexpr ErrorInfo kTable[] = {
    {error_code::Generic, kGeneric, R::Disable, "Generic error"},
    {error_code::Overcurrent, kCurrent, R::Disable, "Overcurrent error"},
    {error_code::Overvoltage, kVoltage, R::Disable, "Overvoltage error"},
    {error_code::Undervoltage, kVoltage, R::Disable, "Undervoltage error"},
    {error_code::Overtemperature, kTemperature, R::Disable, "Overtemperature error"},
    {error_code::HardwareDefect, kGeneric, R::Disable, "Hardware defect error"},
    {error_code::HardwareMemory, kGeneric, R::Disable, "Hardware memory error"},
    {error_code::InternalSoftware, kGeneric, R::Disable, "Internal software error"},
    {error_code::SoftwareParameter, kGeneric, R::FaultReactionCode, "Software parameter error"},
    {error_code::CurrentOffset, kCurrent, R::Disable, "Current offset error"},
    {error_code::PositionSensor, kProfile, R::Disable, "Position sensor error"},
    {error_code::PositionSensorBreach, kProfile, R::Disable, "Position sensor breach"},
    {error_code::PositionSensorResolution, kProfile, R::Disable, "Position sensor resolution error"},
    {error_code::PositionSensorIndex, kProfile, R::Disable, "Position sensor index error"},
    {error_code::HallSensor, kProfile, R::Disable, "Hall sensor error"},
    {error_code::HallSensorNotFound, kProfile, R::Disable, "Hall sensor not found error"},
    {error_code::HallAngleDetection, kProfile, R::FaultReactionCode, "Hall angle detection error"},
    {error_code::BissEncoder, kProfile, R::FaultReactionCode, "BiSS encoder error"},
    {error_code::MissingMainSensor, kProfile, R::Disable, "Missing main sensor error"},
    {error_code::MissingCommutationSensor, kProfile, R::Disable, "Missing commutation sensor error"},
    {error_code::EthercatStateMachine, kComm, R::AbortConnectionCode, "EtherCAT state machine error"},
    {error_code::TorqueFault, kProfile, R::FaultReactionCode, "Torque fault"},
    {error_code::FollowingError, kMotion, R::FaultReactionCode, "Following error"},
    {error_code::NegativeLimitSwitch, kMotion, R::FaultReactionCode, "Negative limit switch error"},
    {error_code::PositiveLimitSwitch, kMotion, R::FaultReactionCode, "Positive limit switch error"},
    {error_code::SoftwarePositionLimit, kMotion, R::FaultReactionCode, "Software position limit error"},
    {error_code::MaxSpeed, kProfile, R::FaultReactionCode, "Max speed error"},
    {error_code::Sto, kGeneric, R::Disable, "STO error"},
    {error_code::SystemOverloaded, kGeneric, R::Disable, "System overloaded error"},
    {error_code::Watchdog, kGeneric, R::Disable, "Watchdog error"},
    {error_code::ControllerGain, kProfile, R::FaultReactionCode, "Controller gain error"},
    {error_code::AutoTuningIdentification, kProfile, R::Disable, "Auto-tuning identification error"},
};
constexpr std::size_t kCount = sizeof(kTable) / sizeof(kTable[0]);
}  // namespace

std::span<const ErrorInfo> error_table() {
    return std::span<const ErrorInfo>(kTable, kCount);
}

const ErrorInfo* find_error(uint16_t code) {
    auto t = error_table();
    auto it = std::find_if(t.begin(), t.end(), [code](const ErrorInfo& e) { return e.code == code; });
    return it == t.end() ? nullptr : &*it;
}

}  // namespace drive
