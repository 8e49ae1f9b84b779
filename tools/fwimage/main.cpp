// fwimage build --payload FILE --version 0x01200000 [--vendor 0xFB --product 0x30010000 | --esi FILE |
//               --config FILE] -o image.bin        (vendor, product and name default to the drive's own)
// fwimage info image.bin [--vendor V --product P]
// Exit codes: 0 ok, 1 failure (an image that does not verify, a file that cannot be written), 2 usage (bad
// options, an input file that cannot be read).
#include <CLI/CLI.hpp>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <iterator>
#include <string>
#include <vector>

#include "foe/image.hpp"
#include "identity.hpp"
#include "util/input_file.hpp"

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

// A regular file of at most kMaxInputBytes (the largest image a firmware store takes), checked first.
constexpr std::size_t kMaxInputBytes = std::size_t{64} << 20;
bool read_file(const std::string& path, std::vector<uint8_t>& out) {
    try {
        out = util::read_input_bytes(path, kMaxInputBytes, "input file");
    } catch (const util::InputFileError& e) {
        std::fprintf(stderr, "fwimage: %s\n", e.what());
        return false;
    }
    return true;
}

// The image to `path`, or to standard output for "-"; says why on failure.
bool write_file(const std::string& path, const std::vector<uint8_t>& bytes) {
    FILE* f = path == "-" ? stdout : std::fopen(path.c_str(), "wb");
    if (!f) {
        std::fprintf(stderr, "fwimage: cannot write %s: %s\n", path.c_str(), std::strerror(errno));
        return false;
    }
    const bool ok = std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size() && std::fflush(f) == 0;
    const int err = errno;
    const bool closed = f == stdout || std::fclose(f) == 0;
    if (!ok || !closed) {
        std::fprintf(stderr, "fwimage: cannot write %s: %s\n", path.c_str(),
                     std::strerror(err ? err : errno));
        return false;
    }
    return true;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"Build and inspect firmware images for the soft EtherCAT drive (FoE download)"};
    app.set_version_flag("--version", std::string("fwimage ") + SOFTECAT_VERSION);
    app.require_subcommand(1);

    const fwimage::DeviceIdentity defaults = fwimage::default_identity();
    std::string payload_path, out_path, version_text, vendor_text, product_text, name, esi_path, config_path;
    auto* build = app.add_subcommand("build", "wrap a payload into a firmware image");
    build->add_option("--payload", payload_path, "payload file")->required();
    build->add_option("--version", version_text, "firmware version = revision 0x1018:03 (e.g. 0x01200000)")
        ->required();
    build->add_option("--vendor", vendor_text, "vendor id the image is for (default: the device's)");
    build->add_option("--product", product_text, "product code the image is for (default: the device's)");
    auto* esi_opt = build->add_option("--esi", esi_path,
                                      "take vendor, product and name from this ESI file (first Device)");
    build->add_option("--config", config_path, "take vendor, product and name from this device configuration")
        ->excludes(esi_opt);
    build->add_option("-o,--output", out_path, "image file to write ('-': standard output)")->required();
    build->add_option("--name", name, "device name for the firmware file name (default: the device's)");

    std::string image_path, check_vendor, check_product;
    auto* info = app.add_subcommand("info", "print and verify an image's header");
    info->add_option("image", image_path, "image file")->required();
    info->add_option("--vendor", check_vendor, "verify against this vendor id (default: the image's own)");
    info->add_option("--product", check_product,
                     "verify against this product code (default: the image's own)");
    info->add_option("--name", name, "device name for the firmware file name (default: the device's)");

    try {
        app.parse(argc, argv);
    } catch (const CLI::Success& e) {  // --help, --version
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        std::cerr << "fwimage: " << e.what() << " (fwimage --help)\n";  // one line
        return 2;
    }

    if (build->parsed()) {
        fwimage::DeviceIdentity device = defaults;
        std::string error;
        if (!esi_path.empty() || !config_path.empty()) {
            auto from_file = esi_path.empty() ? fwimage::identity_from_config(config_path, error)
                                              : fwimage::identity_from_esi(esi_path, error);
            if (!from_file) {
                std::fprintf(stderr, "fwimage: %s\n", error.c_str());
                return 2;
            }
            device = *from_file;
        }
        foe::ImageIdentity id{device.vendor_id, device.product_code};
        uint32_t version = 0;
        if (!parse_u32(version_text, version) ||
            (!vendor_text.empty() && !parse_u32(vendor_text, id.vendor_id)) ||
            (!product_text.empty() && !parse_u32(product_text, id.product_code))) {
            std::fprintf(
                stderr,
                "fwimage: --version, --vendor and --product take 32-bit numbers (0x... or decimal)\n");
            return 2;
        }
        if (name.empty()) name = device.device_name;
        std::vector<uint8_t> payload;
        if (!read_file(payload_path, payload)) return 2;
        if (payload.size() > foe::kMaxPayload) {
            std::fprintf(stderr, "fwimage: %s: payload too large (%zu bytes, at most %zu)\n",
                         payload_path.c_str(), payload.size(), static_cast<std::size_t>(foe::kMaxPayload));
            return 2;
        }
        const auto image = foe::build_image(payload, id, version);
        if (!write_file(out_path, image)) return 1;
        // The summary goes to stderr when the image itself goes to standard output.
        std::fprintf(out_path == "-" ? stderr : stdout,
                     "%s: %zu bytes for vendor 0x%08X product 0x%08X, firmware file name %s\n",
                     out_path == "-" ? "<stdout>" : out_path.c_str(), image.size(), id.vendor_id,
                     id.product_code, foe::firmware_file_name(name, id.product_code, version).c_str());
        return 0;
    }

    if (name.empty()) name = defaults.device_name;
    std::vector<uint8_t> bytes;
    if (!read_file(image_path, bytes)) return 2;
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
