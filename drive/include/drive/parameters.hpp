#pragma once
// What an Axis is told and what it reports, in the device units of the MAXPOS firmware specification §3.3
// (position inc, velocity rpm, acceleration rpm/s, torque per mille of the motor rated torque, current mA):
// its configuration (`Parameters`), the master's process-data outputs (`Command`) and the values it computes
// (`Feedback`), and the loop rates. The parts of an Axis (device_control.hpp ... homing.hpp) take what they
// need from here without an Axis.
#include <array>
#include <cstdint>
#include <limits>

#include "drive/objects.hpp"

namespace drive {

// A speed limit (0x607F max profile velocity, 0x6080 max motor speed) of 0 limits nothing: vendors' ESIs
// ship them 0 where the device sets its own (a limit of 0 would forbid every move).
constexpr uint32_t speed_limit(uint32_t v) {
    return v == 0 ? std::numeric_limits<uint32_t>::max() : v;
}

// Configuration objects. Defaults: the drive's, declared once in drive/objects.hpp (a dictionary that has the
// object replaces them with its own every cycle).
struct Parameters {
    // Motor data 0x3001, 0x6402
    uint16_t nominal_current = vendor::MotorNominalCurrent.def;             // :01 mA
    uint16_t output_current_limit = vendor::MotorOutputCurrentLimit.def;    // :02 mA
    uint8_t pole_pairs = vendor::MotorPolePairs.def;                        // :03
    uint16_t thermal_time_constant = vendor::MotorThermalTimeConstant.def;  // :04 in 100 ms
    uint32_t torque_constant = vendor::MotorTorqueConstant.def;  // :05 uNm/A (0 -> 0x8331 on enable)
    uint16_t motor_type = obj::MotorType.def;                    // 0x6402
    // Encoder 0x3010
    uint32_t encoder_pulses = vendor::EncoderPulses.def;     // :01 pulses/rev, inc/rev = 4 x
    uint16_t encoder_type = vendor::EncoderType.def;         // :02 bit0 index present
    uint32_t axis_misc = vendor::AxisConfigurationMisc.def;  // 0x3000:04 bit0 polarity: 1 = inverse
    // Current loop 0x30A0 (2^-16 V/A; I gain per 40 us current-loop sample, see decisions)
    uint32_t current_p = vendor::CurrentPGain.def, current_i = vendor::CurrentIGain.def,
             current_ff = vendor::CurrentFfGain.def;
    // Position (and velocity) loop 0x30A1
    uint32_t bandwidth = vendor::PositionBandwidth.def;   // :01 0.001 Hz
    uint32_t damping = vendor::PositionDamping.def;       // :02 per mille of critical
    uint32_t reset_time = vendor::PositionResetTime.def;  // :03 us
    uint32_t inertia = vendor::Inertia.def;               // :04 mg cm^2
    uint32_t friction = vendor::Friction.def;             // :05 nNm/rpm (viscous)
    // CSP: the position loop feeds its own demand's velocity forward (and its inertia and friction), as a
    // drive that interpolates the cyclic set-points does; false: only the master's 0x60B1/0x60B2 offsets
    // (MAXPOS).
    bool csp_own_feed_forward = false;
    // Option codes 0x6007, 0x605A..0x605E
    int16_t abort_connection = obj::AbortConnectionOptionCode.def;
    int16_t quick_stop = obj::QuickStopOptionCode.def;
    int16_t shutdown = obj::ShutdownOptionCode.def;
    int16_t disable_operation = obj::DisableOperationOptionCode.def;
    int16_t halt = obj::HaltOptionCode.def;
    int16_t fault_reaction = obj::FaultReactionOptionCode.def;
    // Motion limits and profile
    uint32_t following_error_window = obj::FollowingErrorWindow.def;    // 0x6065 inc; 0xFFFFFFFF = off
    uint16_t following_error_timeout = obj::FollowingErrorTimeout.def;  // 0x6066 ms
    int32_t sw_limit_min = obj::SoftwarePositionLimitMin.def;           // 0x607D:01
    int32_t sw_limit_max = obj::SoftwarePositionLimitMax.def;           // 0x607D:02
    int32_t range_min = obj::PositionRangeLimitMin.def;                 // 0x607B:01 (-2^31 = off)
    int32_t range_max = obj::PositionRangeLimitMax.def;                 // 0x607B:02
    uint32_t max_profile_velocity = obj::MaxProfileVelocity.def;        // 0x607F rpm
    uint32_t max_motor_speed = obj::MaxMotorSpeed.def;                  // 0x6080 rpm
    uint32_t profile_velocity = obj::ProfileVelocity.def;               // 0x6081 rpm
    uint32_t profile_acceleration = obj::ProfileAcceleration.def;       // 0x6083 rpm/s
    uint32_t profile_deceleration = obj::ProfileDeceleration.def;       // 0x6084 rpm/s
    uint32_t quick_stop_deceleration = obj::QuickStopDeceleration.def;  // 0x6085 rpm/s
    uint32_t max_acceleration = obj::MaxAcceleration.def;               // 0x60C5 rpm/s
    // Profile torque: 0x6087 per mille of the rated torque per second (0 or 0xFFFFFFFF: no ramp), 0x6088
    // (0 linear, 1 sin^2)
    uint32_t torque_slope = obj::TorqueSlope.def;
    int16_t torque_profile_type = obj::TorqueProfileType.def;
    // Homing
    int8_t homing_method = obj::HomingMethod.def;                            // 0x6098
    uint32_t homing_speed_switch = obj::HomingSpeedSwitchSearch.def;         // 0x6099:01 rpm
    uint32_t homing_speed_zero = obj::HomingSpeedZeroSearch.def;             // 0x6099:02 rpm
    uint32_t homing_acceleration = obj::HomingAcceleration.def;              // 0x609A rpm/s
    int32_t home_position = vendor::HomePosition.def;                        // 0x30B0 inc
    int32_t home_offset_move = vendor::HomeOffsetMoveDistance.def;           // 0x30B1 inc
    uint16_t homing_current_threshold = vendor::HomingCurrentThreshold.def;  // 0x30B2 mA
    // Interpolated position mode: sub-mode 0x60C0 (0 = linear interpolation, the one the drive serves)
    int16_t interpolation_sub_mode = obj::InterpolationSubMode.def;
    // Interpolation 0x60C2 (value x 10^index s); 0 = no interpolation
    uint8_t interpolation_value = obj::InterpolationTimePeriodValue.def;
    int8_t interpolation_index = obj::InterpolationTimeIndex.def;
    // Standstill 0x30E0
    uint32_t standstill_window = vendor::StandstillWindow.def;          // rpm; 0xFFFFFFFF = detection off
    uint16_t standstill_time = vendor::StandstillWindowTime.def;        // ms
    uint16_t standstill_timeout = vendor::StandstillWindowTimeout.def;  // ms; 0xFFFF = no timeout
    // Digital inputs 0x3141:02, 0x3142:01..06
    uint16_t input_polarity = vendor::DigitalInputPolarity.def;
    std::array<uint8_t, 6> input_function{
        vendor::DigitalInput1Configuration.def, vendor::DigitalInput2Configuration.def,
        vendor::DigitalInput3Configuration.def, vendor::DigitalInput4Configuration.def,
        vendor::DigitalInput5Configuration.def, vendor::DigitalInput6Configuration.def};
    int16_t touch_probe_source = obj::TouchProbe1Source.def;  // 0x60D0:01
    // 0x6502: the modes the device announces; the drive takes only those it also implements.
    uint32_t supported_modes = obj::SupportedDriveModes.def;
    // 0x608F position encoder resolution: increments per motor revolutions; 0 increments: 4 x encoder_pulses.
    uint32_t resolution_increments = obj::PositionEncoderIncrements.def;
    uint32_t resolution_revolutions = obj::PositionEncoderRevolutions.def;
    // 0x6091 gear ratio (motor : shaft revolutions) and 0x6092 feed constant (feed : shaft revolutions): the
    // position units of the position objects (Drive converts them; the axis works in increments).
    uint32_t gear_motor_revolutions = obj::GearMotorRevolutions.def;
    uint32_t gear_shaft_revolutions = obj::GearShaftRevolutions.def;
    uint32_t feed = obj::FeedConstantFeed.def;
    uint32_t feed_shaft_revolutions = obj::FeedConstantShaftRevolutions.def;

