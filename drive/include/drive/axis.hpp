#pragma once
// One servo axis that runs without an object dictionary (its defaults are the dictionary's, declared once in
// od/drive_objects.hpp), composed of value types that each own their state: device control
// (device_control.hpp), the set-point generator (setpoint.hpp), the cascaded loops and observer
// (controller.hpp), supervision and errors (supervisor.hpp), the touch probe (touch_probe.hpp) and homing
// (homing.hpp), plus the simulated machine (plant.hpp, environment.hpp). Drive (drive.hpp) copies the
// dictionary's values into `Parameters`/`Command` before each cycle and the `Feedback` back after it; tests
// can drive an Axis directly.
//
// Units at this interface are the device units of the MAXPOS firmware specification §3.3: position inc,
// velocity rpm, acceleration rpm/s, torque per mille of the motor rated torque, current mA.
#include <array>
#include <cstdint>
#include <limits>

#include "drive/controller.hpp"
#include "drive/device_control.hpp"
#include "drive/environment.hpp"
#include "drive/event_sink.hpp"
#include "drive/faults.hpp"
#include "drive/homing.hpp"
#include "drive/plant.hpp"
#include "drive/profile.hpp"
#include "drive/setpoint.hpp"
#include "drive/state_machine.hpp"
#include "drive/supervisor.hpp"
#include "drive/touch_probe.hpp"
#include "od/drive_objects.hpp"

namespace drive {

// Configuration objects. Defaults: the dictionary's, declared once in od/drive_objects.hpp (the MAXPOS
// firmware specification's defaults, except where docs/decisions/od.md notes otherwise).
struct Parameters {
    // Motor data 0x3001, 0x6402
    uint16_t nominal_current = od::obj::MotorNominalCurrent.def;             // :01 mA
    uint16_t output_current_limit = od::obj::MotorOutputCurrentLimit.def;    // :02 mA
    uint8_t pole_pairs = od::obj::MotorPolePairs.def;                        // :03
    uint16_t thermal_time_constant = od::obj::MotorThermalTimeConstant.def;  // :04 in 100 ms
    uint32_t torque_constant = od::obj::MotorTorqueConstant.def;  // :05 uNm/A (0 -> 0x8331 on enable)
    uint16_t motor_type = od::obj::MotorType.def;                 // 0x6402
    // Encoder 0x3010
    uint32_t encoder_pulses = od::obj::EncoderPulses.def;     // :01 pulses/rev, inc/rev = 4 x
    uint16_t encoder_type = od::obj::EncoderType.def;         // :02 bit0 index present
    uint32_t axis_misc = od::obj::AxisConfigurationMisc.def;  // 0x3000:04 bit0 polarity: 1 = inverse
    // Current loop 0x30A0 (2^-16 V/A; I gain per 40 us current-loop sample, see decisions)
    uint32_t current_p = od::obj::CurrentPGain.def, current_i = od::obj::CurrentIGain.def,
             current_ff = od::obj::CurrentFfGain.def;
    // Position (and velocity) loop 0x30A1
    uint32_t bandwidth = od::obj::PositionBandwidth.def;   // :01 0.001 Hz
    uint32_t damping = od::obj::PositionDamping.def;       // :02 per mille of critical
    uint32_t reset_time = od::obj::PositionResetTime.def;  // :03 us
    uint32_t inertia = od::obj::Inertia.def;               // :04 mg cm^2
    uint32_t friction = od::obj::Friction.def;             // :05 nNm/rpm (viscous)
    // Option codes 0x6007, 0x605A..0x605E
    int16_t abort_connection = od::obj::AbortConnectionOptionCode.def;
    int16_t quick_stop = od::obj::QuickStopOptionCode.def;
    int16_t shutdown = od::obj::ShutdownOptionCode.def;
    int16_t disable_operation = od::obj::DisableOperationOptionCode.def;
    int16_t halt = od::obj::HaltOptionCode.def;
    int16_t fault_reaction = od::obj::FaultReactionOptionCode.def;
    // Motion limits and profile
    uint32_t following_error_window = od::obj::FollowingErrorWindow.def;    // 0x6065 inc; 0xFFFFFFFF = off
    uint16_t following_error_timeout = od::obj::FollowingErrorTimeout.def;  // 0x6066 ms
    int32_t sw_limit_min = od::obj::SoftwarePositionLimitMin.def;           // 0x607D:01
    int32_t sw_limit_max = od::obj::SoftwarePositionLimitMax.def;           // 0x607D:02
    int32_t range_min = od::obj::PositionRangeLimitMin.def;                 // 0x607B:01 (-2^31 = off)
    int32_t range_max = od::obj::PositionRangeLimitMax.def;                 // 0x607B:02
    uint32_t max_profile_velocity = od::obj::MaxProfileVelocity.def;        // 0x607F rpm
    uint32_t max_motor_speed = od::obj::MaxMotorSpeed.def;                  // 0x6080 rpm
    uint32_t profile_velocity = od::obj::ProfileVelocity.def;               // 0x6081 rpm
    uint32_t profile_acceleration = od::obj::ProfileAcceleration.def;       // 0x6083 rpm/s
    uint32_t profile_deceleration = od::obj::ProfileDeceleration.def;       // 0x6084 rpm/s
    uint32_t quick_stop_deceleration = od::obj::QuickStopDeceleration.def;  // 0x6085 rpm/s
    uint32_t max_acceleration = od::obj::MaxAcceleration.def;               // 0x60C5 rpm/s
    // Homing
    int8_t homing_method = od::obj::HomingMethod.def;                         // 0x6098
    uint32_t homing_speed_switch = od::obj::HomingSpeedSwitchSearch.def;      // 0x6099:01 rpm
    uint32_t homing_speed_zero = od::obj::HomingSpeedZeroSearch.def;          // 0x6099:02 rpm
    uint32_t homing_acceleration = od::obj::HomingAcceleration.def;           // 0x609A rpm/s
    int32_t home_position = od::obj::HomePosition.def;                        // 0x30B0 inc
    int32_t home_offset_move = od::obj::HomeOffsetMoveDistance.def;           // 0x30B1 inc
    uint16_t homing_current_threshold = od::obj::HomingCurrentThreshold.def;  // 0x30B2 mA
    // Interpolation 0x60C2 (value x 10^index s); 0 = no interpolation
    uint8_t interpolation_value = od::obj::InterpolationTimePeriodValue.def;
    int8_t interpolation_index = od::obj::InterpolationTimeIndex.def;
    // Standstill 0x30E0
    uint32_t standstill_window = od::obj::StandstillWindow.def;          // rpm; 0xFFFFFFFF = detection off
    uint16_t standstill_time = od::obj::StandstillWindowTime.def;        // ms
    uint16_t standstill_timeout = od::obj::StandstillWindowTimeout.def;  // ms; 0xFFFF = no timeout
    // Digital inputs 0x3141:02, 0x3142:01..06
    uint16_t input_polarity = od::obj::DigitalInputPolarity.def;
    std::array<uint8_t, 6> input_function{
        od::obj::DigitalInput1Configuration.def, od::obj::DigitalInput2Configuration.def,
        od::obj::DigitalInput3Configuration.def, od::obj::DigitalInput4Configuration.def,
        od::obj::DigitalInput5Configuration.def, od::obj::DigitalInput6Configuration.def};
    int16_t touch_probe_source = od::obj::TouchProbe1Source.def;  // 0x60D0:01

