#include "foe/store.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "util/atomic_file.hpp"
#include "util/crc.hpp"

namespace foe {
namespace {

std::string errno_text(const char* what) {
    return std::string(what) + ": " + std::strerror(errno);
}

bool write_all(int fd, const uint8_t* p, std::size_t n) {
    while (n > 0) {
        const ssize_t w = ::write(fd, p, n);
        if (w < 0) {
            if (errno == EINTR) continue;
            return false;
        }
        p += w;
        n -= static_cast<std::size_t>(w);
    }
    return true;
}

// Reads exactly n bytes at offset; false on error or end of file.
bool pread_all(int fd, uint8_t* p, std::size_t n, uint64_t offset) {
    while (n > 0) {
        const ssize_t r = ::pread(fd, p, n, static_cast<off_t>(offset));
        if (r < 0 && errno == EINTR) continue;
        if (r <= 0) return false;
        p += r;
        n -= static_cast<std::size_t>(r);
        offset += static_cast<uint64_t>(r);
    }
    return true;
}

}  // namespace

std::string_view to_string(StoreStep s) {
    switch (s) {
        case StoreStep::CreateTemp:
            return "create temp";
        case StoreStep::Append:
            return "append";
        case StoreStep::SyncTemp:
            return "sync temp";
        case StoreStep::RenameSlot:
            return "rename slot";
        case StoreStep::SyncDir:
            return "sync dir";
        case StoreStep::ReadBack:
            return "read back";
        case StoreStep::WritePointer:
            return "write pointer";
        case StoreStep::SyncPointer:
            return "sync pointer";
        case StoreStep::RenamePointer:
            return "rename pointer";
        case StoreStep::SyncPointerDir:
            return "sync pointer dir";
    }
    return "?";
}

FirmwareStore::FirmwareStore(StoreConfig config) : config_(std::move(config)) {
    if (config_.read_back_chunk < 512) config_.read_back_chunk = 512;
    buffer_.resize(config_.read_back_chunk);
}

FirmwareStore::~FirmwareStore() {
    if (fd_ >= 0) ::close(fd_);
}

std::filesystem::path FirmwareStore::slot_path(unsigned slot) const {
    return config_.dir / (slot == 0 ? "slot0.bin" : "slot1.bin");
}

std::filesystem::path FirmwareStore::pointer_path() const {
    return config_.dir / "active";
}

bool FirmwareStore::fail(StoreError& error, ErrorCode code, std::string text) {
    error.code = code;
    error.text = std::move(text);
    abort();
    return false;
}

bool FirmwareStore::sync_dir(StoreError& error) {
    if (util::sync_directory(config_.dir)) return true;
    error = {ErrorCode::FlashError, errno_text("fsync directory")};
    return false;
}

std::optional<StoredImage> FirmwareStore::verify_slot(unsigned slot) {
    const auto path = slot_path(slot);
    // Only a regular file is a slot (O_NONBLOCK: a FIFO in its place must not hang the start). Its size
    // must be the one its header announces before any of the payload is read.
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    if (fd < 0) return std::nullopt;
    struct stat st {};
    std::optional<StoredImage> result;
    uint8_t head[kImageHeaderSize];
    if (::fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && pread_all(fd, head, kImageHeaderSize, 0)) {
        std::span<const uint8_t, kImageHeaderSize> hs(head, kImageHeaderSize);
        const ImageHeader h = decode_header(hs);
        const uint64_t size = static_cast<uint64_t>(st.st_size);
        if (check_header(h, config_.identity) == ImageError::Ok &&
            size == kImageHeaderSize + uint64_t{h.payload_length} && size <= config_.max_image_bytes) {
            uint32_t crc = header_crc(hs);
            uint64_t off = kImageHeaderSize;
            bool ok = true;
            while (ok && off < size) {
                const std::size_t n =
                    static_cast<std::size_t>(std::min<uint64_t>(buffer_.size(), size - off));
                ok = pread_all(fd, buffer_.data(), n, off);
                if (ok) crc = util::crc32({buffer_.data(), n}, crc);
                off += n;
            }
            if (ok && crc == h.crc)
                result = StoredImage{
                    slot, h, firmware_file_name(config_.device_name, h.product_code, h.version), path, size};
        }
    }
    ::close(fd);
    return result;
}

bool FirmwareStore::open(StoreError* error) {
    StoreError local;
    StoreError& err = error ? *error : local;
    abort();
    std::error_code ec;
    std::filesystem::create_directories(config_.dir, ec);
    if (ec) {
        err = {ErrorCode::FlashError, "create " + config_.dir.string() + ": " + ec.message()};
        return false;
    }
    // Leftovers of an interrupted write: never valid, never pointed at.
    for (const char* tmp : {"slot0.bin.tmp", "slot1.bin.tmp", "active.tmp"})
        std::filesystem::remove(config_.dir / tmp, ec);

    // The pointer is the commit point of a download: it is switched only once the image is stored and
    // verified, and the master gets the final ACK only after that. No pointer file at all means no download
    // ever got that far: a slot file then is what remains of a first download killed between its slot rename
    // and its pointer switch, never acknowledged, so it does not boot (the same rule as with a previous
    // image, whose pointer keeps naming the old slot). The file stays; the next download replaces it.
    int pointed = -1;
    bool pointer_exists = false;
    // The pointer is at most "slotN\n": a regular file of up to 16 bytes is read, anything else names no
    // slot.
    const int fd = ::open(pointer_path().c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    if (fd < 0) pointer_exists = errno != ENOENT;
    if (fd >= 0) {
        pointer_exists = true;
        char text[16] = {};
        struct stat st {};
        const bool regular = ::fstat(fd, &st) == 0 && S_ISREG(st.st_mode);
        const ssize_t n = regular ? ::read(fd, text, sizeof text - 1) : -1;
        ::close(fd);
        const std::string_view s(text, n > 0 ? static_cast<std::size_t>(n) : 0);
        if (s == "slot0\n" || s == "slot0") pointed = 0;
        if (s == "slot1\n" || s == "slot1") pointed = 1;
    }
    active_.reset();
    slots_[0].reset();
    slots_[1].reset();
    if (!pointer_exists) return true;
    slots_[0] = verify_slot(0);
    slots_[1] = verify_slot(1);
    if (pointed >= 0 && slots_[pointed]) {
        active_ = slots_[pointed];
    } else {
        for (unsigned s : {0u, 1u}) {
            if (!active_ && slots_[s]) active_ = slots_[s];
        }
        if (active_) {
            // Repair the pointer so that the slot written next is never the one it names.
            target_ = active_->slot;
            next_ = StoreStep::WritePointer;
            phase_ = Phase::Committing;
            const bool ok = commit_all(err) == Progress::Done;
            return ok;
        }
    }
    return true;
}

const StoredImage* FirmwareStore::find(std::string_view name) const {
    if (active_ && active_->file_name == name) return &*active_;
    for (const auto& s : slots_) {
        if (s && s->file_name == name) return &*s;
    }
    return nullptr;
}

bool FirmwareStore::begin_write(StoreError& error) {
    abort();
    target_ = active_ ? 1 - active_->slot : 0;
    received_ = 0;
    header_ok_ = false;
    crc_ = 0;
    progress_.store(0, std::memory_order_relaxed);
    step(StoreStep::CreateTemp);
    const auto tmp = slot_path(target_).string() + ".tmp";
    fd_ = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd_ < 0) {
        error = {errno == ENOSPC ? ErrorCode::DiskFull : ErrorCode::FlashError,
                 errno_text("create slot file")};
        return false;
    }
    phase_ = Phase::Receiving;
    return true;
}

bool FirmwareStore::append(std::span<const uint8_t> data, StoreError& error) {
    if (phase_ != Phase::Receiving) return fail(error, ErrorCode::Illegal, "no image being written");
    if (data.empty()) return true;
    std::span<const uint8_t> payload = data;
    if (!header_ok_) {
        const std::size_t take = std::min<std::size_t>(kImageHeaderSize - received_, data.size());
        std::memcpy(header_bytes_ + received_, data.data(), take);
        payload = data.subspan(take);
        if (received_ + take == kImageHeaderSize) {
            std::span<const uint8_t, kImageHeaderSize> hs(header_bytes_, kImageHeaderSize);
            header_ = decode_header(hs);
            const ImageError e = check_header(header_, config_.identity);
            if (e != ImageError::Ok) {
                VerifyResult r{e, header_};
                return fail(error, foe_error(e), describe(r, config_.identity));
            }
            if (kImageHeaderSize + uint64_t{header_.payload_length} > config_.max_image_bytes)
                return fail(error, ErrorCode::DiskFull, "image larger than the slot allows");
            header_ok_ = true;
            crc_ = header_crc(hs);
        }
    }
    if (header_ok_ && received_ + data.size() > kImageHeaderSize + uint64_t{header_.payload_length})
        return fail(error, ErrorCode::FileHeaderError, std::string(to_string(ImageError::TrailingData)));
    if (!payload.empty()) crc_ = util::crc32(payload, crc_);
    step(StoreStep::Append);
    if (!write_all(fd_, data.data(), data.size())) {
        const bool full = errno == ENOSPC || errno == EFBIG || errno == EDQUOT;
        return fail(error, full ? ErrorCode::DiskFull : ErrorCode::FlashError, errno_text("write slot file"));
    }
    received_ += data.size();
    return true;
}

bool FirmwareStore::finish(StoreError& error) {
    if (phase_ != Phase::Receiving) return fail(error, ErrorCode::Illegal, "no image being written");
    if (!header_ok_) {
        return fail(error, ErrorCode::FileHeaderError, std::string(to_string(ImageError::TooShort)));
    }
    if (received_ != kImageHeaderSize + uint64_t{header_.payload_length})
        return fail(error, ErrorCode::FileHeaderError, std::string(to_string(ImageError::Truncated)));
    if (crc_ != header_.crc)
        return fail(error, ErrorCode::InvalidChecksum, std::string(to_string(ImageError::BadChecksum)));
    phase_ = Phase::Committing;
    next_ = StoreStep::SyncTemp;
    progress_.store(compute_progress(), std::memory_order_relaxed);
    return true;
}

FirmwareStore::Progress FirmwareStore::commit_step(StoreError& error) {
    const Progress p = run_step(error);
    progress_.store(p == Progress::Done ? 100 : compute_progress(), std::memory_order_relaxed);
    return p;
}

FirmwareStore::Progress FirmwareStore::run_step(StoreError& error) {
    if (phase_ != Phase::Committing) {
        error = {ErrorCode::Illegal, "nothing to commit"};
        return Progress::Failed;
    }
    auto failed = [&](ErrorCode code, std::string text) {
        fail(error, code, std::move(text));
        return Progress::Failed;
    };
    const StoreStep s = next_;
    step(s);
    switch (s) {
        case StoreStep::SyncTemp: {
            const bool ok = ::fsync(fd_) == 0;
            const int e = errno;
            ::close(fd_);
            fd_ = -1;
            if (!ok) {
                errno = e;
                return failed(ErrorCode::FlashError, errno_text("fsync slot file"));
            }
            next_ = StoreStep::RenameSlot;
            return Progress::Running;
        }
        case StoreStep::RenameSlot: {
            const auto path = slot_path(target_);
            if (::rename((path.string() + ".tmp").c_str(), path.c_str()) != 0)
                return failed(ErrorCode::FlashError, errno_text("rename slot file"));
            slots_[target_].reset();  // the old content of the inactive slot is gone
            next_ = StoreStep::SyncDir;
            return Progress::Running;
        }
        case StoreStep::SyncDir:
            if (!sync_dir(error)) return failed(error.code, error.text);
            next_ = StoreStep::ReadBack;
            read_back_offset_ = 0;
            return Progress::Running;
        case StoreStep::ReadBack: {
            const uint64_t size = kImageHeaderSize + uint64_t{header_.payload_length};
            if (read_back_offset_ == 0) {
                fd_ = ::open(slot_path(target_).c_str(), O_RDONLY | O_CLOEXEC);
                if (fd_ < 0) return failed(ErrorCode::FlashError, errno_text("open slot file"));
                struct stat st {};
                uint8_t head[kImageHeaderSize];
                if (::fstat(fd_, &st) != 0 || static_cast<uint64_t>(st.st_size) != size ||
                    !pread_all(fd_, head, kImageHeaderSize, 0) ||
                    std::memcmp(head, header_bytes_, kImageHeaderSize) != 0)
                    return failed(ErrorCode::FlashError, "slot file differs from the received image");
                read_back_crc_ =
                    header_crc(std::span<const uint8_t, kImageHeaderSize>(head, kImageHeaderSize));
                read_back_offset_ = kImageHeaderSize;
            } else {
                const std::size_t n =
                    static_cast<std::size_t>(std::min<uint64_t>(buffer_.size(), size - read_back_offset_));
                if (!pread_all(fd_, buffer_.data(), n, read_back_offset_))
                    return failed(ErrorCode::FlashError, errno_text("read back slot file"));
                read_back_crc_ = util::crc32({buffer_.data(), n}, read_back_crc_);
                read_back_offset_ += n;
            }
            if (read_back_offset_ >= size) {
                ::close(fd_);
                fd_ = -1;
                if (read_back_crc_ != header_.crc)
                    return failed(ErrorCode::FlashError, "slot file read back with a wrong checksum");
                slots_[target_] = StoredImage{
                    target_, header_,
                    firmware_file_name(config_.device_name, header_.product_code, header_.version),
                    slot_path(target_), size};
                next_ = StoreStep::WritePointer;
            }
            return Progress::Running;
        }
        case StoreStep::WritePointer: {
            const auto tmp = pointer_path().string() + ".tmp";
            fd_ = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
            const char* text = target_ == 0 ? "slot0\n" : "slot1\n";
            if (fd_ < 0 || !write_all(fd_, reinterpret_cast<const uint8_t*>(text), 6))
                return failed(errno == ENOSPC ? ErrorCode::DiskFull : ErrorCode::FlashError,
                              errno_text("write pointer file"));
            next_ = StoreStep::SyncPointer;
            return Progress::Running;
        }
        case StoreStep::SyncPointer: {
            const bool ok = ::fsync(fd_) == 0;
            ::close(fd_);
            fd_ = -1;
            if (!ok) return failed(ErrorCode::FlashError, errno_text("fsync pointer file"));
            next_ = StoreStep::RenamePointer;
            return Progress::Running;
        }
        case StoreStep::RenamePointer: {
            const auto tmp = pointer_path().string() + ".tmp";
            if (::rename(tmp.c_str(), pointer_path().c_str()) != 0)
                return failed(ErrorCode::FlashError, errno_text("rename pointer file"));
            active_ = slots_[target_];  // the switch
            next_ = StoreStep::SyncPointerDir;
            return Progress::Running;
        }
        case StoreStep::SyncPointerDir: {
            phase_ = Phase::Idle;
            if (!sync_dir(error)) return Progress::Failed;
            return Progress::Done;
        }
        case StoreStep::CreateTemp:
        case StoreStep::Append:
            break;
    }
    return failed(ErrorCode::ProgramError, "bad commit step");
}

FirmwareStore::Progress FirmwareStore::commit_all(StoreError& error) {
    for (;;) {
        const Progress p = commit_step(error);
        if (p != Progress::Running) return p;
    }
}

void FirmwareStore::abort() {
    if (fd_ >= 0) {
        ::close(fd_);
        fd_ = -1;
    }
    std::error_code ec;
    if (phase_ == Phase::Receiving || (phase_ == Phase::Committing && next_ <= StoreStep::RenameSlot))
        std::filesystem::remove(slot_path(target_).string() + ".tmp", ec);
    if (phase_ == Phase::Committing && next_ > StoreStep::WritePointer && next_ <= StoreStep::RenamePointer)
        std::filesystem::remove(pointer_path().string() + ".tmp", ec);
    phase_ = Phase::Idle;
}

uint16_t FirmwareStore::compute_progress() const {
    if (phase_ != Phase::Committing) return 0;
    switch (next_) {
        case StoreStep::CreateTemp:
        case StoreStep::Append:
        case StoreStep::SyncTemp:
            return 5;
        case StoreStep::RenameSlot:
            return 10;
        case StoreStep::SyncDir:
            return 15;
        case StoreStep::ReadBack: {
            const uint64_t size = kImageHeaderSize + uint64_t{header_.payload_length};
            return static_cast<uint16_t>(20 + 60 * read_back_offset_ / (size ? size : 1));
        }
        case StoreStep::WritePointer:
            return 80;
        case StoreStep::SyncPointer:
            return 85;
        case StoreStep::RenamePointer:
            return 90;
        case StoreStep::SyncPointerDir:
            return 95;
    }
    return 0;
}

// ---- reading a stored image back -------------------------------------------------------------------

int FirmwareStore::open_image(const StoredImage& image) {
    const int fd = ::open(image.path.c_str(), O_RDONLY | O_CLOEXEC);
    return fd >= 0 ? fd : -errno;
}

long FirmwareStore::read_image(int handle, uint64_t offset, std::span<uint8_t> out) {
    for (;;) {
        const ssize_t r = ::pread(handle, out.data(), out.size(), static_cast<off_t>(offset));
        if (r < 0 && errno == EINTR) continue;
        return r < 0 ? -1 : static_cast<long>(r);
    }
}

void FirmwareStore::close_image(int handle) {
    if (handle >= 0) ::close(handle);
}

}  // namespace foe
