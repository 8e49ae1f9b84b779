#pragma once
// Supervision of one axis: the active errors and warnings with the error register (0x603F, 0x1001), fault
// reset, the checks the cycle runs (following error, limit switches, software position limits, speed) and
// standstill detection (0x30E0). It records errors and says what they ask for; device control
// (device_control.hpp) runs the reaction, Axis sequences the two.
#include <algorithm>
#include <array>
#include <cstdint>

#include "drive/event_sink.hpp"
#include "drive/frame.hpp"
#include "drive/wire/error_codes.hpp"

namespace drive {

class Supervisor {
  public:
    // A raised error that asks for a fault reaction (not a warning, not already active): its reaction class
    // and the option code that selects the reaction (0x605E or 0x6007, 0 for the others).
    struct Raised {
        bool react = false;
        Reaction reaction = Reaction::Disable;
        int16_t option = 0;
    };
    // Records error `code`: a warning (statusword bit 7) when its option code says "fault signal only"
    // (0x605E = -1, 0x6007 = 1), otherwise an active error, announced with the emergency's manufacturer
    // bytes `mfr` (once while active).
    Raised raise(uint16_t code, int16_t fault_reaction_option, int16_t abort_connection_option,
                 const std::array<uint8_t, 5>& mfr, EventSink& sink);

    // The causes a fault reset cannot clear while they last.
    struct Causes {
        bool sto = false;                 // STO inputs not both high
        bool no_torque_constant = false;  // 0x3001:05 = 0
        bool overspeed = false;           // above 0x6080
        bool present(uint16_t code) const;
    };
    // Fault reset: clears every error and warning, unless a cause is still present (false: refused).
    bool reset(const Causes& causes, EventSink& sink);
    // A fault reset outside Fault acknowledges the warnings.
    void acknowledge_warnings(EventSink& sink);

    // Standstill detection: |averaged speed| within `window` rpm (0xFFFFFFFF = detection off) for `time_ms`.
    void standstill(double vel_avg_rpm, uint32_t window, uint16_t time_ms, int64_t dt_ns);
    // Following error (MAXPOS firmware specification §4.6): `checked` in a position-controlled mode with the
    // drive enabled; true when |ferr| stayed above `window` (0xFFFFFFFF = off) for `timeout_ms`.
    bool following_error(bool checked, double ferr, uint32_t window, uint16_t timeout_ms, int64_t dt_ns);
    // The limit checks of an enabled drive outside homing: the limit switches when moving into them, the
    // software position limits on the actual position (`check_actual`, not in PPM, which clamps the target)
    // and on the CSP target. `v` is the direction of motion.
    struct Motion {
        double v = 0;
        bool neg_switch = false, pos_switch = false;
        int64_t actual = 0;  // reported frame, unwrapped
        bool check_actual = true;
        bool target_outside = false;  // the CSP target is outside the software position limits
    };
    // Up to three errors, in the order they are raised.
    struct Found {
        std::array<uint16_t, 3> codes{};
        int count = 0;
    };
    static Found limits(const Motion& m, const PositionFrame& f);
    // |speed| (rad/s) above 0x6080 (rpm).
    static bool overspeed(double speed_rad_s, uint32_t max_rpm);

    bool error_active(uint16_t code) const {
        return std::find(active_.begin(), active_.end(), code) != active_.end() && code != 0;
    }
    bool warning() const {
        return std::any_of(warnings_.begin(), warnings_.end(), [](uint16_t w) { return w != 0; });
    }
    uint16_t last_error() const { return last_error_; }
    uint8_t error_register() const { return error_register_; }
    bool still() const { return still_; }

  private:
    std::array<uint16_t, 8> active_{};
    std::array<uint16_t, 8> warnings_{};
    uint16_t last_error_ = 0;
    uint8_t error_register_ = 0;
    double ferr_time_ms_ = 0;
    double still_ms_ = 0;
    bool still_ = false;
};

}  // namespace drive
