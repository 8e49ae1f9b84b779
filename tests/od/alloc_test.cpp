// The per-frame / per-cycle paths of the dictionary allocate nothing: read, write (with validators and
// listeners), set, Ref<T>, lookup.
#include <gtest/gtest.h>

#include "maxpos/maxpos.hpp"
#include "support/alloc_counter.hpp"

TEST(OdAlloc, AccessPathsAllocateNothing) {
    od::Dictionary d = maxpos::dictionary(maxpos::description());
    int heard = 0;
    d.add_listener(0x6040, [&heard](const od::Entry&) { ++heard; });
    d.add_validator(0x6040, [](const od::Entry&, std::span<const uint8_t>) { return od::Status::Ok; });
    auto pos = d.ref<int32_t>(0x6064, 0);
    uint8_t out[64];
    std::size_t len = 0;
    const uint8_t cw[2] = {0x0F, 0x00};
    const uint8_t mode[1] = {9};
    const uint64_t before = alloc_counter::total();
    ASSERT_GT(before, 0u);  // the counting operator new is the one in use
    for (int i = 0; i < 1000; ++i) {
        ASSERT_EQ(d.write(0x6040, 0, od::AlState::Op, cw), od::Status::Ok);
        ASSERT_EQ(d.write(0x6060, 0, od::AlState::Op, mode), od::Status::Ok);  // value-set validator
        ASSERT_EQ(d.read(0x6041, 0, od::AlState::Op, out, len), od::Status::Ok);
        ASSERT_EQ(d.read(0x1008, 0, od::AlState::Op, out, len), od::Status::Ok);
        ASSERT_EQ(d.set<int32_t>(0x6064, 0, i), od::Status::Ok);
        pos.set(pos.get() + 1);
        ASSERT_NE(d.find(0x1A00, 3), nullptr);
        ASSERT_FALSE(d.raw(0x607A, 0).empty());
        ASSERT_EQ(d.write(0x6060, 0, od::AlState::Op, cw), od::Status::LengthTooHigh);
    }
    EXPECT_EQ(alloc_counter::total() - before, 0u);
    EXPECT_EQ(heard, 1000);
}
