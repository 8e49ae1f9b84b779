#pragma once
// A master's esc::Link to an in-process slave with up to kSlots frames in flight in fixed buffers (a master
// may send several frames before it reads the replies): send() copies the frame into the next slot and hands
// it to `deliver` (which processes it in place: an ESC, a segment, then whatever
// firmware work the test runs) and keeps it for receive() if deliver says it comes back. Nothing is
// allocated per frame, for the tests that count allocations on the cyclic paths.
#include <algorithm>
#include <array>
#include <cstdint>
#include <span>

#include "esc/link.hpp"

namespace test_support {

// Deliver: bool(std::span<uint8_t> frame), true if the frame goes back to the master.
template <typename Deliver>
class FixedLink final : public esc::Link {
  public:
    explicit FixedLink(Deliver deliver) : deliver_(deliver) {}
    int fd() const override { return -1; }
    std::size_t receive(std::span<uint8_t> buf) override {
        while (count_ > 0) {
            Slot& s = slots_[head_];
            head_ = (head_ + 1) % kSlots;
            --count_;
            if (s.length == 0) continue;  // not sent back
            const std::size_t n = std::min(buf.size(), s.length);
            std::copy_n(s.frame.begin(), n, buf.begin());
            return n;
        }
        return 0;
    }
    bool send(std::span<const uint8_t> f) override {
        if (f.size() > slots_[0].frame.size() || count_ == kSlots) return false;
        Slot& s = slots_[(head_ + count_) % kSlots];
        std::copy(f.begin(), f.end(), s.frame.begin());
        s.length = deliver_(std::span<uint8_t>(s.frame.data(), f.size())) ? f.size() : 0;
        ++count_;
        return true;
    }

  private:
    static constexpr std::size_t kSlots = 8;
    struct Slot {
        std::array<uint8_t, 2048> frame{};
        std::size_t length = 0;
    };
    Deliver deliver_;
    std::array<Slot, kSlots> slots_{};
    std::size_t head_ = 0, count_ = 0;
};

}  // namespace test_support
