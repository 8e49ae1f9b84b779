#pragma once
// CiA 402 device control of one axis (IEC 61800-7-201 §6.2.2): the state of the power drive system, the
// power stage, the transition waiting for the drive to stop, the stop ramp and the fault reaction. The
// transitions are decoded in state_machine.hpp; what a transition asks of the other parts (the loops and
// set-points on enabling, homing and the profile on a stop, supervision on a fault reset) goes through the
// narrow `Parts` interface, which Axis implements.
#include <cstdint>

#include "drive/event_sink.hpp"
#include "drive/faults.hpp"
#include "drive/state_machine.hpp"
#include "drive/wire/error_codes.hpp"

namespace drive {

// How a stop brings the motor to rest: a deceleration ramp (0x6084 or 0x6085), at the current limit (the
// velocity loop brakes to zero speed with the current it may give: quick stop and fault reaction option codes
// 3/4/7/8), or by switching the power stage off.
enum class StopKind : uint8_t { None, Ramp, Limit, Disable };

class DeviceControl {
  public:
    // What device control asks of the other parts of the axis.
    class Parts {
      public:
        // Transition 4: the error that refuses to switch the power stage on (0: none).
        virtual uint16_t enable_refused() = 0;
        // Transition 4 done: the loops and set-points start from where the motor is.
        virtual void powered() = 0;
        // A stop began: a running homing is interrupted; a ramp or a stop at the current limit starts from
        // the actual motion. Returns the ramp's deceleration `decel_rpm_s` in inc/s^2, limited by 0x60C5
        // (unused for the other kinds).
        virtual double stopping(StopKind kind, double decel_rpm_s) = 0;
        // Transition 16: the set-points hold where the quick-stop ramp got to.
        virtual void resumed() = 0;
        // Transition 15: supervision clears the errors; false when a cause is still present.
        virtual bool fault_reset() = 0;
        // A fault reset outside Fault: supervision acknowledges the warnings.
        virtual void acknowledge_warnings() = 0;
        // An error (from a refused transition 4).
        virtual void fault(uint16_t code) = 0;

      protected:
        ~Parts() = default;
    };
    // The option codes and decelerations the transitions use.
    struct Options {
        int16_t shutdown = 0;                  // 0x605B
        int16_t disable_operation = 0;         // 0x605C
        uint32_t profile_deceleration = 0;     // 0x6084 rpm/s
        uint32_t quick_stop_deceleration = 0;  // 0x6085 rpm/s
        int16_t quick_stop = 6;                // 0x605A
    };

    // Start-up: transition 1 (Not Ready to Switch On -> Switch On Disabled).
    void start(EventSink& sink) { enter(State::SwitchOnDisabled, sink); }
    // The controlword of this cycle: the transition it commands, if one can run now.
    void command(uint16_t controlword, const AxisFaults& faults, const Options& o, Parts& parts,
                 EventSink& sink, int64_t now_ns);
    // An error was raised that asks for the reaction `rx` with option code `option`; `at_rest`: the motor
    // stands still (standstill window). Transition 13, and 14 at once for a powerless drive at rest.
    void react(Reaction rx, int16_t option, bool at_rest, const Options& o, Parts& parts, EventSink& sink,
               int64_t now_ns);
    // Once per cycle after the loops: completes a waiting transition (or the fault reaction) when the ramp is
    // over and the motor stands still (`still`), detection is off (0x30E0:01 = 0xFFFFFFFF) or 0x30E0:03 ms
    // passed.
    void settle(bool still, uint32_t standstill_window, uint16_t standstill_timeout_ms, EventSink& sink,
                int64_t now_ns);
    // The stop ramp (or the stop at the current limit) reached zero speed.
    void ramp_reached(bool at_zero) { ramp_done_ = at_zero || ramp_done_; }
    // End of the cycle: the controlword is the previous one from now on.
    void end_cycle(uint16_t controlword) { cw_prev_ = controlword; }

    State state() const { return state_; }
    bool power() const { return power_; }
    StopKind stop() const { return stop_; }
    double stop_deceleration() const { return stop_decel_; }  // inc/s^2
    bool ramp_done() const { return ramp_done_; }
    bool waiting() const { return pending_.active; }  // a transition waits for the drive to stop
    uint16_t previous_controlword() const { return cw_prev_; }
    // Operation enabled and no transition waiting: the drive follows its set-points.
    bool operational() const { return state_ == State::OperationEnabled && !pending_.active; }

  private:
    struct Pending {  // a transition waiting for the drive to stop
        bool active = false;
        State to = State::SwitchOnDisabled;
        int number = -1;
        int64_t since_ns = 0;
    };
    void enter(State s, EventSink& sink);
    void begin_stop(StopKind kind, double decel_rpm_s, Parts& parts);

    State state_ = State::NotReadyToSwitchOn;
    bool power_ = false;
    uint16_t cw_prev_ = 0;  // controlword of the previous cycle (mode bits)
    Pending pending_;
    StopKind stop_ = StopKind::None;
    double stop_decel_ = 0;  // inc/s^2
    bool ramp_done_ = false;
    bool fra_ = false;  // fault reaction running
};

}  // namespace drive
