// The deliberate CoE faults (coe/faults.hpp, `ecat-slave --fault`): each one breaks the one behaviour it
// names, and the same request to a server without it gets the answer ETG.1000.6 prescribes.
#include <gtest/gtest.h>

#include <numeric>

#include "coe/sdo_server.hpp"
#include "coe_test_support.hpp"

using namespace coe_test;

namespace {

coe::CoeConfig with(const coe::CoeFaults& faults) {
    coe::CoeConfig c;
    c.faults = faults;
    return c;
}

struct Server {
    explicit Server(const coe::CoeFaults& faults = {})
        : server(
              dict, [this] { return state; }, with(faults)) {}
    od::Dictionary dict = make_test_dictionary();
    od::AlState state = od::AlState::PreOp;
    coe::CoeServer server;
    RecordingSender out;

    Bytes ask(const Bytes& request) {
        server.handle(request, out);
        EXPECT_EQ(out.messages.size(), 1u);
        if (out.messages.empty()) return {};
        return out.take().payload;
    }
};

const Bytes kDownloadOk{0x00, 0x30, 0x60};

Bytes head(const Bytes& b, std::size_t n) {
    return Bytes(b.begin(), b.begin() + static_cast<std::ptrdiff_t>(std::min(n, b.size())));
}

TEST(CoeFaults, CaNoPadding) {
    coe::CoeFaults f;
    f.ca_no_padding = true;
    Server clean, faulty(f);
    // Complete-access upload of 0x1018 from subindex 0: sub 0 in 16 bits + 4 x 32 bits = 18 bytes.
    const Bytes a = clean.ask(sdo(0x50, 0x1018, 0));
    ASSERT_GE(a.size(), 12u);
    EXPECT_EQ(le32(a, 6), 18u);
    EXPECT_EQ(a[10], 4);
    EXPECT_EQ(a[11], 0);  // the padding byte
    EXPECT_EQ(le32(a, 12), 0xFBu);
    const Bytes b = faulty.ask(sdo(0x50, 0x1018, 0));
    ASSERT_GE(b.size(), 11u);
    EXPECT_EQ(le32(b, 6), 17u);
    EXPECT_EQ(b[10], 4);
    EXPECT_EQ(le32(b, 11), 0xFBu);  // vendor id right behind the 8-bit subindex 0
    // From subindex 1 nothing changes.
    EXPECT_EQ(clean.ask(sdo(0x50, 0x1018, 1)), faulty.ask(sdo(0x50, 0x1018, 1)));
}

TEST(CoeFaults, InfoErrorShort) {
    coe::CoeFaults f;
    f.info_error_short = true;
    Server clean, faulty(f);
    const Bytes a = clean.ask(info(0x03, {0x55, 0x55}));  // object description of a missing object
    ASSERT_EQ(a.size(), 10u);
    EXPECT_EQ(a[2] & 0x7F, 0x07);
    EXPECT_EQ(le32(a, 6), 0x06020000u);
    const Bytes b = faulty.ask(info(0x03, {0x55, 0x55}));
    EXPECT_EQ(b.size(), 8u);
    EXPECT_EQ(b[2] & 0x7F, 0x07);
    EXPECT_EQ(le16(b, 6), 0x0000);  // the low half of 0x06020000, the rest is missing
    // Successful answers are unchanged.
    EXPECT_EQ(clean.ask(info(0x03, {0x18, 0x10})), faulty.ask(info(0x03, {0x18, 0x10})));
}

TEST(CoeFaults, AbortMissingObject) {
    coe::CoeFaults f;
    f.abort_missing_object = true;
    Server clean, faulty(f);
    EXPECT_EQ(clean.ask(sdo(0x40, 0x5555, 0)), abort_reply(0x5555, 0, 0x06020000));
    EXPECT_EQ(faulty.ask(sdo(0x40, 0x5555, 0)), abort_reply(0x5555, 0, 0x06090011));
    EXPECT_EQ(clean.ask(sdo(0x2B, 0x5555, 0, 1)), abort_reply(0x5555, 0, 0x06020000));
    EXPECT_EQ(faulty.ask(sdo(0x2B, 0x5555, 0, 1)), abort_reply(0x5555, 0, 0x06090011));
    // A missing subindex keeps its code.
    EXPECT_EQ(faulty.ask(sdo(0x40, 0x1018, 9)), abort_reply(0x1018, 9, 0x06090011));
}

TEST(CoeFaults, AbortCommandDownload) {
    coe::CoeFaults f;
    f.download_abort_command = true;
    Server clean, faulty(f);
    EXPECT_EQ(clean.ask(sdo(0x23, 0x1018, 1, 7)), abort_reply(0x1018, 1, 0x06010002));
    Bytes expected = abort_reply(0x1018, 1, 0x06010002);
    expected[2] = 0x23;  // the request's command byte instead of 0x80
    EXPECT_EQ(faulty.ask(sdo(0x23, 0x1018, 1, 7)), expected);
    // Aborts of uploads, and downloads that succeed, are unchanged.
    EXPECT_EQ(faulty.ask(sdo(0x40, 0x5555, 0)), abort_reply(0x5555, 0, 0x06020000));
    EXPECT_EQ(head(faulty.ask(sdo(0x2B, 0x6040, 0, 6)), 3), kDownloadOk);
    EXPECT_EQ(faulty.ask(sdo(0x40, 0x5555, 0)), abort_reply(0x5555, 0, 0x06020000));
}

TEST(CoeFaults, PdoMapInSafeOp) {
    coe::CoeFaults f;
    f.pdo_map_in_safe_op = true;
    Server clean, faulty(f);
    clean.state = faulty.state = od::AlState::SafeOp;
    EXPECT_EQ(clean.ask(sdo(0x2F, 0x1C12, 0, 0)), abort_reply(0x1C12, 0, 0x08000022));
    EXPECT_EQ(clean.dict.get<uint8_t>(0x1C12, 0), 1);
    EXPECT_EQ(head(faulty.ask(sdo(0x2F, 0x1C12, 0, 0)), 3), kDownloadOk);
    EXPECT_EQ(faulty.dict.get<uint8_t>(0x1C12, 0), 0);  // written in Safe-Op
    EXPECT_EQ(head(faulty.ask(sdo(0x23, 0x1600, 2, 0x60410010)), 3), kDownloadOk);
    // In Op the fault changes nothing.
    faulty.state = od::AlState::Op;
    EXPECT_EQ(faulty.ask(sdo(0x2F, 0x1C12, 0, 1)), abort_reply(0x1C12, 0, 0x08000022));
}

TEST(CoeFaults, DownloadToggleUnchecked) {
    coe::CoeFaults f;
    f.download_toggle_unchecked = true;
    Server clean, faulty(f);
    const Bytes data{1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
    for (Server* s : {&clean, &faulty}) {
        const Bytes init = s->ask(sdo(0x21, 0x2000, 0, 10));  // normal download, 10 bytes in segments
        ASSERT_EQ(head(init, 3), kDownloadOk);
    }
    // The first segment must carry toggle 0; this one says 1.
    EXPECT_EQ(clean.ask(segment(0x11, data)), abort_reply(0x2000, 0, 0x05030000));
    const Bytes b = faulty.ask(segment(0x11, data));
    EXPECT_EQ(head(b, 3), (Bytes{0x00, 0x30, 0x30}));
    const auto stored = faulty.dict.raw(0x2000, 0);
    ASSERT_GE(stored.size(), 10u);
    EXPECT_EQ(stored[9], 10);
}

TEST(CoeFaults, UploadToggleStuck) {
    coe::CoeFaults f;
    f.upload_toggle_stuck = true;
    Server clean, faulty(f);
    Bytes v(300);
    std::iota(v.begin(), v.end(), uint8_t{1});
    for (Server* s : {&clean, &faulty}) {
        ASSERT_EQ(s->dict.set_raw(0x2000, 0, v), od::Status::Ok);
        const Bytes init = s->ask(sdo(0x40, 0x2000, 0));  // 300 bytes: initiate + segments
        ASSERT_EQ(init[2], 0x41);
        EXPECT_EQ(s->ask(segment(0x60, {}))[2] & 0x10, 0x00);  // first segment: toggle 0
    }
    EXPECT_EQ(clean.ask(segment(0x70, {}))[2] & 0x10, 0x10);  // second segment: toggle 1
    EXPECT_EQ(faulty.ask(segment(0x70, {}))[2] & 0x10, 0x00);
}

TEST(CoeFaults, ExpeditedSizeWrong) {
    coe::CoeFaults f;
    f.expedited_size_wrong = true;
    Server clean, faulty(f);
    EXPECT_EQ(clean.ask(sdo(0x40, 0x6041, 0))[2], 0x4B);   // 2 bytes
    EXPECT_EQ(faulty.ask(sdo(0x40, 0x6041, 0))[2], 0x43);  // says 4
    EXPECT_EQ(clean.ask(sdo(0x40, 0x6060, 0))[2], 0x4F);
    EXPECT_EQ(faulty.ask(sdo(0x40, 0x6060, 0))[2], 0x43);
    EXPECT_EQ(clean.ask(sdo(0x40, 0x1018, 1)), faulty.ask(sdo(0x40, 0x1018, 1)));  // 4 bytes: right anyway
}

TEST(CoeFaults, ReadOnlyWriteConfirmed) {
    coe::CoeFaults f;
    f.read_only_write_confirmed = true;
    Server clean, faulty(f);
    EXPECT_EQ(clean.ask(sdo(0x23, 0x1000, 0, 0x1234)), abort_reply(0x1000, 0, 0x06010002));
    EXPECT_EQ(head(faulty.ask(sdo(0x23, 0x1000, 0, 0x1234)), 3), kDownloadOk);
    EXPECT_EQ(faulty.dict.get<uint32_t>(0x1000, 0), 0x00020192u);  // not written
    // Writable objects still take the value.
    EXPECT_EQ(head(faulty.ask(sdo(0x2B, 0x6040, 0, 6)), 3), kDownloadOk);
    EXPECT_EQ(faulty.dict.get<uint16_t>(0x6040, 0), 6);
}

TEST(CoeFaults, RangeUnchecked) {
    coe::CoeFaults f;
    f.value_range_unchecked = true;
    Server clean, faulty(f);
    EXPECT_EQ(clean.ask(sdo(0x2B, 0x2002, 0, 500)), abort_reply(0x2002, 0, 0x06090031));     // max 100
    EXPECT_EQ(clean.ask(sdo(0x2B, 0x2002, 0, 0xFF00)), abort_reply(0x2002, 0, 0x06090032));  // -256 < -100
    EXPECT_EQ(head(faulty.ask(sdo(0x2B, 0x2002, 0, 500)), 3), kDownloadOk);
    EXPECT_EQ(head(faulty.ask(sdo(0x2B, 0x2002, 0, 0xFF00)), 3), kDownloadOk);
    EXPECT_EQ(faulty.dict.get<int16_t>(0x2002, 0), 5);  // the default, untouched
    // A wrong length is still refused.
    EXPECT_EQ(faulty.ask(sdo(0x23, 0x2002, 0, 50)), abort_reply(0x2002, 0, 0x06070012));
}

TEST(CoeFaults, InfoWrongType) {
    coe::CoeFaults f;
    f.info_entry_wrong_type = true;
    Server clean, faulty(f);
    const Bytes a = clean.ask(info(0x05, {0x18, 0x10, 0x01, 0x00}));  // entry description 0x1018:01
    const Bytes b = faulty.ask(info(0x05, {0x18, 0x10, 0x01, 0x00}));
    ASSERT_GE(a.size(), 12u);
    ASSERT_GE(b.size(), 12u);
    EXPECT_EQ(le16(a, 10), 0x0007);  // UNSIGNED32
    EXPECT_EQ(le16(b, 10), 0x0005);  // says UNSIGNED8
    EXPECT_EQ(le16(b, 12), 32);      // bit length still right
    // Subindex 0 and object descriptions are unchanged.
    EXPECT_EQ(clean.ask(info(0x05, {0x41, 0x60, 0x00, 0x00})),
              faulty.ask(info(0x05, {0x41, 0x60, 0x00, 0x00})));
    EXPECT_EQ(clean.ask(info(0x03, {0x18, 0x10})), faulty.ask(info(0x03, {0x18, 0x10})));
}

}  // namespace
