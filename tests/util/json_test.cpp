// util::JsonWriter and util::json_string: RFC 8259 text, always valid UTF-8 whatever bytes come in.
#include "util/json.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <sstream>

namespace {

TEST(Json, NestingAndCommas) {
    std::ostringstream o;
    util::JsonWriter w(o);
    w.begin_object();
    w.member("a", 1).member("b", "x");
    w.key("list").begin_array().value(true).value(false).null().begin_object().end_object().end_array();
    w.key("empty").begin_array().end_array();
    w.end_object();
    EXPECT_EQ(o.str(), "{\"a\":1,\"b\":\"x\",\"list\":[true,false,null,{}],\"empty\":[]}\n");
}

TEST(Json, Numbers) {
    std::ostringstream o;
    util::JsonWriter w(o);
    w.begin_array()
        .value(int64_t{-9223372036854775807 - 1})
        .value(uint64_t{18446744073709551615u})
        .value(0.1)
        .value(1.5)
        .value(-0.0)
        .value(std::numeric_limits<double>::quiet_NaN())
        .value(std::numeric_limits<double>::infinity())
        .end_array();
    EXPECT_EQ(o.str(), "[-9223372036854775808,18446744073709551615,0.1,1.5,-0,null,null]\n");
}

TEST(Json, EscapesEveryControlCharacterQuoteAndBackslash) {
    std::string all;
    for (int c = 0; c < 0x20; ++c)
        all += static_cast<char>(c);
    all += "\"\\\x7f";
    const std::string j = util::json_string(all);
    ASSERT_EQ(j.front(), '"');
    ASSERT_EQ(j.back(), '"');
    for (std::size_t i = 1; i + 1 < j.size(); ++i)
        EXPECT_GE(static_cast<unsigned char>(j[i]), 0x20) << i;
    EXPECT_NE(j.find("\\u0000"), std::string::npos);
    EXPECT_NE(j.find("\\u001f"), std::string::npos);
    EXPECT_NE(j.find("\\\""), std::string::npos);
    EXPECT_NE(j.find("\\\\"), std::string::npos);
    EXPECT_NE(j.find("\\u007f"), std::string::npos);
}

TEST(Json, Utf8PassesAndOtherBytesAreLatin1) {
    EXPECT_EQ(util::json_string("Ger\xC3\xA4t \xE2\x82\xAC \xF0\x9F\x98\x80"),
              "\"Ger\xC3\xA4t \xE2\x82\xAC \xF0\x9F\x98\x80\"");
    // ISO-8859-1 "Gerät": 0xE4 alone is not UTF-8, it becomes U+00E4.
    EXPECT_EQ(util::json_string("Ger\xE4t"), "\"Ger\xC3\xA4t\"");
    // Overlong, surrogate and truncated sequences are not UTF-8 either.
    EXPECT_EQ(util::json_string("\xC0\xAF"), "\"\xC3\x80\xC2\xAF\"");
    EXPECT_EQ(util::json_string("\xED\xA0\x80"), "\"\xC3\xAD\xC2\xA0\xC2\x80\"");
    EXPECT_EQ(util::json_string("\xE2\x82"), "\"\xC3\xA2\xC2\x82\"");
}

}  // namespace
