// softecat_util (little-endian helpers, CRC-32, crash-safe file write) and the SII CRC-8 of esc_wire
// (esc/wire/sii.hpp).
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <string_view>
#include <vector>

#include "esc/wire/frame_builder.hpp"
#include "esc/wire/sii.hpp"
#include "util/atomic_file.hpp"
#include "util/crc.hpp"
#include "util/le.hpp"
#include "util/strfmt.hpp"

namespace {

std::span<const uint8_t> bytes(std::string_view s) {
    return {reinterpret_cast<const uint8_t*>(s.data()), s.size()};
}

std::vector<uint8_t> read_all(const std::filesystem::path& p) {
    std::ifstream f(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

class TempDir {
  public:
    TempDir() {
        std::string t = (std::filesystem::temp_directory_path() / "softecat_util_XXXXXX").string();
        path_ = ::mkdtemp(t.data());
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::permissions(path_, std::filesystem::perms::owner_all, ec);
        std::filesystem::remove_all(path_, ec);
    }
    const std::filesystem::path& path() const { return path_; }

  private:
    std::filesystem::path path_;
};

}  // namespace

TEST(Crc32, KnownCheckValue) {
    // The CRC-32 (IEEE 802.3) check value of "123456789".
    EXPECT_EQ(util::crc32(bytes("123456789")), 0xCBF43926u);
    EXPECT_EQ(util::crc32({}), 0u);
}

TEST(Crc32, ContinuesOverPieces) {
    const uint32_t head = util::crc32(bytes("12345"));
    EXPECT_EQ(util::crc32(bytes("6789"), head), 0xCBF43926u);
}

TEST(SiiCrc8, KnownVectors) {
    // CRC-8, polynomial 0x07, initial value 0xFF, MSB first, no final xor (the SII word 7 checksum): check
    // value of "123456789", and the words 0-6 of an ESI's ConfigData 050403ccc409 (rest zero), both worked
    // out independently of this implementation (table-driven).
    EXPECT_EQ(esc::sii::crc8(bytes("123456789").data(), 9), 0xFB);
    const std::array<uint8_t, 14> header = {0x05, 0x04, 0x03, 0xCC, 0xC4, 0x09, 0, 0, 0, 0, 0, 0, 0, 0};
    EXPECT_EQ(esc::sii::crc8(header.data(), header.size()), 0xD8);
    const std::array<uint8_t, 14> zeros{};
    EXPECT_EQ(esc::sii::crc8(zeros.data(), zeros.size()), 0x30);
    static_assert(esc::sii::crc8(nullptr, 0) == 0xFF);
}

TEST(LittleEndian, GetPutRoundTrip) {
    uint8_t b[8] = {};
    util::put16(b, 0x1234);
    EXPECT_EQ(b[0], 0x34);
    EXPECT_EQ(b[1], 0x12);
    EXPECT_EQ(util::get16(b), 0x1234);
    util::put32(b, 0xA1B2C3D4u);
    EXPECT_EQ(b[0], 0xD4);
    EXPECT_EQ(b[3], 0xA1);
    EXPECT_EQ(util::get32(b), 0xA1B2C3D4u);
    util::put64(b, 0x0102030405060708ull);
    EXPECT_EQ(b[0], 0x08);
    EXPECT_EQ(b[7], 0x01);
    EXPECT_EQ(util::get64(b), 0x0102030405060708ull);
    util::put_n(b, 0xABCDEF, 3);
    EXPECT_EQ(util::get_n(b, 3), 0xABCDEFu);
    std::vector<uint8_t> v;
    util::append16(v, 0xBEEF);
    util::append32(v, 0x11223344u);
    ASSERT_EQ(v.size(), 6u);
    EXPECT_EQ(util::get16(v, 0), 0xBEEF);
    EXPECT_EQ(util::get32(v, 2), 0x11223344u);
    EXPECT_EQ(util::le_bytes(0x0A0B, 2), (std::vector<uint8_t>{0x0B, 0x0A}));
}

TEST(AtomicFile, WritesAndReplaces) {
    TempDir dir;
    const auto file = dir.path() / "sub" / "state.bin";
    std::vector<std::string> steps;
    const std::vector<uint8_t> first = {1, 2, 3};
    ASSERT_EQ(util::write_file_atomic(file, first, [&](std::string_view s) { steps.emplace_back(s); }), "");
    EXPECT_EQ(read_all(file), first);
    EXPECT_EQ(steps, (std::vector<std::string>{"temp-written", "renamed", "done"}));
    const std::vector<uint8_t> second(5000, 0x5A);
    ASSERT_EQ(util::write_file_atomic(file, second), "");
    EXPECT_EQ(read_all(file), second);
    EXPECT_FALSE(std::filesystem::exists(dir.path() / "sub" / "state.bin.tmp"));
}

TEST(AtomicFile, FailedWriteKeepsTheOldFile) {
    TempDir dir;
    const auto file = dir.path() / "state.bin";
    const std::vector<uint8_t> old = {9, 8, 7};
    ASSERT_EQ(util::write_file_atomic(file, old), "");
    // A directory where the temp file must go: creating "<file>.tmp" fails, the old file stays.
    std::filesystem::create_directory(dir.path() / "state.bin.tmp");
    std::filesystem::create_directory(dir.path() / "state.bin.tmp" / "x");
    const std::string err = util::write_file_atomic(file, std::vector<uint8_t>{1, 1, 1, 1});
    EXPECT_NE(err.find("cannot create"), std::string::npos) << err;
    EXPECT_EQ(read_all(file), old);
}

TEST(AtomicFile, StaleTempIsRemoved) {
    TempDir dir;
    const auto file = dir.path() / "f";
    std::ofstream(dir.path() / "f.tmp") << "partial";
    EXPECT_TRUE(util::remove_stale_temp(file));
    EXPECT_FALSE(util::remove_stale_temp(file));
}

TEST(FrameBuilder, ChainsDatagramsAndReadsThemBack) {
    const uint8_t data[2] = {0x34, 0x12};
    const auto f = esc::wire::FrameBuilder()
                       .add(esc::Command::FPWR, 7, 0x1001, 0x0120, data)
                       .add_zero(esc::Command::FPRD, 8, 0x1001, 0x0130, 2)
                       .build();
    ASSERT_EQ(f.size(), 60u);
    EXPECT_EQ(f[12], 0x88);
    EXPECT_EQ(f[13], 0xA4);
    EXPECT_EQ(util::get16(f.data() + 14), 0x1000 | (2 * 12 + 4));
    esc::wire::DatagramReader r(f);
    ASSERT_TRUE(r.valid());
    esc::wire::DatagramView v;
    ASSERT_TRUE(r.next(v));
    EXPECT_EQ(v.command, static_cast<uint8_t>(esc::Command::FPWR));
    EXPECT_EQ(v.index, 7);
    EXPECT_EQ(v.adp, 0x1001);
    EXPECT_EQ(v.ado, 0x0120);
    EXPECT_TRUE(v.more());
    ASSERT_EQ(v.data.size(), 2u);
    EXPECT_EQ(util::get16(v.data.data()), 0x1234);
    ASSERT_TRUE(r.next(v));
    EXPECT_FALSE(v.more());
    EXPECT_EQ(v.ado, 0x0130);
    EXPECT_FALSE(r.next(v));
    EXPECT_FALSE(r.malformed());
    EXPECT_EQ(esc::wire::datagram_wkc(f, 1), 0);
    EXPECT_EQ(esc::wire::datagram_wkc(f, 2), -1);
}

// A message carries a path of any length whole (a fixed char array cut "ecatctl: /tmp/<long path>/bad.bin:
// chec").
TEST(Strprintf, KeepsTextOfAnyLength) {
    const std::string path = "/tmp/" + std::string(300, 'd') + "/bad.bin";
    const std::string text = util::strprintf("%s: checksum word 7 is 0x%04x", path.c_str(), 0x12u);
    EXPECT_EQ(text, path + ": checksum word 7 is 0x0012");
    EXPECT_EQ(util::strprintf("%s", ""), "");
    EXPECT_EQ(util::strprintf("%d", -7), "-7");
}

// The one hex spelling of messages: upper-case digits, at least as many as asked, never cut.
TEST(Strprintf, HexHasAtLeastTheDigitsAskedAndNeverCuts) {
    EXPECT_EQ(util::hex(0x1C12), "0x1C12");
    EXPECT_EQ(util::hex(0x7, 2), "0x07");
    EXPECT_EQ(util::hex(0x00110000, 8), "0x00110000");
    EXPECT_EQ(util::hex(0x12345, 4), "0x12345");
    EXPECT_EQ(util::hex(0xFFFFFFFFFFFFFFFFull, 4), "0xFFFFFFFFFFFFFFFF");
}

// The reader walks a chain as an ESC does (docs/decisions/esc.md, "Frame tolerance"): the header Length is
// not evaluated, a datagram past the end of the frame is malformed, EtherCAT in UDP/IP is found.
TEST(FrameBuilder, ReaderIgnoresTheHeaderLengthAndFindsUdp) {
    const uint8_t data[2] = {0x34, 0x12};
    auto f = esc::wire::FrameBuilder().add(esc::Command::FPWR, 7, 0x1001, 0x0120, data).build();
    f[14] = 0x3C;  // the whole frame length, as libethercat writes it
    esc::wire::DatagramReader r(f);
    esc::wire::DatagramView v;
    ASSERT_TRUE(r.valid());
    ASSERT_TRUE(r.next(v));
    EXPECT_EQ(v.index, 7);
    EXPECT_FALSE(r.next(v));
    EXPECT_FALSE(r.malformed());
    f[16 + 6] = 0x60;  // a datagram length past the end
    esc::wire::DatagramReader bad(f);
    EXPECT_FALSE(bad.next(v));
    EXPECT_TRUE(bad.malformed());
    // The same chain in IPv4/UDP to port 0x88A4.
    std::vector<uint8_t> u(f.begin(), f.begin() + 12);
    const uint8_t ip_udp[30] = {0x08, 0x00, 0x45, 0,  0, 48, 0,   0,    0,    0,    64,   0x11, 0,  0, 10,
                                0,    0,    1,    10, 0, 0,  255, 0x88, 0xA4, 0x88, 0xA4, 0,    28, 0, 0};
    u.insert(u.end(), ip_udp, ip_udp + sizeof ip_udp);
    const auto g = esc::wire::FrameBuilder().add(esc::Command::FPWR, 9, 0x1001, 0x0120, data).build();
    u.insert(u.end(), g.begin() + 14, g.begin() + 16 + 14);
    const auto loc = esc::wire::locate_ecat(u);
    ASSERT_TRUE(loc.found);
    EXPECT_EQ(loc.header, 42u);
    EXPECT_EQ(loc.udp_checksum, 40u);
    esc::wire::DatagramReader ru(u);
    ASSERT_TRUE(ru.valid());
    ASSERT_TRUE(ru.next(v));
    EXPECT_EQ(v.index, 9);
    u[14] = 0x46;  // IP header length 6: not for an ESC
    EXPECT_FALSE(esc::wire::DatagramReader(u).valid());
}
