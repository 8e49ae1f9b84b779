// Homing mode (6) [001 §4.5, digest §2.3]: the methods of 0x60E3, run as a small phase machine on top of the
// profile generator. Edges and index pulses are latched in the plant sub-steps (on_edge/on_index) at the
// position where they really happened, so the reference point does not depend on the cycle time.
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
    // Homing clears touch-probe states and latched values [001 §4.5].
    tp_status_ &= 0x1;
    tp_pos_ = tp_neg_ = 0;
    tp_pos_cnt_ = tp_neg_cnt_ = 0;
    hmethod_ = params.homing_method;
    referenced_ = false;
    hstat_ = HomingStatus::InProgress;
    hedge_ = hindex_ = false;
    hsettle_ = 0;
    hbit_ = -1;
    hrise_ = true;
    profile_.reset(demand_pos_, demand_vel_);
    const int m = hmethod_;
    const bool neg = func_ & ((1ull << 0) | (1ull << 24));
    const bool pos = func_ & ((1ull << 1) | (1ull << 25));
    const bool home = func_ & (1ull << 2);
    if (uses_index(m) && !(params.encoder_type & 0x1)) {
        homing_fail();
        return;
    }
    if (limit_method(m)) {
        const bool negative = (m == 1 || m == 17);
        hbit_ = negative ? 0 : 1;
        hdir_ = negative ? -1 : 1;
        if (negative ? neg : pos) {  // already on the switch: only back off
            hdir_ = -hdir_;
            hrise_ = false;
            hphase_ = HomingPhase::Backoff;
        } else {
            hphase_ = HomingPhase::Search;
        }
    } else if (home_method(m)) {
        hbit_ = 2;
        hdir_ = (m == 7 || m == 23) ? 1 : -1;
        if (home) {  // starts on the switch: go the other way to its edge
            hdir_ = -hdir_;
            hrise_ = false;
            hphase_ = HomingPhase::Backoff;
        } else {
            hphase_ = HomingPhase::Search;
        }
    } else if (m == 33 || m == 34) {
        hdir_ = m == 33 ? -1 : 1;
        hsearch_origin_ = static_cast<double>(count_);
        hphase_ = HomingPhase::ToIndex;
    } else if (m == 37) {
        href_ = static_cast<double>(count_);
        hphase_ = HomingPhase::Offset;
    } else if (current_method(m)) {
        hdir_ = (m == -1 || m == -3) ? 1 : -1;
        hphase_ = HomingPhase::Search;
    } else {
        homing_fail();
        return;
    }
    sink_->diag(Severity::Info, 0, "Homing started");
}

void Axis::homing_fail() {
    hstat_ = HomingStatus::Error;
    hphase_ = HomingPhase::Stopping;
    referenced_ = false;
    sink_->diag(Severity::Warning, 0, "Homing error");
}

void Axis::homing_finish_ok() {
    const double target =
        std::floor(href_ + offset_sign(hmethod_) * static_cast<double>(params.home_offset_move));
    shift_ = static_cast<int64_t>(params.home_position) - static_cast<int64_t>(target);
    profile_.reset(target, 0);
    hstat_ = HomingStatus::Done;
    hphase_ = HomingPhase::Finished;
    referenced_ = true;
    sink_->diag(Severity::Info, 0, "Homing attained");
}

void Axis::homing_tick(double h) {
    const double fast = rpm_to_inc_s(params.homing_speed_switch);
    const double slow = rpm_to_inc_s(params.homing_speed_zero);
    const double acc = decel_limit(params.homing_acceleration);
    if (hstat_ != HomingStatus::InProgress) {
        profile_.step_velocity(0.0, acc, acc, h);
        return;
    }
    if (halted_) {  // halt in homing: stop with the homing acceleration [001 Table 4-29]
        if (profile_.step_velocity(0.0, acc, acc, h)) {
            hstat_ = HomingStatus::Interrupted;
            hphase_ = HomingPhase::Finished;
        }
        return;
    }
    const int m = hmethod_;
    const double threshold = params.homing_current_threshold * 1e-3;
    const double current = std::abs(plant_.current());
    const bool neg = func_ & ((1ull << 0) | (1ull << 24));
    const bool pos = func_ & ((1ull << 1) | (1ull << 25));
    switch (hphase_) {
        case HomingPhase::Search:
            profile_.step_velocity(hdir_ * fast, acc, acc, h);
            // A limit switch that is not the target of the search ends homing with an error.
            if (limit_method(m) && ((hbit_ == 0 && pos) || (hbit_ == 1 && neg))) return homing_fail();
            if (home_method(m) && ((hdir_ < 0 && neg) || (hdir_ > 0 && pos))) return homing_fail();
            if (current_method(m)) {
                // Only at constant speed: the acceleration current must not look like the stop.
                hsettle_ = profile_.velocity() == hdir_ * fast ? hsettle_ + 1 : 0;
                if (current > threshold && hsettle_ > 20) {
                    if (m == -3 || m == -4) {
                        href_ = static_cast<double>(count_);
                        hphase_ = HomingPhase::Offset;
                    } else {
                        hdir_ = -hdir_;
                        hphase_ = HomingPhase::Backoff;
                    }
                }
            } else if (hedge_) {
                hedge_ = false;
                hdir_ = -hdir_;
                hrise_ = false;
                hphase_ = HomingPhase::Backoff;
            }
            break;
        case HomingPhase::Backoff:
            profile_.step_velocity(hdir_ * slow, acc, acc, h);
            if (current_method(m)) {
                const double v = profile_.velocity();
                if (current < threshold && ((hdir_ > 0 && v > 0) || (hdir_ < 0 && v < 0))) {
                    hsearch_origin_ = static_cast<double>(count_);
                    hindex_ = false;
                    hphase_ = HomingPhase::ToIndex;
                }
            } else if (hedge_) {
                hedge_ = false;
                if (m == 17 || m == 18 || m == 23 || m == 27) {
                    href_ = hevent_pos_;
                    hphase_ = HomingPhase::Offset;
                } else {
                    hsearch_origin_ = hevent_pos_;
                    hindex_ = false;
                    hphase_ = HomingPhase::ToIndex;
                }
            }
            break;
        case HomingPhase::ToIndex:
            profile_.step_velocity(hdir_ * slow, acc, acc, h);
            if (hindex_) {
                href_ = hevent_pos_;
                hphase_ = HomingPhase::Offset;
            } else if (std::abs(static_cast<double>(count_) - hsearch_origin_) > 2.0 * res_) {
                return homing_fail();  // no index within two turns
            }
            break;
        case HomingPhase::Offset: {
            const double target =
                std::floor(href_ + offset_sign(m) * static_cast<double>(params.home_offset_move));
            if (profile_.step_position(target, fast, acc, acc, h)) homing_finish_ok();
            break;
        }
        case HomingPhase::Stopping:
        case HomingPhase::Finished:
            profile_.step_velocity(0.0, acc, acc, h);
            break;
    }
}

}  // namespace drive
