// SDO server (ETG.1000.6 §5.6.2): byte-level requests and the replies they must get.
#include <gtest/gtest.h>

#include <numeric>

#include "coe/abort.hpp"
#include "coe/pdo_validation.hpp"
#include "coe/sdo_server.hpp"
#include "coe_test_support.hpp"

using namespace coe_test;

namespace {

class SdoServer : public ::testing::Test {
  protected:
    od::Dictionary dict = make_test_dictionary();
    od::AlState state = od::AlState::PreOp;
    coe::CoeServer server{dict, [this] { return state; }};
    RecordingSender out;

    // Sends one request and returns the one reply it must produce.
    Bytes ask(const Bytes& request) {
        server.handle(request, out);
        EXPECT_EQ(out.messages.size(), 1u);
        if (out.messages.empty()) return {};
        Sent s = out.take();
        EXPECT_EQ(s.type, ecat::MailboxType::CoE);
        return s.payload;
    }
    Bytes big_value(std::size_t n) {
        Bytes v(n);
        std::iota(v.begin(), v.end(), uint8_t{1});
        EXPECT_EQ(dict.set_raw(0x2000, 0, v), od::Status::Ok);
        return v;
    }
};

// ---- Expedited ------------------------------------------------------------------------------------------

TEST_F(SdoServer, ExpeditedUploadOf4ByteEntryAnswers43) {
    // Worked example: read 0x1018:01.
    EXPECT_EQ(ask(sdo(0x40, 0x1018, 1)), (Bytes{0x00, 0x30, 0x43, 0x18, 0x10, 0x01, 0xFB, 0x00, 0x00, 0x00}));
}

TEST_F(SdoServer, ExpeditedUploadOf2And1ByteEntriesAnswer4BAnd4F) {
    EXPECT_EQ(ask(sdo(0x40, 0x6041, 0)), (Bytes{0x00, 0x30, 0x4B, 0x41, 0x60, 0x00, 0x50, 0x02, 0x00, 0x00}));
    EXPECT_EQ(ask(sdo(0x40, 0x6060, 0)), (Bytes{0x00, 0x30, 0x4F, 0x60, 0x60, 0x00, 0x08, 0x00, 0x00, 0x00}));
    // EPOS4 Application Notes §5.4: read 0x6064 -> 43 64 60 00 CA 04 00 00 (= 1226).
    EXPECT_EQ(ask(sdo(0x40, 0x6064, 0)), (Bytes{0x00, 0x30, 0x43, 0x64, 0x60, 0x00, 0xCA, 0x04, 0x00, 0x00}));
}

TEST_F(SdoServer, ExpeditedDownloadWithSizeIndicated) {
    EXPECT_EQ(ask(sdo(0x2B, 0x6040, 0, 0x000F)), (Bytes{0x00, 0x30, 0x60, 0x40, 0x60, 0x00, 0, 0, 0, 0}));
    EXPECT_EQ(dict.get<uint16_t>(0x6040, 0), 0x000F);
    EXPECT_EQ(ask(sdo(0x23, 0x607A, 0, 0xFFFFFF38)), (Bytes{0x00, 0x30, 0x60, 0x7A, 0x60, 0x00, 0, 0, 0, 0}));
    EXPECT_EQ(dict.get<int32_t>(0x607A, 0), -200);
    EXPECT_EQ(ask(sdo(0x2F, 0x6060, 0, 0x01)), (Bytes{0x00, 0x30, 0x60, 0x60, 0x60, 0x00, 0, 0, 0, 0}));
    EXPECT_EQ(dict.get<int8_t>(0x6060, 0), 1);
}

TEST_F(SdoServer, ExpeditedDownloadWithoutSizeTakesTheEntrySize) {
    // EPOS4 Application Notes §5.4: write 0x6040 = 0x000F as 22 40 60 00 0F 00 00 00.
    EXPECT_EQ(ask(sdo(0x22, 0x6040, 0, 0x000F)), (Bytes{0x00, 0x30, 0x60, 0x40, 0x60, 0x00, 0, 0, 0, 0}));
    EXPECT_EQ(dict.get<uint16_t>(0x6040, 0), 0x000F);
}

// ---- Normal and segmented -------------------------------------------------------------------------------

TEST_F(SdoServer, NormalUploadOfAStringCarriesSizeAndData) {
    EXPECT_EQ(ask(sdo(0x40, 0x1008, 0)), (Bytes{0x00, 0x30, 0x41, 0x08, 0x10, 0x00, 0x06, 0x00, 0x00, 0x00,
                                                'M', 'A', 'X', 'P', 'O', 'S'}));
}

TEST_F(SdoServer, SegmentedUploadAlternatesToggleAndEndsWithLastBit) {
    Bytes v = big_value(300);
    Bytes r = ask(sdo(0x40, 0x2000, 0));
    ASSERT_EQ(r.size(), 122u);  // initiate response: 10 + (122 - 10) bytes of data
    EXPECT_EQ(r[2], 0x41);
    EXPECT_EQ(le32(r, 6), 300u);
    Bytes got(r.begin() + 10, r.end());
    EXPECT_TRUE(server.transfer_in_progress());

    r = ask(segment(0x60, Bytes(7, 0)));
    ASSERT_EQ(r.size(), 122u);
    EXPECT_EQ(r[2], 0x00);  // toggle 0, more to come
    got.insert(got.end(), r.begin() + 3, r.end());

    r = ask(segment(0x70, Bytes(7, 0)));
    ASSERT_EQ(r.size(), 3u + (300 - 112 - 119));
    EXPECT_EQ(r[2], 0x11);  // toggle 1, last segment
    got.insert(got.end(), r.begin() + 3, r.end());
    EXPECT_EQ(got, v);
    EXPECT_FALSE(server.transfer_in_progress());
}

TEST_F(SdoServer, ShortLastUploadSegmentIsPaddedToSevenBytes) {
    Bytes v = big_value(112 + 3);
    Bytes r = ask(sdo(0x40, 0x2000, 0));
    ASSERT_EQ(r.size(), 122u);
    r = ask(segment(0x60, Bytes(7, 0)));
    // toggle 0, 4 unused bytes (bits 3:1 = 4), last: 0x09; mailbox length stays 10.
    EXPECT_EQ(r, (Bytes{0x00, 0x30, 0x09, v[112], v[113], v[114], 0, 0, 0, 0}));
}

TEST_F(SdoServer, SegmentedDownloadStoresTheWholeValue) {
    Bytes v(200);
    std::iota(v.begin(), v.end(), uint8_t{7});
    Bytes req = sdo(0x21, 0x2000, 0, 200);
    req.insert(req.end(), v.begin(), v.begin() + 50);
    EXPECT_EQ(ask(req), (Bytes{0x00, 0x30, 0x60, 0x00, 0x20, 0x00, 0, 0, 0, 0}));
    EXPECT_TRUE(server.transfer_in_progress());

    EXPECT_EQ(ask(segment(0x00, Bytes(v.begin() + 50, v.begin() + 169))),
              (Bytes{0x00, 0x30, 0x20, 0, 0, 0, 0, 0, 0, 0}));
    EXPECT_EQ(ask(segment(0x11, Bytes(v.begin() + 169, v.end()))),
              (Bytes{0x00, 0x30, 0x30, 0, 0, 0, 0, 0, 0, 0}));
    auto stored = dict.raw(0x2000, 0);
    EXPECT_EQ(Bytes(stored.begin(), stored.end()), v);
}

TEST_F(SdoServer, ShortDownloadSegmentUsesTheUnusedBytesField) {
    Bytes req = sdo(0x21, 0x2000, 0, 10, {1, 2, 3, 4, 5, 6, 7});
    ask(req);
    // 3 data bytes padded to 7: toggle 0, unused 4 (0x08), last (0x01).
    EXPECT_EQ(ask(segment(0x09, Bytes{8, 9, 10, 0, 0, 0, 0})),
              (Bytes{0x00, 0x30, 0x20, 0, 0, 0, 0, 0, 0, 0}));
    auto stored = dict.raw(0x2000, 0);
    EXPECT_EQ(Bytes(stored.begin(), stored.end()), (Bytes{1, 2, 3, 4, 5, 6, 7, 8, 9, 10}));
}

TEST_F(SdoServer, NormalDownloadThatFitsNeedsNoSegments) {
    EXPECT_EQ(ask(sdo(0x21, 0x2000, 0, 5, {'h', 'e', 'l', 'l', 'o'})),
              (Bytes{0x00, 0x30, 0x60, 0x00, 0x20, 0x00, 0, 0, 0, 0}));
    EXPECT_FALSE(server.transfer_in_progress());
    EXPECT_EQ(dict.raw(0x2000, 0).size(), 5u);
}

// KickCAT sends every download of more than 4 bytes that fits one mailbox as a normal initiate with the size
// indicator clear: 0x20 (0x30 with complete access), Complete Size, then the data (ETG.1000.6 §5.6.2.1.1:
// with e = 0 the Complete Size field is present whatever s says). The slave must store it, not wait for
// segments.
TEST_F(SdoServer, NormalDownloadWithSizeBitClearButCompleteSizeIsStoredAtOnce) {
    EXPECT_EQ(ask(sdo(0x20, 0x2000, 0, 5, {'h', 'e', 'l', 'l', 'o'})),
              (Bytes{0x00, 0x30, 0x60, 0x00, 0x20, 0x00, 0, 0, 0, 0}));
    EXPECT_FALSE(server.transfer_in_progress());
    auto stored = dict.raw(0x2000, 0);
    EXPECT_EQ(Bytes(stored.begin(), stored.end()), (Bytes{'h', 'e', 'l', 'l', 'o'}));
}

TEST_F(SdoServer, CompleteAccessDownloadWithSizeBitClearChangesTheAssignment) {
    // Exactly KickCAT's request for 0x1C12 := {0x1600, 0x1601} with complete access.
    Bytes req = sdo(0x30, 0x1C12, 0, 6, {0x02, 0x00, 0x00, 0x16, 0x01, 0x16});
    EXPECT_EQ(ask(req), (Bytes{0x00, 0x30, 0x70, 0x12, 0x1C, 0x00, 0, 0, 0, 0}));
    EXPECT_FALSE(server.transfer_in_progress());
    EXPECT_EQ(dict.get<uint8_t>(0x1C12, 0), 2);
    EXPECT_EQ(dict.get<uint16_t>(0x1C12, 1), 0x1600);
    EXPECT_EQ(dict.get<uint16_t>(0x1C12, 2), 0x1601);
}

TEST_F(SdoServer, SizeBitClearCompleteSizeLargerThanTheDataPresentContinuesWithSegments) {
    EXPECT_EQ(ask(sdo(0x20, 0x2000, 0, 10, {1, 2, 3, 4})),
              (Bytes{0x00, 0x30, 0x60, 0x00, 0x20, 0x00, 0, 0, 0, 0}));
    EXPECT_TRUE(server.transfer_in_progress());
    // The Complete Size is binding: a last segment that leaves bytes missing is refused, nothing stored.
    Bytes before(dict.raw(0x2000, 0).begin(), dict.raw(0x2000, 0).end());
    EXPECT_EQ(ask(segment(0x07, Bytes{5, 6, 7, 8, 0, 0, 0})), abort_reply(0x2000, 0, 0x06070013));
    EXPECT_EQ(Bytes(dict.raw(0x2000, 0).begin(), dict.raw(0x2000, 0).end()), before);
    // Complete with the right number of bytes: stored.
    ask(sdo(0x20, 0x2000, 0, 10, {1, 2, 3, 4}));
    EXPECT_EQ(ask(segment(0x03, Bytes{5, 6, 7, 8, 9, 10, 0})),
              (Bytes{0x00, 0x30, 0x20, 0, 0, 0, 0, 0, 0, 0}));
    auto stored = dict.raw(0x2000, 0);
    EXPECT_EQ(Bytes(stored.begin(), stored.end()), (Bytes{1, 2, 3, 4, 5, 6, 7, 8, 9, 10}));
}

TEST_F(SdoServer, SizeBitClearCompleteSizeAboveTheEntryIs06070012) {
    EXPECT_EQ(ask(sdo(0x20, 0x2000, 0, 301, {1, 2, 3, 4})), abort_reply(0x2000, 0, 0x06070012));
    EXPECT_FALSE(server.transfer_in_progress());
    // Complete access: 0x1C12 holds SI0 + 2 entries = 6 bytes; 8 announced and present.
    EXPECT_EQ(ask(sdo(0x30, 0x1C12, 0, 8, {0x02, 0x00, 0x00, 0x16, 0x01, 0x16, 0x00, 0x00})),
              abort_reply(0x1C12, 0, 0x06070012));
    EXPECT_EQ(dict.get<uint8_t>(0x1C12, 0), 1);
}

TEST_F(SdoServer, BytesBeyondTheCompleteSizeAreNotStored) {
    // A master that pads its message: the Complete Size it named is what it meant, with s = 0 as with s = 1.
    for (uint8_t cmd : {uint8_t{0x20}, uint8_t{0x21}}) {
        EXPECT_EQ(ask(sdo(cmd, 0x2000, 0, 5, {'w', 'o', 'r', 'l', 'd', 0, 0, 0})),
                  (Bytes{0x00, 0x30, 0x60, 0x00, 0x20, 0x00, 0, 0, 0, 0}));
        auto stored = dict.raw(0x2000, 0);
        EXPECT_EQ(Bytes(stored.begin(), stored.end()), (Bytes{'w', 'o', 'r', 'l', 'd'}));
    }
}

TEST_F(SdoServer, SizeBitClearWithCompleteSizeZeroLeavesTheSizeToTheSegments) {
    // Nothing announced: the data present is kept and segments follow, up to the entry's capacity.
    EXPECT_EQ(ask(sdo(0x20, 0x2000, 0, 0, {1, 2, 3})),
              (Bytes{0x00, 0x30, 0x60, 0x00, 0x20, 0x00, 0, 0, 0, 0}));
    EXPECT_TRUE(server.transfer_in_progress());
    EXPECT_EQ(ask(segment(0x09, Bytes{4, 5, 6, 0, 0, 0, 0})), (Bytes{0x00, 0x30, 0x20, 0, 0, 0, 0, 0, 0, 0}));
    auto stored = dict.raw(0x2000, 0);
    EXPECT_EQ(Bytes(stored.begin(), stored.end()), (Bytes{1, 2, 3, 4, 5, 6}));
}

TEST_F(SdoServer, DownloadSegmentWithWrongToggleAbortsWith05030000) {
    ask(sdo(0x21, 0x2000, 0, 20, {1, 2, 3, 4}));
    EXPECT_EQ(ask(segment(0x10, Bytes(7, 0))), abort_reply(0x2000, 0, coe::abort::ToggleBit));
    EXPECT_FALSE(server.transfer_in_progress());
}

TEST_F(SdoServer, UploadSegmentWithWrongToggleAbortsWith05030000) {
    big_value(300);
    ask(sdo(0x40, 0x2000, 0));
    EXPECT_EQ(ask(segment(0x70, Bytes(7, 0))), abort_reply(0x2000, 0, coe::abort::ToggleBit));
    EXPECT_FALSE(server.transfer_in_progress());
}

TEST_F(SdoServer, SegmentWithoutTransferAbortsWith05040001) {
    EXPECT_EQ(ask(segment(0x60, Bytes(7, 0))), abort_reply(0, 0, coe::abort::UnknownCommand));
    EXPECT_EQ(ask(segment(0x00, Bytes(7, 0))), abort_reply(0, 0, coe::abort::UnknownCommand));
}

TEST_F(SdoServer, NewRequestCancelsAStaleSegmentedTransfer) {
    big_value(300);
    ask(sdo(0x40, 0x2000, 0));
    ASSERT_TRUE(server.transfer_in_progress());
    // The master abandons the upload and reads something else: answered normally.
    EXPECT_EQ(ask(sdo(0x40, 0x1000, 0)), (Bytes{0x00, 0x30, 0x43, 0x00, 0x10, 0x00, 0x92, 0x01, 0x02, 0x00}));
    EXPECT_FALSE(server.transfer_in_progress());
    EXPECT_EQ(ask(segment(0x60, Bytes(7, 0))), abort_reply(0, 0, coe::abort::UnknownCommand));
}

TEST_F(SdoServer, AbandonedTransferTimesOutInPollWith05040000) {
    big_value(300);
    ask(sdo(0x40, 0x2000, 0));
    server.poll(1'000'000'000, out);  // stamps the transfer
    server.poll(2'500'000'000, out);  // 1.5 s: still alive
    EXPECT_TRUE(out.messages.empty());
    server.poll(3'000'000'001, out);
    ASSERT_EQ(out.messages.size(), 1u);
    EXPECT_EQ(out.take().payload, abort_reply(0x2000, 0, coe::abort::Timeout));
    EXPECT_FALSE(server.transfer_in_progress());
}

TEST_F(SdoServer, MasterAbortEndsTheTransferSilently) {
    big_value(300);
    ask(sdo(0x40, 0x2000, 0));
    server.handle(sdo(0x80, 0x2000, 0, coe::abort::General), out);
    EXPECT_TRUE(out.messages.empty());
    EXPECT_FALSE(server.transfer_in_progress());
}

// ---- Abort codes ----------------------------------------------------------------------------------------

TEST_F(SdoServer, AbortObjectDoesNotExist06020000) {
    EXPECT_EQ(ask(sdo(0x40, 0x5555, 0)), abort_reply(0x5555, 0, 0x06020000));
    EXPECT_EQ(ask(sdo(0x2F, 0x5555, 0, 1)), abort_reply(0x5555, 0, 0x06020000));
}

TEST_F(SdoServer, AbortSubindexDoesNotExist06090011) {
    // EPOS4 Application Notes §5.4.2: abort bytes 4..7 = 11 00 09 06.
    EXPECT_EQ(ask(sdo(0x40, 0x1018, 7)), (Bytes{0x00, 0x20, 0x80, 0x18, 0x10, 0x07, 0x11, 0x00, 0x09, 0x06}));
}

TEST_F(SdoServer, AbortReadOnly06010002AndWriteOnly06010001) {
    EXPECT_EQ(ask(sdo(0x23, 0x1000, 0, 1)), abort_reply(0x1000, 0, 0x06010002));
    EXPECT_EQ(ask(sdo(0x40, 0x2001, 0)), abort_reply(0x2001, 0, 0x06010001));
}

TEST_F(SdoServer, AbortLengthTooHigh06070012AndTooLow06070013) {
    EXPECT_EQ(ask(sdo(0x23, 0x6040, 0, 0x000F)), abort_reply(0x6040, 0, 0x06070012));
    EXPECT_EQ(ask(sdo(0x2F, 0x6040, 0, 0x0F)), abort_reply(0x6040, 0, 0x06070013));
    // A normal download announcing more than the entry can hold is refused before any segment.
    EXPECT_EQ(ask(sdo(0x21, 0x2000, 0, 301)), abort_reply(0x2000, 0, 0x06070012));
    // A segmented download ending short of its announced size.
    ask(sdo(0x21, 0x2000, 0, 20, {1, 2, 3, 4}));
    EXPECT_EQ(ask(segment(0x01, Bytes{1, 2, 3, 4, 5, 6, 7})), abort_reply(0x2000, 0, 0x06070013));
}

TEST_F(SdoServer, AbortValueTooHigh06090031TooLow06090032) {
    EXPECT_EQ(ask(sdo(0x2B, 0x2002, 0, 101)), abort_reply(0x2002, 0, 0x06090031));
    EXPECT_EQ(ask(sdo(0x2B, 0x2002, 0, 0xFF9B)), abort_reply(0x2002, 0, 0x06090032));  // -101
    EXPECT_EQ(ask(sdo(0x2B, 0x2002, 0, 100)), (Bytes{0x00, 0x30, 0x60, 0x02, 0x20, 0x00, 0, 0, 0, 0}));
}

TEST_F(SdoServer, AbortValueRange06090030FromAValidator) {
    // Diagnosis history flags: bits above b5 are not supported.
    coe::DiagnosisHistory diag(dict, &server.emergency());
    EXPECT_EQ(ask(sdo(0x2B, 0x10F3, 5, 0x0040)), abort_reply(0x10F3, 5, 0x06090030));
}

TEST_F(SdoServer, AbortWrongState08000022) {
    EXPECT_EQ(ask(sdo(0x2F, 0x2003, 0, 1)), abort_reply(0x2003, 0, 0x08000022));
    state = od::AlState::SafeOp;
    EXPECT_EQ(ask(sdo(0x2F, 0x1600, 0, 0)), abort_reply(0x1600, 0, 0x08000022));
    state = od::AlState::Op;
    EXPECT_EQ(ask(sdo(0x2F, 0x2003, 0, 1)), (Bytes{0x00, 0x30, 0x60, 0x03, 0x20, 0x00, 0, 0, 0, 0}));
}

// An ESI may declare the assignment and mapping objects "rw" in every state (Beckhoff terminals, Inovance
// drives); the device still refuses their change while process data runs (ETG.1000.6 PDO assignment).
TEST(SdoServerPdoObjects, ChangeRefusedOutsidePreOpWhateverTheAccessFlags) {
    od::Dictionary d;
    d.add(composite(0x1600, od::ObjectCode::Record, "RxPDO 1", od::DataType::PdoMapping,
                    {entry(0, "Number of entries", od::DataType::Unsigned8, od::access::RW, uint64_t{1}),
                     entry(1, "Entry 1", od::DataType::Unsigned32, od::access::RW, uint64_t{0x70000108})}));
    d.add(
        composite(0x1C12, od::ObjectCode::Array, "RxPDO assign", od::DataType::Unsigned16,
                  {entry(0, "Number of assigned PDOs", od::DataType::Unsigned8, od::access::RW, uint64_t{1}),
                   entry(1, "PDO 1", od::DataType::Unsigned16, od::access::RW, uint64_t{0x1600})}));
    d.add(var(0x2000, "Setting", entry(0, "", od::DataType::Unsigned8, od::access::RW)));
    od::AlState state = od::AlState::SafeOp;
    coe::CoeServer server{d, [&state] { return state; }};
    RecordingSender out;
    auto ask = [&](const Bytes& request) {
        server.handle(request, out);
        return out.messages.empty() ? Bytes{} : out.take().payload;
    };
    for (od::AlState s : {od::AlState::SafeOp, od::AlState::Op}) {
        state = s;
        EXPECT_EQ(ask(sdo(0x2F, 0x1C12, 0, 1)), abort_reply(0x1C12, 0, 0x08000022));
        EXPECT_EQ(ask(sdo(0x2F, 0x1600, 0, 1)), abort_reply(0x1600, 0, 0x08000022));
        // Segmented too (normal download of 4 bytes, size indicated).
        EXPECT_EQ(ask(Bytes{0x00, 0x20, 0x21, 0x00, 0x16, 0x01, 4, 0, 0, 0, 0x08, 0x01, 0x00, 0x70}),
                  abort_reply(0x1600, 1, 0x08000022));
        // Other "rw" objects stay writable.
        EXPECT_EQ(ask(sdo(0x2F, 0x2000, 0, 5)), (Bytes{0x00, 0x30, 0x60, 0x00, 0x20, 0x00, 0, 0, 0, 0}));
    }
    EXPECT_EQ(d.get<uint8_t>(0x1C12, 0), 1);
    state = od::AlState::PreOp;
    EXPECT_EQ(ask(sdo(0x2F, 0x1C12, 0, 0)), (Bytes{0x00, 0x30, 0x60, 0x12, 0x1C, 0x00, 0, 0, 0, 0}));
    EXPECT_EQ(d.get<uint8_t>(0x1C12, 0), 0);
}

TEST_F(SdoServer, AbortNotMappable06040041AndPdoLength06040042) {
    coe::install_pdo_validators(dict, coe::PdoLimits{4});
    EXPECT_EQ(ask(sdo(0x2F, 0x1600, 0, 0)), (Bytes{0x00, 0x30, 0x60, 0x00, 0x16, 0x00, 0, 0, 0, 0}));
    EXPECT_EQ(ask(sdo(0x23, 0x1600, 1, 0x60410010)), abort_reply(0x1600, 1, 0x06040041));
    // 0x6040 (16) + 0x607A (32) = 6 bytes > 4.
    EXPECT_EQ(ask(sdo(0x2F, 0x1600, 0, 2)), abort_reply(0x1600, 0, 0x06040042));
}

TEST_F(SdoServer, AbortUnknownCommandSpecifier05040001) {
    EXPECT_EQ(ask(sdo(0xE0, 0x1000, 0)), abort_reply(0x1000, 0, 0x05040001));
    EXPECT_EQ(ask(sdo(0xC0, 0x1000, 0)), abort_reply(0x1000, 0, 0x05040001));  // block download: not CoE
    EXPECT_EQ(ask(sdo(0xA0, 0x1000, 0)), abort_reply(0x1000, 0, 0x05040001));  // block upload: not CoE
}

TEST_F(SdoServer, AbortCompleteAccessFromSubindexAbove1Is06010000) {
    EXPECT_EQ(ask(sdo(0x50, 0x1018, 2)), abort_reply(0x1018, 2, 0x06010000));
}

// A device that does not announce complete access (ESI CoE CompleteAccess absent, SII CoE details bit 5
// clear) aborts complete-access uploads and downloads with 0x06010004 (ETG.1000.6); single entries work.
TEST(SdoServerWithoutCompleteAccess, CompleteAccessIsAbortedWith06010004) {
    od::Dictionary dict = make_test_dictionary();
    coe::CoeConfig config;
    config.complete_access = false;
    coe::CoeServer server{dict, [] { return od::AlState::PreOp; }, config};
    RecordingSender out;
    auto ask = [&](const Bytes& request) {
        server.handle(request, out);
        return out.messages.empty() ? Bytes{} : out.take().payload;
    };
    EXPECT_EQ(ask(sdo(0x50, 0x1018, 0)), abort_reply(0x1018, 0, 0x06010004));
    EXPECT_EQ(ask(sdo(0x31, 0x1C12, 0)), abort_reply(0x1C12, 0, 0x06010004));
    EXPECT_EQ(ask(sdo(0x40, 0x1018, 1)), (Bytes{0x00, 0x30, 0x43, 0x18, 0x10, 0x01, 0xFB, 0x00, 0x00, 0x00}));
}

TEST(SdoAbortCodes, EveryObjectModelResultMapsToItsStandardCode) {
    using S = od::Status;
    const std::pair<S, uint32_t> table[] = {
        {S::Ok, 0},
        {S::NoObject, 0x06020000},
        {S::NoSubindex, 0x06090011},
        {S::ReadOnly, 0x06010002},
        {S::WriteOnly, 0x06010001},
        {S::LengthMismatch, 0x06070010},
        {S::LengthTooHigh, 0x06070012},
        {S::LengthTooLow, 0x06070013},
        {S::ValueTooHigh, 0x06090031},
        {S::ValueTooLow, 0x06090032},
        {S::InvalidValue, 0x06090030},
        {S::MaxBelowMin, 0x06090036},
        {S::NotMappable, 0x06040041},
        {S::PdoLengthExceeded, 0x06040042},
        {S::Incompatible, 0x06040043},
        {S::WrongState, 0x08000022},
        {S::CannotStore, 0x08000020},
        {S::HardwareError, 0x06060000},
        {S::OutOfMemory, 0x05040005},
        {S::GeneralError, 0x08000000},
    };
    for (auto [s, code] : table)
        EXPECT_EQ(coe::abort_code(s), code) << od::to_string(s);
}

TEST_F(SdoServer, ValidatorResultsReachTheMasterAsTheirAbortCodes) {
    // Results only the application produces (store failures, general errors, length mismatch) still travel.
    od::Status next = od::Status::CannotStore;
    dict.add_validator(0x2002, [&](const od::Entry&, std::span<const uint8_t>) { return next; });
    EXPECT_EQ(ask(sdo(0x2B, 0x2002, 0, 1)), abort_reply(0x2002, 0, 0x08000020));
    next = od::Status::GeneralError;
    EXPECT_EQ(ask(sdo(0x2B, 0x2002, 0, 1)), abort_reply(0x2002, 0, 0x08000000));
    next = od::Status::LengthMismatch;
    EXPECT_EQ(ask(sdo(0x2B, 0x2002, 0, 1)), abort_reply(0x2002, 0, 0x06070010));
}

// ---- Complete access ------------------------------------------------------------------------------------

TEST_F(SdoServer, CompleteAccessUploadOf1C12PadsSubindex0To16Bits) {
    // ETG.1000.6 complete access: subindex 0 travels as 16 bits, so 0x1C12 with one PDO reads 01 00 | 00 16.
    EXPECT_EQ(ask(sdo(0x50, 0x1C12, 0)), (Bytes{0x00, 0x30, 0x53, 0x12, 0x1C, 0x00, 0x01, 0x00, 0x00, 0x16}));
}

TEST_F(SdoServer, CompleteAccessUploadOfARecordCarriesEveryEntry) {
    Bytes r = ask(sdo(0x50, 0x1018, 0));
    EXPECT_EQ(r, (Bytes{0x00, 0x30, 0x51, 0x18, 0x10, 0x00, 18,   0,    0,    0,  // normal, CA, size 18
                        0x04, 0x00,                                               // SI0 + padding
                        0xFB, 0,    0,    0,    0x00, 0x00, 0x01, 0x30, 0x00, 0x00,
                        0x20, 0x01, 0x78, 0x56, 0x34, 0x12}));
}

TEST_F(SdoServer, CompleteAccessUploadFromSubindex1LeavesSubindex0Out) {
    Bytes r = ask(sdo(0x50, 0x1018, 1));
    ASSERT_EQ(r.size(), 26u);
    EXPECT_EQ(le32(r, 6), 16u);
    EXPECT_EQ(le32(r, 10), 0xFBu);
    EXPECT_EQ(le32(r, 22), 0x12345678u);
}

TEST_F(SdoServer, CompleteAccessPacksBitEntries) {
    // 0x3000: SI0 (16 bits), Bit A at bit 16, Bit B at bit 17, Word on the next byte boundary.
    EXPECT_EQ(ask(sdo(0x50, 0x3000, 0)),
              (Bytes{0x00, 0x30, 0x51, 0x00, 0x30, 0x00, 5, 0, 0, 0, 0x03, 0x00, 0x01, 0xEF, 0xBE}));
    Bytes req = sdo(0x31, 0x3000, 0, 5, {0x03, 0x00, 0x02, 0x34, 0x12});
    EXPECT_EQ(ask(req), (Bytes{0x00, 0x30, 0x70, 0x00, 0x30, 0x00, 0, 0, 0, 0}));
    EXPECT_EQ(dict.get<uint8_t>(0x3000, 1), 0);
    EXPECT_EQ(dict.get<uint8_t>(0x3000, 2), 1);
    EXPECT_EQ(dict.get<uint16_t>(0x3000, 3), 0x1234);
}

TEST_F(SdoServer, CompleteAccessDownloadOfAnAssignment) {
    // Normal CA download: SI0 = 2, 0x1600, 0x1601.
    Bytes req = sdo(0x31, 0x1C12, 0, 6, {0x02, 0x00, 0x00, 0x16, 0x01, 0x16});
    EXPECT_EQ(ask(req), (Bytes{0x00, 0x30, 0x70, 0x12, 0x1C, 0x00, 0, 0, 0, 0}));
    EXPECT_EQ(dict.get<uint8_t>(0x1C12, 0), 2);
    EXPECT_EQ(dict.get<uint16_t>(0x1C12, 1), 0x1600);
    EXPECT_EQ(dict.get<uint16_t>(0x1C12, 2), 0x1601);
    // Expedited CA download of 4 bytes: SI0 = 1, 0x1601.
    EXPECT_EQ(ask(sdo(0x33, 0x1C12, 0, 0x16010001)), (Bytes{0x00, 0x30, 0x70, 0x12, 0x1C, 0x00, 0, 0, 0, 0}));
    EXPECT_EQ(dict.get<uint8_t>(0x1C12, 0), 1);
    EXPECT_EQ(dict.get<uint16_t>(0x1C12, 1), 0x1601);
}

TEST_F(SdoServer, CompleteAccessDownloadFromSubindex1KeepsSubindex0) {
    EXPECT_EQ(ask(sdo(0x33, 0x1C12, 1, 0x16011600)), (Bytes{0x00, 0x30, 0x70, 0x12, 0x1C, 0x01, 0, 0, 0, 0}));
    EXPECT_EQ(dict.get<uint8_t>(0x1C12, 0), 1);
    EXPECT_EQ(dict.get<uint16_t>(0x1C12, 1), 0x1600);
    EXPECT_EQ(dict.get<uint16_t>(0x1C12, 2), 0x1601);
}

TEST_F(SdoServer, CompleteAccessDownloadOfAWholePdoMappingAsTwinCatDoes) {
    coe::install_pdo_validators(dict);
    Bytes req = sdo(0x31, 0x1600, 0, 14,
                    {0x03, 0x00, 0x10, 0x00, 0x40, 0x60, 0x20, 0x00, 0x7A, 0x60, 0x08, 0x00, 0x60, 0x60});
    EXPECT_EQ(ask(req), (Bytes{0x00, 0x30, 0x70, 0x00, 0x16, 0x00, 0, 0, 0, 0}));
    EXPECT_EQ(dict.get<uint8_t>(0x1600, 0), 3);
    EXPECT_EQ(dict.get<uint32_t>(0x1600, 3), 0x60600008u);
    EXPECT_EQ(coe::mapped_bits(dict, 0x1600), 56u);
}

TEST_F(SdoServer, SegmentedCompleteAccessDownload) {
    coe::install_pdo_validators(dict);
    // 0x1600 whole: SI0 = 4 + four entries = 18 bytes, sent as 6 + 7 + 5.
    Bytes img{0x04, 0x00, 0x10, 0x00, 0x40, 0x60, 0x20, 0x00, 0x7A,
              0x60, 0x08, 0x00, 0x60, 0x60, 0x08, 0x00, 0x00, 0x00};
    Bytes req = sdo(0x31, 0x1600, 0, 18);
    req.insert(req.end(), img.begin(), img.begin() + 6);
    EXPECT_EQ(ask(req), (Bytes{0x00, 0x30, 0x70, 0x00, 0x16, 0x00, 0, 0, 0, 0}));
    EXPECT_EQ(ask(segment(0x00, Bytes(img.begin() + 6, img.begin() + 13))),
              (Bytes{0x00, 0x30, 0x20, 0, 0, 0, 0, 0, 0, 0}));
    Bytes last(img.begin() + 13, img.end());
    last.resize(7, 0);
    EXPECT_EQ(ask(segment(0x15, last)), (Bytes{0x00, 0x30, 0x30, 0, 0, 0, 0, 0, 0, 0}));
    EXPECT_EQ(dict.get<uint8_t>(0x1600, 0), 4);
    EXPECT_EQ(dict.get<uint32_t>(0x1600, 3), 0x60600008u);
    EXPECT_EQ(dict.get<uint32_t>(0x1600, 4), 0x00000008u);  // an 8-bit gap
    EXPECT_EQ(coe::mapped_bits(dict, 0x1600), 64u);
}

TEST_F(SdoServer, FailedCompleteAccessDownloadLeavesTheObjectAsItWas) {
    coe::install_pdo_validators(dict);
    // Entry 2 maps a TxPDO object into an RxPDO: refused, entry 1 and SI0 restored.
    Bytes req = sdo(0x31, 0x1600, 0, 10, {0x02, 0x00, 0x08, 0x00, 0x60, 0x60, 0x10, 0x00, 0x41, 0x60});
    EXPECT_EQ(ask(req), abort_reply(0x1600, 0, 0x06040041));
    EXPECT_EQ(dict.get<uint8_t>(0x1600, 0), 2);
    EXPECT_EQ(dict.get<uint32_t>(0x1600, 1), 0x60400010u);
    EXPECT_EQ(dict.get<uint32_t>(0x1600, 2), 0x607A0020u);
}

TEST_F(SdoServer, CompleteAccessDownloadLengthChecks) {
    // Longer than SI0 + 2 entries of 0x1C12.
    EXPECT_EQ(ask(sdo(0x31, 0x1C12, 0, 8, {0x02, 0x00, 0x00, 0x16, 0x01, 0x16, 0x00, 0x00})),
              abort_reply(0x1C12, 0, 0x06070012));
    // SI0 = 2 but only one entry given.
    EXPECT_EQ(ask(sdo(0x31, 0x1C12, 0, 4, {0x02, 0x00, 0x00, 0x16})), abort_reply(0x1C12, 0, 0x06070013));
    // Half an entry.
    EXPECT_EQ(ask(sdo(0x31, 0x1C12, 0, 5, {0x01, 0x00, 0x00, 0x16, 0x01})),
              abort_reply(0x1C12, 0, 0x06070013));
}

TEST_F(SdoServer, CompleteAccessDownloadOfAReadOnlyObjectIs06010002) {
    Bytes img{0x04, 0x00, 0xFB, 0, 0, 0, 0, 0, 1, 0x30, 0, 0, 0x20, 1, 0x78, 0x56, 0x34, 0x12};
    Bytes req = sdo(0x31, 0x1018, 0, 18);
    req.insert(req.end(), img.begin(), img.end());
    EXPECT_EQ(ask(req), abort_reply(0x1018, 0, 0x06010002));
}

TEST_F(SdoServer, SegmentedCompleteAccessUploadWithSmallMailbox) {
    RecordingSender small(16);
    server.handle(sdo(0x50, 0x1018, 0), small);
    ASSERT_EQ(small.messages.size(), 1u);
    Bytes r = small.take().payload;
    EXPECT_EQ(r[2], 0x51);
    EXPECT_EQ(le32(r, 6), 18u);
    Bytes img(r.begin() + 10, r.end());
    uint8_t toggle = 0;
    while (server.transfer_in_progress()) {
        server.handle(segment(static_cast<uint8_t>(0x60 | (toggle << 4)), Bytes(7, 0)), small);
        ASSERT_EQ(small.messages.size(), 1u);
        Bytes s = small.take().payload;
        std::size_t n = s.size() - 3;
        if (s.size() == 10) n = 7 - ((s[2] >> 1) & 7);
        img.insert(img.end(), s.begin() + 3, s.begin() + 3 + static_cast<std::ptrdiff_t>(n));
        toggle ^= 1;
    }
    EXPECT_EQ(img, (Bytes{0x04, 0x00, 0xFB, 0, 0, 0, 0, 0, 1, 0x30, 0, 0, 0x20, 1, 0x78, 0x56, 0x34, 0x12}));
}

// ---- Mailbox-level behaviour ----------------------------------------------------------------------------

TEST_F(SdoServer, ServedInPreOpSafeOpOpOnly) {
    EXPECT_FALSE(server.available(od::AlState::Init));
    EXPECT_FALSE(server.available(od::AlState::Boot));
    EXPECT_TRUE(server.available(od::AlState::PreOp));
    EXPECT_TRUE(server.available(od::AlState::SafeOp));
    EXPECT_TRUE(server.available(od::AlState::Op));
    EXPECT_EQ(server.type(), ecat::MailboxType::CoE);
}

TEST_F(SdoServer, UnsupportedCoeServiceGetsMailboxErrorServiceNotSupported) {
    server.handle(Bytes{0x00, 0x50, 0, 0, 0, 0, 0, 0, 0, 0}, out);  // RxPDO over mailbox
    ASSERT_EQ(out.messages.size(), 1u);
    Sent s = out.take();
    EXPECT_EQ(s.type, ecat::MailboxType::Error);
    EXPECT_EQ(s.payload, (Bytes{0x01, 0x00, 0x04, 0x00}));
}

TEST_F(SdoServer, TruncatedRequestsGetMailboxErrorSizeTooShort) {
    server.handle(Bytes{0x00}, out);
    server.handle(Bytes{0x00, 0x20, 0x40, 0x00, 0x10}, out);
    ASSERT_EQ(out.messages.size(), 2u);
    for (const auto& s : out.messages) {
        EXPECT_EQ(s.type, ecat::MailboxType::Error);
        EXPECT_EQ(s.payload, (Bytes{0x01, 0x00, 0x06, 0x00}));
    }
}

TEST_F(SdoServer, ReplyTheSenderCannotTakeIsSentFromPoll) {
    out.set_queue(0);
    server.handle(sdo(0x40, 0x1018, 1), out);
    EXPECT_TRUE(out.messages.empty());
    EXPECT_TRUE(server.output_pending());
    out.set_queue(8);
    server.poll(1, out);
    ASSERT_EQ(out.messages.size(), 1u);
    EXPECT_EQ(out.take().payload, (Bytes{0x00, 0x30, 0x43, 0x18, 0x10, 0x01, 0xFB, 0x00, 0x00, 0x00}));
    EXPECT_FALSE(server.output_pending());
}

TEST_F(SdoServer, LeavingTheMailboxStatesDropsTransfers) {
    big_value(300);
    ask(sdo(0x40, 0x2000, 0));
    server.on_state_change(od::AlState::PreOp, od::AlState::Init);
    EXPECT_FALSE(server.transfer_in_progress());
}

}  // namespace
