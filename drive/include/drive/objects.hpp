#pragma once
// The drive's vocabulary: the objects the CiA 402 core (drive/) binds, named once.
//
// - The standard objects (IEC 61800-7-201 / CiA 402, and 0x1001 of CiA 301): a typed handle per entry,
//   `drive::obj::Controlword` = {0x6040, 0}. Every CiA 402 dictionary that has the object has it at this
//   index with this type, so the drive binds them by index in any vendor's dictionary (drive.hpp).
// - The parameters CiA 402 gives no object for (motor data, encoder, loop gains, standstill window, ...):
//   each vendor keeps them in its own manufacturer objects, so a device description says where
//   (drive::Binding, a list in drive::VendorObjects); without one the drive runs on the default here.
//
// The `def` of a handle is the drive's own default: the value the axis runs on when the dictionary lacks the
// object. A dictionary's declared default replaces it (the drive loads every bound entry every cycle).
// The defaults are those of the MAXPOS firmware specification (maxon), the first device the drive was
// written for; docs/decisions/drive.md says where the motor model's are used instead.
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <string_view>

namespace drive {

// What the drive does with an entry: reads it as configuration, reads it as a command from the master
// (RxPDO), or writes it (feedback).
enum class Role : uint8_t { Parameter, Command, Feedback };

template <typename T>
struct Obj {
    using type = T;
    uint16_t index;
    uint8_t sub;
    T def;  // the drive's default without the object
};

// 0x605A's default in IEC 61800-7-201 (2: quick stop ramp, then switch on disabled): what a drive whose
// dictionary has no 0x605A does. The handle's default (6) is the MAXPOS's.
inline constexpr int16_t kProfileQuickStopOptionCode = 2;

// Modes of operation 0x6060 the drive implements (IEC 61800-7-201).
namespace modes {
inline constexpr int8_t ProfilePosition = 1;
inline constexpr int8_t ProfileVelocity = 3;
inline constexpr int8_t ProfileTorque = 4;
inline constexpr int8_t Homing = 6;
inline constexpr int8_t InterpolatedPosition = 7;
inline constexpr int8_t CyclicSyncPosition = 8;
inline constexpr int8_t CyclicSyncVelocity = 9;
inline constexpr int8_t CyclicSyncTorque = 10;
}  // namespace modes
inline constexpr std::array<int8_t, 8> kModesOfOperation{
    modes::ProfilePosition,      modes::ProfileVelocity,
    modes::ProfileTorque,        modes::Homing,
    modes::InterpolatedPosition, modes::CyclicSyncPosition,
    modes::CyclicSyncVelocity,   modes::CyclicSyncTorque};
// The entry a mode takes its set-point from ({0, 0}: none, the controlword alone): without it in the
// dictionary the mode cannot be served, and the drive neither takes it nor announces it in 0x6502.
struct SetpointEntry {
    uint16_t index;
    uint8_t sub;
};
constexpr SetpointEntry mode_setpoint_entry(int m) {
    switch (m) {
        case modes::ProfilePosition:
        case modes::CyclicSyncPosition:
            return {0x607A, 0};  // target position
        case modes::ProfileVelocity:
        case modes::CyclicSyncVelocity:
            return {0x60FF, 0};  // target velocity
        case modes::ProfileTorque:
        case modes::CyclicSyncTorque:
            return {0x6071, 0};  // target torque
        case modes::InterpolatedPosition:
            return {0x60C1, 1};  // interpolation data record, the position set-point
        default:
            return {0, 0};
    }
}
// 0x6502 Supported Drive Modes: bit (mode - 1) for each mode (IEC 61800-7-201).
constexpr uint32_t mode_bit(int m) {
    return m >= 1 && m <= 32 ? 1u << (m - 1) : 0u;
}
constexpr uint32_t supported_drive_modes() {
    uint32_t bits = 0;
    for (int8_t m : kModesOfOperation)
        bits |= mode_bit(m);
    return bits;
}
// Homing methods 0x6098 the drive implements: IEC 61800-7-201 methods and maxon's current threshold methods
// -1..-4 (MAXPOS firmware specification §7.2.75), in the order of the MAXPOS's 0x60E3:01..0F.
inline constexpr std::array<int8_t, 15> kHomingMethods{1,  2,  7,  11, 17, 18, 23, 27,
                                                       33, 34, 37, -1, -2, -3, -4};

template <std::size_t N>
constexpr bool contains(const std::array<int8_t, N>& set, int v) {
    for (int8_t x : set)
        if (x == v) return true;
    return false;
}

// X(name, index, subindex, C++ type, drive default, role): the CiA 402 objects the drive binds by index.
// clang-format off
#define DRIVE_CIA402_OBJECTS(X) \
    /* configuration */ \
    X(MotorType,                      0x6402, 0, uint16_t, 10,      Parameter) \
    X(AbortConnectionOptionCode,      0x6007, 0, int16_t,  3,       Parameter) \
    X(QuickStopOptionCode,            0x605A, 0, int16_t,  6,       Parameter) \
    X(ShutdownOptionCode,             0x605B, 0, int16_t,  0,       Parameter) \
    X(DisableOperationOptionCode,     0x605C, 0, int16_t,  1,       Parameter) \
    X(HaltOptionCode,                 0x605D, 0, int16_t,  2,       Parameter) \
    X(FaultReactionOptionCode,        0x605E, 0, int16_t,  2,       Parameter) \
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
    X(TorqueSlope,                    0x6087, 0, uint32_t, 0,       Parameter) /* 0: not set, no ramp */ \
    X(TorqueProfileType,              0x6088, 0, int16_t,  0,       Parameter) \
    X(MaxAcceleration,                0x60C5, 0, uint32_t, 0xFFFFFFFF, Parameter) \
    X(HomingMethod,                   0x6098, 0, int8_t,   37,      Parameter) \
    X(HomingSpeedSwitchSearch,        0x6099, 1, uint32_t, 100,     Parameter) \
    X(HomingSpeedZeroSearch,          0x6099, 2, uint32_t, 10,      Parameter) \
    X(HomingAcceleration,             0x609A, 0, uint32_t, 1000,    Parameter) \
    X(InterpolationSubMode,           0x60C0, 0, int16_t,  0,       Parameter) \
    X(InterpolationTimePeriodValue,   0x60C2, 1, uint8_t,  1,       Parameter) \
    X(InterpolationTimeIndex,         0x60C2, 2, int8_t,   -3,      Parameter) \
    X(TouchProbe1Source,              0x60D0, 1, int16_t,  -1,      Parameter) \
    X(SupportedDriveModes,            0x6502, 0, uint32_t, supported_drive_modes(), Parameter) \
    X(PositionEncoderIncrements,      0x608F, 1, uint32_t, 0,       Parameter) /* 0: the encoder's 4 x pulses */ \
    X(PositionEncoderRevolutions,     0x608F, 2, uint32_t, 1,       Parameter) \
    X(GearMotorRevolutions,           0x6091, 1, uint32_t, 1,       Parameter) \
    X(GearShaftRevolutions,           0x6091, 2, uint32_t, 1,       Parameter) \
    X(FeedConstantFeed,               0x6092, 1, uint32_t, 0,       Parameter) /* 0: one revolution in inc */ \
    X(FeedConstantShaftRevolutions,   0x6092, 2, uint32_t, 1,       Parameter) \
    /* commands: the RxPDO objects */ \
    X(Controlword,                    0x6040, 0, uint16_t, 0,       Command) \
    X(ModesOfOperation,               0x6060, 0, int8_t,   8,       Command) \
    X(TargetPosition,                 0x607A, 0, int32_t,  0,       Command) \
    X(TargetVelocity,                 0x60FF, 0, int32_t,  0,       Command) \
    X(TargetTorque,                   0x6071, 0, int16_t,  0,       Command) \
    X(InterpolationDataPosition,      0x60C1, 1, int32_t,  0,       Command) \
    X(PositionOffset,                 0x60B0, 0, int32_t,  0,       Command) \
    X(VelocityOffset,                 0x60B1, 0, int32_t,  0,       Command) \
    X(TorqueOffset,                   0x60B2, 0, int16_t,  0,       Command) \
    X(TouchProbeFunction,             0x60B8, 0, uint16_t, 0,       Command) \
    /* feedback: TxPDO objects and computed values */ \
    X(Statusword,                     0x6041, 0, uint16_t, 0,       Feedback) \
    X(ModesOfOperationDisplay,        0x6061, 0, int8_t,   1,       Feedback) \
    X(PositionDemandValue,            0x6062, 0, int32_t,  0,       Feedback) \
    X(PositionActualValue,            0x6064, 0, int32_t,  0,       Feedback) \
    X(VelocityDemandValue,            0x606B, 0, int32_t,  0,       Feedback) \
    X(VelocityActualValue,            0x606C, 0, int32_t,  0,       Feedback) \
    X(TorqueDemand,                   0x6074, 0, int16_t,  0,       Feedback) \
    X(TorqueActualValue,              0x6077, 0, int16_t,  0,       Feedback) \
    X(CurrentActualValue,             0x6078, 0, int16_t,  0,       Feedback) \
    X(FollowingErrorActualValue,      0x60F4, 0, int32_t,  0,       Feedback) \
    X(MotorRatedTorque,               0x6076, 0, uint32_t, 0,       Feedback) \
    X(DigitalInputs,                  0x60FD, 0, uint32_t, 0,       Feedback) \
    X(TouchProbeStatus,               0x60B9, 0, uint16_t, 0,       Feedback) \
    X(TouchProbePosition1Positive,    0x60BA, 0, int32_t,  0,       Feedback) \
    X(TouchProbePosition1Negative,    0x60BB, 0, int32_t,  0,       Feedback) \
    X(TouchProbe1PositiveEdgeCounter, 0x60D5, 0, uint16_t, 0,       Feedback) \
    X(TouchProbe1NegativeEdgeCounter, 0x60D6, 0, uint16_t, 0,       Feedback) \
    X(ErrorCode,                      0x603F, 0, uint16_t, 0,       Feedback) \
    X(ErrorRegister,                  0x1001, 0, uint8_t,  0,       Feedback)

// X(name, C++ type, drive default, role): the parameters and values CiA 402 gives no object for. A device
// binds each to one of its objects (drive::Binding) or the drive runs on the default.
#define DRIVE_VENDOR_PARAMETERS(X) \
    /* motor, sensor, axis configuration */ \
    X(MotorNominalCurrent,            uint16_t, 5000,    Parameter) /* mA */ \
    X(MotorOutputCurrentLimit,        uint16_t, 15000,   Parameter) /* mA */ \
    X(MotorPolePairs,                 uint8_t,  1,       Parameter) \
    X(MotorThermalTimeConstant,       uint16_t, 40,      Parameter) /* 0.1 s */ \
    X(MotorTorqueConstant,            uint32_t, 0,       Parameter) /* uNm/A; unbound: the motor model's */ \
    X(EncoderPulses,                  uint32_t, 500,     Parameter) /* pulses/rev, 4 inc per pulse */ \
    X(EncoderType,                    uint16_t, 0x0001,  Parameter) /* bit 0: index channel */ \
    X(AxisConfigurationMisc,          uint32_t, 0,       Parameter) /* bit 0: polarity inverted */ \
    /* control parameters; unbound: the tuning commission() writes for the motor model */ \
    X(CurrentPGain,                   uint32_t, 32768,   Parameter) \
    X(CurrentIGain,                   uint32_t, 4096,    Parameter) \
    X(CurrentFfGain,                  uint32_t, 0,       Parameter) \
    X(PositionBandwidth,              uint32_t, 4000,    Parameter) \
    X(PositionDamping,                uint32_t, 1000,    Parameter) \
    X(PositionResetTime,              uint32_t, 1000000, Parameter) \
    X(Inertia,                        uint32_t, 100000,  Parameter) \
    X(Friction,                       uint32_t, 0,       Parameter) \
    /* homing with a home position and the current threshold methods */ \
    X(HomePosition,                   int32_t,  0,       Parameter) \
    X(HomeOffsetMoveDistance,         int32_t,  0,       Parameter) \
    X(HomingCurrentThreshold,         uint16_t, 500,     Parameter) \
    /* standstill window, digital inputs */ \
    X(StandstillWindow,               uint32_t, 30,      Parameter) \
    X(StandstillWindowTime,           uint16_t, 50,      Parameter) \
    X(StandstillWindowTimeout,        uint16_t, 1000,    Parameter) \
    X(DigitalInputPolarity,           uint16_t, 0x0000,  Parameter) \
    X(DigitalInput1Configuration,     uint8_t,  0,       Parameter) \
    X(DigitalInput2Configuration,     uint8_t,  1,       Parameter) \
    X(DigitalInput3Configuration,     uint8_t,  2,       Parameter) \
    X(DigitalInput4Configuration,     uint8_t,  19,      Parameter) \
    X(DigitalInput5Configuration,     uint8_t,  20,      Parameter) \
    X(DigitalInput6Configuration,     uint8_t,  21,      Parameter) \
    /* computed values */ \
    X(PositionActualValueSensor1,     int32_t,  0,       Feedback) \
    X(VelocityActualValueSensor1,     int32_t,  0,       Feedback) \
    X(VelocityActualAveragedSensor1,  int32_t,  0,       Feedback) \
    X(VelocityActualValueAveraged,    int32_t,  0,       Feedback) \
    X(CurrentDemandValue,             int16_t,  0,       Feedback) \
    X(CurrentActualValueAveraged,     int16_t,  0,       Feedback) \
    X(DigitalInputLogicState,         uint16_t, 0,       Feedback) \
    X(EncoderIndexPosition,           int32_t,  0,       Feedback) \
    X(MainSensorResolution,           uint32_t, 2000,    Feedback)
// clang-format on

namespace obj {
#define DRIVE_OBJECT_HANDLE(name, idx, sub, T, def, role) inline constexpr Obj<T> name{idx, sub, def};
DRIVE_CIA402_OBJECTS(DRIVE_OBJECT_HANDLE)
#undef DRIVE_OBJECT_HANDLE
}  // namespace obj

// The vendor parameters by name, and their C++ types and defaults.
enum class Param : uint8_t {
#define DRIVE_PARAM_ENUM(name, T, def, role) name,
    DRIVE_VENDOR_PARAMETERS(DRIVE_PARAM_ENUM)
#undef DRIVE_PARAM_ENUM
};
template <typename T>
struct VendorParam {
    using type = T;
    Param param;
    T def;
};
namespace vendor {
#define DRIVE_PARAM_HANDLE(name, T, def, role) inline constexpr VendorParam<T> name{Param::name, def};
DRIVE_VENDOR_PARAMETERS(DRIVE_PARAM_HANDLE)
#undef DRIVE_PARAM_HANDLE
}  // namespace vendor
// Bytes of a vendor parameter's value.
constexpr std::size_t param_size(Param p) {
    switch (p) {
#define DRIVE_PARAM_SIZE(name, T, def, role) \
    case Param::name:                        \
        return sizeof(T);
        DRIVE_VENDOR_PARAMETERS(DRIVE_PARAM_SIZE)
#undef DRIVE_PARAM_SIZE
    }
    return 0;
}
constexpr bool param_signed(Param p) {
    switch (p) {
#define DRIVE_PARAM_SIGNED(name, T, def, role) \
    case Param::name:                          \
        return std::numeric_limits<T>::is_signed;
        DRIVE_VENDOR_PARAMETERS(DRIVE_PARAM_SIGNED)
#undef DRIVE_PARAM_SIGNED
    }
    return false;
}

// Where a device keeps one vendor parameter.
struct Binding {
    Param param;
    uint16_t index;
    uint8_t sub;
};
// An object a master may write only while the power stage is off ("Power Disable"): every subindex, or
// only `sub` (sub >= 0).
struct PowerDisableOnly {
    uint16_t index;
    int16_t sub = -1;
};
// What a device description tells the drive beyond CiA 402: where its vendor parameters are, and which
// objects it lets a master write only with the power stage off. Empty: a plain CiA 402 device.
struct VendorObjects {
    std::span<const Binding> bindings;
    std::span<const PowerDisableOnly> power_disable_only;
    // The object a binding names for `p`, or nullptr.
    const Binding* find(Param p) const {
        for (const Binding& b : bindings)
            if (b.param == p) return &b;
        return nullptr;
    }
};

// One handle, type-erased: for tests and tools that walk the list.
struct ObjInfo {
    std::string_view name;
    uint16_t index;
    uint8_t sub;
    uint8_t size;  // bytes
    bool is_signed;
    Role role;
    int64_t def;
};
// The CiA 402 objects (DRIVE_CIA402_OBJECTS).
std::span<const ObjInfo> cia402_objects();
// The name of a vendor parameter.
std::string_view param_name(Param p);

}  // namespace drive
