// ecatctl's typed values (REAL32/REAL64, CoE data types) and the complete-access layout it decodes.
#include <gtest/gtest.h>

#include "coe_view.hpp"
#include "format.hpp"

using namespace ecatctl;
using Bytes = std::vector<uint8_t>;

TEST(EcatctlTyped, Real32AndReal64BothWays) {
    auto f = encode_value(ValueType::F32, "1.5");
    ASSERT_TRUE(f);
    EXPECT_EQ(*f, (Bytes{0x00, 0x00, 0xC0, 0x3F}));  // IEEE 754 single 1.5, little-endian
    EXPECT_EQ(format_value(ValueType::F32, *f), "1.5");
    auto d = encode_value(ValueType::F64, "-2.25");
    ASSERT_TRUE(d);
    EXPECT_EQ(*d, (Bytes{0, 0, 0, 0, 0, 0, 0x02, 0xC0}));
    EXPECT_EQ(format_value(ValueType::F64, *d), "-2.25");
    EXPECT_EQ(format_value(ValueType::F32, Bytes{0xDB, 0x0F, 0x49, 0x40}), "3.14159274");
    EXPECT_FALSE(encode_value(ValueType::F32, "1.5x"));
    EXPECT_FALSE(encode_value(ValueType::F64, ""));
    EXPECT_EQ(parse_type("real32"), ValueType::F32);
    EXPECT_EQ(parse_type("real64"), ValueType::F64);
    EXPECT_FALSE(parse_type("f32"));  // only the CoE names
    EXPECT_EQ(type_size(ValueType::F64), 8u);
}

TEST(EcatctlTyped, ValuesPrintByTheirCoeType) {
    EXPECT_EQ(format_typed(dtype::VisibleString, 64, Bytes{'M', 'A', 'X', 0, 0, 0, 0, 0}), "MAX");
    EXPECT_EQ(format_typed(dtype::Integer16, 16, Bytes{0xFE, 0xFF}), "0xfffe (-2)");
    EXPECT_EQ(format_typed(dtype::Unsigned32, 32, Bytes{0x10, 0x00, 0x40, 0x60}), "0x60400010 (1614807056)");
    EXPECT_EQ(format_typed(dtype::Real32, 32, Bytes{0x00, 0x00, 0xC0, 0x3F}), "1.5");
    EXPECT_EQ(format_typed(dtype::Boolean, 1, Bytes{0x03}), "0x01 (1)");  // only the entry's bit
    EXPECT_EQ(format_typed(dtype::OctetString, 24, Bytes{0x01, 0xAB, 0x00}), "01 ab 00");
    auto b = encode_typed(dtype::Integer32, 32, {"-5"});
    ASSERT_TRUE(b);
    EXPECT_EQ(*b, (Bytes{0xFB, 0xFF, 0xFF, 0xFF}));
    EXPECT_EQ(*encode_typed(dtype::VisibleString, 64, {"a", "b"}), (Bytes{'a', ' ', 'b'}));
    EXPECT_EQ(esi_type_name(dtype::Unsigned16), "UINT");
    EXPECT_EQ(esi_type_name(dtype::Real64), "LREAL");
}

TEST(EcatctlTyped, CompleteAccessOfAnAssignmentSplitsPerSubindex) {
    const std::vector<EntryView> e{{0, dtype::Unsigned8, 8, 0x3F, "Count"},
                                   {1, dtype::Unsigned16, 16, 0x3F, "First"},
                                   {2, dtype::Unsigned16, 16, 0x3F, "Second"}};
    // Subindex 0 occupies 16 bits; here only one of two entries is in the image.
    auto parts = split_complete_access(e, 0, Bytes{0x01, 0x00, 0x00, 0x16});
    ASSERT_EQ(parts.size(), 2u);
    EXPECT_EQ(parts[0].value, Bytes{0x01});
    EXPECT_EQ(parts[1].entry.name, "First");
    EXPECT_EQ(parts[1].value, (Bytes{0x00, 0x16}));
    // From subindex 1: no subindex-0 slot.
    parts = split_complete_access(e, 1, Bytes{0x00, 0x16, 0x01, 0x16});
    ASSERT_EQ(parts.size(), 2u);
    EXPECT_EQ(parts[1].value, (Bytes{0x01, 0x16}));
}

TEST(EcatctlTyped, CompleteAccessPacksBitEntries) {
    // As the slave lays it out: SI0 (16 bits), bit A at bit 16, bit B at bit 17, the word on the next byte.
    const std::vector<EntryView> e{{0, dtype::Unsigned8, 8, 0x07, "Count"},
                                   {1, dtype::Boolean, 1, 0x3F, "A"},
                                   {2, dtype::Boolean, 1, 0x3F, "B"},
                                   {3, dtype::Unsigned16, 16, 0x3F, "Word"}};
    auto parts = split_complete_access(e, 0, Bytes{0x03, 0x00, 0x01, 0xEF, 0xBE});
    ASSERT_EQ(parts.size(), 4u);
    EXPECT_EQ(parts[1].value, Bytes{0x01});
    EXPECT_EQ(parts[2].value, Bytes{0x00});
    EXPECT_EQ(parts[3].value, (Bytes{0xEF, 0xBE}));
}

TEST(EcatctlTyped, ExtractBitsAcrossBytes) {
    EXPECT_EQ(extract_bits(Bytes{0xF0, 0x0F}, 4, 8), Bytes{0xFF});
    EXPECT_EQ(extract_bits(Bytes{0x34, 0x12, 0x78}, 8, 16), (Bytes{0x12, 0x78}));
    EXPECT_EQ(extract_bits(Bytes{0x01}, 4, 16), (Bytes{0x00, 0x00}));  // past the image: zeros
}