    bool operator==(const Parameters&) const = default;
};

// Process-data outputs of the master (RxPDO objects).
struct Command {
    uint16_t controlword = obj::Controlword.def;                  // 0x6040
    int8_t mode = obj::ModesOfOperation.def;                      // 0x6060
    int32_t target_position = obj::TargetPosition.def;            // 0x607A
    int32_t target_velocity = obj::TargetVelocity.def;            // 0x60FF
    int16_t target_torque = obj::TargetTorque.def;                // 0x6071
    int32_t ip_position = obj::InterpolationDataPosition.def;     // 0x60C1:01
    int32_t position_offset = obj::PositionOffset.def;            // 0x60B0
    int32_t velocity_offset = obj::VelocityOffset.def;            // 0x60B1
    int16_t torque_offset = obj::TorqueOffset.def;                // 0x60B2
    uint16_t touch_probe_function = obj::TouchProbeFunction.def;  // 0x60B8

    bool operator==(const Command&) const = default;
};

// Process-data inputs and other values the drive computes.
struct Feedback {
    uint16_t statusword = 0;             // 0x6041
    int8_t mode_display = 0;             // 0x6061
    int32_t position_demand = 0;         // 0x6062
    int32_t position_actual = 0;         // 0x6064 (also 0x60E4:01)
    int32_t velocity_demand = 0;         // 0x606B
    int32_t velocity_actual = 0;         // 0x606C (also 0x60E5:01)
    int32_t velocity_averaged = 0;       // 0x30D5 (also 0x60E5:09)
    int16_t torque_demand = 0;           // 0x6074
    int16_t torque_actual = 0;           // 0x6077
    int16_t current_actual = 0;          // 0x6078
    int16_t current_demand = 0;          // 0x30D0
    int16_t current_averaged = 0;        // 0x30D1
    int32_t following_error = 0;         // 0x60F4
    uint32_t motor_rated_torque = 0;     // 0x6076 uNm
    uint32_t digital_inputs = 0;         // 0x60FD
    uint16_t input_logic_state = 0;      // 0x3141:01
    int32_t index_position = 0;          // 0x3010:04
    uint16_t touch_probe_status = 0;     // 0x60B9
    int32_t touch_probe_pos = 0;         // 0x60BA
    int32_t touch_probe_neg = 0;         // 0x60BB
    uint16_t touch_probe_pos_count = 0;  // 0x60D5
    uint16_t touch_probe_neg_count = 0;  // 0x60D6
    uint16_t error_code = 0;             // 0x603F
    uint8_t error_register = 0;          // 0x1001
};

// Loop rates: current loop 25 kHz, velocity loop 5 kHz, position loop and trajectory 2.5 kHz; the plant is
// integrated in 10 us steps.
constexpr int64_t kCurrentTickNs = 40000;
constexpr int kPlantStepsPerTick = 4;
constexpr int kVelocityDivider = 5;
constexpr int kPositionDivider = 10;

}  // namespace drive
