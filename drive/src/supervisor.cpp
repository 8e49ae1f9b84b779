// Supervision (Supervisor): errors and warnings, fault reset, the cycle's checks, standstill.
#include "drive/supervisor.hpp"

#include <cmath>
#include <limits>

#include "axis_internal.hpp"
#include "drive/errors.hpp"

namespace drive {

using namespace detail;

Supervisor::Raised Supervisor::raise(uint16_t code, int16_t fault_reaction_option,
                                     int16_t abort_connection_option, const std::array<uint8_t, 5>& mfr,
                                     EventSink& sink) {
    const ErrorInfo* info = find_error(code);
    const uint8_t reg = info ? info->error_register : 0x01;
    const Reaction rx = info ? info->reaction : Reaction::Disable;
    const std::string_view name = info ? info->name : std::string_view("Unknown error");
    // Reaction "fault signal only": a warning (statusword bit 7), no state change.
    const int16_t option = rx == Reaction::FaultReactionCode     ? fault_reaction_option
                           : rx == Reaction::AbortConnectionCode ? abort_connection_option
                                                                 : 0;
    const bool signal_only = (rx == Reaction::FaultReactionCode && option == -1) ||
                             (rx == Reaction::AbortConnectionCode && option == 1);
    if (signal_only) {
        if (std::find(warnings_.begin(), warnings_.end(), code) == warnings_.end()) {
            auto slot = std::find(warnings_.begin(), warnings_.end(), uint16_t{0});
            if (slot != warnings_.end()) *slot = code;
            sink.diag(Severity::Warning, code, name);
        }
        return {};
    }
    if (error_active(code)) return {};  // already active: no second emergency
    auto slot = std::find(active_.begin(), active_.end(), uint16_t{0});
    if (slot != active_.end()) *slot = code;
    last_error_ = code;
    // CiA 301 (0x1001): the generic bit is signalled at any error situation, beside the error's own bits.
    error_register_ |= reg | error_register::kGeneric;
    sink.raise(code, error_register_, mfr);
    return {true, rx, option};
}

bool Supervisor::Causes::present(uint16_t code) const {
    switch (code) {
        case error_code::Sto:
            return sto;
        case error_code::TorqueFault:
            return no_torque_constant;
        case error_code::MaxSpeed:
            return overspeed;
        default:
            return false;
    }
}

bool Supervisor::reset(const Causes& causes, EventSink& sink) {
    for (uint16_t c : active_) {
        if (c && causes.present(c)) {
            sink.diag(Severity::Warning, c, "Fault reset refused: cause still present");
            return false;
        }
    }
    for (auto& c : active_) {
        if (!c) continue;
        const uint16_t code = c;
        c = 0;
        uint8_t reg = 0;
        for (uint16_t o : active_)
            if (o) reg |= (find_error(o) ? find_error(o)->error_register : 0x01) | error_register::kGeneric;
        error_register_ = reg;
        sink.clear(code, error_register_);
    }
    acknowledge_warnings(sink);
    error_register_ = 0;
    last_error_ = 0;
    return true;
}

void Supervisor::acknowledge_warnings(EventSink& sink) {
    for (auto& w : warnings_) {
        if (w) sink.clear(w, error_register_);
        w = 0;
    }
}

void Supervisor::standstill(double vel_avg_rpm, uint32_t window, uint16_t time_ms, int64_t dt_ns) {
    const bool in = window == kNoWindow || std::abs(vel_avg_rpm) <= static_cast<double>(window);
    if (in) {
        still_ms_ += static_cast<double>(dt_ns) * 1e-6;
        still_ = still_ms_ >= time_ms;
    } else {
        still_ms_ = 0;
        still_ = false;
    }
}

bool Supervisor::following_error(bool checked, double ferr, uint32_t window, uint16_t timeout_ms,
                                 int64_t dt_ns) {
    if (checked && following_error_checked(window) && ferr > static_cast<double>(window)) {
        ferr_time_ms_ += static_cast<double>(dt_ns) * 1e-6;
        return ferr_time_ms_ >= timeout_ms;
    }
    ferr_time_ms_ = 0;
    return false;
}

Supervisor::Found Supervisor::limits(const Motion& m, const PositionFrame& f) {
    Found found;
    auto add = [&](uint16_t code) { found.codes[static_cast<std::size_t>(found.count++)] = code; };
    // Limit switches: error when reaching one, or when driving further into it after a fault reset.
    if (m.neg_switch && m.v < -1e-6) add(error_code::NegativeLimitSwitch);
    if (m.pos_switch && m.v > 1e-6) add(error_code::PositiveLimitSwitch);
    const bool below = f.sw_min != std::numeric_limits<int32_t>::min() && m.actual < f.sw_min;
    const bool above = f.sw_max != std::numeric_limits<int32_t>::max() && m.actual > f.sw_max;
    if ((m.check_actual && ((below && m.v < 0) || (above && m.v > 0))) || m.target_outside)
        add(error_code::SoftwarePositionLimit);
    return found;
}

bool Supervisor::overspeed(double speed_rad_s, uint32_t max_rpm) {
    return std::abs(speed_rad_s) * 60.0 / kTwoPi > static_cast<double>(speed_limit(max_rpm));
}

}  // namespace drive
