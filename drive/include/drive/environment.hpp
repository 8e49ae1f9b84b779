#pragma once
// The machine around the motor, as the user configures it: limit switches, a home switch, mechanical stops,
// and digital inputs the user toggles at run time. Positions are in raw encoder increments (the encoder count
// since power-on, before any homing shift), so a test can place a switch "at 5000 inc" directly.
//
// Wiring: each switch drives one physical input DigIN1..6 (pin high = switch active, before the drive's
// polarity 0x3141:02). The drive maps pins to functions with 0x3142 (defaults: DigIN1 negative limit,
// DigIN2 positive limit, DigIN3 home switch), so the default wiring below matches the default configuration.
// Positions here are physical: inverting the axis polarity (0x3000:04) does not move the switches.
#include <array>
#include <cstdint>
#include <limits>

namespace drive {

class Environment {
  public:
    static constexpr int kPins = 6;
    static constexpr double kNone = std::numeric_limits<double>::quiet_NaN();

    struct Switch {
        bool present = false;
        double from = 0, to = 0;  // active while from <= position <= to (raw increments)
        int pin = 0;              // 1..6
    };

    // Negative limit switch: active at and below `at`. Positive: active at and above `at`.
    void set_negative_limit(double at, int pin = 1);
    void set_positive_limit(double at, int pin = 2);
    // Home switch active on [from, to].
    void set_home_switch(double from, double to, int pin = 3);
    void remove_switches();
    // Hard mechanical stops (raw increments); NaN = none. Read by the drive when it configures the plant.
    void set_mechanical_stops(double lo, double hi) { stop_lo_ = lo, stop_hi_ = hi, stops_changed_ = true; }
    double stop_lo() const { return stop_lo_; }
    double stop_hi() const { return stop_hi_; }
    bool take_stops_changed() {
        bool c = stops_changed_;
        stops_changed_ = false;
        return c;
    }

    // A pin the user drives directly (pins no switch is wired to). Takes effect at the given time (ns on the
    // drive's clock), so an edge can fall between two drive cycles; now_ns <= 0 = immediately.
    void set_input(int pin, bool level, int64_t at_ns = 0);
    // STO inputs: DigIN5/6 are STO-IN1/2 (MAXPOS firmware specification §5); both must be high for the power
    // stage. Default high.
    void set_sto(bool released) {
        set_input(5, released);
        set_input(6, released);
    }

    // Pin levels (bit n-1 = DigIN n) at a raw position and time.
    uint16_t pins(double position, int64_t t_ns) const;
    // True when the pins cannot change for any position and any time in [from_ns, to_ns] (no switch wired,
    // no timed input change due after from_ns and at or before to_ns); `level` is then their value. Lets the
    // drive skip pins() in its 10 us machine steps.
    bool constant_over(int64_t from_ns, int64_t to_ns, uint16_t& level) const;

  private:
    std::array<Switch, 3> switches_{};  // neg, pos, home
    struct Manual {
        bool level = false;
        bool pending = false;
        bool next = false;
        int64_t at = 0;
    };
    std::array<Manual, kPins> manual_{{{}, {}, {}, {}, {true, false, false, 0}, {true, false, false, 0}}};
    double stop_lo_ = kNone, stop_hi_ = kNone;
    bool stops_changed_ = true;
};

}  // namespace drive
