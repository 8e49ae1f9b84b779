#pragma once
// The objects the drive (drive/) binds, named once: a typed handle per entry, `od::obj::Controlword` =
// {0x6040, 0}, with the default the dictionary declares for it. The object table (drive_profile.cpp) takes
// these defaults from here (its rows say "=") and drive::Parameters/Command initialise from them, so each
// default is stated once. Likewise the value sets the validators check and the drive implements: the modes
// of operation, the homing methods, and the SyncManager communication types of 0x1C00.
// Objects and values as the MAXPOS firmware specification (chapter 7) declares them; object meanings
// IEC 61800-7-201 (CiA 402) and ETG.1000.6.
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string_view>

#include "od/device.hpp"
#include "od/dictionary.hpp"

namespace od {

// What the drive does with an entry: reads it as configuration, reads it as a command from the master
// (RxPDO), or writes it (feedback).
enum class Role : uint8_t { Parameter, Command, Feedback };

template <typename T>
struct Obj {
    using type = T;
    uint16_t index;
    uint8_t sub;
    T def;  // the default the dictionary declares
};

// X(name, index, subindex, C++ type, default, role); § numbers: the MAXPOS firmware specification.
// clang-format off
#define OD_DRIVE_OBJECTS(X) \
    /* motor, sensor, axis configuration (MAXPOS firmware specification §7.2.22-7.2.24, §7.2.100) */ \
    X(MotorNominalCurrent,            0x3001, 1, uint16_t, 5000,    Parameter) \
    X(MotorOutputCurrentLimit,        0x3001, 2, uint16_t, 15000,   Parameter) \
    X(MotorPolePairs,                 0x3001, 3, uint8_t,  1,       Parameter) \
    X(MotorThermalTimeConstant,       0x3001, 4, uint16_t, 40,      Parameter) \
    X(MotorTorqueConstant,            0x3001, 5, uint32_t, 0,       Parameter) \
    X(MotorType,                      0x6402, 0, uint16_t, 10,      Parameter) \
    X(EncoderPulses,                  0x3010, 1, uint32_t, 500,     Parameter) \
    X(EncoderType,                    0x3010, 2, uint16_t, 0x0001,  Parameter) \
    X(AxisConfigurationMisc,          0x3000, 4, uint32_t, 0,       Parameter) \
    /* control parameters (§7.2.30, §7.2.31) */ \
    X(CurrentPGain,                   0x30A0, 1, uint32_t, 32768,   Parameter) \
    X(CurrentIGain,                   0x30A0, 2, uint32_t, 4096,    Parameter) \
    X(CurrentFfGain,                  0x30A0, 3, uint32_t, 0,       Parameter) \
    X(PositionBandwidth,              0x30A1, 1, uint32_t, 4000,    Parameter) \
    X(PositionDamping,                0x30A1, 2, uint32_t, 1000,    Parameter) \
    X(PositionResetTime,              0x30A1, 3, uint32_t, 1000000, Parameter) \
    X(Inertia,                        0x30A1, 4, uint32_t, 100000,  Parameter) \
    X(Friction,                       0x30A1, 5, uint32_t, 0,       Parameter) \
    /* option codes (§7.2.44, §7.2.48-7.2.52) */ \
    X(AbortConnectionOptionCode,      0x6007, 0, int16_t,  3,       Parameter) \
    X(QuickStopOptionCode,            0x605A, 0, int16_t,  6,       Parameter) \
    X(ShutdownOptionCode,             0x605B, 0, int16_t,  0,       Parameter) \
    X(DisableOperationOptionCode,     0x605C, 0, int16_t,  1,       Parameter) \
    X(HaltOptionCode,                 0x605D, 0, int16_t,  2,       Parameter) \
    X(FaultReactionOptionCode,        0x605E, 0, int16_t,  2,       Parameter) \
    /* motion limits and profile (§7.2.57-7.2.73, §7.2.89) */ \
    X(FollowingErrorWindow,           0x6065, 0, uint32_t, 2000,    Parameter) \
    X(FollowingErrorTimeout,          0x6066, 0, uint16_t, 0,       Parameter) \
    X(SoftwarePositionLimitMin,       0x607D, 1, int32_t,  std::numeric_limits<int32_t>::min(), Parameter) \
    X(SoftwarePositionLimitMax,       0x607D, 2, int32_t,  std::numeric_limits<int32_t>::max(), Parameter) \
    X(PositionRangeLimitMin,          0x607B, 1, int32_t,  std::numeric_limits<int32_t>::min(), Parameter) \
    X(PositionRangeLimitMax,          0x607B, 2, int32_t,  std::numeric_limits<int32_t>::max(), Parameter) \
    X(MaxProfileVelocity,             0x607F, 0, uint32_t, 200000,  Parameter) \
    X(MaxMotorSpeed,                  0x6080, 0, uint32_t, 200000,  Parameter) \
    X(ProfileVelocity,                0x6081, 0, uint32_t, 1000,    Parameter) \
    X(ProfileAcceleration,            0x6083, 0, uint32_t, 10000,   Parameter) \
    X(ProfileDeceleration,            0x6084, 0, uint32_t, 10000,   Parameter) \
    X(QuickStopDeceleration,          0x6085, 0, uint32_t, 15000,   Parameter) \
    X(MaxAcceleration,                0x60C5, 0, uint32_t, 0xFFFFFFFF, Parameter) \
    /* homing (§7.2.32-7.2.34, §7.2.75-7.2.77) */ \
    X(HomingMethod,                   0x6098, 0, int8_t,   37,      Parameter) \
    X(HomingSpeedSwitchSearch,        0x6099, 1, uint32_t, 100,     Parameter) \
    X(HomingSpeedZeroSearch,          0x6099, 2, uint32_t, 10,      Parameter) \
    X(HomingAcceleration,             0x609A, 0, uint32_t, 1000,    Parameter) \
    X(HomePosition,                   0x30B0, 0, int32_t,  0,       Parameter) \
    X(HomeOffsetMoveDistance,         0x30B1, 0, int32_t,  0,       Parameter) \
    X(HomingCurrentThreshold,         0x30B2, 0, uint16_t, 500,     Parameter) \
    /* interpolation, standstill, inputs, touch probe source (§7.2.88, §7.2.38-7.2.40, §7.2.90) */ \
    X(InterpolationTimePeriodValue,   0x60C2, 1, uint8_t,  1,       Parameter) \
    X(InterpolationTimeIndex,         0x60C2, 2, int8_t,   -3,      Parameter) \
    X(StandstillWindow,               0x30E0, 1, uint32_t, 30,      Parameter) \
    X(StandstillWindowTime,           0x30E0, 2, uint16_t, 50,      Parameter) \
    X(StandstillWindowTimeout,        0x30E0, 3, uint16_t, 1000,    Parameter) \
    X(DigitalInputPolarity,           0x3141, 2, uint16_t, 0x0000,  Parameter) \
    X(DigitalInput1Configuration,     0x3142, 1, uint8_t,  0,       Parameter) \
    X(DigitalInput2Configuration,     0x3142, 2, uint8_t,  1,       Parameter) \
    X(DigitalInput3Configuration,     0x3142, 3, uint8_t,  2,       Parameter) \
    X(DigitalInput4Configuration,     0x3142, 4, uint8_t,  19,      Parameter) \
    X(DigitalInput5Configuration,     0x3142, 5, uint8_t,  20,      Parameter) \
    X(DigitalInput6Configuration,     0x3142, 6, uint8_t,  21,      Parameter) \
    X(TouchProbe1Source,              0x60D0, 1, int16_t,  -1,      Parameter) \
    /* commands: the RxPDO objects (§7.2.46, §7.2.53, §7.2.61, §7.2.65, §7.2.81-7.2.84, §7.2.99) */ \
    X(Controlword,                    0x6040, 0, uint16_t, 0,       Command) \
    X(ModesOfOperation,               0x6060, 0, int8_t,   8,       Command) \
    X(TargetPosition,                 0x607A, 0, int32_t,  0,       Command) \
    X(TargetVelocity,                 0x60FF, 0, int32_t,  0,       Command) \
    X(TargetTorque,                   0x6071, 0, int16_t,  0,       Command) \
    X(PositionOffset,                 0x60B0, 0, int32_t,  0,       Command) \
    X(VelocityOffset,                 0x60B1, 0, int32_t,  0,       Command) \
    X(TorqueOffset,                   0x60B2, 0, int16_t,  0,       Command) \
    X(TouchProbeFunction,             0x60B8, 0, uint16_t, 0,       Command) \
    /* feedback: TxPDO objects and computed values */ \
    X(Statusword,                     0x6041, 0, uint16_t, 0,       Feedback) \
    X(ModesOfOperationDisplay,        0x6061, 0, int8_t,   1,       Feedback) \
    X(PositionDemandValue,            0x6062, 0, int32_t,  0,       Feedback) \
    X(PositionActualValue,            0x6064, 0, int32_t,  0,       Feedback) \
    X(PositionActualValueSensor1,     0x60E4, 1, int32_t,  0,       Feedback) \
    X(VelocityDemandValue,            0x606B, 0, int32_t,  0,       Feedback) \
    X(VelocityActualValue,            0x606C, 0, int32_t,  0,       Feedback) \
    X(VelocityActualValueSensor1,     0x60E5, 1, int32_t,  0,       Feedback) \
    X(VelocityActualAveragedSensor1,  0x60E5, 9, int32_t,  0,       Feedback) \
    X(VelocityActualValueAveraged,    0x30D5, 0, int32_t,  0,       Feedback) \
    X(TorqueActualValue,              0x6077, 0, int16_t,  0,       Feedback) \
    X(CurrentActualValue,             0x6078, 0, int16_t,  0,       Feedback) \
    X(CurrentDemandValue,             0x30D0, 0, int16_t,  0,       Feedback) \
    X(CurrentActualValueAveraged,     0x30D1, 0, int16_t,  0,       Feedback) \
    X(FollowingErrorActualValue,      0x60F4, 0, int32_t,  0,       Feedback) \
    X(MotorRatedTorque,               0x6076, 0, uint32_t, 0,       Feedback) \
    X(DigitalInputs,                  0x60FD, 0, uint32_t, 0,       Feedback) \
    X(DigitalInputLogicState,         0x3141, 1, uint16_t, 0,       Feedback) \
    X(EncoderIndexPosition,           0x3010, 4, int32_t,  0,       Feedback) \
    X(TouchProbeStatus,               0x60B9, 0, uint16_t, 0,       Feedback) \
    X(TouchProbePosition1Positive,    0x60BA, 0, int32_t,  0,       Feedback) \
    X(TouchProbePosition1Negative,    0x60BB, 0, int32_t,  0,       Feedback) \
    X(TouchProbe1PositiveEdgeCounter, 0x60D5, 0, uint16_t, 0,       Feedback) \
    X(TouchProbe1NegativeEdgeCounter, 0x60D6, 0, uint16_t, 0,       Feedback) \
    X(ErrorCode,                      0x603F, 0, uint16_t, 0,       Feedback) \
    X(ErrorRegister,                  0x1001, 0, uint8_t,  0,       Feedback) \
    X(MainSensorResolution,           0x3000, 5, uint32_t, 2000,    Feedback)
// clang-format on

namespace obj {
#define OD_DRIVE_OBJECT_HANDLE(name, idx, sub, T, def, role) inline constexpr Obj<T> name{idx, sub, def};
OD_DRIVE_OBJECTS(OD_DRIVE_OBJECT_HANDLE)
#undef OD_DRIVE_OBJECT_HANDLE

// Objects (whole) the drive refers to by index only: those a master may write only in "Power Disable"
// (MAXPOS firmware specification §7.2.22-7.2.29, §7.2.78-7.2.80, §7.2.100).
inline constexpr uint16_t AxisConfiguration = 0x3000;
inline constexpr uint16_t MotorData = 0x3001;
inline constexpr uint16_t DigitalIncrementalEncoder1 = 0x3010;
inline constexpr uint16_t AnalogIncrementalEncoder = 0x3011;
inline constexpr uint16_t SsiAbsoluteEncoder = 0x3012;
inline constexpr uint16_t BissAbsoluteEncoder = 0x3014;
inline constexpr uint16_t DigitalHallSensor = 0x301A;
inline constexpr uint16_t DigitalIncrementalEncoder2 = 0x3020;
inline constexpr uint16_t SiUnitPosition = 0x60A8;
inline constexpr uint16_t SiUnitVelocity = 0x60A9;
inline constexpr uint16_t SiUnitAcceleration = 0x60AA;
inline constexpr uint16_t SupportedHomingMethods = 0x60E3;
inline constexpr uint16_t SupportedDriveModes = 0x6502;
inline constexpr uint16_t SyncManagerCommunicationType = 0x1C00;
}  // namespace obj

// One handle, type-erased: for tests and tools that walk the list.
struct ObjInfo {
    std::string_view name;
    uint16_t index;
    uint8_t sub;
    uint8_t size;  // bytes
    bool is_signed;
    Role role;
    Number def;
};
std::span<const ObjInfo> drive_objects();

// Modes of operation 0x6060 the drive implements (IEC 61800-7-201; MAXPOS firmware specification §7.2.53).
namespace modes {
inline constexpr int8_t ProfilePosition = 1;
inline constexpr int8_t ProfileVelocity = 3;
inline constexpr int8_t Homing = 6;
inline constexpr int8_t CyclicSyncPosition = 8;
inline constexpr int8_t CyclicSyncVelocity = 9;
inline constexpr int8_t CyclicSyncTorque = 10;
}  // namespace modes
inline constexpr std::array<int8_t, 6> kModesOfOperation{
    modes::ProfilePosition,    modes::ProfileVelocity,    modes::Homing,
    modes::CyclicSyncPosition, modes::CyclicSyncVelocity, modes::CyclicSyncTorque};
// 0x6502 Supported Drive Modes: bit (mode - 1) for each mode (IEC 61800-7-201).
constexpr uint32_t supported_drive_modes() {
    uint32_t bits = 0;
    for (int8_t m : kModesOfOperation)
        bits |= 1u << (m - 1);
    return bits;
}
// Homing methods 0x6098 the drive implements, in the order of 0x60E3:01..0F (MAXPOS firmware
// specification §7.2.75, §7.2.93).
inline constexpr std::array<int8_t, 15> kHomingMethods{1,  2,  7,  11, 17, 18, 23, 27,
                                                       33, 34, 37, -1, -2, -3, -4};

template <std::size_t N>
constexpr bool contains(const std::array<int8_t, N>& set, int v) {
    for (int8_t x : set)
        if (x == v) return true;
    return false;
}

// 0x1C00:01..04: the communication type of SM0..SM3, in the order the device places them.
inline constexpr std::array<SmKind, 4> kSmCommunicationTypes{SmKind::MBoxOut, SmKind::MBoxIn, SmKind::Outputs,
                                                             SmKind::Inputs};

// The default a table row marked "=" takes: from a handle above or one of the value sets. Empty if none.
std::optional<Number> declared_default(uint16_t index, uint8_t sub);

}  // namespace od
