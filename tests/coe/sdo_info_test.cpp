// SDO information service (CoE service 8, ETG.1000.6 SDO Information).
#include <gtest/gtest.h>

#include "coe/abort.hpp"
#include "coe/sdo_info.hpp"
#include "coe/sdo_server.hpp"
#include "coe_test_support.hpp"

using namespace coe_test;

namespace {

class SdoInfo : public ::testing::Test {
  protected:
    od::Dictionary dict = make_test_dictionary();
    coe::CoeServer server{dict, [] { return od::AlState::PreOp; }};

    // Collects a (possibly fragmented) answer: checks the fragment headers and returns the joined bodies.
    Bytes collect(RecordingSender& out, uint8_t opcode, std::size_t* fragments = nullptr) {
        Bytes body;
        std::size_t n = 0;
        int expected_left = -1;
        while (true) {
            if (out.messages.empty()) server.poll(0, out);
            if (out.messages.empty()) break;
            Sent s = out.take();
            EXPECT_EQ(s.type, ecat::MailboxType::CoE);
            EXPECT_LE(s.payload.size(), out.max_payload());
            EXPECT_EQ(s.payload[0], 0x00);
            EXPECT_EQ(s.payload[1], 0x80);
            EXPECT_EQ(s.payload[2] & 0x7F, opcode);
            const uint16_t left = le16(s.payload, 4);
            if (expected_left >= 0) {
                EXPECT_EQ(left, expected_left);
            }
            EXPECT_EQ((s.payload[2] & 0x80) != 0, left > 0);
            body.insert(body.end(), s.payload.begin() + 6, s.payload.end());
            ++n;
            if (left == 0) break;
            expected_left = left - 1;
        }
        if (fragments) *fragments = n;
        return body;
    }
    // The whole answer (opcode 0x02) to "get OD list" of list type `type`, through the default sender.
    Bytes od_list(uint8_t type) {
        RecordingSender out;
        server.handle(info(0x01, {type, 0x00}), out);
        return collect(out, 0x02);
    }
    std::vector<uint16_t> indexes(const Bytes& body) {
        std::vector<uint16_t> v;
        for (std::size_t i = 2; i + 1 < body.size(); i += 2)
            v.push_back(le16(body, i));
        return v;
    }
    std::vector<uint16_t> expected(uint16_t list_type) {
        std::vector<uint16_t> v;
        for (const auto& o : dict.objects())
            if (coe::in_od_list(o, list_type)) v.push_back(o.index);
        return v;
    }
};

TEST_F(SdoInfo, OdListAllObjects) {
    Bytes body = od_list(0x01);
    ASSERT_GE(body.size(), 2u);
    EXPECT_EQ(le16(body, 0), 1u);
    auto all = indexes(body);
    EXPECT_EQ(all.size(), dict.objects().size());
    EXPECT_EQ(all.front(), 0x1000);
    EXPECT_EQ(all.back(), 0x607A);
}

TEST_F(SdoInfo, OdListPerListType) {
    const std::pair<uint16_t, std::vector<uint16_t>> lists[] = {
        {2, {0x6040, 0x6060, 0x607A}},
        {3, {0x1001, 0x10F3, 0x6041, 0x6064}},
        {4, {0x1600, 0x1601, 0x1A00, 0x1A01}},
        {5, {0x2002}},
    };
    for (const auto& [type, want] : lists) {
        Bytes body = od_list(static_cast<uint8_t>(type));
        ASSERT_GE(body.size(), 2u);
        EXPECT_EQ(le16(body, 0), type);
        EXPECT_EQ(indexes(body), want) << "list type " << type;
    }
}

TEST_F(SdoInfo, OdListType0GivesTheLengthsOfLists1To5) {
    Bytes body = od_list(0x00);
    ASSERT_EQ(body.size(), 12u);
    EXPECT_EQ(le16(body, 0), 0u);
    EXPECT_EQ(le16(body, 2), dict.objects().size());
    EXPECT_EQ(le16(body, 4), 3u);
    EXPECT_EQ(le16(body, 6), 4u);
    EXPECT_EQ(le16(body, 8), 4u);
    EXPECT_EQ(le16(body, 10), 1u);
}

TEST_F(SdoInfo, OdListIsFragmentedForASmallMailbox) {
    RecordingSender out(16);  // 10 bytes of list per fragment
    server.handle(info(0x01, {0x01, 0x00}), out);
    std::size_t fragments = 0;
    Bytes body = collect(out, 0x02, &fragments);
    const std::size_t total = 2 + 2 * dict.objects().size();
    EXPECT_EQ(fragments, (total + 9) / 10);
    EXPECT_EQ(body.size(), total);
    EXPECT_EQ(le16(body, 0), 1u);
    EXPECT_EQ(indexes(body), expected(1));
}

TEST_F(SdoInfo, FragmentsWaitForRoomInTheSenderQueue) {
    RecordingSender out(16, 1);
    server.handle(info(0x01, {0x01, 0x00}), out);
    EXPECT_EQ(out.messages.size(), 1u);
    EXPECT_TRUE(server.output_pending());
    Bytes body = collect(out, 0x02);  // takes one, polls for the next
    EXPECT_EQ(indexes(body), expected(1));
    EXPECT_FALSE(server.output_pending());
}

TEST_F(SdoInfo, ANewRequestCancelsPendingFragments) {
    RecordingSender out(16, 1);
    server.handle(info(0x01, {0x01, 0x00}), out);
    out.take();
    server.handle(info(0x03, {0x00, 0x10}), out);
    Bytes body = collect(out, 0x04);
    EXPECT_EQ(le16(body, 0), 0x1000u);
    server.poll(0, out);
    EXPECT_TRUE(out.messages.empty());
}

TEST_F(SdoInfo, ObjectDescription) {
    RecordingSender out;
    server.handle(info(0x03, {0x18, 0x10}), out);
    ASSERT_EQ(out.messages.size(), 1u);
    Bytes want{0x00, 0x80, 0x04, 0x00, 0x00, 0x00, 0x18, 0x10, 0x23, 0x00, 0x04, 0x09};
    for (char c : std::string("Identity"))
        want.push_back(static_cast<uint8_t>(c));
    EXPECT_EQ(out.take().payload, want);
}

TEST_F(SdoInfo, ObjectDescriptionOfVarAndArray) {
    RecordingSender out;
    server.handle(info(0x03, {0x41, 0x60}), out);
    Bytes r = out.take().payload;
    EXPECT_EQ(le16(r, 8), 0x0006u);  // UNSIGNED16
    EXPECT_EQ(r[10], 0);
    EXPECT_EQ(r[11], 0x07);  // VAR
    server.handle(info(0x03, {0x12, 0x1C}), out);
    r = out.take().payload;
    EXPECT_EQ(r[10], 2);
    EXPECT_EQ(r[11], 0x08);  // ARRAY
}

TEST_F(SdoInfo, EntryDescriptionWithUnitDefaultMinimumMaximum) {
    RecordingSender out;
    server.handle(info(0x05, {0x02, 0x20, 0x00, 0x78}), out);
    ASSERT_EQ(out.messages.size(), 1u);
    Bytes want{0x00, 0x80, 0x06, 0x00, 0x00, 0x00, 0x02, 0x20, 0x00, 0x78,  // index, subindex, value info
               0x03, 0x00, 0x10, 0x00,                                      // INTEGER16, 16 bits
               0x3F, 0x02,                                                  // rw in all states, setting
               0x00, 0x00, 0x03, 0xFD,                                      // unit: milli (-3) second (0x03)
               0x05, 0x00,                                                  // default 5
               0x9C, 0xFF,                                                  // minimum -100
               0x64, 0x00};                                                 // maximum 100
    for (char c : std::string("Limited"))
        want.push_back(static_cast<uint8_t>(c));
    EXPECT_EQ(out.take().payload, want);
}

TEST_F(SdoInfo, EntryDescriptionWithoutValueInfoAndTypeLimits) {
    RecordingSender out;
    server.handle(info(0x05, {0x41, 0x60, 0x00, 0x07}), out);  // SOEM asks with 0x07: no extra fields
    Bytes r = out.take().payload;
    EXPECT_EQ(r[9], 0x07);
    EXPECT_EQ(le16(r, 10), 0x0006u);
    EXPECT_EQ(le16(r, 12), 16u);
    EXPECT_EQ(le16(r, 14), 0x0087u);  // ro + TxPDO
    EXPECT_EQ(std::string(r.begin() + 16, r.end()), "Statusword");
    // Undeclared limits: the type's own.
    server.handle(info(0x05, {0x41, 0x60, 0x00, 0x60}), out);
    r = out.take().payload;
    EXPECT_EQ(le16(r, 16), 0x0000u);
    EXPECT_EQ(le16(r, 18), 0xFFFFu);
}

TEST_F(SdoInfo, EntryDescriptionOfARecordEntryAndABitEntry) {
    RecordingSender out;
    server.handle(info(0x05, {0x18, 0x10, 0x02, 0x00}), out);
    Bytes r = out.take().payload;
    EXPECT_EQ(le16(r, 10), 0x0007u);
    EXPECT_EQ(le16(r, 12), 32u);
    EXPECT_EQ(std::string(r.begin() + 16, r.end()), "Product Code");
    server.handle(info(0x05, {0x00, 0x30, 0x01, 0x00}), out);
    r = out.take().payload;
    EXPECT_EQ(le16(r, 10), 0x0001u);  // BOOLEAN
    EXPECT_EQ(le16(r, 12), 1u);
}

TEST_F(SdoInfo, ErrorResponsesCarryTheAbortCodeAndALength10) {
    RecordingSender out;
    server.handle(info(0x03, {0x55, 0x55}), out);
    EXPECT_EQ(out.take().payload, (Bytes{0x00, 0x80, 0x07, 0x00, 0x00, 0x00, 0x00, 0x00, 0x02, 0x06}));
    server.handle(info(0x05, {0x18, 0x10, 0x09, 0x00}), out);
    EXPECT_EQ(out.take().payload, (Bytes{0x00, 0x80, 0x07, 0x00, 0x00, 0x00, 0x11, 0x00, 0x09, 0x06}));
    server.handle(info(0x05, {0x55, 0x55, 0x00, 0x00}), out);
    EXPECT_EQ(out.take().payload, (Bytes{0x00, 0x80, 0x07, 0x00, 0x00, 0x00, 0x00, 0x00, 0x02, 0x06}));
    server.handle(info(0x01, {0x06, 0x00}), out);  // no list type 6
    EXPECT_EQ(le32(out.take().payload, 6), coe::abort::ValueRange);
    server.handle(info(0x09, {}), out);  // unknown opcode
    EXPECT_EQ(le32(out.take().payload, 6), coe::abort::UnknownCommand);
}

TEST_F(SdoInfo, LongEntryDescriptionIsFragmented) {
    RecordingSender out(12);
    server.handle(info(0x05, {0x02, 0x20, 0x00, 0x78}), out);
    std::size_t fragments = 0;
    Bytes body = collect(out, 0x06, &fragments);
    EXPECT_EQ(body.size(), 20u + 7u);
    EXPECT_EQ(fragments, (27u + 5u) / 6u);
    EXPECT_EQ(std::string(body.begin() + 20, body.end()), "Limited");
}

TEST(SdoInfoUnits, SiUnitsWithPrefixes) {
    EXPECT_EQ(coe::unit_code("ms"), 0xFD030000u);
    EXPECT_EQ(coe::unit_code("s"), 0x00030000u);
    EXPECT_EQ(coe::unit_code("mA"), 0xFD040000u);
    EXPECT_EQ(coe::unit_code("V"), 0x00260000u);
    EXPECT_EQ(coe::unit_code("kHz"), 0x03200000u);
    EXPECT_EQ(coe::unit_code("inc"), 0u);
    EXPECT_EQ(coe::unit_code(""), 0u);
}

}  // namespace
