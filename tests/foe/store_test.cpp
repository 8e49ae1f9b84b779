#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <map>

#include "foe/store.hpp"
#include "foe_test_support.hpp"

using namespace foe;
using foe_test::kMaxpos;
using foe_test::TempDir;

namespace {

StoreConfig config(const std::filesystem::path& dir) {
    StoreConfig c;
    c.dir = dir;
    c.identity = kMaxpos;
    c.read_back_chunk = 64 << 10;
    return c;
}

// Writes an image the way the FoE server does: begin, append in pieces, finish, commit.
StoreError install(FirmwareStore& s, const std::vector<uint8_t>& image, std::size_t piece = 50'000) {
    StoreError e;
    if (!s.begin_write(e)) return e;
    for (std::size_t off = 0; off < image.size(); off += piece) {
        const std::size_t n = std::min(piece, image.size() - off);
        if (!s.append({image.data() + off, n}, e)) return e;
    }
    if (!s.finish(e)) return e;
    if (s.commit_all(e) != FirmwareStore::Progress::Done) return e;
    return {};
}

std::vector<uint8_t> large_image(uint32_t version, std::size_t size = 150'000) {
    return build_image(foe_test::payload_bytes(size, version), kMaxpos, version);
}

bool no_temp_files(const std::filesystem::path& dir) {
    for (const auto& f : std::filesystem::directory_iterator(dir))
        if (f.path().extension() == ".tmp") return false;
    return true;
}

// Forks a child that installs `image` into the store at dir and calls stop() (which ends it) before commit
// step k. The child exits 3 if the store does not open, 2 if step k never came (the step list changed) unless
// may_finish, then 0 for an installed image, 4 for a refused one. Returns the child's pid (-1: no fork).
pid_t install_in_child(const std::filesystem::path& dir, const std::vector<uint8_t>& image, std::size_t k,
                       void (*stop)(), bool may_finish) {
    const pid_t child = ::fork();
    if (child != 0) return child;
    FirmwareStore s(config(dir));
    if (!s.open()) ::_exit(3);
    std::size_t count = 0;
    s.set_step_hook([&](StoreStep) {
        if (count++ == k) stop();
    });
    StoreError e = install(s, image);
    if (!may_finish) ::_exit(2);
    ::_exit(e.code == ErrorCode::NotDefined ? 0 : 4);
}

}  // namespace

TEST(FoeStore, EmptyDirectoryHasNoActiveImage) {
    TempDir d;
    FirmwareStore s(config(d.path / "state"));
    ASSERT_TRUE(s.open());
    EXPECT_FALSE(s.active_image().has_value());
}

TEST(FoeStore, InstallAlternatesSlotsAndSurvivesReopen) {
    TempDir d;
    {
        FirmwareStore s(config(d.path));
        ASSERT_TRUE(s.open());
        EXPECT_EQ(install(s, large_image(0x01200000)).code, ErrorCode::NotDefined);
        ASSERT_TRUE(s.active_image());
        EXPECT_EQ(s.active_image()->slot, 0u);
        EXPECT_EQ(s.active_image()->header.version, 0x01200000u);
        EXPECT_EQ(s.active_image()->file_name, "MAXPOS_0120h_3001h_0000h_0000h.bin");
        EXPECT_EQ(install(s, large_image(0x01300000)).code, ErrorCode::NotDefined);
        EXPECT_EQ(s.active_image()->slot, 1u);
        ASSERT_TRUE(s.image(0));  // the previous image is kept in the other slot
        EXPECT_EQ(s.image(0)->header.version, 0x01200000u);
    }
    FirmwareStore s(config(d.path));
    ASSERT_TRUE(s.open());
    ASSERT_TRUE(s.active_image());
    EXPECT_EQ(s.active_image()->header.version, 0x01300000u);
    EXPECT_NE(s.find("MAXPOS_0120h_3001h_0000h_0000h.bin"), nullptr);
    EXPECT_TRUE(no_temp_files(d.path));
}

