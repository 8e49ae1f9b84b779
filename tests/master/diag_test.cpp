// Decoding of diagnosis history (0x10F3) messages as `ecatctl diag` prints them. The bytes come from the
// slave's own encoder (coe::DiagnosisHistory::encode) where the coe library is there, so both sides of the
// wire are checked against each other, and from hand-written ETG.1020 layouts.
#include <gtest/gtest.h>

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "master/diag.hpp"
#include "util/le.hpp"

namespace {

using master::DiagEntry;
using master::DiagHeader;

std::vector<uint8_t> message(uint32_t code, uint16_t flags, uint16_t text, uint64_t ts,
                             std::vector<uint8_t> params = {}) {
    std::vector<uint8_t> b;
    util::append32(b, code);
    util::append16(b, flags);
    util::append16(b, text);
    util::append64(b, ts);
    b.insert(b.end(), params.begin(), params.end());
    return b;
}

std::string_view names(uint16_t code) {
    return code == 0x8611 ? "Following error" : "";
}

TEST(DiagDecode, EmergencyDerivedErrorWithByteArray) {
    // 0x8611 following error, error, 1 parameter: byte array of 5 bytes.
    auto b = message(0x8611E800, 0x0102, 0, 12'345'678'901ull, {0x05, 0x10, 1, 2, 3, 4, 5});
    auto e = master::decode_diag_message(b, 7);
    ASSERT_TRUE(e);
    EXPECT_EQ(e->subindex, 7);
    EXPECT_EQ(e->code, 0x8611E800u);
    EXPECT_TRUE(e->from_emergency());
    EXPECT_EQ(e->emergency_code(), 0x8611);
    EXPECT_EQ(e->type, 2);
    EXPECT_FALSE(e->local_time);
    EXPECT_EQ(e->timestamp_ns, 12'345'678'901ull);
    ASSERT_EQ(e->params.size(), 1u);
    EXPECT_EQ(e->params[0].kind(), 1u);
    EXPECT_EQ(e->params[0].data, (std::vector<uint8_t>{1, 2, 3, 4, 5}));
    EXPECT_FALSE(e->truncated);
    EXPECT_EQ(master::diag_text(*e, names), "Following error");
    EXPECT_EQ(master::diag_text(*e), "monitoring error");  // no table: the CiA 301 class
    EXPECT_EQ(master::format_diag_line(*e, names),
              ":07  00:00:12.345  error    0x8611e800  Following error  [bytes 01 02 03 04 05]");
}

TEST(DiagDecode, ManufacturerMessageTakesItsTextFromTheAsciiParameter) {
    auto b = message(0x0000E000, 0x0111, 0, 5, {0x05, 0x20, 'h', 'e', 'l', 'l', 'o'});
    auto e = master::decode_diag_message(b, 6);
    ASSERT_TRUE(e);
    EXPECT_EQ(e->type, 1);
    EXPECT_TRUE(e->local_time);
    EXPECT_EQ(master::diag_text(*e), "hello");
    // The text once, not again as a parameter.
    EXPECT_EQ(master::format_diag_line(*e), ":06  00:00:00.000 (local)  warning  0x0000e000  hello");
}

TEST(DiagDecode, ValueParametersOfCoeDataTypes) {
    // UINT16 0x1234, INT32 -2, UINT8 7, then a text id.
    auto b = message(0x00001000, 0x0300, 0x0042, 0,
                     {0x06, 0x00, 0x34, 0x12, 0x04, 0x00, 0xFE, 0xFF, 0xFF, 0xFF, 0x05, 0x00, 0x07});
    auto e = master::decode_diag_message(b);
    ASSERT_TRUE(e);
    ASSERT_EQ(e->params.size(), 3u);
    EXPECT_EQ(master::format_diag_param(e->params[0]), "0x1234 (4660)");
    EXPECT_EQ(master::format_diag_param(e->params[1]), "-2");
    EXPECT_EQ(master::format_diag_param(e->params[2]), "0x07 (7)");
    EXPECT_EQ(master::diag_text(*e), "text id 0x0042");
    // With the device's texts (its ESI DiagMessages), the whole text.
    auto texts = [](uint16_t id) -> std::string_view { return id == 0x0042 ? "Homing attained" : ""; };
    EXPECT_EQ(master::diag_text(*e, nullptr, texts), "Homing attained");
    EXPECT_NE(master::format_diag_line(*e, nullptr, texts).find("Homing attained  [0x1234"),
              std::string::npos);
}

TEST(DiagDecode, ATextIdAboutAnErrorShowsTheTextThenTheErrorName) {
    auto b = message(0x8611E800, 0x0001, 0x8020, 9, {});  // warning, no parameter, text id 0x8020
    auto e = master::decode_diag_message(b, 6);
    ASSERT_TRUE(e);
    auto names = [](uint16_t code) -> std::string_view { return code == 0x8611 ? "Following error" : ""; };
    auto texts = [](uint16_t id) -> std::string_view {
        return id == 0x8020 ? "Fault reset refused: cause still present" : "";
    };
    EXPECT_EQ(master::diag_text(*e, names, texts),
              "Fault reset refused: cause still present (Following error)");
    EXPECT_EQ(master::diag_text(*e, names), "Following error");  // without the texts: the error's name
}

TEST(DiagDecode, AFaultWhoseTextIsItsErrorsNameSaysItOnce) {
    // What the drive stores for a fault: the error's diag code, its text id, the manufacturer bytes.
    auto b = message(0x8611E800, 0x0102, 0x8611, 9, {0x05, 0x10, 8, 8, 0, 0, 0});
    auto e = master::decode_diag_message(b, 6);
    ASSERT_TRUE(e);
    auto names = [](uint16_t code) -> std::string_view { return code == 0x8611 ? "Following error" : ""; };
    auto texts = [](uint16_t id) -> std::string_view { return id == 0x8611 ? "Following error" : ""; };
    EXPECT_EQ(master::diag_text(*e, names, texts), "Following error");
    // A lookup that holds state (the texts of an ESI read at run time, as ecatctl diag --esi does).
    const std::map<uint16_t, std::string> from_esi{{0x8611, "Schleppfehler"}};
    const master::TextIdLookup esi = [&from_esi](uint16_t id) -> std::string_view {
        auto it = from_esi.find(id);
        return it != from_esi.end() ? std::string_view(it->second) : std::string_view();
    };
    EXPECT_EQ(master::diag_text(*e, names, esi), "Schleppfehler (Following error)");
}

TEST(DiagDecode, AWarningNamedByItsCodeDoesNotRepeatItsCutText) {
    // What the drive stores for a warning: diag code from the error code, the name cut to 14 characters.
    std::vector<uint8_t> p{0x0E, 0x20};
    for (char c : std::string("Negative limit"))
        p.push_back(static_cast<uint8_t>(c));
    auto b = message(0x8A80E800, 0x0101, 0, 7, p);
    auto e = master::decode_diag_message(b, 8);
    ASSERT_TRUE(e);
    auto names = [](uint16_t code) -> std::string_view {
        return code == 0x8A80 ? "Negative limit switch" : "";
    };
    EXPECT_EQ(master::format_diag_line(*e, names),
              ":08  00:00:00.000  warning  0x8a80e800  Negative limit switch");
}

TEST(DiagDecode, ShortAndCutMessages) {
    EXPECT_FALSE(master::decode_diag_message({}));
    auto b = message(0x8611E800, 0x0202, 0, 1);
    EXPECT_FALSE(master::decode_diag_message(std::span<const uint8_t>(b).first(15)));
    // An all-zero slot is empty.
    EXPECT_FALSE(master::decode_diag_message(std::vector<uint8_t>(32, 0)));
    // Two parameters announced, none there.
    auto e = master::decode_diag_message(b);
    ASSERT_TRUE(e);
    EXPECT_TRUE(e->truncated);
    EXPECT_TRUE(e->params.empty());
    // A byte array longer than the bytes left, and an unknown data type, stop the decoding.
    auto c = message(1, 0x0100, 0, 1, {0x08, 0x10, 1, 2});
    EXPECT_TRUE(master::decode_diag_message(c)->truncated);
    auto d = message(1, 0x0200, 0, 1, {0x05, 0x00, 9, 0x09, 0x00, 'x'});
    auto de = master::decode_diag_message(d);
    ASSERT_TRUE(de);
    EXPECT_EQ(de->params.size(), 1u);
    EXPECT_TRUE(de->truncated);
    EXPECT_NE(master::format_diag_line(*de).find("cut short"), std::string::npos);
    // Kinds 4..15 are not defined.
    auto f = message(1, 0x0100, 0, 1, {0x01, 0x40, 1});
    EXPECT_TRUE(master::decode_diag_message(f)->truncated);
}

TEST(DiagOrder, RingNotYetFull) {
    DiagHeader h{10, 8, 0, true, 0};
    EXPECT_EQ(master::diag_message_order(h, true, false),
              (std::vector<uint8_t>{8, 7, 6, 15, 14, 13, 12, 11, 10, 9}));
    EXPECT_EQ(master::diag_message_order(h, false, false).front(), 9);
    EXPECT_EQ(master::diag_message_order(h, false, false).back(), 8);
}

TEST(DiagOrder, OnlyNewStopsAtTheAcknowledgedMessageAcrossTheWrap) {
    DiagHeader h{10, 7, 14, true, 0};
    EXPECT_EQ(master::diag_message_order(h, true, true), (std::vector<uint8_t>{7, 6, 15}));
    EXPECT_EQ(master::diag_message_order(h, false, true), (std::vector<uint8_t>{15, 6, 7}));
    h.acknowledged = 7;
    EXPECT_TRUE(master::diag_message_order(h, true, true).empty());
    h.acknowledged = 0;  // nothing acknowledged: all are new
    EXPECT_EQ(master::diag_message_order(h, true, true).size(), 10u);
}

TEST(DiagOrder, NoMessagesOrNonsense) {
    EXPECT_TRUE(master::diag_message_order({10, 0, 0, false, 0}, true, false).empty());
    EXPECT_TRUE(master::diag_message_order({10, 16, 0, false, 0}, true, false).empty());
    EXPECT_TRUE(master::diag_message_order({0, 6, 0, false, 0}, true, false).empty());
    EXPECT_EQ(master::diag_message_order({1, 6, 6, false, 0}, true, false), (std::vector<uint8_t>{6}));
}

TEST(DiagText, FlagsTimeAndClasses) {
    EXPECT_EQ(master::format_diag_flags(0), "overwrite mode");
    EXPECT_EQ(master::format_diag_flags(0x0031), "send as emergency, acknowledge mode, overflow");
    EXPECT_EQ(master::format_diag_flags(0x000E),
              "info not stored, warnings not stored, errors not stored, overwrite mode");
    EXPECT_EQ(master::format_diag_time(1'000'000'001ull), "00:00:01.000");
    // 849055596.6 s of DC system time (what the soft slave reports, set to the wall time): a UTC date.
    EXPECT_EQ(master::format_diag_time(849'055'596'600'000'000ull), "2026-11-27 00:46:36.600 UTC");
    EXPECT_EQ(master::format_diag_time(0, true), "00:00:00.000");
    EXPECT_EQ(master::format_diag_time(90'061'250'000'000ull, true), "1d 01:01:01.250");
    EXPECT_EQ(master::format_diag_time(90'061'250'000'000ull), "1d 01:01:01.250");
    EXPECT_EQ(master::emergency_class_name(0x2310), "current error");
    EXPECT_EQ(master::emergency_class_name(0x8180), "communication error");
    EXPECT_EQ(master::emergency_class_name(0xFF01), "device specific error");
    EXPECT_EQ(master::diag_type_name(2), "error");
    EXPECT_EQ(master::diag_type_name(7), "unknown");
    // A Unicode string parameter (UTF-16LE) is the text of a message with text id 0.
    auto b = message(0x0000E001, 0x0100, 0, 0, {0x06, 0x30, 'o', 0, 'k', 0, '!', 0});
    auto u = master::decode_diag_message(b);
    ASSERT_TRUE(u);
    EXPECT_EQ(master::diag_text(*u), "ok!");
    DiagEntry reset;
    reset.code = 0x0000E800;
    EXPECT_EQ(master::diag_text(reset), "no error (error reset)");
}

}  // namespace

#if defined(MASTER_DIAG_WITH_COE)
#include "coe/diagnosis.hpp"

namespace {

// The slave's encoder and the master's decoder agree.
TEST(DiagDecode, RoundTripThroughTheSlavesEncoder) {
    const uint8_t mfr[5] = {9, 8, 7, 6, 5};
    const uint8_t u16[2] = {0x34, 0x12};
    const coe::DiagParam params[] = {coe::DiagParam::byte_array(mfr),
                                     coe::DiagParam::value(od::DataType::Unsigned16, u16),
                                     coe::DiagParam::ascii("a long text that will be cut")};
    coe::DiagMessage m;
    m.code = coe::DiagnosisHistory::from_emergency(0x2310);
    m.type = coe::DiagType::Warning;
    m.timestamp_ns = 987'654'321'000ull;
    m.params = params;
    uint8_t out[48];
    const std::size_t n = coe::DiagnosisHistory::encode(m, out);
    auto e = master::decode_diag_message(std::span<const uint8_t>(out, n), 9);
    ASSERT_TRUE(e);
    EXPECT_EQ(e->code, 0x2310E800u);
    EXPECT_EQ(e->type, 1);
    EXPECT_EQ(e->timestamp_ns, 987'654'321'000ull);
    ASSERT_EQ(e->params.size(), 3u);
    EXPECT_EQ(e->params[0].data, (std::vector<uint8_t>{9, 8, 7, 6, 5}));
    EXPECT_EQ(master::format_diag_param(e->params[1]), "0x1234 (4660)");
    EXPECT_EQ(e->params[2].kind(), 2u);
    EXPECT_EQ(e->params[2].data.size(), 48u - 16 - 7 - 4 - 2);  // cut to the room left
    EXPECT_FALSE(e->truncated);
}

}  // namespace
#endif
