#include <gtest/gtest.h>
#include <poll.h>

#include <array>
#include <numeric>
#include <thread>
#include <vector>

#include "esc/link_loopback.hpp"

namespace {

bool readable(const esc::Link& link, int timeout_ms = 0) {
    pollfd p{link.fd(), POLLIN, 0};
    return ::poll(&p, 1, timeout_ms) == 1 && (p.revents & POLLIN) != 0;
}

std::vector<uint8_t> frame_of(std::size_t n, uint8_t seed) {
    std::vector<uint8_t> f(n);
    std::iota(f.begin(), f.end(), seed);
    return f;
}

TEST(LoopbackLink, FrameSentOnOneEndArrivesOnTheOther) {
    auto [a, b] = esc::LoopbackLink::make_pair();
    const auto f = frame_of(60, 1);
    ASSERT_TRUE(a->send(f));
    std::array<uint8_t, esc::kMaxFrameSize> buf{};
    EXPECT_EQ(a->receive(buf), 0u) << "the sender must not receive its own frame";
    ASSERT_EQ(b->receive(buf), f.size());
    EXPECT_TRUE(std::equal(f.begin(), f.end(), buf.begin()));
    EXPECT_EQ(b->receive(buf), 0u);
}

TEST(LoopbackLink, BothDirectionsAreIndependentAndOrdered) {
    auto [a, b] = esc::LoopbackLink::make_pair(8);
    for (uint8_t i = 0; i < 5; ++i)
        ASSERT_TRUE(a->send(frame_of(29 + i, i)));
    ASSERT_TRUE(b->send(frame_of(100, 0x55)));
    std::array<uint8_t, esc::kMaxFrameSize> buf{};
    ASSERT_EQ(a->receive(buf), 100u);
    EXPECT_EQ(buf[0], 0x55);
    for (uint8_t i = 0; i < 5; ++i) {
        ASSERT_EQ(b->receive(buf), 29u + i);
        EXPECT_EQ(buf[0], i);
    }
}

TEST(LoopbackLink, FdIsReadableExactlyWhileFramesWait) {
    auto [a, b] = esc::LoopbackLink::make_pair();
    EXPECT_FALSE(readable(*b));
    ASSERT_TRUE(a->send(frame_of(60, 0)));
    ASSERT_TRUE(a->send(frame_of(60, 1)));
    EXPECT_TRUE(readable(*b));
    EXPECT_EQ(b->pending(), 2u);
    std::array<uint8_t, esc::kMaxFrameSize> buf{};
    ASSERT_GT(b->receive(buf), 0u);
    EXPECT_TRUE(readable(*b)) << "one frame still waits";
    ASSERT_GT(b->receive(buf), 0u);
    EXPECT_FALSE(readable(*b));
    EXPECT_FALSE(readable(*a));
}

TEST(LoopbackLink, FullQueueRefusesInsteadOfOverwriting) {
    auto [a, b] = esc::LoopbackLink::make_pair(2);
    EXPECT_TRUE(a->send(frame_of(60, 1)));
    EXPECT_TRUE(a->send(frame_of(60, 2)));
    EXPECT_FALSE(a->send(frame_of(60, 3)));
    std::array<uint8_t, esc::kMaxFrameSize> buf{};
    ASSERT_EQ(b->receive(buf), 60u);
    EXPECT_EQ(buf[0], 1);
    EXPECT_TRUE(a->send(frame_of(60, 4)));
    ASSERT_EQ(b->receive(buf), 60u);
    EXPECT_EQ(buf[0], 2);
    ASSERT_EQ(b->receive(buf), 60u);
    EXPECT_EQ(buf[0], 4);
}

TEST(LoopbackLink, RejectsEmptyAndOversizedFramesAndTruncatesToTheBuffer) {
    auto [a, b] = esc::LoopbackLink::make_pair();
    EXPECT_FALSE(a->send({}));
    std::vector<uint8_t> big(esc::kMaxFrameSize + 1, 0xAA);
    EXPECT_FALSE(a->send(big));
    big.resize(esc::kMaxFrameSize);
    EXPECT_TRUE(a->send(big));
    std::array<uint8_t, 16> small{};
    EXPECT_EQ(b->receive(small), small.size());
    EXPECT_EQ(small[15], 0xAA);
    EXPECT_THROW(esc::LoopbackLink::make_pair(0), esc::LinkError);
}

TEST(LoopbackLink, WakesAPollerInAnotherThread) {
    auto [a, b] = esc::LoopbackLink::make_pair();
    std::thread sender([&a = a] {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        const std::array<uint8_t, 60> f{};
        a->send(f);
    });
    EXPECT_TRUE(readable(*b, 5000));
    sender.join();
}

}  // namespace
