// ecatctl's text helpers.
#include <gtest/gtest.h>

#include "format.hpp"

using namespace ecatctl;

TEST(EcatctlFormat, ParsesDecimalHexAndBinaryWithinRange) {
    EXPECT_EQ(parse_number("4660", 0xFFFF), 4660u);
    EXPECT_EQ(parse_number("0x1234", 0xFFFF), 0x1234u);
    EXPECT_EQ(parse_number("0X1a", 0xFF), 0x1Au);
    EXPECT_EQ(parse_number("0b101", 0xFF), 5u);
    EXPECT_EQ(parse_number("0", 0), 0u);
    EXPECT_FALSE(parse_number("0x10000", 0xFFFF));
    EXPECT_FALSE(parse_number("", 10));
    EXPECT_FALSE(parse_number("0x", 10));
    EXPECT_FALSE(parse_number("12a", 1000));
    EXPECT_FALSE(parse_number("-1", 1000));
    EXPECT_FALSE(parse_number("99999999999999999999999", ~uint64_t{0}));
}

TEST(EcatctlFormat, TypedValuesRoundTripLittleEndian) {
    auto b = encode_value(ValueType::U16, "0x1234");
    ASSERT_TRUE(b);
    EXPECT_EQ(*b, (std::vector<uint8_t>{0x34, 0x12}));
    EXPECT_EQ(format_value(ValueType::U16, *b), "0x1234 (4660)");
    auto n = encode_value(ValueType::I16, "-2");
    ASSERT_TRUE(n);
    EXPECT_EQ(*n, (std::vector<uint8_t>{0xFE, 0xFF}));
    EXPECT_EQ(format_value(ValueType::I16, *n), "0xfffe (-2)");
    EXPECT_EQ(*encode_value(ValueType::I8, "-128"), (std::vector<uint8_t>{0x80}));
    EXPECT_FALSE(encode_value(ValueType::I8, "-129"));
    EXPECT_FALSE(encode_value(ValueType::I8, "128"));
    EXPECT_FALSE(encode_value(ValueType::U8, "256"));
    EXPECT_FALSE(encode_value(ValueType::U8, "-1"));
    auto q = encode_value(ValueType::U64, "0xffffffffffffffff");
    ASSERT_TRUE(q);
    EXPECT_EQ(format_value(ValueType::U64, *q), "0xffffffffffffffff (18446744073709551615)");
    EXPECT_EQ(format_value(ValueType::U32, std::vector<uint8_t>{1, 0, 0, 0}), "0x00000001 (1)");
    EXPECT_EQ(format_value(ValueType::U32, std::vector<uint8_t>{1, 0}), "");  // wrong size
}

TEST(EcatctlFormat, TypeNames) {
    EXPECT_EQ(parse_type("u8"), ValueType::U8);
    EXPECT_EQ(parse_type("uint32"), ValueType::U32);
    EXPECT_EQ(parse_type("i64"), ValueType::I64);
    EXPECT_FALSE(parse_type("float"));
    EXPECT_EQ(type_size(ValueType::U64), 8u);
}

TEST(EcatctlFormat, HexDumpSixteenPerLine) {
    std::vector<uint8_t> d(18);
    for (std::size_t i = 0; i < d.size(); ++i)
        d[i] = static_cast<uint8_t>(i);
    EXPECT_EQ(hex_dump(0x0130, d),
              "0x0130: 00 01 02 03 04 05 06 07 08 09 0a 0b 0c 0d 0e 0f\n"
              "0x0140: 10 11\n");
    EXPECT_EQ(hex_dump(0, {}), "");
}

// `pd` / `pd --all` say why a run failed at its end (issue 25: SAFEOP+ERR after a watchdog, exit 0 before).
TEST(EcatctlFormat, EndStateSaysTheStateTheErrorAndTheAlStatusCode) {
    EXPECT_EQ(end_state_text("SAFEOP", true, 0x001B, "Sync manager watchdog", "OP"),
              "ended in SAFEOP+ERR, not OP, AL status code 0x001b (Sync manager watchdog)");
    EXPECT_EQ(end_state_text("PREOP", false, 0, "", "SAFEOP"), "ended in PREOP, not SAFEOP");
    EXPECT_EQ(end_state_text("", false, 0, "", "OP"),
              "no AL status at the end (is the slave still there?), not OP");
}

// `download` without --type encodes values by the entry's CoE type from SDO information.
TEST(EcatctlFormat, ValueTypeOfCoeBasicTypes) {
    EXPECT_EQ(value_type_of(0x0006), ValueType::U16);
    EXPECT_EQ(value_type_of(0x0004), ValueType::I32);
    EXPECT_EQ(value_type_of(0x0007), ValueType::U32);
    EXPECT_EQ(value_type_of(0x0002), ValueType::I8);
    EXPECT_EQ(value_type_of(0x0009), std::nullopt);  // VISIBLE_STRING: text
    EXPECT_EQ(value_type_of(0x0029), std::nullopt);  // a structure
}
