// The slave runtime event loop. See softslave/runtime.hpp.
#include "softslave/runtime.hpp"

#include <poll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <sys/timerfd.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

namespace softslave {

namespace {

constexpr uint64_t kNever = std::numeric_limits<uint64_t>::max();

std::atomic<Runtime*> g_signal_target{nullptr};
volatile std::sig_atomic_t g_stop_signalled = 0;

void on_stop_signal(int) {
    g_stop_signalled = 1;
    Runtime* r = g_signal_target.load();
    if (r != nullptr) r->request_stop();
}

}  // namespace

Runtime::Runtime(esc::Link& link, esc::Esc& esc, const esc::Clock& clock)
    : link_(link), esc_(esc), clock_(clock), buffer_(esc::kMaxFrameSize), in_copy_(esc::kMaxFrameSize) {
    timer_fd_ = ::timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
    if (timer_fd_ < 0) throw std::runtime_error(std::string("timerfd_create: ") + std::strerror(errno));
    stop_fd_ = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    if (stop_fd_ < 0) {
        ::close(timer_fd_);
        throw std::runtime_error(std::string("eventfd: ") + std::strerror(errno));
    }
}

Runtime::~Runtime() {
    if (g_signal_target.load() == this) g_signal_target.store(nullptr);
    ::close(timer_fd_);
    ::close(stop_fd_);
}

void Runtime::request_stop() {
    const uint64_t one = 1;
    (void)!::write(stop_fd_, &one, sizeof one);
}

bool Runtime::stop_requested() const {
    pollfd p{stop_fd_, POLLIN, 0};
    return ::poll(&p, 1, 0) > 0 && (p.revents & POLLIN) != 0;
}

void Runtime::run() {
    while (run_once(-1)) {
    }
}

bool Runtime::run_once(int timeout_ms) {
    arm_timer();
    pollfd fds[3] = {
        {link_.fd(), POLLIN, 0},
        {timer_fd_, POLLIN, 0},
        {stop_fd_, POLLIN, 0},
    };
    const int n = ::poll(fds, 3, timeout_ms);
    if (n < 0) {
        if (errno == EINTR) return !stop_requested();
        throw std::runtime_error(std::string("poll: ") + std::strerror(errno));
    }
    if (fds[2].revents & POLLIN) return false;
    ++stats_.wakeups;
    const bool link_event = link_.fd() < 0 || fds[0].revents != 0;
    if (link_event) {
        handle_frames();
        if (fds[0].revents & POLLERR) {
            // A pending socket error (e.g. ENETDOWN) keeps poll() returning; reading SO_ERROR clears it.
            int err = 0;
            socklen_t len = sizeof err;
            (void)::getsockopt(fds[0].fd, SOL_SOCKET, SO_ERROR, &err, &len);
            ++stats_.link_errors;
            if (link_check_ && !link_check_()) {
                link_lost_ = true;
                return false;
            }
        }
    }
    if (fds[1].revents & POLLIN) {
        uint64_t expirations = 0;
        if (::read(timer_fd_, &expirations, sizeof expirations) == sizeof expirations)
            ++stats_.timer_expiries;
        armed_ns_ = 0;
    }
    if (link_event || (fds[1].revents & POLLIN) || n == 0) service();
    return true;
}

void Runtime::handle_frames() {
    for (int i = 0; i < kMaxBurst; ++i) {
        const std::size_t len = link_.receive(buffer_);
        if (len == 0) break;
        const uint64_t rx_ns = clock_.now_ns();
        ++stats_.frames_received;
        std::span<uint8_t> frame(buffer_.data(), len);
        if (capture_ != nullptr) std::memcpy(in_copy_.data(), buffer_.data(), len);
        const bool reply = esc_.process_frame(frame, rx_ns);
        if (reply) {
            if (link_.send(frame))
                ++stats_.frames_sent;
            else
                ++stats_.send_errors;
        } else {
            ++stats_.frames_dropped;
        }
        // Recorded after the reply went out, so the capture never delays a frame.
        if (capture_ != nullptr) {
            capture_->write(std::span<const uint8_t>(in_copy_.data(), len));
            if (reply) capture_->write(frame);
        }
    }
}

void Runtime::service() {
    esc_.tick();
    if (firmware_ != nullptr) firmware_->poll(clock_.now_ns());
}

void Runtime::arm_timer() {
    uint64_t deadline = esc_.next_event_ns();
    if (firmware_ != nullptr) deadline = std::min(deadline, firmware_->next_deadline_ns());
    if (deadline == kNever) deadline = 0;  // disarm
    if (deadline == 0 && armed_ns_ == 0) return;
    if (deadline == armed_ns_) return;
    itimerspec spec{};
    if (deadline != 0) {
        spec.it_value.tv_sec = static_cast<time_t>(deadline / 1000000000ull);
        spec.it_value.tv_nsec = static_cast<long>(deadline % 1000000000ull);
    }
    if (::timerfd_settime(timer_fd_, TFD_TIMER_ABSTIME, &spec, nullptr) < 0)
        throw std::runtime_error(std::string("timerfd_settime: ") + std::strerror(errno));
    armed_ns_ = deadline;
}

void install_stop_signals() {
    struct sigaction sa {};
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = 0;
    ::sigaction(SIGINT, &sa, nullptr);
    ::sigaction(SIGTERM, &sa, nullptr);
}

void set_signal_target(Runtime* runtime) {
    g_signal_target.store(runtime);
    if (runtime != nullptr && g_stop_signalled != 0) runtime->request_stop();
}

bool stop_signalled() {
    return g_stop_signalled != 0;
}

}  // namespace softslave
