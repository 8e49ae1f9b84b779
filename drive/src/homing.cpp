// Homing mode (6) (IEC 61800-7-201 homing mode; MAXPOS firmware specification §4.5, §7.2.75-7.2.77; EPOS4
// Application Notes §7.3): the methods of 0x60E3, run as a small phase machine on top of the profile
// generator (Homing). Edges and index pulses are latched in the plant sub-steps (Axis::on_edge/on_index) at
// the position where they really happened, so the reference point does not depend on the cycle time.
#include "drive/homing.hpp"

#include <cmath>

#include "drive/objects.hpp"

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

void Homing::start(const Parameters& p, uint64_t functions, double actual, EventSink& sink) {
    method_ = p.homing_method;
    referenced_ = false;
    status_ = HomingStatus::InProgress;
    edge_ = index_ = false;
    settle_ = 0;
    bit_ = -1;
    rise_ = true;
    const int m = method_;
    const bool neg = functions & ((1ull << 0) | (1ull << 24));
    const bool pos = functions & ((1ull << 1) | (1ull << 25));
    const bool home = functions & (1ull << 2);
    // Only the methods of 0x60E3 (declared once in drive/objects.hpp).
    if (!contains(kHomingMethods, m) || (uses_index(m) && !(p.encoder_type & 0x1))) {
        fail(sink);
        return;
    }
    if (limit_method(m)) {
        const bool negative = (m == 1 || m == 17);
        bit_ = negative ? 0 : 1;
        dir_ = negative ? -1 : 1;
        if (negative ? neg : pos) {  // already on the switch: only back off
            dir_ = -dir_;
            rise_ = false;
            phase_ = HomingPhase::Backoff;
        } else {
            phase_ = HomingPhase::Search;
        }
    } else if (home_method(m)) {
        bit_ = 2;
        dir_ = (m == 7 || m == 23) ? 1 : -1;
        if (home) {  // starts on the switch: go the other way to its edge
            dir_ = -dir_;
            rise_ = false;
            phase_ = HomingPhase::Backoff;
        } else {
            phase_ = HomingPhase::Search;
        }
    } else if (m == 33 || m == 34) {
        dir_ = m == 33 ? -1 : 1;
        search_origin_ = actual;
        phase_ = HomingPhase::ToIndex;
    } else if (m == 37) {
        ref_ = actual;
        phase_ = HomingPhase::Offset;
    } else if (current_method(m)) {
        dir_ = (m == -1 || m == -3) ? 1 : -1;
        phase_ = HomingPhase::Search;
    } else {
        fail(sink);
        return;
    }
    sink.diag(Severity::Info, 0, "Homing started");
}

void Homing::set_here(int32_t home_position, int64_t count, EventSink& sink) {
    // MAXPOS firmware specification §4.5.3.11.
    method_ = 37;
    ref_ = static_cast<double>(count);
    shift_ = static_cast<int64_t>(home_position) - count;
    status_ = HomingStatus::Done;
    phase_ = HomingPhase::Finished;
    referenced_ = true;
    sink.diag(Severity::Info, 0, "Homing attained");
}

void Homing::fail(EventSink& sink) {
    status_ = HomingStatus::Error;
    phase_ = HomingPhase::Stopping;
    referenced_ = false;
    sink.diag(Severity::Warning, 0, "Homing error");
}

void Homing::finish(Profile& profile, const Parameters& p, EventSink& sink) {
    const double target = std::floor(ref_ + offset_sign(method_) * static_cast<double>(p.home_offset_move));
    shift_ = static_cast<int64_t>(p.home_position) - static_cast<int64_t>(target);
    profile.reset(target, 0);
    status_ = HomingStatus::Done;
    phase_ = HomingPhase::Finished;
    referenced_ = true;
    sink.diag(Severity::Info, 0, "Homing attained");
}

