// Homing mode (6) (IEC 61800-7-201 homing mode; MAXPOS firmware specification §4.5, §7.2.75-7.2.77; EPOS4
// Application Notes §7.3): the methods of 0x60E3, run as a small phase machine on top of the profile
// generator. Edges and index pulses are latched in the plant sub-steps (on_edge/on_index) at the position
// where they really happened, so the reference point does not depend on the cycle time.
#include <cmath>

#include "drive/axis.hpp"

namespace drive {

namespace {
bool limit_method(int m) {
    return m == 1 || m == 2 || m == 17 || m == 18;
}
bool home_method(int m) {
    return m == 7 || m == 11 || m == 23 || m == 27;
}
bool current_method(int m) {
    return m <= -1 && m >= -4;
}
bool uses_index(int m) {
    return m == 1 || m == 2 || m == 7 || m == 11 || m == 33 || m == 34 || m == -1 || m == -2;
}
// Direction of the offset move: away from the limit switch or the mechanical stop for those methods,
// positive (as 0x30B1 is signed) for the others.
int offset_sign(int m) {
    if (m == 2 || m == 18 || m == -1 || m == -3) return -1;
    return 1;
}
}  // namespace

void Axis::homing_start() {
    // Homing clears touch-probe states and latched values (MAXPOS firmware specification §4.5).
    tp_.clear_for_homing();
    home_.method = params.homing_method;
    home_.referenced = false;
    home_.status = HomingStatus::InProgress;
    home_.edge = home_.index = false;
    home_.settle = 0;
    home_.bit = -1;
    home_.rise = true;
    sp_.profile.reset(sp_.demand_pos, sp_.demand_vel);
    const int m = home_.method;
    const bool neg = func_ & ((1ull << 0) | (1ull << 24));
    const bool pos = func_ & ((1ull << 1) | (1ull << 25));
    const bool home = func_ & (1ull << 2);
    // Only the methods of 0x60E3 (declared once in od/drive_objects.hpp, also the 0x6098 validator's).
    if (!od::contains(od::kHomingMethods, m) || (uses_index(m) && !(params.encoder_type & 0x1))) {
        homing_fail();
        return;
    }
    if (limit_method(m)) {
        const bool negative = (m == 1 || m == 17);
        home_.bit = negative ? 0 : 1;
        home_.dir = negative ? -1 : 1;
        if (negative ? neg : pos) {  // already on the switch: only back off
            home_.dir = -home_.dir;
            home_.rise = false;
            home_.phase = HomingPhase::Backoff;
        } else {
            home_.phase = HomingPhase::Search;
        }
    } else if (home_method(m)) {
        home_.bit = 2;
        home_.dir = (m == 7 || m == 23) ? 1 : -1;
        if (home) {  // starts on the switch: go the other way to its edge
            home_.dir = -home_.dir;
            home_.rise = false;
            home_.phase = HomingPhase::Backoff;
        } else {
            home_.phase = HomingPhase::Search;
        }
    } else if (m == 33 || m == 34) {
        home_.dir = m == 33 ? -1 : 1;
        home_.search_origin = static_cast<double>(count_);
        home_.phase = HomingPhase::ToIndex;
    } else if (m == 37) {
        home_.ref = static_cast<double>(count_);
        home_.phase = HomingPhase::Offset;
    } else if (current_method(m)) {
        home_.dir = (m == -1 || m == -3) ? 1 : -1;
        home_.phase = HomingPhase::Search;
    } else {
        homing_fail();
        return;
    }
    sink_->diag(Severity::Info, 0, "Homing started");
}

void Axis::homing_fail() {
    home_.status = HomingStatus::Error;
    home_.phase = HomingPhase::Stopping;
    home_.referenced = false;
    sink_->diag(Severity::Warning, 0, "Homing error");
}

void Axis::homing_finish_ok() {
    const double target =
        std::floor(home_.ref + offset_sign(home_.method) * static_cast<double>(params.home_offset_move));
    shift_ = static_cast<int64_t>(params.home_position) - static_cast<int64_t>(target);
    sp_.profile.reset(target, 0);
    home_.status = HomingStatus::Done;
    home_.phase = HomingPhase::Finished;
    home_.referenced = true;
    sink_->diag(Severity::Info, 0, "Homing attained");
}

void Axis::homing_tick(double h) {
    const double fast = rpm_to_inc_s(params.homing_speed_switch);
    const double slow = rpm_to_inc_s(params.homing_speed_zero);
    const double acc = decel_limit(params.homing_acceleration);
    if (home_.status != HomingStatus::InProgress) {
        sp_.profile.step_velocity(0.0, acc, acc, h);
        return;
    }
    if (sp_.halted) {  // halt in homing: stop with the homing acceleration (MAXPOS firmware specification
                       // Table 4-29)
        if (sp_.profile.step_velocity(0.0, acc, acc, h)) {
            home_.status = HomingStatus::Interrupted;
            home_.phase = HomingPhase::Finished;
        }
        return;
    }
    const int m = home_.method;
    const double threshold = params.homing_current_threshold * 1e-3;
    const double current = std::abs(plant_.current());
    const bool neg = func_ & ((1ull << 0) | (1ull << 24));
    const bool pos = func_ & ((1ull << 1) | (1ull << 25));
    switch (home_.phase) {
        case HomingPhase::Search:
            sp_.profile.step_velocity(home_.dir * fast, acc, acc, h);
            // A limit switch that is not the target of the search ends homing with an error.
            if (limit_method(m) && ((home_.bit == 0 && pos) || (home_.bit == 1 && neg))) return homing_fail();
            if (home_method(m) && ((home_.dir < 0 && neg) || (home_.dir > 0 && pos))) return homing_fail();
            if (current_method(m)) {
                // Only at constant speed: the acceleration current must not look like the stop.
                home_.settle = sp_.profile.velocity() == home_.dir * fast ? home_.settle + 1 : 0;
                if (current > threshold && home_.settle > 20) {
                    if (m == -3 || m == -4) {
                        home_.ref = static_cast<double>(count_);
                        home_.phase = HomingPhase::Offset;
                    } else {
                        home_.dir = -home_.dir;
                        home_.phase = HomingPhase::Backoff;
                    }
                }
            } else if (home_.edge) {
                home_.edge = false;
                home_.dir = -home_.dir;
                home_.rise = false;
                home_.phase = HomingPhase::Backoff;
            }
            break;
        case HomingPhase::Backoff:
            sp_.profile.step_velocity(home_.dir * slow, acc, acc, h);
            if (current_method(m)) {
                const double v = sp_.profile.velocity();
                if (current < threshold && ((home_.dir > 0 && v > 0) || (home_.dir < 0 && v < 0))) {
                    home_.search_origin = static_cast<double>(count_);
                    home_.index = false;
                    home_.phase = HomingPhase::ToIndex;
                }
            } else if (home_.edge) {
                home_.edge = false;
                if (m == 17 || m == 18 || m == 23 || m == 27) {
                    home_.ref = home_.event_pos;
                    home_.phase = HomingPhase::Offset;
                } else {
                    home_.search_origin = home_.event_pos;
                    home_.index = false;
                    home_.phase = HomingPhase::ToIndex;
                }
            }
            break;
        case HomingPhase::ToIndex:
            sp_.profile.step_velocity(home_.dir * slow, acc, acc, h);
            if (home_.index) {
                home_.ref = home_.event_pos;
                home_.phase = HomingPhase::Offset;
            } else if (std::abs(static_cast<double>(count_) - home_.search_origin) > 2.0 * res_) {
                return homing_fail();  // no index within two turns
            }
            break;
        case HomingPhase::Offset: {
            const double target =
                std::floor(home_.ref + offset_sign(m) * static_cast<double>(params.home_offset_move));
            if (sp_.profile.step_position(target, fast, acc, acc, h)) homing_finish_ok();
            break;
        }
        case HomingPhase::Stopping:
        case HomingPhase::Finished:
            sp_.profile.step_velocity(0.0, acc, acc, h);
            break;
    }
}

}  // namespace drive
