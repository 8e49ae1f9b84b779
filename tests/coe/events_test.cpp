// Application events (drive::EventSink's raise / clear / diag) turned into emergencies and 0x10F3 messages.
#include <gtest/gtest.h>

#include <array>

#include "coe/events.hpp"
#include "coe/sdo_server.hpp"
#include "coe_test_support.hpp"

using namespace coe_test;

namespace {

class Events : public ::testing::Test {
  protected:
    od::Dictionary dict = make_test_dictionary();
    coe::CoeServer server{dict, [] { return od::AlState::Op; }};
    coe::DiagnosisHistory history{dict, &server.emergency()};
    uint64_t now = 1'000'000'000;
    coe::EventReporter events{server.emergency(), &history, [this] { return now; }};

    Bytes message(uint8_t sub) {
        auto r = dict.raw(0x10F3, sub);
        return Bytes(r.begin(), r.end());
    }
};

TEST_F(Events, RaiseSendsTheEmergencyAndStoresAnErrorMessage) {
    const std::array<uint8_t, 5> mfr{0x08, 0x08, 0, 0, 0};  // drive state, mode
    events.raise(0x8611, 0x80, mfr);
    ASSERT_EQ(server.emergency().pending(), 1u);
    const auto& e = server.emergency().front();
    EXPECT_EQ(Bytes(e.begin(), e.end()), (Bytes{0x00, 0x10, 0x11, 0x86, 0x80, 0x08, 0x08, 0, 0, 0}));
    Bytes m = message(6);
    ASSERT_EQ(m.size(), 16u + 2u + 5u);
    EXPECT_EQ(le32(m, 0), 0x8611E800u);
    EXPECT_EQ(le16(m, 4), 0x0102u);  // error, 1 parameter
    EXPECT_EQ(le32(m, 8), 1'000'000'000u);
    EXPECT_EQ(le16(m, 16), 0x1005u);  // byte array of 5
}

TEST_F(Events, OnlyTheLastClearedErrorSendsTheNoErrorEmergency) {
    const std::array<uint8_t, 5> mfr{};
    events.raise(0x8611, 0x80, mfr);
    events.raise(0x7320, 0xA0, mfr);
    server.emergency().discard_all();
    events.clear(0x8611, 0x20);
    EXPECT_TRUE(server.emergency().empty());
    events.clear(0x1234, 0x20);  // a warning: never raised as an error
    EXPECT_TRUE(server.emergency().empty());
    events.clear(0x7320, 0x00);
    ASSERT_EQ(server.emergency().pending(), 1u);
    const auto& e = server.emergency().front();
    EXPECT_EQ(Bytes(e.begin(), e.end()), (Bytes{0x00, 0x10, 0, 0, 0, 0, 0, 0, 0, 0}));
    EXPECT_EQ(events.active(), 0u);
}

TEST_F(Events, DiagMessagesCarryTheirTextAndType) {
    events.diag(coe::DiagType::Warning, 0x8A80, "Negative limit");
    events.diag(coe::DiagType::Info, 0, "Homing attained");
    Bytes w = message(6);
    EXPECT_EQ(le32(w, 0), 0x8A80E800u);
    EXPECT_EQ(le16(w, 4), 0x0101u);
    EXPECT_EQ(le16(w, 16), 0x2000u | 14u);
    EXPECT_EQ(std::string(w.begin() + 18, w.end()), "Negative limit");
    Bytes i = message(7);
    EXPECT_EQ(le32(i, 0), coe::EventReporter::kManufacturerDiagCode);
    EXPECT_EQ(le16(i, 4), 0x0100u);
    EXPECT_TRUE(server.emergency().empty());  // diagnosis only
}

TEST_F(Events, WithSendAsEmergencyAnErrorStillGoesOutOnce) {
    ASSERT_EQ(dict.write(0x10F3, 5, od::AlState::PreOp, Bytes{0x01, 0x00}), od::Status::Ok);
    const std::array<uint8_t, 5> mfr{};
    events.raise(0x2310, 0x02, mfr);
    EXPECT_EQ(server.emergency().pending(), 1u);
    events.diag(coe::DiagType::Warning, 0x8A81, "Positive limit");  // a diagnosis goes out as emergency too
    EXPECT_EQ(server.emergency().pending(), 2u);
}

TEST(EventsWithoutHistory, EmergenciesOnly) {
    coe::Emergency emcy;
    coe::EventReporter events(emcy, nullptr);
    const uint8_t mfr[5] = {1, 2, 3, 4, 5};
    events.raise(0x5280, 0x01, mfr);
    events.diag(coe::DiagType::Info, 0, "ignored");
    events.clear(0x5280, 0);
    EXPECT_EQ(emcy.pending(), 2u);
}

}  // namespace

TEST_F(Events, TextsWithAnIdAreStoredByIdWithoutTheText) {
    const od::DiagMessageText texts[] = {{0x8011, "Homing attained", "information", 0}};
    events.set_texts(texts);
    events.diag(coe::DiagType::Info, 0, "Homing attained");
    events.diag(coe::DiagType::Warning, 0x8A80, "Negative limit");  // no id: the text as before
    Bytes i = message(6);
    EXPECT_EQ(le32(i, 0), coe::EventReporter::kManufacturerDiagCode);
    EXPECT_EQ(le16(i, 4), 0x0000u);  // info, no parameter
    EXPECT_EQ(le16(i, 6), 0x8011u);  // text id
    Bytes w = message(7);
    EXPECT_EQ(le16(w, 4), 0x0101u);
    EXPECT_EQ(le16(w, 6), 0u);
}

// ETG.1020: the message an error raises carries the text id of the device's text for that code (the ESI's
// DiagMessage), beside the emergency's manufacturer bytes; a code without a text, none.
TEST_F(Events, ARaisedErrorCarriesTheTextIdOfItsCodesText) {
    const od::DiagMessageText texts[] = {{0x0042, "Wire break", "error", 0x7320},
                                         {0x0043, "Not about a code", "error", 0}};
    events.set_texts(texts);
    const std::array<uint8_t, 5> mfr{1, 2, 3, 4, 5};
    events.raise(0x7320, 0x20, mfr);
    events.raise(0x2310, 0x02, mfr);
    Bytes m = message(6);
    EXPECT_EQ(le32(m, 0), 0x7320E800u);
    EXPECT_EQ(le16(m, 4), 0x0102u);  // error, the manufacturer bytes still as parameter
    EXPECT_EQ(le16(m, 6), 0x0042u);
    EXPECT_EQ(le16(m, 16), 0x1005u);
    Bytes n = message(7);
    EXPECT_EQ(le32(n, 0), 0x2310E800u);
    EXPECT_EQ(le16(n, 6), 0u);  // no text for 0x2310 (a text with error code 0 is not one)
    // Texts from an ESI name no code: the error's name (the application's) finds its text.
    events.raise(0x3210, 0x04, mfr, "Not about a code");
    EXPECT_EQ(le16(message(8), 6), 0x0043u);
    EXPECT_EQ(server.emergency().pending(), 3u);
}
