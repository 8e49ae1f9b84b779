#pragma once
// Shared pieces of the fuzz harnesses (tests/fuzz/*_fuzz.cpp). Each harness is a function
//   int fuzz::<name>::fuzz_one(const uint8_t* data, std::size_t size)
// that the libFuzzer entry (entry.cpp, clang with -DSOFTECAT_FUZZ=ON) and the replay test (replay_test.cpp,
// any compiler) both call, so every corpus and regression input is checked in a normal build too.
#include <stdlib.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "ecat/mailbox_handler.hpp"
#include "od/dictionary.hpp"

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

// The input of the frame harnesses (slave, esc_frame, esi_line): records of [control byte][16-bit length]
// [frame] to the end of the input. fn(control, frame) runs for each; frame is a copy of the record the
// harness may change (an ESC writes into the frame it forwards), in one buffer reused for every record.
template <class Fn>
void for_each_frame(const uint8_t* data, std::size_t size, Fn&& fn) {
    Input in(data, size);
    std::vector<uint8_t> frame;
    frame.reserve(2048);
    while (!in.empty()) {
        const uint8_t control = in.u8();
        const auto record = in.record();
        frame.assign(record.begin(), record.end());
        fn(control, frame);
    }
}

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

// A private directory for one process's state directories (tmpfs when there is one: no disk writes, cheap
// fsync), removed when the process ends.
struct ScratchDir {
    std::filesystem::path path;
    ScratchDir() {
        std::string t = (std::filesystem::is_directory("/dev/shm") ? "/dev/shm" : "/tmp");
        t += "/softecat-fuzz-XXXXXX";
        if (::mkdtemp(t.data()) == nullptr) finding("cannot create a temporary directory");
        path = t;
    }
    ~ScratchDir() {
        std::error_code ec;
        std::filesystem::remove_all(path, ec);
    }
    ScratchDir(const ScratchDir&) = delete;
    ScratchDir& operator=(const ScratchDir&) = delete;
};

// A dictionary built once per process and put back into its built state before each input. Building the
// drive's dictionary (some 400 entries with names, limits and validators) was most of what an input cost;
// putting its values back costs a comparison per entry (and a copy for the few an input changed). Values
// are all of a dictionary's state besides its objects (fixed once built) and its hooks: the hooks of the
// build (value sets, PDO validators) belong to the dictionary and stay; every object a harness builds per
// input installs its hooks with itself as owner and removes them when it is destroyed (od::Dictionary's
// owner rule), so nothing of an input is left for the next one. Scalars are put back through their storage
// (Dictionary::mutable_raw, fixed once built), strings (their length changes) through set_raw(); no
// listener is left to notify, as no object of the last input is alive.
class PristineDictionary {
  public:
    // `finish` completes the build in place (hooks that keep the dictionary's address, such as the PDO
    // validators, are installed there, after the move).
    template <typename Finish>
    PristineDictionary(od::Dictionary built, Finish finish) : dict_(std::move(built)) {
        finish(dict_);
        for (const od::Object& o : dict_.objects())
            for (const od::Entry& e : o.entries) {
                const std::span<const uint8_t> v = dict_.raw(o.index, e.subindex);
                const std::span<uint8_t> storage = dict_.mutable_raw(o.index, e.subindex);
                if (storage.empty())
                    strings_.push_back({o.index, e.subindex, bytes_.size(), v.size()});
                else
                    scalars_.push_back({storage, bytes_.size()});
                bytes_.insert(bytes_.end(), v.begin(), v.end());
            }
    }
    // The dictionary with every value as built. Call with no object of the last input left alive.
    od::Dictionary& fresh() {
        for (const Scalar& s : scalars_)
            if (std::memcmp(s.storage.data(), bytes_.data() + s.at, s.storage.size()) != 0)
                std::memcpy(s.storage.data(), bytes_.data() + s.at, s.storage.size());
        for (const String& s : strings_) {
            const std::span<const uint8_t> want(bytes_.data() + s.at, s.size);
            const std::span<const uint8_t> now = dict_.raw(s.index, s.sub);
            if (now.size() == want.size() && std::equal(now.begin(), now.end(), want.begin())) continue;
            FUZZ_CHECK(dict_.set_raw(s.index, s.sub, want) == od::Status::Ok);
        }
        return dict_;
    }

  private:
    struct Scalar {
        std::span<uint8_t> storage;
        std::size_t at;
    };
    struct String {
        uint16_t index;
        uint8_t sub;
        std::size_t at;
        std::size_t size;
    };
    od::Dictionary dict_;
    std::vector<Scalar> scalars_;
    std::vector<String> strings_;
    std::vector<uint8_t> bytes_;
};

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
