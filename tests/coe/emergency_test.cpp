// Emergency (CoE service 1, ETG.1000.6 Emergency: error code + error register + 5 bytes).
#include <gtest/gtest.h>

#include <array>

#include "coe/emergency.hpp"
#include "coe/sdo_server.hpp"
#include "coe_test_support.hpp"

using namespace coe_test;

namespace {

TEST(Emergency, EncodingIsCoeHeaderCodeRegisterAndFiveBytes) {
    const uint8_t mfr[] = {0xAA, 0xBB, 0xCC};
    auto m = coe::Emergency::encode(0x2310, 0x03, mfr);
    EXPECT_EQ(Bytes(m.begin(), m.end()), (Bytes{0x00, 0x10, 0x10, 0x23, 0x03, 0xAA, 0xBB, 0xCC, 0x00, 0x00}));
    const uint8_t too_long[] = {1, 2, 3, 4, 5, 6, 7};
    m = coe::Emergency::encode(0x8611, 0x81, too_long);
    EXPECT_EQ(Bytes(m.begin(), m.end()), (Bytes{0x00, 0x10, 0x11, 0x86, 0x81, 1, 2, 3, 4, 5}));
}

TEST(Emergency, RaiseAndClearMaintainTheErrorRegister) {
    od::Dictionary dict = make_test_dictionary();
    coe::Emergency e(&dict);
    e.raise(0x2310, 0x03);  // overcurrent: generic + current (MAXPOS firmware specification Table 8-141:
                            // 00000010 -> as given)
    EXPECT_EQ(dict.get<uint8_t>(0x1001, 0), 0x03);
    e.raise(0x8611, 0x80);  // following error: the motion bit
    EXPECT_EQ(dict.get<uint8_t>(0x1001, 0), 0x83);
    EXPECT_TRUE(e.active(0x2310));
    e.clear(0x2310);
    // The motion bit, and the generic bit: CiA 301 signals it at any error situation, whatever bits the error
    // itself names.
    EXPECT_EQ(dict.get<uint8_t>(0x1001, 0), 0x81);
    EXPECT_FALSE(e.active(0x2310));
    e.clear(0x2310);  // not active: nothing
    e.clear(0x8611);
    EXPECT_EQ(dict.get<uint8_t>(0x1001, 0), 0x00);
    ASSERT_EQ(e.pending(), 3u);
    EXPECT_EQ(e.front()[4], 0x03);
    e.pop();
    EXPECT_EQ(e.front()[4], 0x83);
    e.pop();
    // All cleared: the "no error" emergency, code 0000, register 00.
    EXPECT_EQ(Bytes(e.front().begin(), e.front().end()), (Bytes{0x00, 0x10, 0, 0, 0, 0, 0, 0, 0, 0}));
}

TEST(Emergency, SendLeavesTheApplicationsErrorRegisterAlone) {
    od::Dictionary dict = make_test_dictionary();
    ASSERT_EQ(dict.set<uint8_t>(0x1001, 0, 0x80), od::Status::Ok);  // kept by the drive itself
    coe::Emergency e(&dict);
    const std::array<uint8_t, 5> mfr{0x08, 0x01, 0, 0, 0};
    e.send(0x8611, 0x80, mfr);
    e.send(0x0000, 0x00);
    EXPECT_EQ(dict.get<uint8_t>(0x1001, 0), 0x80);
    EXPECT_EQ(e.active_count(), 0u);
    ASSERT_EQ(e.pending(), 2u);
    EXPECT_EQ(Bytes(e.front().begin(), e.front().end()),
              (Bytes{0x00, 0x10, 0x11, 0x86, 0x80, 0x08, 0x01, 0, 0, 0}));
}

TEST(Emergency, ClearAllSendsOneNoErrorMessage) {
    coe::Emergency e;
    e.raise(0x3210, 0x04);
    e.raise(0x4210, 0x08);
    e.discard_all();
    e.clear_all();
    EXPECT_EQ(e.error_register(), 0);
    ASSERT_EQ(e.pending(), 1u);
    EXPECT_EQ(e.front()[2], 0);
    e.pop();
    e.clear_all();
    EXPECT_TRUE(e.empty());
}

TEST(Emergency, FullQueueDropsTheOldest) {
    coe::Emergency e(nullptr, 2);
    e.raise(0x1000, 0x01);
    e.raise(0x2000, 0x01);
    e.raise(0x3000, 0x01);
    EXPECT_EQ(e.pending(), 2u);
    EXPECT_EQ(e.dropped(), 1u);
    EXPECT_EQ(le16(Bytes(e.front().begin(), e.front().end()), 2), 0x2000);
}

TEST(Emergency, ServerSendsQueuedEmergenciesFromPollInMailboxStates) {
    od::Dictionary dict = make_test_dictionary();
    od::AlState state = od::AlState::Init;
    coe::CoeServer server(dict, [&] { return state; });
    RecordingSender out;
    server.emergency().raise(0x8180, 0x10);
    server.poll(0, out);
    EXPECT_TRUE(out.messages.empty());  // no mailbox in Init
    state = od::AlState::PreOp;
    server.poll(1, out);
    ASSERT_EQ(out.messages.size(), 1u);
    Sent s = out.take();
    EXPECT_EQ(s.type, ecat::MailboxType::CoE);
    EXPECT_EQ(s.payload, (Bytes{0x00, 0x10, 0x80, 0x81, 0x11, 0, 0, 0, 0, 0}));
    EXPECT_TRUE(server.emergency().empty());
}

TEST(Emergency, EmergencyWaitsUntilAFragmentedAnswerIsOut) {
    od::Dictionary dict = make_test_dictionary();
    coe::CoeServer server(dict, [] { return od::AlState::PreOp; });
    RecordingSender out(16, 1);
    server.handle(info(0x01, {0x01, 0x00}), out);
    server.emergency().raise(0x5280, 0x01);
    std::size_t fragments = 0;
    while (true) {
        out.messages.clear();
        server.poll(0, out);
        if (out.messages.empty()) break;
        if (out.messages.front().payload[1] == 0x10) break;  // the emergency
        ++fragments;
    }
    ASSERT_EQ(out.messages.size(), 1u);
    EXPECT_EQ(out.messages.front().payload[1], 0x10);
    EXPECT_GT(fragments, 0u);
    EXPECT_FALSE(server.output_pending());
}

TEST(Emergency, QueueFullInTheSenderKeepsTheMessage) {
    od::Dictionary dict = make_test_dictionary();
    coe::CoeServer server(dict, [] { return od::AlState::Op; });
    RecordingSender out(122, 0);
    server.emergency().raise(0xFF01, 0x01);
    server.poll(0, out);
    EXPECT_EQ(server.emergency().pending(), 1u);
    out.set_queue(4);
    server.poll(1, out);
    EXPECT_EQ(out.messages.size(), 1u);
    EXPECT_EQ(server.emergency().pending(), 0u);
}

}  // namespace