    bool operator==(const Parameters&) const = default;
};

// Process-data outputs of the master (RxPDO objects).
struct Command {
    uint16_t controlword = od::obj::Controlword.def;                  // 0x6040
    int8_t mode = od::obj::ModesOfOperation.def;                      // 0x6060
    int32_t target_position = od::obj::TargetPosition.def;            // 0x607A
    int32_t target_velocity = od::obj::TargetVelocity.def;            // 0x60FF
    int16_t target_torque = od::obj::TargetTorque.def;                // 0x6071
    int32_t position_offset = od::obj::PositionOffset.def;            // 0x60B0
    int32_t velocity_offset = od::obj::VelocityOffset.def;            // 0x60B1
    int16_t torque_offset = od::obj::TorqueOffset.def;                // 0x60B2
    uint16_t touch_probe_function = od::obj::TouchProbeFunction.def;  // 0x60B8

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

class Axis {
  public:
    explicit Axis(EventSink* sink = nullptr);

    Parameters params;
    AxisFaults faults;  // testing aid: deliberate deviations (drive/faults.hpp), all off
    Command command;
    const Feedback& feedback() const { return fb_; }

    Environment& environment() { return env_; }
    MotorModel& motor() { return motor_; }  // call reconfigure() after changing it
    void reconfigure() { plant_dirty_ = true; }
    void set_event_sink(EventSink* s) { sink_ = s ? s : &null_sink_; }

    // One drive cycle: evaluates `command` (written by the master before), runs the loops and the machine for
    // dt_ns, and updates feedback(). now_ns is the time at the start of the cycle.
    void cycle(int64_t now_ns, int64_t dt_ns);
    // The master is gone (SM watchdog, ESM left Op): reaction per 0x6007 with error 0x8180.
    void connection_lost();
    // Raise an error from outside (e.g. the communication side); reaction per its class.
    void raise_error(uint16_t code);

