// fwimage build --payload FILE --version 0x01200000 --vendor 0xFB --product 0x30010000 -o image.bin
// fwimage info image.bin [--vendor V --product P]
#include <CLI/CLI.hpp>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "foe/image.hpp"

namespace {

bool parse_u32(const std::string& text, uint32_t& out) {
    if (text.empty()) return false;
    errno = 0;
    char* end = nullptr;
    const unsigned long long v = std::strtoull(text.c_str(), &end, 0);
    if (errno != 0 || *end != '\0' || text[0] == '-' || v > 0xFFFFFFFFull) return false;
    out = static_cast<uint32_t>(v);
    return true;
}

bool read_file(const std::string& path, std::vector<uint8_t>& out) {
    std::ifstream f(path, std::ios::binary);
    if (!f) return false;
    out.assign(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
    return !f.bad();
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"Build and inspect firmware images for the soft EtherCAT drive (FoE download)"};
    app.require_subcommand(1);

    std::string payload_path, out_path, version_text, vendor_text = "0xFB", product_text, name = "MAXPOS";
    auto* build = app.add_subcommand("build", "wrap a payload into a firmware image");
    build->add_option("--payload", payload_path, "payload file")->required();
    build->add_option("--version", version_text, "firmware version = revision 0x1018:03 (e.g. 0x01200000)")
        ->required();
    build->add_option("--vendor", vendor_text, "vendor id the image is for (default 0xFB)");
    build->add_option("--product", product_text, "product code the image is for (e.g. 0x30010000)")
        ->required();
    build->add_option("-o,--output", out_path, "image file to write")->required();
    build->add_option("--name", name, "device name for the firmware file name (default MAXPOS)");

    std::string image_path, check_vendor, check_product;
    auto* info = app.add_subcommand("info", "print and verify an image's header");
    info->add_option("image", image_path, "image file")->required();
    info->add_option("--vendor", check_vendor, "verify against this vendor id (default: the image's own)");
    info->add_option("--product", check_product,
                     "verify against this product code (default: the image's own)");
    info->add_option("--name", name, "device name for the firmware file name (default MAXPOS)");

    CLI11_PARSE(app, argc, argv);

    if (build->parsed()) {
        foe::ImageIdentity id;
        uint32_t version = 0;
        if (!parse_u32(version_text, version) || !parse_u32(vendor_text, id.vendor_id) ||
            !parse_u32(product_text, id.product_code)) {
            std::fprintf(
                stderr,
                "fwimage: --version, --vendor and --product take 32-bit numbers (0x... or decimal)\n");
            return 2;
        }
        std::vector<uint8_t> payload;
        if (!read_file(payload_path, payload)) {
            std::fprintf(stderr, "fwimage: cannot read %s\n", payload_path.c_str());
            return 1;
        }
        if (payload.size() > foe::kMaxPayload) {
            std::fprintf(stderr, "fwimage: payload too large\n");
            return 1;
        }
        const auto image = foe::build_image(payload, id, version);
        std::ofstream f(out_path, std::ios::binary | std::ios::trunc);
        f.write(reinterpret_cast<const char*>(image.data()), static_cast<std::streamsize>(image.size()));
        f.close();
        if (!f) {
            std::fprintf(stderr, "fwimage: cannot write %s\n", out_path.c_str());
            return 1;
        }
        std::printf("%s: %zu bytes, firmware file name %s\n", out_path.c_str(), image.size(),
                    foe::firmware_file_name(name, id.product_code, version).c_str());
        return 0;
    }

    std::vector<uint8_t> bytes;
    if (!read_file(image_path, bytes)) {
        std::fprintf(stderr, "fwimage: cannot read %s\n", image_path.c_str());
        return 1;
    }
    if (bytes.size() < foe::kImageHeaderSize) {
        std::printf("%s: %zu bytes: %s\n", image_path.c_str(), bytes.size(),
                    std::string(foe::to_string(foe::ImageError::TooShort)).c_str());
        return 1;
    }
    const auto h = foe::decode_header(
        std::span<const uint8_t, foe::kImageHeaderSize>(bytes.data(), foe::kImageHeaderSize));
    foe::ImageIdentity id{h.vendor_id, h.product_code};
    if ((!check_vendor.empty() && !parse_u32(check_vendor, id.vendor_id)) ||
        (!check_product.empty() && !parse_u32(check_product, id.product_code))) {
        std::fprintf(stderr, "fwimage: --vendor and --product take 32-bit numbers\n");
        return 2;
    }
    const auto r = foe::verify_image(bytes, id);
    std::printf("file           %s (%zu bytes)\n", image_path.c_str(), bytes.size());
    std::printf("magic          0x%08X%s\n", h.magic, h.magic == foe::kImageMagic ? " (SEFW)" : " (wrong)");
    std::printf("header         version %u, %u bytes, flags 0x%08X\n", h.header_version, h.header_size,
                h.flags);
    std::printf("vendor id      0x%08X\n", h.vendor_id);
    std::printf("product code   0x%08X\n", h.product_code);
    std::printf("version        0x%08X (0x100A \"%s\")\n", h.version,
                foe::software_version_text(h.version).c_str());
    std::printf("payload        %u bytes\n", h.payload_length);
    std::printf("crc-32         0x%08X\n", h.crc);
    std::printf("file name      %s\n", foe::firmware_file_name(name, h.product_code, h.version).c_str());
    std::printf("verify         %s\n", r.ok() ? "ok" : foe::describe(r, id).c_str());
    return r.ok() ? 0 : 1;
}
