#pragma once
// Shared pieces of the fuzz harnesses (tests/fuzz/*_fuzz.cpp). Each harness is a function
//   int fuzz::<name>::fuzz_one(const uint8_t* data, std::size_t size)
// that the libFuzzer entry (entry.cpp, clang with -DSOFTECAT_FUZZ=ON) and the replay test (replay_test.cpp,
// any compiler) both call, so every corpus and regression input is checked in a normal build too.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <span>

#include "ecat/mailbox_handler.hpp"

namespace fuzz {

// Reads an input front to back; past the end everything is zero / empty.
class Input {
  public:
    Input(const uint8_t* data, std::size_t size) : data_(data), size_(size) {}
    bool empty() const { return at_ >= size_; }
    std::size_t left() const { return size_ - at_; }
    uint8_t u8() { return at_ < size_ ? data_[at_++] : 0; }
    uint16_t u16() {
        const uint16_t lo = u8();
        return static_cast<uint16_t>(lo | (u8() << 8));
    }
    std::span<const uint8_t> take(std::size_t n) {
        n = std::min(n, left());
        const std::span<const uint8_t> s(data_ + at_, n);
        at_ += n;
        return s;
    }
    std::span<const uint8_t> rest() { return take(left()); }
    // One record of a sequence: a little-endian 16-bit length, then that many bytes (fewer at the end).
    std::span<const uint8_t> record() { return take(u16()); }

  private:
    const uint8_t* data_;
    std::size_t size_;
    std::size_t at_ = 0;
};

// A finding: abort, so that libFuzzer (and the replay test, through a death) reports it with a stack.
[[noreturn]] inline void finding(const char* what) {
    // NOLINTNEXTLINE: stderr is the report channel of a fuzz target
    std::fputs(what, stderr);
    std::fputc('\n', stderr);
    std::abort();
}
#define FUZZ_CHECK(cond)                                           \
    do {                                                           \
        if (!(cond)) ::fuzz::finding("fuzz check failed: " #cond); \
    } while (0)

// The reply side of a mailbox: checks what a protocol server sends against the contract and keeps it.
class CheckingSender final : public ecat::MailboxSender {
  public:
    explicit CheckingSender(std::size_t max_payload) : max_(max_payload) {}
    bool send(ecat::MailboxType, std::span<const uint8_t> payload) override {
        if (full) return false;
        FUZZ_CHECK(payload.size() <= max_);
        // Touch every byte: ASan sees a read past a buffer, MSan-like garbage shows up nowhere else.
        uint8_t x = 0;
        for (uint8_t b : payload)
            x = static_cast<uint8_t>(x ^ b);
        checksum ^= x;
        ++sent;
        return true;
    }
    std::size_t max_payload() const override { return max_; }
    bool full = false;  // the queue is full: send() refuses (a server must keep the reply for poll())
    uint64_t sent = 0;
    uint8_t checksum = 0;

  private:
    std::size_t max_;
};

}  // namespace fuzz