    State state() const { return dc_.state; }
    int8_t active_mode() const { return sp_.mode; }
    bool power_on() const { return dc_.power; }
    bool referenced() const { return home_.referenced; }
    bool i2t_limiting() const { return ctl_.i2t_active; }
    double thermal_load() const { return ctl_.thermal; }  // I2t state, 1.0 = limit
    const Plant& plant() const { return plant_; }
    double position_demand_inc() const { return sp_.demand_pos + shift_; }  // reported frame, unrounded
    double raw_position_inc() const;   // exact simulated position in raw increments (after polarity)
    double phys_position_inc() const;  // the same before polarity: the frame of the Environment
    int64_t home_shift() const { return shift_; }
    int32_t increments_per_rev() const { return res_; }
    // Ids of active errors (up to 8), for tests and diagnostics.
    bool error_active(uint16_t code) const;

  private:
    // Axis runs its parts against each other; each group below lives in the .cpp named after the part.
    // axis.cpp: configuration, the cycle, the machine (plant, inputs, encoder) and the feedback
    void derive();
    void machine_step(double raw, int64_t t_ns);  // after a plant step: inputs, encoder index
    void edges(double prev, double raw, int64_t t_ns, uint64_t changed);  // input edges within a step
    void on_edge(int bit, bool rising, double raw_pos);
    void on_index(double raw_pos);
    void update_feedback();
    // device_control.cpp
    void device_control(int64_t now_ns);
    void enter(State s, int number);
    void begin_stop(StopKind kind, double decel_rpm_s, int64_t now_ns);
    void check_pending(int64_t now_ns);
    // supervisor.cpp
    void fault(uint16_t code, int64_t now_ns);
    void fault_reset();
    bool cause_present(uint16_t code) const;
    void supervise(int64_t now_ns, int64_t dt_ns);
    // setpoint.cpp
    void mode_commands(int64_t now_ns, int64_t dt_ns);
    void switch_mode(int8_t m);
    void trajectory_tick(int64_t t_ns);
    // controller.cpp
    void position_tick();
    void velocity_tick();
    void current_tick(int64_t t_ns);
    // touch_probe.cpp
    void tp_latch(bool rising, double raw_pos);
    // homing.cpp
    void homing_start();
    void homing_tick(double h);
    void homing_finish_ok();
    void homing_fail();
    // helpers (axis.cpp)
    uint64_t functions(uint16_t pins) const;
    uint64_t functions_now(uint16_t pins);  // functions() remembered for the last pins within one cycle
    void prepare_steps(int64_t from_ns, int64_t to_ns);
    int32_t clamp_i32(double v) const;
    bool range_on() const;
    int32_t report(int64_t v) const;                           // a position as the dictionary shows it
    double unwrap(int32_t target, double near_raw) const;      // modulo target -> raw increments
    double i_meas() const { return pol_ * plant_.current(); }  // current in the axis' direction
    double rpm_to_inc_s(double rpm) const { return rpm * res_ / 60.0; }
    double inc_to_rad(double inc) const { return inc * rad_per_inc_; }
    double decel_limit(double d) const;

    EventSink* sink_;
    NullEventSink null_sink_;
    Environment env_;
    MotorModel motor_;
    Plant plant_;
    Feedback fb_;

    // the parts, each owning its state
    DeviceControl dc_;
    SetpointGenerator sp_;
    Controller ctl_;
    Supervisor sup_;
    TouchProbe tp_;
    Homing home_;

    // configuration derived from params
    int32_t res_ = 2000;
    // 2 pi / res_ and res_ / 2 pi: multiplications instead of divisions in the current loop's feedback chain
    double rad_per_inc_ = 6.283185307179586 / 2000;
    double inc_per_rad_ = 2000 / 6.283185307179586;
    double pol_ = 1.0;  // 0x3000:04 bit 0: -1 = inverse polarity
    double km_plant_ = -1;
    bool plant_dirty_ = true;
    int64_t now_ns_ = 0;

    // encoder and inputs
    int64_t count_ = 0;  // raw encoder count
    int64_t shift_ = 0;  // reported = raw + shift
    int64_t index_count_ = 0;
    double prev_raw_pos_ = 0;
    uint64_t func_ = 0;  // 0x60FD-style function bits, bit 26 = touch probe input, bits 32..37 = pins
    uint16_t pins_ = 0;
    // per-cycle caches of the 10 us machine steps (prepare_steps; same values as computing them each step)
    bool fn_valid_ = false;  // functions_now(): fn_pins_ -> fn_value_ under this cycle's parameters
    uint16_t fn_pins_ = 0;
    uint64_t fn_value_ = 0;
    bool pins_fixed_ = false;  // the environment's pins cannot change during this cycle's steps
    uint16_t fixed_pins_ = 0;
    bool index_on_ = false;  // encoder index (0x3010:02 bit 0)
    double index_p0_ = 0;    // where the index sits within a turn, inc
    double index_k_ = 0;     // floor((prev_raw_pos_ - p0) / res): the turn the last step ended in
    double index_lo_ = 0, index_hi_ = 0;  // raw - p0 strictly inside this turn: no division needed
    // timing
    int64_t tick_ = 0;
    int64_t residual_ns_ = 0;
};

}  // namespace drive