void Homing::edge(int bit, bool rising, double v, double raw_pos) {
    if (status_ == HomingStatus::InProgress && bit == bit_ && rising == rise_ && moving_on(v)) {
        edge_ = true;
        event_pos_ = raw_pos;
    }
}

void Homing::index_pulse(double v, double raw_pos) {
    if (status_ == HomingStatus::InProgress && phase_ == HomingPhase::ToIndex && moving_on(v)) {
        index_ = true;
        event_pos_ = raw_pos;
    }
}

void Homing::tick(Profile& profile, const Motion& mo, const Inputs& in, const Parameters& p, EventSink& sink,
                  double h) {
    const double fast = mo.fast;
    const double slow = mo.slow;
    const double acc = mo.acc;
    if (status_ != HomingStatus::InProgress) {
        profile.step_velocity(0.0, acc, acc, h);
        return;
    }
    if (in.halted) {  // halt in homing: stop with the homing acceleration (MAXPOS firmware specification
                      // Table 4-29)
        if (profile.step_velocity(0.0, acc, acc, h)) {
            status_ = HomingStatus::Interrupted;
            phase_ = HomingPhase::Finished;
        }
        return;
    }
    const int m = method_;
    const double threshold = p.homing_current_threshold * 1e-3;
    const double current = in.current;
    const bool neg = in.functions & ((1ull << 0) | (1ull << 24));
    const bool pos = in.functions & ((1ull << 1) | (1ull << 25));
    switch (phase_) {
        case HomingPhase::Search:
            profile.step_velocity(dir_ * fast, acc, acc, h);
            // A limit switch that is not the target of the search ends homing with an error.
            if (limit_method(m) && ((bit_ == 0 && pos) || (bit_ == 1 && neg))) return fail(sink);
            if (home_method(m) && ((dir_ < 0 && neg) || (dir_ > 0 && pos))) return fail(sink);
            if (current_method(m)) {
                // Only at constant speed: the acceleration current must not look like the stop.
                settle_ = profile.velocity() == dir_ * fast ? settle_ + 1 : 0;
                if (current > threshold && settle_ > 20) {
                    if (m == -3 || m == -4) {
                        ref_ = in.actual;
                        phase_ = HomingPhase::Offset;
                    } else {
                        dir_ = -dir_;
                        phase_ = HomingPhase::Backoff;
                    }
                }
            } else if (edge_) {
                edge_ = false;
                dir_ = -dir_;
                rise_ = false;
                phase_ = HomingPhase::Backoff;
            }
            break;
        case HomingPhase::Backoff:
            profile.step_velocity(dir_ * slow, acc, acc, h);
            if (current_method(m)) {
                const double v = profile.velocity();
                if (current < threshold && ((dir_ > 0 && v > 0) || (dir_ < 0 && v < 0))) {
                    search_origin_ = in.actual;
                    index_ = false;
                    phase_ = HomingPhase::ToIndex;
                }
            } else if (edge_) {
                edge_ = false;
                if (m == 17 || m == 18 || m == 23 || m == 27) {
                    ref_ = event_pos_;
                    phase_ = HomingPhase::Offset;
                } else {
                    search_origin_ = event_pos_;
                    index_ = false;
                    phase_ = HomingPhase::ToIndex;
                }
            }
            break;
        case HomingPhase::ToIndex:
            profile.step_velocity(dir_ * slow, acc, acc, h);
            if (index_) {
                ref_ = event_pos_;
                phase_ = HomingPhase::Offset;
            } else if (std::abs(in.actual - search_origin_) > 2.0 * in.resolution) {
                return fail(sink);  // no index within two turns
            }
            break;
        case HomingPhase::Offset: {
            const double target = std::floor(ref_ + offset_sign(m) * static_cast<double>(p.home_offset_move));
            if (profile.step_position(target, fast, acc, acc, h)) finish(profile, p, sink);
            break;
        }
        case HomingPhase::Stopping:
        case HomingPhase::Finished:
            profile.step_velocity(0.0, acc, acc, h);
            break;
    }
}

}  // namespace drive
