// The soft drive starting over a state directory with crafted files (issue 14, findings 3 and 7): every
// loader checks sizes against the bytes present before reserving anything, so a bad file is reported and
// the defaults run; temporaries an interrupted save left behind are removed at the start.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "device/device.hpp"
#include "esc/clock.hpp"
#include "esc/esc.hpp"
#include "foe/image.hpp"
#include "maxpos/maxpos.hpp"
#include "od/store.hpp"
#include "support/temp_dir.hpp"
#include "util/crc.hpp"

namespace fs = std::filesystem;

namespace {

struct StateDir : test_support::TempDir {
    StateDir() : TempDir("softdrive-state-") {}
};

// An ESC on a manual clock and the options that start a Device from the state directory dir, its log kept.
struct PowerOn {
    esc::ManualClock clock;
    esc::Esc esc{esc::EscConfig{}, clock};
    std::ostringstream log;
    device::DeviceOptions options;
    explicit PowerOn(const fs::path& dir) {
        clock.set(1'000'000'000);
        options.state_dir = dir;
        options.log = &log;
    }
};

void put32(std::vector<uint8_t>& b, std::size_t at, uint32_t v) {
    for (int i = 0; i < 4; ++i)
        b[at + i] = static_cast<uint8_t>(v >> (8 * i));
}

void write_file(const fs::path& p, const std::vector<uint8_t>& b) {
    std::ofstream(p, std::ios::binary | std::ios::trunc)
        .write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
}

// The file the campaign found: 40 bytes, this device's identity, record count 0xFFFFFFFF, valid CRCs.
std::vector<uint8_t> parameters_with_count(const od::Identity& id, uint32_t count) {
    std::vector<uint8_t> b(40, 0);
    const char magic[8] = {'S', 'E', 'C', 'A', 'T', 'P', 'R', 'M'};
    std::copy(magic, magic + 8, b.begin());
    b[8] = 1;    // format version
    b[10] = 40;  // header bytes
    put32(b, 12, id.vendor_id);
    put32(b, 16, id.product_code);
    put32(b, 20, id.revision);
    put32(b, 24, count);
    put32(b, 28, 0);  // payload bytes
    put32(b, 32, util::crc32({}));
    put32(b, 36, util::crc32(std::span<const uint8_t>(b).first(36)));
    return b;
}

// sii-writes.bin announcing 0xFFFFFFFF words, CRC right.
std::vector<uint8_t> sii_writes_with_count(uint32_t count) {
    std::vector<uint8_t> b = {'S', 'E', 'C', 'A', 'T', 'S', 'I', 'I', 0, 0, 0, 0, 0, 0, 0, 0};
    put32(b, 8, count);
    put32(b, 12, util::crc32(std::span<const uint8_t>(b).first(12)));
    return b;
}

}  // namespace

TEST(DeviceStateFiles, CraftedFilesAreReportedAndTheDefaultsRun) {
    StateDir d;
    const od::DeviceDescription desc = maxpos::description();
    write_file(d.path / "parameters.bin", parameters_with_count(desc.identity, 0xFFFFFFFFu));
    ASSERT_EQ(fs::file_size(d.path / "parameters.bin"), 40u);
    write_file(d.path / device::EepromWrites::kFileName, sii_writes_with_count(0xFFFFFFFFu));
    fs::create_directories(d.path / "firmware");
    {
        foe::ImageHeader h;
        h.vendor_id = desc.identity.vendor_id;
        h.product_code = desc.identity.product_code;
        h.version = 0x01300000;
        h.payload_length = foe::kMaxPayload;
        std::vector<uint8_t> b(foe::kImageHeaderSize);
        foe::encode_header(h, std::span<uint8_t, foe::kImageHeaderSize>(b.data(), foe::kImageHeaderSize));
        write_file(d.path / "firmware" / "slot0.bin", b);
        fs::resize_file(d.path / "firmware" / "slot0.bin",
                        foe::kImageHeaderSize + uint64_t{foe::kMaxPayload});
        std::ofstream(d.path / "firmware" / "active") << "slot0\n";
    }

    PowerOn on(d.path);
    std::unique_ptr<device::Device> dev;
    ASSERT_NO_THROW(dev = std::make_unique<device::Device>(on.esc, on.options)) << on.log.str();
    // Reported ...
    EXPECT_TRUE(dev->parameter_load().found);
    EXPECT_FALSE(dev->parameter_load().applied);
    EXPECT_NE(on.log.str().find("stored parameters"), std::string::npos) << on.log.str();
    EXPECT_NE(on.log.str().find(device::EepromWrites::kFileName), std::string::npos) << on.log.str();
    // ... and the defaults run: the dictionary's stored parameters, the built-in firmware, the SII as built.
    const od::Dictionary defaults = maxpos::dictionary(desc);
    EXPECT_EQ(dev->dictionary().get<uint32_t>(0x6065, 0), defaults.get<uint32_t>(0x6065, 0));
    EXPECT_EQ(dev->dictionary().get<uint32_t>(0x1018, 3), desc.identity.revision);
    EXPECT_FALSE(dev->firmware_store().active_image());
    EXPECT_TRUE(dev->eeprom_writes().empty());
    dev->poll(on.clock.now_ns());
}

TEST(DeviceStateFiles, OversizedSiiWritesFileIsNotRead) {
    StateDir d;
    write_file(d.path / device::EepromWrites::kFileName, sii_writes_with_count(2));
    fs::resize_file(d.path / device::EepromWrites::kFileName, uint64_t{1} << 32);  // sparse 4 GiB
    device::EepromWrites w(d.path);
    const std::string error = w.load();
    EXPECT_NE(error.find("larger than"), std::string::npos) << error;
    EXPECT_TRUE(w.empty());
    fs::remove(d.path / device::EepromWrites::kFileName);
    ASSERT_EQ(::mkfifo((d.path / device::EepromWrites::kFileName).c_str(), 0600), 0);
    EXPECT_FALSE(w.load().empty());  // refused without waiting for a writer
    EXPECT_TRUE(w.empty());
}

// Issue 14, finding 7: temporaries of saves killed half-way (parameters, SII words, firmware slot and
// pointer) are removed when the device starts; the files they were to replace are untouched.
TEST(DeviceStateFiles, StaleTemporariesAreRemovedAtTheStart) {
    StateDir d;
    fs::create_directories(d.path / "firmware");
    // parameters.bin.tmp the way the campaign got it: a save SIGKILLed once its temporary was written.
    {
        od::Dictionary dict = maxpos::dictionary(maxpos::description());
        od::ParameterStore store(d.path);
        const pid_t pid = ::fork();
        ASSERT_GE(pid, 0);
        if (pid == 0) {
            store.on_step = [](std::string_view step) {
                if (step == "temp-written") ::kill(::getpid(), SIGKILL);
            };
            store.save(dict);
            ::_exit(0);
        }
        int status = 0;
        ASSERT_EQ(::waitpid(pid, &status, 0), pid);
        ASSERT_TRUE(WIFSIGNALED(status)) << status;
    }
    const std::vector<fs::path> stale = {
        d.path / "parameters.bin.tmp", d.path / "sii-writes.bin.tmp", d.path / "firmware" / "slot0.bin.tmp",
        d.path / "firmware" / "slot1.bin.tmp", d.path / "firmware" / "active.tmp"};
    for (std::size_t i = 1; i < stale.size(); ++i)
        std::ofstream(stale[i]) << "half written";
    for (const auto& p : stale)
        ASSERT_TRUE(fs::exists(p)) << p;

    PowerOn on(d.path);
    device::Device dev(on.esc, on.options);
    for (const auto& p : stale)
        EXPECT_FALSE(fs::exists(p)) << p;
    EXPECT_NE(on.log.str().find("parameters.bin.tmp left by an interrupted save"), std::string::npos)
        << on.log.str();
    EXPECT_FALSE(dev.parameter_load().found);  // the temporary was never the parameter file
}
