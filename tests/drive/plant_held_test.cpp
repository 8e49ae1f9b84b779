// Plant::advance_held (the four 10 us steps of a current-loop sample from the state at once) against the
// sequential steps it stands for, docs/decisions/drive.md "Cost of a cycle".
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "drive/plant.hpp"

using namespace drive;

namespace {

constexpr int kSteps = Plant::kHeldSteps;

struct Sequential {
    Plant::State s[kSteps];
    bool stop[kSteps];
    bool linear;  // friction sign held and no stop reached: what the held steps stand for
};

Sequential sequential(const Plant& p, Plant::State x, double u) {
    Sequential r{};
    const double w0 = x.velocity;
    r.linear = w0 != 0.0;
    for (int k = 0; k < kSteps; ++k) {
        r.stop[k] = p.advance(x, u, true);
        r.s[k] = x;
        if (r.stop[k] || x.velocity == 0.0 || (x.velocity > 0) != (w0 > 0)) r.linear = false;
    }
    return r;
}

bool same_bits(const Plant::State& a, const Plant::State& b) {
    return std::memcmp(&a, &b, sizeof a) == 0;
}

}  // namespace

TEST(PlantHeld, AgreesWithTheSequentialStepsAndFallsBackAtCrossingsAndStops) {
    MotorModel m;
    Plant p;
    p.configure(m, m.torque_constant, 1e-5);
    const double lo = -3.0, hi = 5.0;
    p.set_stops(lo, hi);
    int fast = 0, fallback = 0;
    for (double i0 : {-12.0, -1.5, -0.01, 0.0, 0.2, 3.0, 15.0})
        for (double w0 : {-900.0, -40.0, -0.5, -1e-3, 0.0, 1e-4, 0.3, 25.0, 1500.0})
            for (double th : {-3.0, -2.99, -1.0, 0.0, 0.7, 4.98, 4.9999, 5.0})
                for (double u : {-48.0, -5.0, 0.0, 1.0, 20.0, 48.0}) {
                    const Plant::State x0{i0, w0, th};
                    const Sequential seq = sequential(p, x0, u);
                    Plant::State x = x0;
                    double angles[kSteps];
                    const bool held = p.advance_held(x, u, angles);
                    const double scale = std::abs(i0) + std::abs(w0) + std::abs(th) + std::abs(u) + 1.0;
                    const double tol = 1e-12 * scale;
                    SCOPED_TRACE(testing::Message()
                                 << "i " << i0 << " w " << w0 << " th " << th << " u " << u);
                    if (held) {
                        ++fast;
                        // Taken only where the sequential steps are linear too (a state that close to a
                        // crossing or a stop that rounding decides does not occur on this grid).
                        EXPECT_TRUE(seq.linear);
                        for (int k = 0; k < kSteps; ++k) {
                            EXPECT_NEAR(angles[k], seq.s[k].angle, tol) << "step " << k;
                            EXPECT_GT(angles[k], lo);
                            EXPECT_LT(angles[k], hi);
                        }
                        EXPECT_NEAR(x.current, seq.s[kSteps - 1].current, tol);
                        EXPECT_NEAR(x.velocity, seq.s[kSteps - 1].velocity, tol);
                        EXPECT_NEAR(x.angle, seq.s[kSteps - 1].angle, tol);
                        EXPECT_FALSE(seq.stop[kSteps - 1]);
                    } else {
                        ++fallback;
                        // Untouched: the caller runs the sequential steps from the same state, bit for bit.
                        EXPECT_TRUE(same_bits(x, x0));
                        EXPECT_FALSE(seq.linear);
                    }
                }
    // Both branches on the grid, the fast one most of the time as in a moving drive.
    EXPECT_GT(fast, 500);
    EXPECT_GT(fallback, 500);
}

TEST(PlantHeld, FallsBackAtRestAndOnNaN) {
    MotorModel m;
    Plant p;
    p.configure(m, m.torque_constant, 1e-5);
    double angles[kSteps];
    Plant::State rest{5.0, 0.0, 1.0};
    EXPECT_FALSE(p.advance_held(rest, 10.0, angles));
    Plant::State bad{0.0, std::nan(""), 1.0};
    EXPECT_FALSE(p.advance_held(bad, 10.0, angles));
    Plant::State bad_angle{0.0, 10.0, std::nan("")};
    EXPECT_FALSE(p.advance_held(bad_angle, 10.0, angles));
    // Without stops a turning shaft takes the fast path, and the positions it reports are those of the steps.
    Plant q;
    q.configure(m, m.torque_constant, 1e-5);
    Plant::State x{1.0, 100.0, 0.0};
    ASSERT_TRUE(q.advance_held(x, 12.0, angles));
    Plant::State y{1.0, 100.0, 0.0};
    for (int k = 0; k < kSteps; ++k) {
        q.advance(y, 12.0, true);
        EXPECT_NEAR(angles[k], y.angle, 1e-13);
    }
}
