#pragma once
// foe::FirmwareSink in memory: the FoE server's contract without a file system (no fsync, no files), for
// the FoE fuzz harness. Same checks as foe::FirmwareStore: the header as soon as it is complete (device,
// size limit), no byte past the announced length, length and CRC at finish(); the commit takes a few
// steps, then the image is active in the other slot.
#include <algorithm>
#include <array>
#include <cstring>
#include <optional>
#include <vector>

#include "foe/image.hpp"
#include "foe/sink.hpp"

namespace fuzz {

class MemorySink final : public foe::FirmwareSink {
  public:
    MemorySink(foe::ImageIdentity identity, std::string device_name, std::size_t max_image_bytes)
        : identity_(identity), device_(std::move(device_name)), max_(max_image_bytes) {}

    // Puts a valid image into a slot and makes it active (as a store opened over an earlier update).
    void install(unsigned slot, std::vector<uint8_t> bytes) {
        const foe::VerifyResult r = foe::verify_image(bytes, identity_);
        if (!r.ok()) return;
        slot &= 1;
        data_[slot] = std::move(bytes);
        slots_[slot] = stored(slot, r.header);
        active_ = slots_[slot];
    }

    const std::optional<foe::StoredImage>& active_image() const override { return active_; }
    const std::optional<foe::StoredImage>& image(unsigned slot) const override { return slots_[slot & 1]; }

    bool begin_write(foe::StoreError&) override {
        abort();
        target_ = active_ ? (active_->slot ^ 1u) : 0u;
        buffer_.clear();
        phase_ = Phase::Receiving;
        return true;
    }
    bool append(std::span<const uint8_t> data, foe::StoreError& error) override {
        if (phase_ != Phase::Receiving) return fail(error, foe::ErrorCode::Illegal, "no image being written");
        const std::size_t before = buffer_.size();
        if (before < foe::kImageHeaderSize && before + data.size() >= foe::kImageHeaderSize) {
            std::array<uint8_t, foe::kImageHeaderSize> h{};
            std::copy(buffer_.begin(), buffer_.end(), h.begin());
            std::copy_n(data.begin(), foe::kImageHeaderSize - before,
                        h.begin() + static_cast<std::ptrdiff_t>(before));
            header_ = foe::decode_header(h);
            if (const foe::ImageError e = foe::check_header(header_, identity_); e != foe::ImageError::Ok)
                return fail(error, foe::foe_error(e), "bad header");
            if (foe::kImageHeaderSize + uint64_t{header_.payload_length} > max_)
                return fail(error, foe::ErrorCode::DiskFull, "image larger than the slot allows");
        }
        if (before + data.size() > foe::kImageHeaderSize &&
            before + data.size() > foe::kImageHeaderSize + uint64_t{header_.payload_length})
            return fail(error, foe::ErrorCode::FileHeaderError, "trailing data");
        buffer_.insert(buffer_.end(), data.begin(), data.end());
        return true;
    }
    bool finish(foe::StoreError& error) override {
        if (phase_ != Phase::Receiving) return fail(error, foe::ErrorCode::Illegal, "no image being written");
        const foe::VerifyResult r = foe::verify_image(buffer_, identity_);
        if (!r.ok()) return fail(error, foe::foe_error(r.error), std::string(foe::to_string(r.error)));
        phase_ = Phase::Committing;
        steps_ = 0;
        progress_ = 0;
        return true;
    }
    Progress commit_step(foe::StoreError& error) override {
        if (phase_ != Phase::Committing) {
            fail(error, foe::ErrorCode::Illegal, "nothing to commit");
            return Progress::Failed;
        }
        if (++steps_ < kCommitSteps) {
            progress_ = static_cast<uint16_t>(steps_ * 100 / kCommitSteps);
            return Progress::Running;
        }
        data_[target_] = std::move(buffer_);
        buffer_.clear();
        slots_[target_] = stored(target_, foe::decode_header(std::span<const uint8_t, foe::kImageHeaderSize>(
                                              data_[target_].data(), foe::kImageHeaderSize)));
        active_ = slots_[target_];
        phase_ = Phase::Idle;
        progress_ = 100;
        return Progress::Done;
    }
    void abort() override {
        if (phase_ != Phase::Idle) buffer_.clear();
        phase_ = Phase::Idle;
    }
    uint16_t progress_done() const override { return progress_; }
    uint16_t progress_entire() const override { return 100; }

    int open_image(const foe::StoredImage& image) override {
        if (!slots_[image.slot & 1]) return -2;  // ENOENT
        ++open_;
        return static_cast<int>(image.slot & 1);
    }
    long read_image(int handle, uint64_t offset, std::span<uint8_t> out) override {
        if (handle < 0 || handle > 1) return -1;
        const std::vector<uint8_t>& d = data_[static_cast<unsigned>(handle)];
        if (offset >= d.size()) return 0;
        const std::size_t n = std::min<uint64_t>(out.size(), d.size() - offset);
        std::memcpy(out.data(), d.data() + offset, n);
        return static_cast<long>(n);
    }
    void close_image(int) override { --open_; }
    int open_images() const { return open_; }

  private:
    enum class Phase : uint8_t { Idle, Receiving, Committing };
    static constexpr unsigned kCommitSteps = 3;

    foe::StoredImage stored(unsigned slot, const foe::ImageHeader& h) const {
        foe::StoredImage s;
        s.slot = slot;
        s.header = h;
        s.file_name = foe::firmware_file_name(device_, h.product_code, h.version);
        s.size = foe::kImageHeaderSize + uint64_t{h.payload_length};
        return s;
    }
    bool fail(foe::StoreError& error, foe::ErrorCode code, std::string text) {
        error.code = code;
        error.text = std::move(text);
        abort();
        return false;
    }

    foe::ImageIdentity identity_;
    std::string device_;
    std::size_t max_;
    std::optional<foe::StoredImage> active_;
    std::optional<foe::StoredImage> slots_[2];
    std::vector<uint8_t> data_[2];
    std::vector<uint8_t> buffer_;
    foe::ImageHeader header_{};
    Phase phase_ = Phase::Idle;
    unsigned target_ = 0;
    unsigned steps_ = 0;
    uint16_t progress_ = 0;
    int open_ = 0;
};

}  // namespace fuzz
