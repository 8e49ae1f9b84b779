#pragma once
// LoopbackLink: two in-process link ends joined by two bounded frame queues, for tests. What one end sends
// the other receives. Each end has an eventfd that is readable while frames are waiting, so poll() works as
// on a real link. Thread-safe (one thread per end is fine). Storage is allocated once, at creation.
#include <memory>
#include <utility>

#include "esc/link.hpp"

namespace esc {

class LoopbackLink final : public Link {
  public:
    struct Queue;  // one direction: fixed slots + eventfd

    // Creates two joined ends; each direction holds at most `capacity` frames (send fails when full).
    static std::pair<std::unique_ptr<LoopbackLink>, std::unique_ptr<LoopbackLink>> make_pair(
        std::size_t capacity = 64);

    ~LoopbackLink() override;
    LoopbackLink(const LoopbackLink&) = delete;
    LoopbackLink& operator=(const LoopbackLink&) = delete;

    int fd() const override;
    std::size_t receive(std::span<uint8_t> buf) override;
    // Returns false if the frame is empty or longer than kMaxFrameSize, or the peer's queue is full.
    bool send(std::span<const uint8_t> frame) override;
    std::string describe() const override { return "loopback"; }
    // Frames waiting to be received on this end.
    std::size_t pending() const;

  private:
    LoopbackLink(std::shared_ptr<Queue> rx, std::shared_ptr<Queue> tx);
    std::shared_ptr<Queue> rx_;
    std::shared_ptr<Queue> tx_;
};

}  // namespace esc
