#pragma once
// Firmware image format: a 32-byte little-endian header the slave verifies, followed by the payload.
//
//   offset size field
//    0     4   magic            "SEFW" (0x53 0x45 0x46 0x57)
//    4     2   header version   1
//    6     2   header size      32
//    8     4   vendor id        the device the image is meant for (0x1018:01)
//   12     4   product code     (0x1018:02: hardware version << 16 | application number)
//   16     4   firmware version (0x1018:03 revision: software version << 16 | application version)
//   20     4   payload length   bytes following the header
//   24     4   flags            0 (reserved; non-zero is refused)
//   28     4   CRC-32           IEEE 802.3 (reflected 0xEDB88320, init and final xor 0xFFFFFFFF) over
//                               header bytes 0..27 followed by the payload
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "foe/wire/foe.hpp"

namespace foe {

constexpr uint32_t kImageMagic = 0x57464553;  // "SEFW" as stored little-endian
constexpr uint16_t kImageHeaderVersion = 1;
constexpr std::size_t kImageHeaderSize = 32;
constexpr uint32_t kMaxPayload = 0x7FFFFFFF;

// Which device an image is for.
struct ImageIdentity {
    uint32_t vendor_id = 0;
    uint32_t product_code = 0;
    // From any identity with vendor_id and product_code (od::Identity): the image format stays od-free.
    template <class Identity>
    static ImageIdentity from(const Identity& id) {
        return {id.vendor_id, id.product_code};
    }
};

struct ImageHeader {
    uint32_t magic = kImageMagic;
    uint16_t header_version = kImageHeaderVersion;
    uint16_t header_size = kImageHeaderSize;
    uint32_t vendor_id = 0;
    uint32_t product_code = 0;
    uint32_t version = 0;
    uint32_t payload_length = 0;
    uint32_t flags = 0;
    uint32_t crc = 0;
};

enum class ImageError : uint8_t {
    Ok,
    TooShort,          // fewer bytes than a header
    BadMagic,          // not a firmware image
    BadHeaderVersion,  // a header version this slave does not know
    BadHeaderSize,     // header size field is not 32
    BadFlags,          // reserved flags set
    WrongVendor,       // meant for another vendor
    WrongProduct,      // meant for another product (hardware)
    Truncated,         // fewer payload bytes than the header says
    TrailingData,      // more bytes than the header says
    BadChecksum,       // CRC-32 mismatch
};

std::string_view to_string(ImageError e);
// The FoE error code a write of such an image is answered with (decisions in docs/decisions/foe.md).
ErrorCode foe_error(ImageError e);

void encode_header(const ImageHeader& h, std::span<uint8_t, kImageHeaderSize> out);
ImageHeader decode_header(std::span<const uint8_t, kImageHeaderSize> in);
// Checks the header alone: magic, versions, size, flags, vendor and product.
ImageError check_header(const ImageHeader& h, const ImageIdentity& identity);
// CRC of the header part the checksum covers (bytes 0..27), to be continued over the payload.
uint32_t header_crc(std::span<const uint8_t, kImageHeaderSize> header);

std::vector<uint8_t> build_image(std::span<const uint8_t> payload, const ImageIdentity& identity,
                                 uint32_t version);

struct VerifyResult {
    ImageError error = ImageError::TooShort;
    ImageHeader header{};
    bool ok() const { return error == ImageError::Ok; }
};
VerifyResult verify_image(std::span<const uint8_t> bytes, const ImageIdentity& identity);
// Error with a readable detail (e.g. "image is for product 0x30020000, this device is 0x30010000").
std::string describe(const VerifyResult& r, const ImageIdentity& identity);

// 0x100A text as the MAXPOS firmware specification writes it: the software version word as 4 hex digits and
// 'h' ("0120h").
std::string software_version_text(uint32_t version);
// Firmware file name per MAXPOS firmware specification §9.2 / EPOS Firmware Specification §15:
// <device>_<SW>h_<HW>h_<AppNo>h_<AppVer>h.bin, e.g. MAXPOS_0120h_3001h_0000h_0000h.bin for product
// 0x30010000, version 0x01200000.
std::string firmware_file_name(std::string_view device_name, uint32_t product_code, uint32_t version);
// Sets what the running image decides: revision (0x1018:03, SII) and software version text (0x100A).
// Identity is od::Identity (template so that the image format stays od-free).
template <class Identity>
void apply_version(Identity& identity, uint32_t version) {
    identity.revision = version;
    identity.software_version = software_version_text(version);
}

}  // namespace foe
