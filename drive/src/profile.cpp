#include "drive/profile.hpp"

#include <algorithm>
#include <cmath>

namespace drive {
namespace {
double approach(double v, double target, double up, double down, double h) {
    // Speeding up (|v| grows in its direction) uses `up`; everything else is braking and uses `down`.
    const bool braking = (v > 0 && target < v) || (v < 0 && target > v);
    const double rate = (braking ? down : up) * h;
    if (std::abs(target - v) <= rate) return target;
    return v + (target > v ? rate : -rate);
}
}  // namespace

bool Profile::step_position(double target, double vmax, double acc, double dec, double h) {
    const double v0 = vel_;
    const double d = target - pos_;
    if (std::abs(d) < 1e-9 && std::abs(vel_) <= dec * h) {
        pos_ = target;
        vel_ = 0;
        acc_ = -v0 / h;
        return true;
    }
    // Work in the direction of the target: vs > 0 = moving toward it.
    const double s = d > 0 ? 1.0 : -1.0;
    const double vs = v0 * s;
    double vn;
    if (vs < 0) {
        vn = std::min(vs + dec * h, 0.0);  // moving away: brake first
    } else {
        // Cap: after this step the rest of the way must still be enough to stop with `dec`
        // (trapezoidal integration: braking from v covers v^2 / (2 dec)).
        const double rest = std::abs(d) - vs * h / 2.0;
        const double dh = dec * h / 2.0;
        const double cap = rest > 0 ? -dh + std::sqrt(dh * dh + 2.0 * dec * rest) : 0.0;
        vn = vs > vmax ? std::max(vs - dec * h, vmax) : std::min(vs + acc * h, vmax);
        // Below the cap by at most one extra braking step: brake a little harder (the step where
        // acceleration turns into deceleration). Further below: the stop is not possible any more,
        // brake with `dec`, pass the target and come back.
        if (vn > cap) vn = cap >= vs - 2.0 * dec * h ? cap : vs - dec * h;
    }
    double p = pos_ + s * 0.5 * (vs + vn) * h;
    double v = s * vn;
    // Arrive exactly: the last step lands on the target.
    if ((target - p) * s <= 1e-9 || (std::abs(target - p) < 1e-6 && std::abs(v) <= dec * h)) {
        if (std::abs(v) <= dec * h * 1.01) {
            p = target;
            v = 0;
        }
    }
    pos_ = p;
    vel_ = v;
    acc_ = (v - v0) / h;
    return pos_ == target && vel_ == 0;
}

bool Profile::step_velocity(double target, double acc, double dec, double h) {
    const double v0 = vel_;
    vel_ = approach(vel_, target, acc, dec, h);
    pos_ += 0.5 * (v0 + vel_) * h;
    acc_ = (vel_ - v0) / h;
    return vel_ == target;
}

}  // namespace drive
