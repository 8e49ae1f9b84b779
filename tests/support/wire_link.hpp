#pragma once
// A master's esc::Link wired straight to an in-process slave: send() hands the frame to the slave's
// `deliver` function (ESC processing, then whatever firmware work the test runs after a reply), and a frame
// the slave sends back is queued for receive(). drop_next() loses the next reply, as a broken cable would.
// A test names its link by deriving from it with the deliver function of its slave.
#include <algorithm>
#include <cstdint>
#include <deque>
#include <functional>
#include <span>
#include <utility>
#include <vector>

#include "esc/link.hpp"

namespace test_support {

class WireLink : public esc::Link {
  public:
    // Processes the frame in place; returns true if it goes back to the master.
    using Deliver = std::function<bool(std::vector<uint8_t>& frame)>;

    explicit WireLink(Deliver deliver) : deliver_(std::move(deliver)) {}
    int fd() const override { return -1; }
    std::size_t receive(std::span<uint8_t> buf) override {
        if (replies_.empty()) return 0;
        const auto f = std::move(replies_.front());
        replies_.pop_front();
        const std::size_t n = std::min(buf.size(), f.size());
        std::copy_n(f.begin(), n, buf.begin());
        return n;
    }
    bool send(std::span<const uint8_t> frame) override {
        std::vector<uint8_t> f(frame.begin(), frame.end());
        const bool back = deliver_(f);
        if (back && !drop_) replies_.push_back(std::move(f));
        drop_ = false;
        return true;
    }
    void drop_next() { drop_ = true; }

  private:
    Deliver deliver_;
    bool drop_ = false;
    std::deque<std::vector<uint8_t>> replies_;
};

}  // namespace test_support
