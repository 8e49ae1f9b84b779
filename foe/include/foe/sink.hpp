#pragma once
// What the FoE server needs from the place firmware images go to and come from: receive a new image piece
// by piece, commit it in steps, drop it, and read a stored image back. foe::FirmwareStore is the real one
// (two slots in a state directory, fsync at every step); anything else (an in-memory sink for fuzzing the
// server without a file system) implements the same contract.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>

#include "foe/image.hpp"
#include "foe/wire/foe.hpp"

namespace foe {

// A failed operation: the FoE error code and a readable detail.
struct StoreError {
    ErrorCode code = ErrorCode::NotDefined;
    std::string text;
};

struct StoredImage {
    unsigned slot = 0;
    ImageHeader header{};
    std::string file_name;  // firmware file name of the image (MAXPOS firmware specification §9.2)
    std::filesystem::path path;
    uint64_t size = 0;  // header + payload
};

class FirmwareSink {
  public:
    enum class Progress : uint8_t { Running, Done, Failed };

    virtual ~FirmwareSink() = default;

    // The image that boots, and the valid image of each slot (0 or 1), if any.
    virtual const std::optional<StoredImage>& active_image() const = 0;
    virtual const std::optional<StoredImage>& image(unsigned slot) const = 0;

    // ---- writing a new image --------------------------------------------------------------------------
    // Starts a new image (any unfinished one is dropped first).
    virtual bool begin_write(StoreError& error) = 0;
    // Appends received bytes; the header is checked as soon as it is complete.
    virtual bool append(std::span<const uint8_t> data, StoreError& error) = 0;
    // All bytes received: checks length and CRC and prepares the commit.
    virtual bool finish(StoreError& error) = 0;
    // One commit step (called repeatedly, possibly from a worker thread). Done: the new image is active.
    virtual Progress commit_step(StoreError& error) = 0;
    // Drops an unfinished image; the active one is not touched.
    virtual void abort() = 0;
    // Commit progress for FoE BUSY (done of entire); safe to read while another thread runs commit_step().
    virtual uint16_t progress_done() const = 0;
    virtual uint16_t progress_entire() const = 0;

    // ---- reading a stored image back (FoE upload) -----------------------------------------------------
    // Opens a stored image for reading: a handle >= 0, or -errno.
    virtual int open_image(const StoredImage& image) = 0;
    // Reads up to out.size() bytes at offset: the number read (0 at the end), or -1 on an error.
    virtual long read_image(int handle, uint64_t offset, std::span<uint8_t> out) = 0;
    virtual void close_image(int handle) = 0;
};

}  // namespace foe
