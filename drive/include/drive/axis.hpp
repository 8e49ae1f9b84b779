#pragma once
// One servo axis that runs without an object dictionary (its defaults are the dictionary's, declared once in
// drive/objects.hpp), composed of parts that each own their state and behaviour and are tested alone:
// device control (device_control.hpp), the set-point generator (setpoint.hpp), the cascaded loops and
// observer (controller.hpp), supervision and errors (supervisor.hpp), the touch probe (touch_probe.hpp) and
// homing (homing.hpp), plus the simulated machine (plant.hpp, environment.hpp). Axis sequences them in the
// cycle and passes each what it needs. Drive (drive.hpp) copies the
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
#include "drive/objects.hpp"
#include "drive/parameters.hpp"
#include "drive/plant.hpp"
#include "drive/profile.hpp"
#include "drive/setpoint.hpp"
#include "drive/state_machine.hpp"
#include "drive/supervisor.hpp"
#include "drive/touch_probe.hpp"

namespace drive {

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

    // The modes the device can serve (0x6502 bits; drive::Drive: those whose set-point object its dictionary
    // has): a mode outside them is not taken, whatever 0x6502 says. Default: every mode the drive implements.
    void serve_modes(uint32_t modes) { served_modes_ = modes; }
    uint32_t served_modes() const { return served_modes_; }

    State state() const { return dc_.state(); }
    int8_t active_mode() const { return sp_.mode(); }
    bool power_on() const { return dc_.power(); }
    bool referenced() const { return home_.referenced(); }
    bool i2t_limiting() const { return ctl_.i2t_active; }
    double thermal_load() const { return ctl_.thermal; }  // I2t state, 1.0 = limit
    const Plant& plant() const { return plant_; }
    double position_demand_inc() const {  // reported frame, unrounded
        return sp_.demand_position() + static_cast<double>(home_.shift());
    }
    double raw_position_inc() const;   // exact simulated position in raw increments (after polarity)
    double phys_position_inc() const;  // the same before polarity: the frame of the Environment
    int64_t home_shift() const { return home_.shift(); }
    int32_t increments_per_rev() const { return res_; }
    // Ids of active errors (up to 8), for tests and diagnostics.
    bool error_active(uint16_t code) const;

  private:
    // Axis composes the parts and sequences them; each part owns its behaviour (its header says what it
    // needs). Here: configuration, the cycle, the machine (plant, inputs, encoder), the feedback, and what
    // passes between the parts.
    class Parts;  // DeviceControl::Parts: what a transition asks of the other parts
    friend class Parts;
    void derive();
    void machine_step(double raw, int64_t t_ns);  // after a plant step: inputs, encoder index
    void edges(double prev, double raw, int64_t t_ns, uint64_t changed);  // input edges within a step
    void on_edge(int bit, bool rising, double raw_pos);
    void on_index(double raw_pos);
    void update_feedback();
    void fault(uint16_t code, int64_t now_ns);  // supervision records, device control reacts
    void supervise(int64_t now_ns, int64_t dt_ns);
    void mode_commands(int64_t now_ns, int64_t dt_ns);
    void trajectory_tick(int64_t t_ns);
    void current_tick(int64_t t_ns);  // controller.cpp: flattened with the controller's sample
    void tp_latch(bool rising, double raw_pos);
    // helpers
    DeviceControl::Options dc_options() const;
    PositionFrame frame() const;
    uint64_t functions(uint16_t pins) const;
    uint64_t functions_now(uint16_t pins);  // functions() remembered for the last pins within one cycle
    void prepare_steps(int64_t from_ns, int64_t to_ns);
    int32_t clamp_i32(double v) const;
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
    uint32_t served_modes_ = supported_drive_modes();

    // encoder and inputs
    int64_t count_ = 0;  // raw encoder count
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
