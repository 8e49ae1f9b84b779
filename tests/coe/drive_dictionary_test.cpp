// The CoE server on od's real drive dictionary (MAXPOS firmware specification, chapter 7).
#include <gtest/gtest.h>

#include <unistd.h>
#include <filesystem>

#include "coe/diagnosis.hpp"
#include "coe/pdo_validation.hpp"
#include "coe/sdo_info.hpp"
#include "coe/sdo_server.hpp"
#include "coe_test_support.hpp"
#include "maxpos/maxpos.hpp"
#include "od/store.hpp"

using namespace coe_test;

namespace {

class DriveDictionary : public ::testing::Test {
  protected:
    od::Dictionary dict = maxpos::dictionary(maxpos::description());
    od::AlState state = od::AlState::PreOp;
    coe::CoeServer server{dict, [this] { return state; }};
    RecordingSender out;

    void SetUp() override { coe::install_pdo_validators(dict); }
    Bytes ask(const Bytes& request) {
        server.handle(request, out);
        EXPECT_EQ(out.messages.size(), 1u);
        return out.messages.empty() ? Bytes{} : out.take().payload;
    }
};

TEST_F(DriveDictionary, IdentityAndDeviceType) {
    EXPECT_EQ(ask(sdo(0x40, 0x1000, 0)), (Bytes{0x00, 0x30, 0x43, 0x00, 0x10, 0x00, 0x92, 0x01, 0x02, 0x00}));
    EXPECT_EQ(ask(sdo(0x40, 0x1018, 1)), (Bytes{0x00, 0x30, 0x43, 0x18, 0x10, 0x01, 0xFB, 0x00, 0x00, 0x00}));
    Bytes r = ask(sdo(0x40, 0x1008, 0));
    EXPECT_EQ(r[2], 0x41);
    EXPECT_EQ(std::string(r.begin() + 10, r.end()), "MAXPOS");
}

TEST_F(DriveDictionary, DefaultAssignmentReadsWithPaddedSubindex0) {
    EXPECT_EQ(ask(sdo(0x50, 0x1C12, 0)), (Bytes{0x00, 0x30, 0x53, 0x12, 0x1C, 0x00, 0x01, 0x00, 0x00, 0x16}));
    EXPECT_EQ(ask(sdo(0x50, 0x1C13, 0)), (Bytes{0x00, 0x30, 0x53, 0x13, 0x1C, 0x00, 0x01, 0x00, 0x00, 0x1A}));
}

TEST_F(DriveDictionary, CompleteAccessUploadOfEveryObjectSucceeds) {
    // Every object of the drive can be read whole; segmented ones are read to the end.
    for (const auto& obj : dict.objects()) {
        server.handle(sdo(0x50, obj.index, 0), out);
        ASSERT_EQ(out.messages.size(), 1u) << std::hex << obj.index;
        Bytes r = out.take().payload;
        EXPECT_NE(r[2], 0x80) << std::hex << obj.index << " abort " << le32(r, 6);
        uint8_t toggle = 0;
        while (server.transfer_in_progress()) {
            server.handle(segment(static_cast<uint8_t>(0x60 | (toggle << 4)), Bytes(7, 0)), out);
            ASSERT_EQ(out.messages.size(), 1u);
            EXPECT_NE(out.take().payload[2], 0x80);
            toggle ^= 1;
        }
    }
}

TEST_F(DriveDictionary, RemapAndCompleteAccessDownloadOfThePdoObjects) {
    EXPECT_EQ(ask(sdo(0x2F, 0x1C12, 0, 0)), (Bytes{0x00, 0x30, 0x60, 0x12, 0x1C, 0x00, 0, 0, 0, 0}));
    Bytes req = sdo(0x31, 0x1600, 0, 10, {0x02, 0x00, 0x10, 0x00, 0x40, 0x60, 0x20, 0x00, 0x7A, 0x60});
    EXPECT_EQ(ask(req), (Bytes{0x00, 0x30, 0x70, 0x00, 0x16, 0x00, 0, 0, 0, 0}));
    EXPECT_EQ(coe::mapped_bits(dict, 0x1600), 48u);
    EXPECT_EQ(ask(sdo(0x33, 0x1C12, 0, 0x16000001)), (Bytes{0x00, 0x30, 0x70, 0x12, 0x1C, 0x00, 0, 0, 0, 0}));
    EXPECT_EQ(dict.get<uint8_t>(0x1C12, 0), 1);
    // An entry while the count is 2: subindex 0 must be 0 first (ETG.1000.6).
    EXPECT_EQ(ask(sdo(0x23, 0x1600, 1, 0x60400010)), abort_reply(0x1600, 1, 0x06010003));
    // Statusword is not an RxPDO object.
    EXPECT_EQ(ask(sdo(0x2F, 0x1600, 0, 0)), (Bytes{0x00, 0x30, 0x60, 0x00, 0x16, 0x00, 0, 0, 0, 0}));
    EXPECT_EQ(ask(sdo(0x23, 0x1600, 1, 0x60410010)), abort_reply(0x1600, 1, 0x06040041));
    state = od::AlState::Op;
    EXPECT_EQ(ask(sdo(0x2F, 0x1C12, 0, 0)), abort_reply(0x1C12, 0, 0x08000022));
}

TEST_F(DriveDictionary, WholeArrayDownloadWithZerosPastTheCount) {
    // 0x1C12 entries only take 0x1600..0x1603 (MAXPOS firmware specification §7.2.15); zeros past the count
    // are not an error.
    Bytes req = sdo(0x31, 0x1C12, 0, 10, {0x01, 0x00, 0x01, 0x16, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00});
    EXPECT_EQ(ask(req), (Bytes{0x00, 0x30, 0x70, 0x12, 0x1C, 0x00, 0, 0, 0, 0}));
    EXPECT_EQ(dict.get<uint8_t>(0x1C12, 0), 1);
    EXPECT_EQ(dict.get<uint16_t>(0x1C12, 1), 0x1601);
    EXPECT_EQ(dict.get<uint16_t>(0x1C12, 2), 0x1601);  // kept its default
    // A zero inside the count is still refused, and nothing changes.
    req = sdo(0x31, 0x1C12, 0, 6, {0x02, 0x00, 0x00, 0x16, 0x00, 0x00});
    EXPECT_EQ(ask(req), abort_reply(0x1C12, 0, 0x06090032));
    EXPECT_EQ(dict.get<uint8_t>(0x1C12, 0), 1);
    EXPECT_EQ(dict.get<uint16_t>(0x1C12, 1), 0x1601);
}

TEST_F(DriveDictionary, SdoInfoListsAreConsistentWithTheDictionary) {
    RecordingSender small(42, 64);
    server.handle(info(0x01, {0x00, 0x00}), small);
    ASSERT_EQ(small.messages.size(), 1u);
    Bytes counts = small.take().payload;
    for (uint16_t type = 1; type <= 5; ++type) {
        server.handle(info(0x01, {static_cast<uint8_t>(type), 0x00}), small);
        std::size_t n = 0;
        while (!small.messages.empty()) {
            Bytes f = small.take().payload;
            n += (f.size() - 6) / 2;
        }
        EXPECT_EQ(n - 1, le16(counts, 6 + 2 * type)) << "list type " << type;  // minus the list type word
    }
    EXPECT_GT(le16(counts, 8), 0u);   // all
    EXPECT_GT(le16(counts, 10), 0u);  // RxPDO
    EXPECT_GT(le16(counts, 12), 0u);  // TxPDO
}

TEST_F(DriveDictionary, EveryEntryHasADescription) {
    for (const auto& obj : dict.objects()) {
        for (const auto& e : obj.entries) {
            server.handle(info(0x05, {static_cast<uint8_t>(obj.index), static_cast<uint8_t>(obj.index >> 8),
                                      e.subindex, 0x78}),
                          out);
            ASSERT_FALSE(out.messages.empty());
            Bytes r = out.take().payload;
            EXPECT_EQ(r[2] & 0x7F, 0x06) << std::hex << obj.index << ":" << int(e.subindex);
            EXPECT_EQ(le16(r, 10), static_cast<uint16_t>(e.type));
            // Long answers (string defaults) come in fragments; the last one says 0 fragments left.
            std::size_t fragments = 1;
            while (le16(r, 4) != 0 && !out.messages.empty()) {
                r = out.take().payload;
                ++fragments;
            }
            EXPECT_EQ(le16(r, 4), 0u);
            EXPECT_TRUE(out.messages.empty());
            EXPECT_LE(fragments, 8u);
        }
    }
}

TEST_F(DriveDictionary, DiagnosisHistoryOnTheDriveObject) {
    coe::DiagnosisHistory diag(dict, &server.emergency());
    EXPECT_EQ(diag.max_messages(), maxpos::kDiagMaxMessages);
    coe::DiagMessage m;
    m.code = coe::DiagnosisHistory::from_emergency(0x8611);
    m.type = coe::DiagType::Error;
    m.timestamp_ns = 123456789;
    EXPECT_EQ(diag.add(m), coe::DiagnosisHistory::Result::Stored);
    EXPECT_EQ(dict.get<uint8_t>(0x10F3, 2), 6);
    Bytes r = ask(sdo(0x40, 0x10F3, 6));
    EXPECT_EQ(r[2], 0x41);
    EXPECT_EQ(le32(r, 6), 16u);
    EXPECT_EQ(le32(r, 10), 0x8611E800u);
    EXPECT_EQ(ask(sdo(0x2F, 0x10F3, 3, 0)), (Bytes{0x00, 0x30, 0x60, 0xF3, 0x10, 0x03, 0, 0, 0, 0}));
    EXPECT_EQ(diag.stored(), 0u);
}

TEST_F(DriveDictionary, StoreWithAWrongSignatureIs08000020) {
    const auto dir =
        std::filesystem::temp_directory_path() / ("coe_test_store_" + std::to_string(::getpid()));
    od::ParameterStore store(dir);
    od::attach_store(dict, store, {});
    EXPECT_EQ(ask(sdo(0x23, 0x1010, 1, 0x12345678)), abort_reply(0x1010, 1, 0x08000020));
    EXPECT_EQ(ask(sdo(0x23, 0x1010, 1, od::kSignatureSave)),
              (Bytes{0x00, 0x30, 0x60, 0x10, 0x10, 0x01, 0, 0, 0, 0}));
    EXPECT_TRUE(std::filesystem::exists(store.file()));
    std::filesystem::remove_all(dir);
}

TEST_F(DriveDictionary, EmergencyUpdatesTheErrorRegister) {
    server.emergency().raise(0x4210, 0x08);
    // Temperature, and the generic bit that CiA 301 signals at any error.
    EXPECT_EQ(ask(sdo(0x40, 0x1001, 0)), (Bytes{0x00, 0x30, 0x4F, 0x01, 0x10, 0x00, 0x09, 0, 0, 0}));
}

}  // namespace
