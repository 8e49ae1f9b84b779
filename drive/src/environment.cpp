#include "drive/environment.hpp"

namespace drive {

void Environment::set_negative_limit(double at, int pin) {
    switches_[0] = {true, -std::numeric_limits<double>::infinity(), at, pin};
}
void Environment::set_positive_limit(double at, int pin) {
    switches_[1] = {true, at, std::numeric_limits<double>::infinity(), pin};
}
void Environment::set_home_switch(double from, double to, int pin) {
    switches_[2] = {true, from, to, pin};
}
void Environment::remove_switches() {
    for (auto& s : switches_)
        s.present = false;
}

void Environment::set_input(int pin, bool level, int64_t at_ns) {
    if (pin < 1 || pin > kPins) return;
    Manual& m = manual_[static_cast<std::size_t>(pin - 1)];
    if (at_ns <= 0) {
        m.level = level;
        m.pending = false;
    } else {
        // A pending change that was already due is folded in first so no edge gets lost.
        if (m.pending && m.at <= at_ns) m.level = m.next;
        m.pending = true;
        m.next = level;
        m.at = at_ns;
    }
}

uint16_t Environment::pins(double position, int64_t t_ns) const {
    uint16_t p = 0;
    for (int i = 0; i < kPins; ++i) {
        const Manual& m = manual_[static_cast<std::size_t>(i)];
        const bool level = (m.pending && t_ns >= m.at) ? m.next : m.level;
        if (level) p |= static_cast<uint16_t>(1u << i);
    }
    for (const Switch& s : switches_) {
        if (!s.present || s.pin < 1 || s.pin > kPins) continue;
        const uint16_t bit = static_cast<uint16_t>(1u << (s.pin - 1));
        if (position >= s.from && position <= s.to)
            p |= bit;
        else
            p &= static_cast<uint16_t>(~bit);
    }
    return p;
}

bool Environment::constant_over(int64_t from_ns, int64_t to_ns, uint16_t& level) const {
    for (const Switch& s : switches_)
        if (s.present && s.pin >= 1 && s.pin <= kPins) return false;
    for (const Manual& m : manual_)
        if (m.pending && m.at > from_ns && m.at <= to_ns) return false;
    level = pins(0.0, from_ns);
    return true;
}

}  // namespace drive
