#pragma once
// A mailbox sender with fixed storage for the "allocate nothing" tests (a recording sender's container would
// allocate): keeps the last message sent and counts them.
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "ecat/mailbox_handler.hpp"

namespace test_support {

class FixedSender final : public ecat::MailboxSender {
  public:
    explicit FixedSender(std::size_t max_payload) : max_(max_payload) {}
    bool send(ecat::MailboxType, std::span<const uint8_t> payload) override {
        if (payload.size() > max_payload()) return false;
        last_len = payload.size();
        std::copy(payload.begin(), payload.end(), last.begin());
        ++count;
        return true;
    }
    std::size_t max_payload() const override { return max_; }

    std::array<uint8_t, 128> last{};
    std::size_t last_len = 0;
    std::size_t count = 0;

  private:
    std::size_t max_;
};

}  // namespace test_support
