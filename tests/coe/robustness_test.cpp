// Bad input never crashes or corrupts: random and mutated requests get an answer the standard names
// (SDO abort, SDO info error or mailbox error) and the server keeps serving.
#include <gtest/gtest.h>

#include <random>

#include "coe/diagnosis.hpp"
#include "coe/pdo_validation.hpp"
#include "coe/sdo_server.hpp"
#include "coe_test_support.hpp"

using namespace coe_test;

namespace {

bool is_standard_answer(const Sent& s) {
    if (s.type == ecat::MailboxType::Error) return s.payload.size() == 4 && s.payload[0] == 0x01;
    if (s.type != ecat::MailboxType::CoE || s.payload.size() < 2) return false;
    const uint8_t service = s.payload[1] >> 4;
    return service == 1 || service == 2 || service == 3 || service == 8;
}

TEST(CoeRobustness, RandomAndMutatedRequestsAreAnsweredAndServingContinues) {
    od::Dictionary dict = make_test_dictionary();
    coe::install_pdo_validators(dict);
    od::AlState state = od::AlState::PreOp;
    coe::CoeServer server(dict, [&] { return state; });
    coe::DiagnosisHistory diag(dict, &server.emergency());
    std::mt19937 rng(1234);
    const std::vector<Bytes> seeds = {sdo(0x40, 0x1018, 1),
                                      sdo(0x2B, 0x6040, 0, 0x000F),
                                      sdo(0x50, 0x1C12, 0),
                                      sdo(0x31, 0x1600, 0, 6, {0x01, 0x00, 0x10, 0x00, 0x40, 0x60}),
                                      sdo(0x21, 0x2000, 0, 20, {1, 2, 3}),
                                      segment(0x00, Bytes(7, 1)),
                                      segment(0x60, Bytes(7, 0)),
                                      info(0x01, {0x01, 0x00}),
                                      info(0x05, {0x02, 0x20, 0x00, 0x78}),
                                      info(0x03, {0xF3, 0x10})};
    const od::AlState states[] = {od::AlState::PreOp, od::AlState::SafeOp, od::AlState::Op};
    for (int round = 0; round < 20000; ++round) {
        RecordingSender out(std::uniform_int_distribution<std::size_t>(10, 200)(rng));
        Bytes req;
        if (round % 3 == 0) {
            req.resize(std::uniform_int_distribution<std::size_t>(0, 40)(rng));
            for (auto& b : req)
                b = static_cast<uint8_t>(rng());
        } else {
            req = seeds[rng() % seeds.size()];
            const int flips = 1 + static_cast<int>(rng() % 4);
            for (int f = 0; f < flips && !req.empty(); ++f)
                req[rng() % req.size()] ^= static_cast<uint8_t>(1u << (rng() % 8));
            if (rng() % 8 == 0) req.resize(rng() % (req.size() + 1));
        }
        if (round % 500 == 0) state = states[rng() % 3];
        server.handle(req, out);
        server.poll(static_cast<uint64_t>(round) * 1'000'000, out);
        for (const auto& s : out.messages) {
            EXPECT_TRUE(is_standard_answer(s)) << "round " << round;
            EXPECT_LE(s.payload.size(), out.max_payload());
        }
    }
    // Still serving, and the dictionary still says what it said.
    state = od::AlState::PreOp;
    RecordingSender out;
    server.handle(sdo(0x40, 0x1018, 1), out);
    ASSERT_FALSE(out.messages.empty());
    EXPECT_EQ(out.messages.back().payload,
              (Bytes{0x00, 0x30, 0x43, 0x18, 0x10, 0x01, 0xFB, 0x00, 0x00, 0x00}));
    EXPECT_EQ(dict.get<uint32_t>(0x1000, 0), 0x00020192u);
}

}  // namespace