TEST(FoeStore, RefusedImagesLeaveTheActiveOne) {
    TempDir d;
    FirmwareStore s(config(d.path));
    ASSERT_TRUE(s.open());
    ASSERT_EQ(install(s, large_image(0x01200000)).code, ErrorCode::NotDefined);

    auto other = build_image(foe_test::payload_bytes(1000, 3), {0xFB, 0x30020000}, 0x01300000);
    EXPECT_EQ(install(s, other).code, ErrorCode::InvalidFirmware);
    auto corrupt = large_image(0x01300000);
    corrupt[5000] ^= 0xFF;
    EXPECT_EQ(install(s, corrupt).code, ErrorCode::InvalidChecksum);
    auto shortened = large_image(0x01300000);
    shortened.resize(shortened.size() - 10);
    EXPECT_EQ(install(s, shortened).code, ErrorCode::FileHeaderError);
    auto longer = large_image(0x01300000);
    longer.push_back(1);
    EXPECT_EQ(install(s, longer).code, ErrorCode::FileHeaderError);
    EXPECT_EQ(install(s, {1, 2, 3}).code, ErrorCode::FileHeaderError);

    ASSERT_TRUE(s.active_image());
    EXPECT_EQ(s.active_image()->header.version, 0x01200000u);
    EXPECT_TRUE(no_temp_files(d.path));
    FirmwareStore again(config(d.path));
    ASSERT_TRUE(again.open());
    EXPECT_EQ(again.active_image()->header.version, 0x01200000u);
}

