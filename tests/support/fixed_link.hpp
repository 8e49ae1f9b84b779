#pragma once
// A master's esc::Link to an in-process slave with one frame in flight in a fixed buffer: send() copies the
// frame there and hands it to `deliver` (which processes it in place: an ESC, a segment, then whatever
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
        const std::size_t n = std::min(buf.size(), len_);
        std::copy_n(frame_.begin(), n, buf.begin());
        len_ = 0;
        return n;
    }
    bool send(std::span<const uint8_t> f) override {
        if (f.size() > frame_.size()) return false;
        std::copy(f.begin(), f.end(), frame_.begin());
        len_ = deliver_(std::span<uint8_t>(frame_.data(), f.size())) ? f.size() : 0;
        return true;
    }

  private:
    Deliver deliver_;
    std::array<uint8_t, 2048> frame_{};
    std::size_t len_ = 0;
};

}  // namespace test_support
