#pragma once
// An exclusive lock on a directory (flock on the directory itself: nothing is written into it, so a
// read-only state directory can be locked too). One device owns a state directory: a second device of the
// same process or another process that locks it gets a clear error instead of sharing parameters.bin,
// firmware images and EEPROM writes with the first. Released when the object goes (or the process ends).
#include <filesystem>
#include <stdexcept>

namespace util {

class DirLockError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

class DirLock {
  public:
    // Creates dir if it is missing (as the device would), then locks it. Throws DirLockError if another
    // holder has it ("DIR: in use by another device or process"); a directory that cannot be created or
    // opened is left to the device's own error handling (no lock, no error here).
    explicit DirLock(const std::filesystem::path& dir);
    ~DirLock();
    DirLock(const DirLock&) = delete;
    DirLock& operator=(const DirLock&) = delete;
    bool held() const { return fd_ >= 0; }

  private:
    int fd_ = -1;
};

}  // namespace util
