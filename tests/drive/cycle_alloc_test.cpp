// The drive cycle allocates nothing while it moves: CSP following a moving set-point and PPM running moves
// one after the other, through drive::Drive on the real dictionary (the path the process-data cycle takes).
#include <gtest/gtest.h>

#include <cstdint>

#include "drive/drive.hpp"
#include "maxpos/maxpos.hpp"
#include "support/alloc_counter.hpp"

namespace drive {
namespace {

struct Bench {
    od::Dictionary d = maxpos::dictionary(maxpos::description());
    NullEventSink sink;
    Drive drv{d, &sink, maxpos::drive_objects()};
    int64_t t = 0;

    explicit Bench(int8_t mode) {
        EXPECT_EQ(commission(d, maxpos::drive_objects(), drv.motor()), od::Status::Ok);
        d.set<int8_t>(0x6060, 0, mode);
        d.set<uint16_t>(0x60B8, 0, 0x0017);  // touch probe armed on the index
        for (uint16_t cw : {0x06, 0x07, 0x0F})
            cycle(cw);
        EXPECT_EQ(drv.axis().state(), State::OperationEnabled);
    }
    void cycle(uint16_t cw) {
        d.set<uint16_t>(0x6040, 0, cw);
        drv.cycle(t, 1'000'000);
        t += 1'000'000;
    }
    int32_t actual() const { return d.get<int32_t>(0x6064, 0); }
};

TEST(CycleAllocation, CyclicSynchronousPositionMoving) {
    Bench b(8);
    const int32_t start = b.actual();
    const alloc_counter::Scope counting;
    for (int k = 0; k < 2000; ++k) {
        b.d.set<int32_t>(0x607A, 0, start + k * 40);  // 40 inc/ms = 1200 rpm at 2000 inc/rev
        b.d.set<int32_t>(0x60B1, 0, 1200);            // velocity pre-control
        b.cycle(0x0F);
    }
    EXPECT_EQ(counting.count(), 0u);
    EXPECT_GT(b.actual() - start, 60000);  // it really moved (tens of turns)
    EXPECT_EQ(b.drv.axis().state(), State::OperationEnabled);
}

TEST(CycleAllocation, ProfilePositionMoves) {
    Bench b(1);
    const int32_t start = b.actual();
    int32_t farthest = start;
    const alloc_counter::Scope counting;
    for (int move = 0; move < 4; ++move) {
        b.d.set<int32_t>(0x607A, 0, start + (move % 2 == 0 ? 20000 : 0));
        b.cycle(0x1F);  // new set-point
        for (int k = 0; k < 600; ++k) {
            b.cycle(0x0F);
            if (b.actual() > farthest) farthest = b.actual();
        }
    }
    EXPECT_EQ(counting.count(), 0u);
    EXPECT_GT(farthest - start, 19000);  // the moves ran
    EXPECT_EQ(b.drv.axis().state(), State::OperationEnabled);
}

}  // namespace
}  // namespace drive
