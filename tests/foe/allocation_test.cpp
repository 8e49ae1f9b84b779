// "Hot paths allocate nothing": once a transfer runs, each DATA/ACK packet and each idle poll() is served
// without touching the heap. This binary links the counting global operator new
// (tests/support/alloc_counter.hpp).
#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <thread>

#include "foe/server.hpp"
#include "foe_test_support.hpp"
#include "support/alloc_counter.hpp"
#include "support/fixed_sender.hpp"
#include "util/le.hpp"

#pragma GCC diagnostic ignored "-Wmismatched-new-delete"

namespace {

using test_support::FixedSender;

std::array<uint8_t, 128> packet(uint8_t op, uint32_t value, std::span<const uint8_t> tail, std::size_t& len) {
    std::array<uint8_t, 128> m{op, 0};
    util::put32(m.data() + 2, value);
    std::copy(tail.begin(), tail.end(), m.begin() + 6);
    len = 6 + tail.size();
    return m;
}

}  // namespace

TEST(FoeAllocation, DataAckAndIdlePollAllocateNothing) {
    foe_test::TempDir dir;
    foe::StoreConfig c;
    c.dir = dir.path;
    c.identity = foe_test::kMaxpos;
    foe::FirmwareStore store(c);
    ASSERT_TRUE(store.open());
    foe::FoeServer server(store);
    server.set_state(od::AlState::Boot);
    FixedSender out(128 - 6);
    const std::size_t chunk = 116;
    const auto image =
        foe::build_image(foe_test::payload_bytes(100 * chunk, 1), foe_test::kMaxpos, 0x01300000);

    std::size_t len = 0;
    const std::string_view name = "MAXPOS";
    auto m = packet(2, 0, {reinterpret_cast<const uint8_t*>(name.data()), name.size()}, len);
    {
        const alloc_counter::Scope counting;
        server.handle({m.data(), len}, out);  // opening the slot file builds its path: the counter is live
        EXPECT_GT(counting.count(), 0u);
    }
    ASSERT_EQ(out.last[0], 4);
    m = packet(3, 1, {image.data(), chunk}, len);
    server.handle({m.data(), len}, out);  // first packet: header checked
    ASSERT_EQ(out.last[0], 4);
    {
        const alloc_counter::Scope counting;
        for (uint32_t p = 2; p <= 100; ++p) {
            m = packet(3, p, {image.data() + (p - 1) * chunk, chunk}, len);
            server.handle({m.data(), len}, out);
            ASSERT_EQ(out.last[0], 4);
            server.poll(p * 1000, out);
        }
        EXPECT_EQ(counting.count(), 0u) << "per DATA packet";
    }
    m = packet(3, 101, {image.data() + 100 * chunk, image.size() - 100 * chunk}, len);
    const std::size_t sent = out.count;
    server.handle({m.data(), len}, out);
    // The last DATA is answered once the image is stored (ACK), or with BUSY if storing takes long
    // (docs/decisions/foe.md): nothing is acknowledged before it is done.
    ASSERT_TRUE(out.count == sent || out.last[0] == 6);
    for (int i = 0; i < 10000 && !server.idle(); ++i) {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));  // the commit runs on its worker
        const std::size_t before = out.count;
        server.poll(1'000'000 + i, out);
        // A master sends the last DATA again only when it was answered BUSY (ETG.1000.6 FoE).
        if (out.count != before && out.last[0] == 6) server.handle({m.data(), len}, out);
    }
    ASSERT_EQ(out.last[0], 4);

    m = packet(1, 0, {reinterpret_cast<const uint8_t*>(name.data()), name.size()}, len);
    server.handle({m.data(), len}, out);
    ASSERT_EQ(out.last[0], 3);
    {
        const alloc_counter::Scope counting;
        for (uint32_t p = 1; p <= 100; ++p) {
            m = packet(4, p, {}, len);
            server.handle({m.data(), len}, out);
            ASSERT_EQ(out.last[0], 3);
            server.poll(2'000'000 + p, out);
        }
        EXPECT_EQ(counting.count(), 0u) << "per ACK while reading";
    }
}
