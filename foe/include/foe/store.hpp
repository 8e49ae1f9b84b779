#pragma once
// Two firmware slots in a state directory. A new image is written to the inactive slot through a temporary
// file (write, fsync, rename, fsync of the directory), read back and verified, and only then made active by
// atomically replacing the small "active" pointer file the same way. Whatever step the process dies at,
// the directory holds the previous active image and a pointer to it, or the new image and a pointer to it.
//
// Files in the directory: slot0.bin, slot1.bin, active ("slot0\n" or "slot1\n"), and *.tmp while writing.
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "foe/image.hpp"
#include "foe/sink.hpp"
#include "foe/wire/foe.hpp"

namespace foe {

// The steps of storing one image, in order. The test hook sees each one just before it runs.
enum class StoreStep : uint8_t {
    CreateTemp,     // create slotN.bin.tmp (the inactive slot)
    Append,         // write one received piece into the temp file (once per piece)
    SyncTemp,       // fsync + close the temp file
    RenameSlot,     // rename slotN.bin.tmp -> slotN.bin
    SyncDir,        // fsync the directory
    ReadBack,       // read the slot file back and verify it (once per chunk)
    WritePointer,   // write active.tmp
    SyncPointer,    // fsync + close active.tmp
    RenamePointer,  // rename active.tmp -> active (the switch)
    SyncPointerDir  // fsync the directory
};
std::string_view to_string(StoreStep s);

struct StoreConfig {
    std::filesystem::path dir;
    ImageIdentity identity;
    std::string device_name = "MAXPOS";    // file name prefix (MAXPOS firmware specification §9.2)
    uint64_t max_image_bytes = 64u << 20;  // larger images are refused with "disk full"
    std::size_t read_back_chunk = 64u << 10;
};

// StoreError and StoredImage: foe/sink.hpp.

class FirmwareStore : public FirmwareSink {
  public:
    explicit FirmwareStore(StoreConfig config);
    ~FirmwareStore() override;
    FirmwareStore(const FirmwareStore&) = delete;
    FirmwareStore& operator=(const FirmwareStore&) = delete;

    // Creates the directory if needed, removes stale temp files, reads the pointer and verifies the slots.
    // The active image is the pointed slot if it verifies, else the other slot if that verifies, else none.
    bool open(StoreError* error = nullptr);
    const std::optional<StoredImage>& active_image() const override { return active_; }
    // A valid stored image in the given slot (0 or 1), verified at open() or after the last commit.
    const std::optional<StoredImage>& image(unsigned slot) const override { return slots_[slot & 1]; }
    // The valid image whose file name is name (the active one first), if any.
    const StoredImage* find(std::string_view name) const;
    const StoreConfig& config() const { return config_; }

    // ---- writing a new image --------------------------------------------------------------------------
    // Starts a new image in the inactive slot (any unfinished one is dropped first).
    bool begin_write(StoreError& error) override;
    // Appends received bytes. The header is checked as soon as it is complete, so an image for another
    // device is refused at its first packet; too many bytes are refused at once.
    bool append(std::span<const uint8_t> data, StoreError& error) override;
    // All bytes received: checks length and CRC and prepares the commit.
    bool finish(StoreError& error) override;
    // One commit step (call repeatedly, e.g. from FoeServer::poll()). Done: the new image is active.
    Progress commit_step(StoreError& error) override;
    // Runs the commit to its end.
    Progress commit_all(StoreError& error);
    // Drops an unfinished image; the active one is not touched.
    void abort() override;
    bool writing() const { return phase_ == Phase::Receiving; }
    bool committing() const { return phase_ == Phase::Committing; }
    uint64_t received() const { return received_; }
    // Commit progress for FoE BUSY (done of entire). Safe to read while another thread runs commit_step().
    uint16_t progress_done() const override { return progress_.load(std::memory_order_relaxed); }
    uint16_t progress_entire() const override { return 100; }

    // Reading a stored image back: a read-only file descriptor of its slot file.
    int open_image(const StoredImage& image) override;
    long read_image(int handle, uint64_t offset, std::span<uint8_t> out) override;
    void close_image(int handle) override;

    // Test hook: called just before each storage step.
    void set_step_hook(std::function<void(StoreStep)> hook) { hook_ = std::move(hook); }

  private:
    enum class Phase : uint8_t { Idle, Receiving, Committing };
    std::filesystem::path slot_path(unsigned slot) const;
    std::filesystem::path pointer_path() const;
    std::optional<StoredImage> verify_slot(unsigned slot);
    bool sync_dir(StoreError& error);
    void step(StoreStep s) {
        if (hook_) hook_(s);
    }
    bool fail(StoreError& error, ErrorCode code, std::string text);
    uint16_t compute_progress() const;
    Progress run_step(StoreError& error);

    StoreConfig config_;
    std::optional<StoredImage> active_;
    std::optional<StoredImage> slots_[2];
    std::function<void(StoreStep)> hook_;
    std::vector<uint8_t> buffer_;  // read-back chunk, allocated once

    Phase phase_ = Phase::Idle;
    unsigned target_ = 0;
    int fd_ = -1;
    uint64_t received_ = 0;
    uint8_t header_bytes_[kImageHeaderSize] = {};
    ImageHeader header_{};
    bool header_ok_ = false;
    uint32_t crc_ = 0;
    StoreStep next_ = StoreStep::SyncTemp;
    uint64_t read_back_offset_ = 0;
    uint32_t read_back_crc_ = 0;
    std::atomic<uint16_t> progress_{0};
};

}  // namespace foe
