#include <gtest/gtest.h>

#include <string>

#include "foe/image.hpp"
#include "foe_test_support.hpp"
#include "od/device.hpp"  // od::Identity (foe/image.hpp is od-free)
#include "util/crc.hpp"

using namespace foe;
using foe_test::kMaxpos;

TEST(FoeImage, Crc32MatchesTheStandardCheckValue) {
    const std::string s = "123456789";
    EXPECT_EQ(util::crc32({reinterpret_cast<const uint8_t*>(s.data()), s.size()}), 0xCBF43926u);
    // Continued over pieces gives the same value.
    const uint32_t part = util::crc32({reinterpret_cast<const uint8_t*>(s.data()), 4});
    EXPECT_EQ(util::crc32({reinterpret_cast<const uint8_t*>(s.data()) + 4, 5}, part), 0xCBF43926u);
}

TEST(FoeImage, BuildThenVerifyRoundTrips) {
    const auto payload = foe_test::payload_bytes(1000, 1);
    const auto image = build_image(payload, kMaxpos, 0x01200000);
    ASSERT_EQ(image.size(), kImageHeaderSize + payload.size());
    EXPECT_EQ(image[0], 'S');
    EXPECT_EQ(image[3], 'W');
    const auto r = verify_image(image, kMaxpos);
    ASSERT_TRUE(r.ok()) << to_string(r.error);
    EXPECT_EQ(r.header.version, 0x01200000u);
    EXPECT_EQ(r.header.vendor_id, 0xFBu);
    EXPECT_EQ(r.header.product_code, 0x30010000u);
    EXPECT_EQ(r.header.payload_length, 1000u);
}

TEST(FoeImage, EmptyPayloadIsAValidImage) {
    const auto image = build_image({}, kMaxpos, 0x01300000);
    EXPECT_TRUE(verify_image(image, kMaxpos).ok());
}

TEST(FoeImage, EveryDefectHasItsOwnError) {
    const auto good = build_image(foe_test::payload_bytes(200, 2), kMaxpos, 0x01200000);
    auto check = [&](std::vector<uint8_t> bytes, ImageError expected) {
        EXPECT_EQ(verify_image(bytes, kMaxpos).error, expected) << to_string(expected);
    };
    check({good.begin(), good.begin() + 31}, ImageError::TooShort);
    auto b = good;
    b[0] ^= 1;
    check(b, ImageError::BadMagic);
    b = good;
    b[4] = 2;
    check(b, ImageError::BadHeaderVersion);
    b = good;
    b[6] = 40;
    check(b, ImageError::BadHeaderSize);
    b = good;
    b[24] = 1;
    check(b, ImageError::BadFlags);
    check({good.begin(), good.end() - 1}, ImageError::Truncated);
    b = good;
    b.push_back(0);
    check(b, ImageError::TrailingData);
    b = good;
    b[100] ^= 0x40;  // payload bit flip
    check(b, ImageError::BadChecksum);
    b = good;
    b[16] ^= 1;  // version changed without a new CRC
    check(b, ImageError::BadChecksum);

    EXPECT_EQ(verify_image(good, {0xFC, 0x30010000}).error, ImageError::WrongVendor);
    const auto other = verify_image(good, {0xFB, 0x30020000});
    EXPECT_EQ(other.error, ImageError::WrongProduct);
    EXPECT_NE(describe(other, {0xFB, 0x30020000}).find("0x30010000"), std::string::npos);
}

TEST(FoeImage, ErrorsMapToFoeCodes) {
    EXPECT_EQ(foe_error(ImageError::BadChecksum), ErrorCode::InvalidChecksum);
    EXPECT_EQ(foe_error(ImageError::WrongProduct), ErrorCode::InvalidFirmware);
    EXPECT_EQ(foe_error(ImageError::WrongVendor), ErrorCode::InvalidFirmware);
    EXPECT_EQ(foe_error(ImageError::BadMagic), ErrorCode::FileHeaderError);
    EXPECT_EQ(foe_error(ImageError::Truncated), ErrorCode::FileHeaderError);
}

TEST(FoeImage, VersionTextAndFileNameFollowTheSeed) {
    EXPECT_EQ(software_version_text(0x01200000), "0120h");
    EXPECT_EQ(firmware_file_name("MAXPOS", 0x30010000, 0x01200000), "MAXPOS_0120h_3001h_0000h_0000h.bin");
    EXPECT_EQ(firmware_file_name("MAXPOS", 0x3001ABCD, 0x0130000F), "MAXPOS_0130h_3001h_ABCDh_000Fh.bin");
    od::Identity id;
    apply_version(id, 0x01300000);
    EXPECT_EQ(id.revision, 0x01300000u);
    EXPECT_EQ(id.software_version, "0130h");
}

TEST(FoeErrors, EveryStandardCodeHasItsText) {
    EXPECT_EQ(error_text(ErrorCode::NotDefined), "Not defined");
    EXPECT_EQ(error_text(ErrorCode::NotFound), "Not found");
    EXPECT_EQ(error_text(ErrorCode::AccessDenied), "Access denied");
    EXPECT_EQ(error_text(ErrorCode::DiskFull), "Disk full");
    EXPECT_EQ(error_text(ErrorCode::Illegal), "Illegal");
    EXPECT_EQ(error_text(ErrorCode::PacketNumberWrong), "Packet number wrong");
    EXPECT_EQ(error_text(ErrorCode::AlreadyExists), "Already exists");
    EXPECT_EQ(error_text(ErrorCode::NoUser), "No user");
    EXPECT_EQ(error_text(ErrorCode::BootstrapOnly), "Bootstrap only");
    EXPECT_EQ(error_text(ErrorCode::NotInBootstrap), "Not in bootstrap");
    EXPECT_EQ(error_text(ErrorCode::NoRights), "No rights");
    EXPECT_EQ(error_text(ErrorCode::ProgramError), "Program error");
    EXPECT_EQ(error_text(ErrorCode::InvalidChecksum), "Invalid checksum");
    EXPECT_EQ(error_text(ErrorCode::InvalidFirmware), "Invalid firmware");
    EXPECT_EQ(error_text(ErrorCode::NoFileToRead), "No file to read");
    EXPECT_EQ(error_text(ErrorCode::FileHeaderError), "File header missing or wrong");
    EXPECT_EQ(error_text(ErrorCode::FlashError), "Flash error");
    EXPECT_EQ(error_text(0x1234u), "Not defined");
}
