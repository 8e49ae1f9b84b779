// Diagnosis history 0x10F3 (ETG.1020 Diagnosis History; MAXPOS firmware specification §7.2.5).
#include <gtest/gtest.h>

#include "coe/diagnosis.hpp"
#include "coe/sdo_server.hpp"
#include "coe_test_support.hpp"

using namespace coe_test;
using coe::DiagnosisHistory;

namespace {

class Diagnosis : public ::testing::Test {
  protected:
    od::Dictionary dict = make_test_dictionary();  // 0x10F3 with 4 messages of 40 bytes
    coe::CoeServer server{dict, [] { return od::AlState::PreOp; }};
    DiagnosisHistory diag{dict, &server.emergency()};
    RecordingSender out;

    Bytes ask(const Bytes& request) {
        server.handle(request, out);
        EXPECT_EQ(out.messages.size(), 1u);
        return out.messages.empty() ? Bytes{} : out.take().payload;
    }
    Bytes read_message(uint8_t sub) {
        Bytes r = ask(sdo(0x40, 0x10F3, sub));
        if (r.size() < 10) return r;
        if (r[2] & 0x02) return Bytes(r.begin() + 6, r.begin() + 6 + (4 - ((r[2] >> 2) & 3)));
        return Bytes(r.begin() + 10, r.end());
    }
    uint8_t u8(uint8_t sub) { return dict.get<uint8_t>(0x10F3, sub); }
    uint16_t flags() { return dict.get<uint16_t>(0x10F3, 5); }
    DiagnosisHistory::Result add(uint32_t code, coe::DiagType t = coe::DiagType::Error) {
        coe::DiagMessage m;
        m.code = code;
        m.type = t;
        m.text_id = 0x1234;
        m.timestamp_ns = 0x0102030405060708;
        return diag.add(m);
    }
    Bytes write_ok(uint8_t sub) { return {0x00, 0x30, 0x60, 0xF3, 0x10, sub, 0, 0, 0, 0}; }
};

TEST_F(Diagnosis, MessageEncodingFollowsEtg1020) {
    const uint8_t value[] = {0x3C};
    const coe::DiagParam params[] = {coe::DiagParam::value(od::DataType::Unsigned8, value),
                                     coe::DiagParam::ascii("ok")};
    coe::DiagMessage m{DiagnosisHistory::from_emergency(0x2310),
                       coe::DiagType::Warning,
                       0x4411,
                       0x1122334455667788,
                       true,
                       params};
    uint8_t buf[64];
    std::size_t n = DiagnosisHistory::encode(m, buf);
    EXPECT_EQ(Bytes(buf, buf + n),
              (Bytes{0x00, 0xE8, 0x10, 0x23,  // diag code: E800 | 2310 << 16
                     0x11, 0x02,              // warning, local time, 2 parameters
                     0x11, 0x44,              // text id
                     0x88, 0x77, 0x66, 0x55, 0x44, 0x33, 0x22, 0x11, 0x05, 0x00, 0x3C,  // UNSIGNED8 = 0x3C
                     0x02, 0x20, 'o',  'k'}));                                          // ASCII string of 2
}

TEST_F(Diagnosis, ValuesThatDoNotFitAreLeftOutTextsAreCut) {
    const uint8_t big[20] = {};
    const uint8_t u32[4] = {1, 2, 3, 4};
    const coe::DiagParam params[] = {coe::DiagParam::byte_array(big),
                                     coe::DiagParam::value(od::DataType::Unsigned32, u32)};
    coe::DiagMessage m{1, coe::DiagType::Info, 0, 0, false, params};
    uint8_t buf[40];
    std::size_t n = DiagnosisHistory::encode(m, buf);
    EXPECT_EQ(n, 16u + 22u);
    EXPECT_EQ(buf[5], 1);  // the UINT32 needs 6 bytes, only 2 are left: one parameter in
    const coe::DiagParam text[] = {coe::DiagParam::ascii("Fault reset refused: cause still present")};
    m.params = text;
    n = DiagnosisHistory::encode(m, buf);
    EXPECT_EQ(n, 40u);
    EXPECT_EQ(buf[5], 1);
    EXPECT_EQ(buf[16] | (buf[17] << 8), 0x2000 | 22);  // ASCII, cut to 22 characters
    EXPECT_EQ(std::string(buf + 18, buf + 40), "Fault reset refused: c");
}

TEST_F(Diagnosis, AddStoresFromSubindex6AndFlagsNewMessage) {
    EXPECT_EQ(u8(1), 4);
    EXPECT_EQ(u8(2), 0);
    EXPECT_EQ(add(0x0000E000), DiagnosisHistory::Result::Stored);
    EXPECT_EQ(u8(2), 6);
    EXPECT_EQ(u8(4), 1);
    Bytes msg = read_message(6);
    ASSERT_EQ(msg.size(), 16u);
    EXPECT_EQ(le32(msg, 0), 0x0000E000u);
    EXPECT_EQ(le16(msg, 4), 0x0002u);
    EXPECT_EQ(le16(msg, 6), 0x1234u);
    // Reading the newest message cleared "new messages available".
    EXPECT_EQ(u8(4), 0);
    add(0x0000E001);
    EXPECT_EQ(u8(2), 7);
    EXPECT_EQ(u8(4), 1);
    read_message(6);  // not the newest
    EXPECT_EQ(u8(4), 1);
}

TEST_F(Diagnosis, OverwriteModeWrapsAndReportsOverflow) {
    for (uint32_t i = 0; i < 4; ++i)
        add(0xE000 + i);
    EXPECT_EQ(u8(2), 9);
    EXPECT_EQ(flags() & DiagnosisHistory::kFlagOverflow, 0);
    EXPECT_EQ(ask(sdo(0x2F, 0x10F3, 3, 8)), write_ok(3));  // acknowledge up to :08
    add(0xE004);                                           // overwrites :06, which was acknowledged
    EXPECT_EQ(u8(2), 6);
    EXPECT_EQ(flags() & DiagnosisHistory::kFlagOverflow, 0);
    EXPECT_EQ(u8(3), 8);
    add(0xE005);  // overwrites :07, acknowledged
    add(0xE006);  // overwrites :08, acknowledged
    add(0xE007);  // overwrites :09, NOT acknowledged
    EXPECT_EQ(u8(2), 9);
    EXPECT_NE(flags() & DiagnosisHistory::kFlagOverflow, 0);
    EXPECT_EQ(u8(3), 0);  // SI3 := 0 when unacknowledged messages were overwritten
    EXPECT_EQ(le32(read_message(9), 0), 0xE007u);
    EXPECT_EQ(diag.stored(), 4u);
}

TEST_F(Diagnosis, AcknowledgeWritesAreRangeChecked) {
    EXPECT_EQ(ask(sdo(0x2F, 0x10F3, 3, 5)), abort_reply(0x10F3, 3, 0x06090032));
    EXPECT_EQ(ask(sdo(0x2F, 0x10F3, 3, 1)), abort_reply(0x10F3, 3, 0x06090032));
    EXPECT_EQ(ask(sdo(0x2F, 0x10F3, 3, 10)), abort_reply(0x10F3, 3, 0x06090031));
    EXPECT_EQ(ask(sdo(0x2F, 0x10F3, 3, 9)), write_ok(3));
    EXPECT_EQ(ask(sdo(0x2F, 0x10F3, 3, 6)), write_ok(3));
}

TEST_F(Diagnosis, WritingZeroClearsAllMessages) {
    add(1);
    add(2);
    EXPECT_EQ(ask(sdo(0x2F, 0x10F3, 3, 0)), write_ok(3));
    EXPECT_EQ(diag.stored(), 0u);
    EXPECT_EQ(u8(2), 0);
    EXPECT_EQ(u8(4), 0);
    EXPECT_EQ(read_message(6).size(), 0u);
    add(3);
    EXPECT_EQ(u8(2), 6);
}

TEST_F(Diagnosis, AcknowledgeModeDiscardsWhenFullUntilAcknowledged) {
    EXPECT_EQ(ask(sdo(0x2B, 0x10F3, 5, DiagnosisHistory::kFlagAcknowledgeMode)), write_ok(5));
    for (uint32_t i = 0; i < 4; ++i)
        EXPECT_EQ(add(0xE000 + i), DiagnosisHistory::Result::Stored);
    EXPECT_EQ(add(0xE004), DiagnosisHistory::Result::Discarded);
    EXPECT_NE(flags() & DiagnosisHistory::kFlagOverflow, 0);
    EXPECT_EQ(u8(2), 9);
    EXPECT_EQ(ask(sdo(0x2F, 0x10F3, 3, 6)), write_ok(3));  // oldest acknowledged: room for one
    EXPECT_EQ(flags() & DiagnosisHistory::kFlagOverflow, 0);
    EXPECT_EQ(add(0xE005), DiagnosisHistory::Result::Stored);
    EXPECT_EQ(u8(2), 6);
    EXPECT_EQ(le32(read_message(6), 0), 0xE005u);
    EXPECT_EQ(add(0xE006), DiagnosisHistory::Result::Discarded);
}

TEST_F(Diagnosis, SuppressFlagsKeepMessageTypesOut) {
    EXPECT_EQ(ask(sdo(0x2B, 0x10F3, 5, DiagnosisHistory::kFlagNoInfo | DiagnosisHistory::kFlagNoWarning)),
              write_ok(5));
    EXPECT_EQ(add(1, coe::DiagType::Info), DiagnosisHistory::Result::Suppressed);
    EXPECT_EQ(add(2, coe::DiagType::Warning), DiagnosisHistory::Result::Suppressed);
    EXPECT_EQ(add(3, coe::DiagType::Error), DiagnosisHistory::Result::Stored);
    EXPECT_EQ(ask(sdo(0x2B, 0x10F3, 5, DiagnosisHistory::kFlagNoError)), write_ok(5));
    EXPECT_EQ(add(4, coe::DiagType::Error), DiagnosisHistory::Result::Suppressed);
    EXPECT_EQ(diag.stored(), 1u);
}

TEST_F(Diagnosis, FlagsWritesKeepTheOverflowBitReadOnly) {
    for (uint32_t i = 0; i < 5; ++i)
        add(i);  // overflow in overwrite mode
    ASSERT_NE(flags() & DiagnosisHistory::kFlagOverflow, 0);
    EXPECT_EQ(ask(sdo(0x2B, 0x10F3, 5, 0x0000)), write_ok(5));  // the master cannot clear b5
    EXPECT_NE(flags() & DiagnosisHistory::kFlagOverflow, 0);
    EXPECT_EQ(ask(sdo(0x2B, 0x10F3, 5, 0x0100)), abort_reply(0x10F3, 5, 0x06090030));
}

TEST_F(Diagnosis, SendAsEmergencyFlag) {
    EXPECT_EQ(ask(sdo(0x2B, 0x10F3, 5, DiagnosisHistory::kFlagEmergency)), write_ok(5));
    coe::DiagMessage m;
    m.code = DiagnosisHistory::from_emergency(0x8611);
    m.type = coe::DiagType::Error;
    diag.add(m);
    m.code = 0x0000E123;  // manufacturer code: device-specific emergency FF00
    diag.add(m);
    ASSERT_EQ(server.emergency().pending(), 2u);
    auto first = server.emergency().front();
    EXPECT_EQ(first[2], 0x11);
    EXPECT_EQ(first[3], 0x86);
    server.emergency().pop();
    auto second = server.emergency().front();
    EXPECT_EQ(Bytes(second.begin(), second.end()),
              (Bytes{0x00, 0x10, 0x00, 0xFF, 0x00, 0x23, 0xE1, 0x00, 0x00, 0x02}));
}

TEST_F(Diagnosis, EmergencyFlagNeedsAnEmergencySender) {
    od::Dictionary d2 = make_test_dictionary();
    DiagnosisHistory lonely(d2);
    EXPECT_EQ(d2.write(0x10F3, 5, od::AlState::PreOp, Bytes{0x01, 0x00}), od::Status::InvalidValue);
}

TEST(DiagnosisSetup, MissingOrMalformedObjectIsRefused) {
    od::Dictionary empty;
    EXPECT_THROW(DiagnosisHistory h(empty), std::logic_error);
    od::Dictionary tiny;
    tiny.add(DiagnosisHistory::make_object(2, 8));  // messages shorter than the 16-byte head
    EXPECT_THROW(DiagnosisHistory h(tiny), std::logic_error);
}

}  // namespace
