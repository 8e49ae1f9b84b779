// LoopbackLink: in-process link pair. See esc/link_loopback.hpp.
#include "esc/link_loopback.hpp"

#include <sys/eventfd.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <mutex>
#include <vector>

namespace esc {

struct LoopbackLink::Queue {
    explicit Queue(std::size_t cap) : capacity(cap), data(cap * kMaxFrameSize), lengths(cap) {
        efd = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
        if (efd < 0)
            throw LinkError(LinkError::Kind::System, std::string("eventfd: ") + std::strerror(errno));
    }
    ~Queue() { ::close(efd); }
    Queue(const Queue&) = delete;
    Queue& operator=(const Queue&) = delete;

    mutable std::mutex mutex;
    std::size_t capacity;
    std::vector<uint8_t> data;  // capacity slots of kMaxFrameSize bytes
    std::vector<std::size_t> lengths;
    std::size_t head = 0;
    std::size_t count = 0;
    int efd = -1;
};

std::pair<std::unique_ptr<LoopbackLink>, std::unique_ptr<LoopbackLink>> LoopbackLink::make_pair(
    std::size_t capacity) {
    if (capacity == 0) throw LinkError(LinkError::Kind::BadArgument, "loopback link capacity must be > 0");
    auto a_to_b = std::make_shared<Queue>(capacity);
    auto b_to_a = std::make_shared<Queue>(capacity);
    std::unique_ptr<LoopbackLink> a(new LoopbackLink(b_to_a, a_to_b));
    std::unique_ptr<LoopbackLink> b(new LoopbackLink(a_to_b, b_to_a));
    return {std::move(a), std::move(b)};
}

LoopbackLink::LoopbackLink(std::shared_ptr<Queue> rx, std::shared_ptr<Queue> tx)
    : rx_(std::move(rx)), tx_(std::move(tx)) {}

LoopbackLink::~LoopbackLink() = default;

int LoopbackLink::fd() const {
    return rx_->efd;
}

std::size_t LoopbackLink::pending() const {
    std::lock_guard<std::mutex> lock(rx_->mutex);
    return rx_->count;
}

std::size_t LoopbackLink::receive(std::span<uint8_t> buf) {
    Queue& q = *rx_;
    std::lock_guard<std::mutex> lock(q.mutex);
    if (q.count == 0) return 0;
    const std::size_t n = std::min(q.lengths[q.head], buf.size());
    std::memcpy(buf.data(), q.data.data() + q.head * kMaxFrameSize, n);
    q.head = (q.head + 1) % q.capacity;
    if (--q.count == 0) {
        uint64_t v = 0;
        (void)!::read(q.efd, &v, sizeof v);  // now empty: make the fd unreadable
    }
    return n;
}

bool LoopbackLink::send(std::span<const uint8_t> frame) {
    if (frame.empty() || frame.size() > kMaxFrameSize) return false;
    Queue& q = *tx_;
    std::lock_guard<std::mutex> lock(q.mutex);
    if (q.count == q.capacity) return false;
    const std::size_t slot = (q.head + q.count) % q.capacity;
    std::memcpy(q.data.data() + slot * kMaxFrameSize, frame.data(), frame.size());
    q.lengths[slot] = frame.size();
    if (q.count++ == 0) {
        const uint64_t one = 1;
        (void)!::write(q.efd, &one, sizeof one);  // now non-empty: make the fd readable
    }
    return true;
}

}  // namespace esc