TEST(FoeStore, OversizedImageIsDiskFull) {
    TempDir d;
    auto c = config(d.path);
    c.max_image_bytes = 10'000;
    FirmwareStore s(c);
    ASSERT_TRUE(s.open());
    EXPECT_EQ(install(s, large_image(0x01200000, 20'000)).code, ErrorCode::DiskFull);
}

TEST(FoeStore, CorruptedActiveSlotFallsBackToTheOtherAndRepairsThePointer) {
    TempDir d;
    {
        FirmwareStore s(config(d.path));
        ASSERT_TRUE(s.open());
        ASSERT_EQ(install(s, large_image(0x01200000)).code, ErrorCode::NotDefined);
        ASSERT_EQ(install(s, large_image(0x01300000)).code, ErrorCode::NotDefined);
    }
    {
        std::fstream f(d.path / "slot1.bin", std::ios::in | std::ios::out | std::ios::binary);
        f.seekp(1000);
        f.put('\x55');
    }
    FirmwareStore s(config(d.path));
    ASSERT_TRUE(s.open());
    ASSERT_TRUE(s.active_image());
    EXPECT_EQ(s.active_image()->header.version, 0x01200000u);
    std::ifstream p(d.path / "active");
    std::string text;
    std::getline(p, text);
    EXPECT_EQ(text, "slot0");
    // The next image goes to slot 1, never over the one that boots.
    ASSERT_EQ(install(s, large_image(0x01400000)).code, ErrorCode::NotDefined);
    EXPECT_EQ(s.active_image()->slot, 1u);
}

TEST(FoeStore, GarbagePointerStillBoots) {
    TempDir d;
    {
        FirmwareStore s(config(d.path));
        ASSERT_TRUE(s.open());
        ASSERT_EQ(install(s, large_image(0x01200000)).code, ErrorCode::NotDefined);
    }
    std::ofstream(d.path / "active") << "slot7\n";
    FirmwareStore s(config(d.path));
    ASSERT_TRUE(s.open());
    ASSERT_TRUE(s.active_image());
    EXPECT_EQ(s.active_image()->header.version, 0x01200000u);
}

TEST(FoeStore, StaleTempFilesAreRemovedAtOpen) {
    TempDir d;
    std::ofstream(d.path / "slot0.bin.tmp") << "half an image";
    std::ofstream(d.path / "active.tmp") << "slot0\n";
    FirmwareStore s(config(d.path));
    ASSERT_TRUE(s.open());
    EXPECT_FALSE(s.active_image());
    EXPECT_TRUE(no_temp_files(d.path));
}

// The process dies just before storage step k, for every k: the previous image stays active (or, once the
// pointer was switched, the new one), the device boots, and the next download works.
TEST(FoeStore, KilledAtEveryStepLeavesABootableDevice) {
    const auto old_image = large_image(0x01200000);
    const auto new_image = large_image(0x01300000, 200'000);

    // Dry run: the sequence of steps.
    std::vector<StoreStep> steps;
    {
        TempDir d;
        FirmwareStore s(config(d.path));
        ASSERT_TRUE(s.open());
        ASSERT_EQ(install(s, old_image).code, ErrorCode::NotDefined);
        s.set_step_hook([&](StoreStep st) { steps.push_back(st); });
        ASSERT_EQ(install(s, new_image).code, ErrorCode::NotDefined);
    }
    std::size_t switch_at = steps.size();
    for (std::size_t i = 0; i < steps.size(); ++i)
        if (steps[i] == StoreStep::RenamePointer) switch_at = i;
    ASSERT_LT(switch_at, steps.size());
    ASSERT_GE(steps.size(), 12u);  // create, 4 appends, sync, rename, sync, >= 3 read-backs, pointer x4

    for (std::size_t k = 0; k < steps.size(); ++k) {
        SCOPED_TRACE("killed before step " + std::to_string(k) + " (" + std::string(to_string(steps[k])) +
                     ")");
        TempDir d;
        {
            FirmwareStore s(config(d.path));
            ASSERT_TRUE(s.open());
            ASSERT_EQ(install(s, old_image).code, ErrorCode::NotDefined);
        }
        const pid_t child = install_in_child(
            d.path, new_image, k, [] { ::_exit(0); }, false);
        ASSERT_GE(child, 0);
        int status = 0;
        ASSERT_EQ(::waitpid(child, &status, 0), child);
        ASSERT_TRUE(WIFEXITED(status));
        ASSERT_EQ(WEXITSTATUS(status), 0);

        FirmwareStore s(config(d.path));
        ASSERT_TRUE(s.open());
        ASSERT_TRUE(s.active_image());
        EXPECT_EQ(s.active_image()->header.version, k <= switch_at ? 0x01200000u : 0x01300000u);
        EXPECT_TRUE(no_temp_files(d.path));
        // And the download can simply be repeated.
        EXPECT_EQ(install(s, new_image).code, ErrorCode::NotDefined);
        EXPECT_EQ(s.active_image()->header.version, 0x01300000u);
    }
}

// Each commit step does a bounded amount of work (one fsync, one rename or one read-back chunk), so a
// poll() that runs one step never stalls the frame loop for the whole image. Prints the step times.
TEST(FoeStore, CommitStepsAreBounded) {
    TempDir d;
    auto c = config(d.path);
    c.read_back_chunk = 64 << 10;
    FirmwareStore s(c);
    ASSERT_TRUE(s.open());
    const auto image = large_image(0x01300000, 1 << 20);
    StoreError e;
    ASSERT_TRUE(s.begin_write(e));
    for (std::size_t off = 0; off < image.size(); off += 1012)
        ASSERT_TRUE(s.append({image.data() + off, std::min<std::size_t>(1012, image.size() - off)}, e));
    ASSERT_TRUE(s.finish(e));
    std::size_t steps = 0, read_backs = 0;
    std::map<std::string, double> worst_ms;
    s.set_step_hook([&](StoreStep st) { read_backs += st == StoreStep::ReadBack; });
    for (;;) {
        const auto t0 = std::chrono::steady_clock::now();
        const auto before = s.progress_done();
        const auto p = s.commit_step(e);
        const double ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        ++steps;
        std::string key = before >= 20 && before < 80 ? "read back" : "step@" + std::to_string(before);
        worst_ms[key] = std::max(worst_ms[key], ms);
        ASSERT_NE(p, FirmwareStore::Progress::Failed) << e.text;
        if (p == FirmwareStore::Progress::Done) break;
    }
    EXPECT_GE(read_backs, image.size() / (64 << 10));  // 1 MiB in >= 16 chunks
    EXPECT_EQ(s.active_image()->header.version, 0x01300000u);
    for (const auto& [k, v] : worst_ms)
        std::printf("  commit %-10s worst %.3f ms\n", k.c_str(), v);
    std::printf("  %zu commit steps for a 1 MiB image\n", steps);
}

// Issue 14, finding 3: every loader checks sizes against the bytes present before reading or reserving.
// Crafted slot and pointer files (a header announcing more than is there or more than a slot may hold, a
// sparse file of the announced size, FIFOs, an oversized pointer) are not images: the store opens, the
// valid image stays active, and a download still works.
TEST(FoeStore, CraftedSlotAndPointerFilesAreNotImages) {
    TempDir d;
    const auto good = large_image(0x01200000);
    {
        FirmwareStore s(config(d.path));
        ASSERT_TRUE(s.open());
        ASSERT_EQ(install(s, good).code, ErrorCode::NotDefined);
        ASSERT_EQ(s.active_image()->slot, 0u);
    }
    auto header_only = [&](uint32_t payload_length) {
        ImageHeader h =
            decode_header(std::span<const uint8_t, kImageHeaderSize>(good.data(), kImageHeaderSize));
        h.payload_length = payload_length;
        std::vector<uint8_t> b(kImageHeaderSize);
        encode_header(h, std::span<uint8_t, kImageHeaderSize>(b.data(), kImageHeaderSize));
        return b;
    };
    auto write_file = [](const std::filesystem::path& p, const std::vector<uint8_t>& b) {
        std::filesystem::remove(p);
        std::ofstream(p, std::ios::binary)
            .write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
    };
    const auto slot1 = d.path / "slot1.bin";
    const auto pointer = d.path / "active";
    for (int variant = 0; variant < 6; ++variant) {
        SCOPED_TRACE("variant " + std::to_string(variant));
        std::filesystem::remove(slot1);
        switch (variant) {
            case 0:  // 32 bytes announcing the largest payload
                write_file(slot1, header_only(kMaxPayload));
                break;
            case 1:  // sparse 2 GiB file of exactly the announced size: larger than a slot may hold
                write_file(slot1, header_only(kMaxPayload));
                std::filesystem::resize_file(slot1, kImageHeaderSize + uint64_t{kMaxPayload});
                break;
            case 2:  // a FIFO in place of the slot
                ASSERT_EQ(::mkfifo(slot1.c_str(), 0600), 0);
                break;
            case 3:  // pointer to slot1 with slot1 crafted
                write_file(slot1, header_only(0xFFFFFFFFu));
                std::ofstream(pointer) << "slot1\n";
                break;
            case 4:  // an oversized (sparse) pointer file that starts like a valid one
                std::ofstream(pointer) << "slot0\n";
                std::filesystem::resize_file(pointer, uint64_t{1} << 32);
                break;
            case 5:  // a FIFO in place of the pointer
                std::filesystem::remove(pointer);
                ASSERT_EQ(::mkfifo(pointer.c_str(), 0600), 0);
                break;
        }
        FirmwareStore s(config(d.path));
        StoreError e;
        ASSERT_TRUE(s.open(&e)) << e.text;  // without hanging on a FIFO; a bad pointer is repaired
        ASSERT_TRUE(s.active_image());
        EXPECT_EQ(s.active_image()->header.version, 0x01200000u);
        EXPECT_FALSE(s.image(1));
        if (variant >= 4) {
            std::filesystem::remove(pointer);
            std::ofstream(pointer) << "slot0\n";
        }
    }
    std::filesystem::remove(slot1);
    FirmwareStore s(config(d.path));
    ASSERT_TRUE(s.open());
    EXPECT_EQ(install(s, large_image(0x01300000)).code, ErrorCode::NotDefined);
    EXPECT_EQ(s.active_image()->header.version, 0x01300000u);
}

// Issue 14, finding 6: a first-ever update SIGKILLed after the slot rename booted the new image although the
// master never got the final ACK (there was no pointer, and open() took any valid slot). With no previous
// image the rule is the one with a previous image: until the pointer switch nothing new boots (here: no
// image at all, the built-in firmware), from the switch on the new image. A child process storing the image
// is killed with SIGKILL just before each storage step in turn.
TEST(FoeStore, FirstUpdateKilledAtEveryStepBootsOnlyWhatWasSwitchedTo) {
    const auto new_image = large_image(0x01300000, 200'000);
    std::vector<StoreStep> steps;
    {
        TempDir d;
        FirmwareStore s(config(d.path));
        ASSERT_TRUE(s.open());
        s.set_step_hook([&](StoreStep st) { steps.push_back(st); });
        ASSERT_EQ(install(s, new_image).code, ErrorCode::NotDefined);
    }
    std::size_t switch_at = steps.size(), rename_slot_at = steps.size();
    for (std::size_t i = 0; i < steps.size(); ++i) {
        if (steps[i] == StoreStep::RenamePointer) switch_at = i;
        if (steps[i] == StoreStep::RenameSlot) rename_slot_at = i;
    }
    ASSERT_LT(rename_slot_at, switch_at);
    ASSERT_LT(switch_at, steps.size());

    for (std::size_t k = 0; k <= steps.size(); ++k) {
        SCOPED_TRACE(
            "killed before step " + std::to_string(k) +
            (k < steps.size() ? " (" + std::string(to_string(steps[k])) + ")" : " (after the last)"));
        TempDir d;
        const pid_t child = install_in_child(
            d.path, new_image, k, [] { ::kill(::getpid(), SIGKILL); }, k >= steps.size());
        ASSERT_GE(child, 0);
        int status = 0;
        ASSERT_EQ(::waitpid(child, &status, 0), child);
        if (k < steps.size()) {
            ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) << status;
        } else {
            ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status;
        }

        FirmwareStore s(config(d.path));
        ASSERT_TRUE(s.open());
        if (k <= switch_at) {
            EXPECT_FALSE(s.active_image()) << "an image the master never got the ACK for boots";
            EXPECT_EQ(s.find("MAXPOS_0130h_3001h_0000h_0000h.bin"), nullptr);
        } else {
            ASSERT_TRUE(s.active_image());
            EXPECT_EQ(s.active_image()->header.version, 0x01300000u);
        }
        EXPECT_TRUE(no_temp_files(d.path));
        // A second start decides the same, and the download can simply be repeated.
        FirmwareStore again(config(d.path));
        ASSERT_TRUE(again.open());
        EXPECT_EQ(again.active_image().has_value(), k > switch_at);
        EXPECT_EQ(install(again, new_image).code, ErrorCode::NotDefined);
        EXPECT_EQ(again.active_image()->header.version, 0x01300000u);
    }
}
