// "Hot paths allocate nothing": once warm, serving CoE requests, emergencies and diagnosis messages does not
// touch the heap. The test binary links the counting global operator new (tests/support/alloc_counter.hpp).
#include <gtest/gtest.h>

#include <array>

#include "coe/diagnosis.hpp"
#include "coe/events.hpp"
#include "coe/pdo_validation.hpp"
#include "coe/sdo_server.hpp"
#include "coe_test_support.hpp"
#include "support/alloc_counter.hpp"
#include "support/fixed_sender.hpp"

// The replacement pairs malloc with free on purpose; GCC cannot see that once gtest's new/delete are inlined.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"

using namespace coe_test;

namespace {

using test_support::FixedSender;

void one_round(coe::CoeServer& server, coe::DiagnosisHistory& diag, FixedSender& out) {
    auto req = [&](const Bytes& b) { server.handle(b, out); };
    req(sdo(0x40, 0x1018, 1));          // expedited upload
    req(sdo(0x2B, 0x6040, 0, 0x000F));  // expedited download
    req(sdo(0x40, 0x1008, 0));          // normal upload
    req(sdo(0x40, 0x2000, 0));          // segmented upload
    uint8_t t = 0;
    while (server.transfer_in_progress()) {
        req(segment(static_cast<uint8_t>(0x60 | (t << 4)), Bytes(7, 0)));
        t ^= 1;
    }
    req(sdo(0x21, 0x2000, 0, 60, {1, 2, 3, 4}));  // segmented download
    req(segment(0x00, Bytes(50, 9)));
    req(segment(0x11, Bytes{1, 2, 3, 4, 5, 6}));
    req(sdo(0x50, 0x1018, 0));                               // complete access upload
    req(sdo(0x31, 0x1C12, 0, 4, {0x01, 0x00, 0x00, 0x16}));  // complete access download
    req(info(0x01, {0x01, 0x00}));                           // fragmented OD list
    for (int i = 0; i < 20; ++i)
        server.poll(1, out);
    req(info(0x05, {0x02, 0x20, 0x00, 0x78}));  // entry description
    req(sdo(0x40, 0x5555, 0));                  // abort
    server.emergency().raise(0x2310, 0x02);
    server.emergency().clear(0x2310);
    const uint8_t v[] = {7};
    const coe::DiagParam p[] = {coe::DiagParam::value(od::DataType::Unsigned8, v)};
    diag.add(coe::DiagMessage{coe::DiagnosisHistory::from_emergency(0x2310), coe::DiagType::Error, 1, 2,
                              false, p});
    server.poll(2, out);
}

TEST(CoeAllocation, ServingRequestsAllocatesNothingOnceWarm) {
    od::Dictionary dict = make_test_dictionary();
    Bytes big(300, 0x5A);
    ASSERT_EQ(dict.set_raw(0x2000, 0, big), od::Status::Ok);
    coe::install_pdo_validators(dict);
    coe::CoeServer server(dict, [] { return od::AlState::PreOp; });
    coe::DiagnosisHistory diag(dict, &server.emergency());
    FixedSender out(58);
    one_round(server, diag, out);  // warm-up: buffers reach their working size
    ASSERT_EQ(dict.set_raw(0x2000, 0, big), od::Status::Ok);
    const std::size_t before = out.count;
    // Every request is built before counting starts (building them allocates).
    std::vector<Bytes> reqs = {sdo(0x40, 0x1018, 1), sdo(0x2B, 0x6040, 0, 0x000F), sdo(0x40, 0x1008, 0),
                               sdo(0x40, 0x2000, 0)};
    for (int i = 0; i < 6; ++i)
        reqs.push_back(segment(static_cast<uint8_t>(0x60 | ((i & 1) << 4)), Bytes(7, 0)));
    reqs.push_back(sdo(0x21, 0x2000, 0, 60, {1, 2, 3, 4}));
    reqs.push_back(segment(0x00, Bytes(50, 9)));
    reqs.push_back(segment(0x11, Bytes{1, 2, 3, 4, 5, 6}));
    reqs.push_back(sdo(0x50, 0x1018, 0));
    reqs.push_back(sdo(0x31, 0x1C12, 0, 4, {0x01, 0x00, 0x00, 0x16}));
    reqs.push_back(info(0x01, {0x01, 0x00}));
    reqs.push_back(info(0x05, {0x02, 0x20, 0x00, 0x78}));
    reqs.push_back(sdo(0x40, 0x5555, 0));
    const uint8_t v[] = {7};
    const coe::DiagParam p[] = {coe::DiagParam::value(od::DataType::Unsigned8, v)};
    const coe::DiagMessage m{
        coe::DiagnosisHistory::from_emergency(0x2310), coe::DiagType::Error, 1, 2, false, p};

    uint64_t now = 5;
    coe::EventReporter events(server.emergency(), &diag, [&now] { return now; });
    const uint8_t mfr[5] = {8, 8, 0, 0, 0};

    const alloc_counter::Scope counting;
    events.raise(0x8611, 0x80, mfr);
    events.diag(coe::DiagType::Warning, 0x8A80, "Negative limit");
    events.clear(0x8611, 0);
    for (const auto& r : reqs) {
        server.handle(r, out);
        for (int i = 0; i < 4; ++i)
            server.poll(1, out);
    }
    server.emergency().raise(0x2310, 0x02);
    server.emergency().clear(0x2310);
    diag.add(m);
    server.poll(2, out);
    EXPECT_EQ(counting.count(), 0u);
    EXPECT_GT(out.count, before + reqs.size());
}

}  // namespace
