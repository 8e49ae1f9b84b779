// (7) Every file the slave loads at start from its state directory, written from the input and loaded by
// the real code. The first byte picks the loader and whether the harness repairs lengths and CRCs first
// (so that mutations get past the checksums to the parsing behind them):
//   0  parameters.bin    od::ParameterStore::load on the drive's dictionary (od/src/store.cpp)
//   1  sii-writes.bin    device::EepromWrites::load, then apply onto the SII (tools/lib/device)
//   2  firmware/         foe::FirmwareStore::open: the slot pointer "active" and both slot images, input =
//                        three records (16-bit length + bytes): pointer, slot0.bin, slot1.bin
//   3  device config     maxpos::load_config of the file (tools/ecat-slave --config)
// The contract (issue 14, finding 3): a bad file is reported and the defaults run; nothing else.
#include <stdlib.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "device/eeprom_writes.hpp"
#include "esi/sii.hpp"
#include "foe/store.hpp"
#include "fuzz_support.hpp"
#include "harnesses.hpp"
#include "maxpos/maxpos.hpp"
#include "od/device_config.hpp"
#include "od/store.hpp"
#include "util/crc.hpp"
#include "util/le.hpp"

namespace fuzz::loaders {
namespace {

const std::filesystem::path& state_dir() {
    static const ScratchDir dir;
    return dir.path;
}

void write_file(const std::filesystem::path& p, std::span<const uint8_t> bytes) {
    std::ofstream f(p, std::ios::binary | std::ios::trunc);
    f.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}
using util::get32;
using util::put32;

const od::DeviceDescription& description() {
    static const od::DeviceDescription d = maxpos::description();
    return d;
}
od::Dictionary& dictionary() {
    static od::Dictionary dict = maxpos::dictionary(description());
    return dict;
}

void parameters(std::vector<uint8_t> b, bool repair) {
    constexpr std::size_t kHeader = od::ParameterStore::kHeaderBytes;
    if (repair && b.size() >= kHeader) {
        put32(b, 28, static_cast<uint32_t>(b.size() - kHeader));
        put32(b, 32, util::crc32(std::span<const uint8_t>(b).subspan(kHeader)));
        put32(b, 36, util::crc32(std::span<const uint8_t>(b).first(36)));
    }
    write_file(state_dir() / "parameters.bin", b);
    // A rejected file changes nothing (all or nothing); an applied one sets stored values, which the next
    // input may overwrite again: the dictionary is built once.
    od::Dictionary& dict = dictionary();
    const od::ParameterStore store(state_dir());
    const od::ParameterStore::LoadResult r = store.load(dict);
    FUZZ_CHECK(r.found);
    FUZZ_CHECK(r.applied == r.error.empty());
}

void eeprom_writes(std::vector<uint8_t> b, bool repair) {
    if (repair && b.size() >= 16) {
        put32(b, 8, static_cast<uint32_t>((b.size() - 16) / 4));
        b.resize(16 + 4 * std::size_t{get32(b, 8)});
        put32(b, b.size() - 4, util::crc32(std::span<const uint8_t>(b).first(b.size() - 4)));
    }
    write_file(state_dir() / "sii-writes.bin", b);
    device::EepromWrites w(state_dir());
    const std::string error = w.load();
    FUZZ_CHECK(error.empty() || w.empty());
    static const std::vector<uint8_t> sii = esi::build_sii(description(), dictionary());
    std::vector<uint8_t> image = sii;
    w.apply(image);
    FUZZ_CHECK(image.size() == sii.size());
}

void repair_image(std::vector<uint8_t>& b) {
    if (b.size() < foe::kImageHeaderSize) return;
    put32(b, 20, static_cast<uint32_t>(b.size() - foe::kImageHeaderSize));
    std::span<const uint8_t, foe::kImageHeaderSize> h(b.data(), foe::kImageHeaderSize);
    put32(b, 28, util::crc32(std::span<const uint8_t>(b).subspan(foe::kImageHeaderSize), foe::header_crc(h)));
}

void firmware(Input& in, bool repair) {
    const std::filesystem::path dir = state_dir() / "firmware";
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
    std::filesystem::create_directories(dir, ec);
    const char* names[3] = {"active", "slot0.bin", "slot1.bin"};
    for (int i = 0; i < 3; ++i) {
        const auto r = in.record();
        if (r.empty() && (in.u8() & 1)) continue;  // no such file
        std::vector<uint8_t> b(r.begin(), r.end());
        if (repair && i > 0) repair_image(b);
        write_file(dir / names[i], b);
    }
    foe::StoreConfig sc;
    sc.dir = dir;
    sc.identity = foe::ImageIdentity::from(description().identity);
    sc.device_name = description().identity.device_name;
    sc.read_back_chunk = 4096;
    foe::FirmwareStore store(sc);
    foe::StoreError e;
    if (store.open(&e) && store.active_image()) {
        const foe::StoredImage& a = *store.active_image();
        FUZZ_CHECK(store.image(a.slot).has_value());
        FUZZ_CHECK(a.size == foe::kImageHeaderSize + uint64_t{a.header.payload_length});
    }
}

void device_config(std::span<const uint8_t> b) {
    write_file(state_dir() / "device.conf", b);
    try {
        const od::DeviceDescription d = maxpos::load_config(state_dir() / "device.conf");
        (void)d;
    } catch (const od::ConfigError&) {
    }
}

}  // namespace

int fuzz_one(const uint8_t* data, std::size_t size) {
    Input in(data, size);
    const uint8_t which = in.u8();
    const bool repair = (which & 0x80) != 0;
    switch (which & 3) {
        case 0: {
            const auto r = in.rest();
            parameters({r.begin(), r.end()}, repair);
            break;
        }
        case 1: {
            const auto r = in.rest();
            eeprom_writes({r.begin(), r.end()}, repair);
            break;
        }
        case 2:
            firmware(in, repair);
            break;
        default:
            device_config(in.rest());
            break;
    }
    return 0;
}

}  // namespace fuzz::loaders
