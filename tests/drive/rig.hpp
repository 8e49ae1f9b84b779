#pragma once
// A test rig around one Axis: a recording event sink, a clock, and helpers to step cycles.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "drive/axis.hpp"
#include "drive/errors.hpp"
#include "recorder.hpp"

namespace drive::test {

struct Rig {
    Recorder rec;
    Axis ax{&rec};
    int64_t t = 0;
    int64_t dt = 1'000'000;  // 1 ms cycle

    Rig() {
        ax.params.torque_constant = 25500;  // uNm/A, as the simulated EC-4pole 30
        ax.params.inertia = 188300;         // mg cm^2 = the simulated rotor + load
        ax.params.bandwidth = 20000;        // 20 Hz position loop
        ax.params.reset_time = 50000;       // 50 ms
        ax.params.friction = 46670;         // nNm/rpm = the simulated 445.7 uNm/(rad/s)
        ax.command.mode = mode::CyclicSyncPosition;
        run(1);
    }
    void run(int cycles) {
        for (int i = 0; i < cycles; ++i) {
            ax.cycle(t, dt);
            t += dt;
        }
    }
    void run_ms(double ms) { run(static_cast<int>(std::lround(ms * 1e6 / static_cast<double>(dt)))); }
    void cw(uint16_t c, int cycles = 1) {
        ax.command.controlword = c;
        run(cycles);
    }
    const Feedback& fb() const { return ax.feedback(); }
    uint16_t sw() const { return ax.feedback().statusword; }
    uint16_t state_bits() const { return ax.feedback().statusword & 0x7F; }
    // Switch on and enable with the CSP target following the actual position.
    void enable() {
        ax.command.target_position = fb().position_actual;
        cw(0x06);
        cw(0x07);
        cw(0x0F);
        ASSERT_EQ(ax.state(), State::OperationEnabled);
    }
    // Runs until pred() or the time limit; returns whether pred() became true.
    template <typename P>
    bool until(P pred, double max_ms) {
        const int n = static_cast<int>(max_ms * 1e6 / static_cast<double>(dt));
        for (int i = 0; i < n; ++i) {
            if (pred()) return true;
            run(1);
        }
        return pred();
    }
    double rpm() const { return ax.plant().velocity() * 60.0 / 6.283185307179586; }
};

}  // namespace drive::test
