// Bad configuration and commands never crash the drive or poison its outputs; the cycle allocates nothing.
#include <gtest/gtest.h>

#include <random>

#include "drive/drive.hpp"
#include "maxpos/maxpos.hpp"
#include "rig.hpp"
#include "support/alloc_counter.hpp"

using namespace drive;
using namespace drive::test;

TEST(Robustness, RandomParametersAndCommandsStayFinite) {
    std::mt19937 rng(402);
    auto pick = [&](uint64_t lo, uint64_t hi) {
        return lo + std::uniform_int_distribution<uint64_t>(0, hi - lo)(rng);
    };
    for (int round = 0; round < 40; ++round) {
        NullEventSink sink;
        Axis ax(&sink);
        Parameters& p = ax.params;
        // Anywhere inside the specification's value ranges (the dictionary enforces those).
        p.nominal_current = static_cast<uint16_t>(pick(0, 5000));
        p.output_current_limit = static_cast<uint16_t>(pick(0, 15000));
        p.thermal_time_constant = static_cast<uint16_t>(pick(1, 10000));
        p.torque_constant = static_cast<uint32_t>(pick(0, 10000000));
        p.encoder_pulses = static_cast<uint32_t>(pick(16, 2500000));
        p.current_p = static_cast<uint32_t>(pick(0, 4000000));
        p.current_i = static_cast<uint32_t>(pick(0, 4000000));
        p.bandwidth = static_cast<uint32_t>(pick(10, 1000000));
        p.damping = static_cast<uint32_t>(pick(0, 10000));
        p.reset_time = static_cast<uint32_t>(pick(100, 3600000000u));
        p.inertia = static_cast<uint32_t>(pick(10, 1000000000));
        p.friction = static_cast<uint32_t>(pick(0, 1000000000));
        p.profile_acceleration = static_cast<uint32_t>(pick(1, 1000000));
        p.profile_deceleration = static_cast<uint32_t>(pick(1, 1000000));
        p.quick_stop_deceleration = static_cast<uint32_t>(pick(1, 1000000));
        p.profile_velocity = static_cast<uint32_t>(pick(1, 200000));
        p.fault_reaction = static_cast<int16_t>(pick(0, 3)) - 1;
        int64_t t = 0;
        const int8_t modes[] = {1, 3, 6, 8, 9, 10, 0, 5, -7};
        for (int k = 0; k < 300; ++k) {
            Command& c = ax.command;
            if (k % 25 == 0) {
                c.mode = modes[pick(0, 8)];
                c.target_position = static_cast<int32_t>(pick(0, 0xFFFFFFFFu));
                c.target_velocity = static_cast<int32_t>(pick(0, 400000)) - 200000;
                c.target_torque = static_cast<int16_t>(pick(0, 65535));
                c.touch_probe_function = static_cast<uint16_t>(pick(0, 65535));
            }
            const uint16_t cws[] = {0x06, 0x07, 0x0F, 0x1F, 0x0B, 0x80, 0x00, 0x11F, 0x7F};
            c.controlword = k < 3 ? cws[k] : cws[pick(0, 8)];
            ax.cycle(t, 1'000'000);
            t += 1'000'000;
            ASSERT_TRUE(std::isfinite(ax.plant().velocity())) << round;
            ASSERT_TRUE(std::isfinite(ax.plant().current())) << round;
            ASSERT_TRUE(std::isfinite(ax.raw_position_inc())) << round;
            ASSERT_LE(std::abs(ax.plant().current()), 15.0 * 1.01 + 48.0 / 0.836) << round;
        }
    }
}

TEST(Robustness, ZeroAndOddCycleTimes) {
    Rig r;
    r.enable();
    r.ax.cycle(r.t, 0);  // no time: only the command is evaluated
    r.ax.cycle(r.t, 12'345);
    r.ax.cycle(r.t, 250'000);
    r.ax.cycle(r.t, -5);
    EXPECT_EQ(r.ax.state(), State::OperationEnabled);
}

TEST(Robustness, SteadyStateCycleAllocatesNothing) {
    od::Dictionary d = maxpos::dictionary(maxpos::description());
    NullEventSink sink;
    Drive drv(d, &sink, maxpos::drive_objects());
    d.set<uint32_t>(0x3001, 5, 25500);
    d.set<uint16_t>(0x60B8, 0, 0x0017);
    int64_t t = 0;
    for (uint16_t cw : {0x06, 0x07, 0x0F}) {
        d.set<uint16_t>(0x6040, 0, cw);
        drv.cycle(t, 1'000'000);
        t += 1'000'000;
    }
    const alloc_counter::Scope counting;
    for (int k = 0; k < 500; ++k) {
        d.set<int32_t>(0x607A, 0, k * 20);
        drv.cycle(t, 1'000'000);
        t += 1'000'000;
    }
    EXPECT_EQ(counting.count(), 0u);
}
