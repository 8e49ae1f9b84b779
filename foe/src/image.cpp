#include "foe/image.hpp"

#include <array>
#include <cstdio>

#include "util/crc.hpp"
#include "util/le.hpp"

namespace foe {
namespace {

using util::get16;
using util::get32;
using util::put16;
using util::put32;

std::string hex32(uint32_t v) {
    char b[16];
    std::snprintf(b, sizeof b, "0x%08X", static_cast<unsigned>(v));
    return b;
}

}  // namespace

std::string_view to_string(ImageError e) {
    switch (e) {
        case ImageError::Ok:
            return "ok";
        case ImageError::TooShort:
            return "shorter than an image header";
        case ImageError::BadMagic:
            return "not a firmware image (magic)";
        case ImageError::BadHeaderVersion:
            return "unknown image header version";
        case ImageError::BadHeaderSize:
            return "wrong image header size";
        case ImageError::BadFlags:
            return "reserved image flags set";
        case ImageError::WrongVendor:
            return "image is for another vendor";
        case ImageError::WrongProduct:
            return "image is for another product";
        case ImageError::Truncated:
            return "image payload shorter than its header says";
        case ImageError::TrailingData:
            return "image longer than its header says";
        case ImageError::BadChecksum:
            return "image checksum wrong";
    }
    return "unknown";
}

ErrorCode foe_error(ImageError e) {
    switch (e) {
        case ImageError::Ok:
            return ErrorCode::NotDefined;
        case ImageError::TooShort:
        case ImageError::BadMagic:
        case ImageError::BadHeaderVersion:
        case ImageError::BadHeaderSize:
        case ImageError::BadFlags:
        case ImageError::Truncated:
        case ImageError::TrailingData:
            return ErrorCode::FileHeaderError;
        case ImageError::WrongVendor:
        case ImageError::WrongProduct:
            return ErrorCode::InvalidFirmware;
        case ImageError::BadChecksum:
            return ErrorCode::InvalidChecksum;
    }
    return ErrorCode::NotDefined;
}

void encode_header(const ImageHeader& h, std::span<uint8_t, kImageHeaderSize> out) {
    uint8_t* p = out.data();
    put32(p + 0, h.magic);
    put16(p + 4, h.header_version);
    put16(p + 6, h.header_size);
    put32(p + 8, h.vendor_id);
    put32(p + 12, h.product_code);
    put32(p + 16, h.version);
    put32(p + 20, h.payload_length);
    put32(p + 24, h.flags);
    put32(p + 28, h.crc);
}

ImageHeader decode_header(std::span<const uint8_t, kImageHeaderSize> in) {
    const uint8_t* p = in.data();
    ImageHeader h;
    h.magic = get32(p + 0);
    h.header_version = get16(p + 4);
    h.header_size = get16(p + 6);
    h.vendor_id = get32(p + 8);
    h.product_code = get32(p + 12);
    h.version = get32(p + 16);
    h.payload_length = get32(p + 20);
    h.flags = get32(p + 24);
    h.crc = get32(p + 28);
    return h;
}

ImageError check_header(const ImageHeader& h, const ImageIdentity& identity) {
    if (h.magic != kImageMagic) return ImageError::BadMagic;
    if (h.header_version != kImageHeaderVersion) return ImageError::BadHeaderVersion;
    if (h.header_size != kImageHeaderSize) return ImageError::BadHeaderSize;
    if (h.flags != 0) return ImageError::BadFlags;
    if (h.payload_length > kMaxPayload) return ImageError::BadHeaderSize;
    if (h.vendor_id != identity.vendor_id) return ImageError::WrongVendor;
    if (h.product_code != identity.product_code) return ImageError::WrongProduct;
    return ImageError::Ok;
}

uint32_t header_crc(std::span<const uint8_t, kImageHeaderSize> header) {
    return util::crc32(header.first<kImageHeaderSize - 4>());
}

std::vector<uint8_t> build_image(std::span<const uint8_t> payload, const ImageIdentity& identity,
                                 uint32_t version) {
    std::vector<uint8_t> out(kImageHeaderSize + payload.size());
    ImageHeader h;
    h.vendor_id = identity.vendor_id;
    h.product_code = identity.product_code;
    h.version = version;
    h.payload_length = static_cast<uint32_t>(payload.size());
    std::span<uint8_t, kImageHeaderSize> head(out.data(), kImageHeaderSize);
    encode_header(h, head);
    h.crc = util::crc32(payload, header_crc(head));
    encode_header(h, head);
    if (!payload.empty()) std::copy(payload.begin(), payload.end(), out.begin() + kImageHeaderSize);
    return out;
}

VerifyResult verify_image(std::span<const uint8_t> bytes, const ImageIdentity& identity) {
    VerifyResult r;
    if (bytes.size() < kImageHeaderSize) return r;
    std::span<const uint8_t, kImageHeaderSize> head(bytes.data(), kImageHeaderSize);
    r.header = decode_header(head);
    r.error = check_header(r.header, identity);
    if (r.error != ImageError::Ok) return r;
    const std::size_t have = bytes.size() - kImageHeaderSize;
    if (have < r.header.payload_length) {
        r.error = ImageError::Truncated;
        return r;
    }
    if (have > r.header.payload_length) {
        r.error = ImageError::TrailingData;
        return r;
    }
    if (util::crc32(bytes.subspan(kImageHeaderSize), header_crc(head)) != r.header.crc) {
        r.error = ImageError::BadChecksum;
        return r;
    }
    r.error = ImageError::Ok;
    return r;
}

std::string describe(const VerifyResult& r, const ImageIdentity& identity) {
    std::string s(to_string(r.error));
    if (r.error == ImageError::WrongVendor)
        s += " (" + hex32(r.header.vendor_id) + ", this device " + hex32(identity.vendor_id) + ")";
    else if (r.error == ImageError::WrongProduct)
        s += " (" + hex32(r.header.product_code) + ", this device " + hex32(identity.product_code) + ")";
    return s;
}

std::string software_version_text(uint32_t version) {
    char b[16];
    std::snprintf(b, sizeof b, "%04Xh", static_cast<unsigned>(version >> 16));
    return b;
}

std::string firmware_file_name(std::string_view device_name, uint32_t product_code, uint32_t version) {
    char b[48];
    std::snprintf(b, sizeof b, "_%04Xh_%04Xh_%04Xh_%04Xh.bin", static_cast<unsigned>(version >> 16),
                  static_cast<unsigned>(product_code >> 16), static_cast<unsigned>(product_code & 0xFFFF),
                  static_cast<unsigned>(version & 0xFFFF));
    return std::string(device_name) + b;
}

}  // namespace foe
