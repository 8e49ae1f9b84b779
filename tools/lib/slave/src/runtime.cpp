// The slave runtime event loop. See slave/runtime.hpp.
#include "slave/runtime.hpp"

#include <poll.h>
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <sys/timerfd.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

namespace slave {

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

void Runtime::add_watch(int fd, uint32_t tag) {
    epoll_event ev{};
    ev.events = EPOLLIN;
    ev.data.u32 = tag;
    if (::epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, fd, &ev) != 0)
        throw std::runtime_error(std::string("epoll_ctl: ") + std::strerror(errno));
}

void Runtime::set_carrier_check(std::function<bool()> check, Log* log, std::string name) {
    carrier_check_ = std::move(check);
    carrier_log_ = log;
    carrier_name_ = std::move(name);
    carrier_due_ns_ = 0;
    carrier_state_ = -1;
    deadline_ns_ = 0;  // the first carrier poll is due at once
}

Runtime::Runtime(esc::Link& link, esc::Segment& segment, const esc::Clock& clock, esc::Link* out)
    : link_(link),
      segment_(segment),
      out_(out),
      clock_(clock),
      buffer_(esc::kMaxFrameSize),
      in_copy_(esc::kMaxFrameSize),
      hold_buffer_(kHoldSlots * esc::kMaxFrameSize),
      hold_slots_(kHoldSlots),
      reply_buffer_(kMaxBurst * esc::kMaxFrameSize),
      reply_lengths_(kMaxBurst) {
    timer_fd_ = ::timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
    if (timer_fd_ < 0) throw std::runtime_error(std::string("timerfd_create: ") + std::strerror(errno));
    stop_fd_ = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    epoll_fd_ = ::epoll_create1(EPOLL_CLOEXEC);
    if (stop_fd_ < 0 || epoll_fd_ < 0) {
        const int err = errno;
        close_fds();
        throw std::runtime_error(std::string("eventfd/epoll_create1: ") + std::strerror(err));
    }
    deadline_ns_ = compute_deadline_ns(clock_.now_ns());
    // Registered once: an epoll wait costs the same however many descriptors it watches, unlike poll().
    const struct {
        int fd;
        uint32_t tag;
    } watched[] = {{link_.fd(), kTagLink},
                   {timer_fd_, kTagTimer},
                   {stop_fd_, kTagStop},
                   {out_ != nullptr ? out_->fd() : -1, kTagOut}};
    for (const auto& w : watched) {
        if (w.fd < 0) continue;
        try {
            add_watch(w.fd, w.tag);
        } catch (...) {
            close_fds();
            throw;
        }
    }
}

// One ESC alone on its wire is a segment of one device: the runtime owns that segment.
Runtime::Runtime(esc::Link& link, esc::Esc& esc, const esc::Clock& clock)
    : Runtime(link, std::make_unique<esc::Segment>(), esc, clock) {}

Runtime::Runtime(esc::Link& link, std::unique_ptr<esc::Segment> own, esc::Esc& esc, const esc::Clock& clock)
    : Runtime(link, (own->add(esc), *own), clock) {
    own_segment_ = std::move(own);
}

void Runtime::close_fds() {
    for (int* fd : {&timer_fd_, &stop_fd_, &epoll_fd_}) {
        if (*fd >= 0) ::close(*fd);
        *fd = -1;
    }
}

void Runtime::set_firmware(Firmware* firmware) {
    if (control_fd_ >= 0) {
        (void)::epoll_ctl(epoll_fd_, EPOLL_CTL_DEL, control_fd_, nullptr);
        control_fd_ = -1;
    }
    if (firmware_ != nullptr) firmware_->set_frame_service(nullptr);
    firmware_ = firmware;
    if (firmware_ != nullptr) firmware_->set_frame_service(this);
    deadline_ns_ = compute_deadline_ns(clock_.now_ns());
    const int fd = firmware != nullptr ? firmware->control_fd() : -1;
    if (fd < 0) return;
    epoll_event ev{};
    ev.events = EPOLLIN;
    ev.data.u32 = kTagControl;
    if (::epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, fd, &ev) != 0)
        throw std::runtime_error(std::string("epoll_ctl (control): ") + std::strerror(errno));
    control_fd_ = fd;
}

Runtime::~Runtime() {
    if (g_signal_target.load() == this) g_signal_target.store(nullptr);
    close_fds();
}

void Runtime::request_stop() {
    stop_flag_.store(true, std::memory_order_relaxed);  // lock-free: safe in a signal handler
    const uint64_t one = 1;
    (void)!::write(stop_fd_, &one, sizeof one);
}

bool Runtime::stop_requested() const {
    if (stop_flag_.load(std::memory_order_relaxed)) return true;
    pollfd p{stop_fd_, POLLIN, 0};
    return ::poll(&p, 1, 0) > 0 && (p.revents & POLLIN) != 0;
}

void Runtime::run() {
    while (run_once(-1)) {
    }
}

bool Runtime::run_once(int timeout_ms) {
    if (!busy_poll_) arm_timer();
    epoll_event events[5];
    const int n = ::epoll_wait(epoll_fd_, events, 5, busy_poll_ ? 0 : timeout_ms);
    if (n < 0) {
        if (errno == EINTR) return !stop_requested();
        throw std::runtime_error(std::string("epoll_wait: ") + std::strerror(errno));
    }
    uint32_t link_events = 0;
    bool timer = false;
    bool control = false;
    uint32_t out_events = 0;
    for (int i = 0; i < n; ++i) {
        switch (events[i].data.u32) {
            case kTagStop:
                return false;
            case kTagLink:
                link_events = events[i].events;
                break;
            case kTagTimer:
                timer = true;
                break;
            case kTagControl:
                control = true;
                break;
            case kTagOut:
                out_events = events[i].events;
                break;
            default:
                break;
        }
    }
    if (n > 0 || !busy_poll_) ++stats_.wakeups;
    bool link_event = link_.fd() < 0 || link_events != 0;
    if (out_ != nullptr && (out_events != 0 || out_->fd() < 0)) {
        handle_out_frames();  // frames coming back from the rest of the line first: they are older
        link_event = true;
        if (out_events & EPOLLERR) {
            // As for the link: a pending error (the out interface lost its carrier or went down) would keep
            // the descriptor ready; reading it clears it. The carrier poll closes the port meanwhile.
            int err = 0;
            socklen_t len = sizeof err;
            (void)::getsockopt(out_->fd(), SOL_SOCKET, SO_ERROR, &err, &len);
            ++stats_.link_errors;
        }
    }
    if (link_event) {
        handle_frames();
        if (link_events & EPOLLERR) {
            // A pending socket error (e.g. ENETDOWN) keeps the descriptor ready; reading SO_ERROR clears it.
            int err = 0;
            socklen_t len = sizeof err;
            (void)::getsockopt(link_.fd(), SOL_SOCKET, SO_ERROR, &err, &len);
            ++stats_.link_errors;
            if (link_check_ && !link_check_()) {
                link_lost_ = true;
                return false;
            }
        }
    }
    if (timer) {
        uint64_t expirations = 0;
        if (::read(timer_fd_, &expirations, sizeof expirations) == sizeof expirations)
            ++stats_.timer_expiries;
        armed_ns_ = 0;
    }
    if (control && firmware_ != nullptr) firmware_->on_control(clock_.now_ns());
    if (busy_poll_) {
        // One pass of the loop: service only when something happened or a deadline passed, so an idle pass
        // costs one epoll_wait and a clock read.
        const uint64_t now = clock_.now_ns();
        note_loop_pass(now);
        if (link_event || control || now >= next_deadline_ns()) service();
        return !stop_flag_.load(std::memory_order_relaxed);
    }
    // With spin_ns_ the timer fires that much before the deadline: nothing is due yet, the spin services it.
    const bool due = timer && (spin_ns_ == 0 || clock_.now_ns() >= next_deadline_ns());
    if (link_event || due || control || n == 0) service();
    // A deadline that comes within kChainNs of this service is waited for awake, also without set_spin():
    // the SYNC0 pulses of a line of ESCs come within a few microseconds of each other, and a sleep and a
    // wake-up for each would cost more than the wait.
    if (!spin_to_deadline(spin_ns_ != 0 ? spin_ns_ : kChainNs)) return false;
    arm_timer();  // for the deadline service() found (no system call when it did not move earlier)
    return true;
}

// Every path that changes what is due (frames, control commands, timers) ends in service(), which computes
// the deadline afresh; until then it stands. With many ESCs this saves a walk over all of them per pass.
uint64_t Runtime::next_deadline_ns() const {
    return deadline_ns_;
}

// The ESCs on clock_ keep their next timer event in their EscSignals, side by side: a look at one array, not
// at every ESC (after service() no signal is stale: tick_escs(ticked_ns_) settled those a PDI access left
// unknown). An ESC on a clock of its own is asked.
uint64_t Runtime::compute_deadline_ns(uint64_t now) const {
    (void)now;
    uint64_t deadline = kNever;
    const int count = static_cast<int>(segment_.size());
    const esc::EscSignals* sig = segment_.signals();
    for (int k = 0; k < count; ++k) {
        if (sig[k].clock == &clock_ && sig[k].due_ns >= deadline) continue;
        if (!segment_.powered(k)) continue;
        deadline =
            std::min(deadline, sig[k].clock == &clock_ ? sig[k].due_ns : segment_.esc(k).next_event_ns());
    }
    if (hold_count_ != 0) deadline = std::min(deadline, hold_slots_[hold_head_].due_ns);
    if (carrier_check_) deadline = std::min(deadline, carrier_due_ns_);
    if (firmware_ != nullptr) deadline = std::min(deadline, firmware_->next_deadline_ns());
    if (capture_ != nullptr && capture_->frames_written() != flushed_frames_)
        deadline = std::min(deadline, capture_flush_due_ns_);
    return deadline;
}

// Called after each wake-up: while the next deadline is at most spin_ns_ away (the timer was armed that
// early), stay awake and service each deadline on time. Several deadlines can fall within a microsecond of
// each other (the stack's own estimate of SYNC0 comes just before the ESC's pulse), so the loop goes on
// after each one until the next is further than spin_ns_ away. Frames that arrive meanwhile are answered and
// serviced as usual (in SM-synchronous mode the application cycle runs on them): spinning never delays a
// reply. A deadline that does not move on when serviced ends the spin after a few rounds.
void Runtime::note_loop_pass(uint64_t now) {
    if (last_pass_ns_ != 0 && now > last_pass_ns_) {
        const uint64_t gap = now - last_pass_ns_;
        if (gap > 50'000) ++stats_.loop_gaps_over_50us;
        if (gap > 1'000'000) ++stats_.loop_gaps_over_1ms;
        stats_.loop_gap_max_ns = std::max(stats_.loop_gap_max_ns, gap);
    }
    last_pass_ns_ = now;
}

bool Runtime::spin_to_deadline(uint64_t window_ns) {
    constexpr int kMaxServicedDeadlines = 8;
    const uint64_t start = clock_.now_ns();
    uint64_t now = start;
    last_pass_ns_ = 0;
    bool spun = false;
    int serviced = 0;
    while (serviced < kMaxServicedDeadlines) {
        const uint64_t deadline = next_deadline_ns();
        if (deadline == kNever || deadline > now + window_ns) break;
        if (now >= deadline) {
            service();
            ++serviced;
        } else {
            spun = true;
            if (stop_flag_.load(std::memory_order_relaxed)) return false;
            int frames = handle_frames();
            if (out_ != nullptr) frames += handle_out_frames();
            if (frames > 0) service();
        }
        now = clock_.now_ns();
        note_loop_pass(now);
    }
    last_pass_ns_ = 0;
    if (spun) {
        ++stats_.spin_waits;
        stats_.spin_ns_total += now - start;
    }
    // The timer may still be armed for a deadline serviced here: it is armed afresh.
    if (spun || serviced > 0 || spin_ns_ != 0) armed_ns_ = 0;
    return true;
}

// Frames that arrived while the runtime was busy (about to tick the ESCs and run the firmware, or between
// two devices' firmware): answered before that work, as a hardware ESC answers whatever its
// microcontroller does. Frames coming back on the out link first: they are older.
int Runtime::serve_frames() {
    int n = out_ != nullptr ? handle_out_frames() : 0;
    n += handle_frames();
    stats_.frames_before_work += static_cast<uint64_t>(n);
    return n;
}

// A frame waits in the link while the runtime is busy, descheduled or stopped; a hardware ESC took it when it
// came. So it is taken at its arrival: the link's receive time stamp (the kernel's, CLOCK_REALTIME)
// converted to clock_ with the offset between the two clocks' "now", read once per burst (a step of the
// real-time clock moves both). The result is kept within [the time the ESCs were last ticked to, now]: a
// frame cannot arrive before what the ESCs already did, nor in the future (a stamp from another time base,
// a clock step). Without stamps (LoopbackLink) the arrival is now, as before.
uint64_t Runtime::arrival_ns(const esc::Link& link, uint64_t now, int64_t& offset, bool& offset_taken) const {
    const uint64_t stamp = link.rx_stamp_ns();
    if (stamp == 0) return now;
    if (!offset_taken) {
        offset = static_cast<int64_t>(clock_.now_ns() - link.stamp_now_ns());
        offset_taken = true;
    }
    const int64_t at = static_cast<int64_t>(stamp) + offset;
    const int64_t lo = static_cast<int64_t>(ticked_ns_), hi = static_cast<int64_t>(now);
    return static_cast<uint64_t>(std::min(std::max(at, lo), hi));
}

// The ESCs' timers are silicon and run at their time: ticked to a frame's arrival before it is walked, a
// SYNC0 pulse due before the frame comes before it, and a watchdog the frame refreshes in time does not
// expire (ticking to now first expired the process-data watchdog of a slave stopped for longer than the
// watchdog while the master's frames kept coming). An ESC on a clock of its own cannot be taken to a time
// of clock_: it is ticked at its own now, after the burst (service()).
//
// Only the ESCs with something due by t are ticked (EscSignals::due_ns: exact after each frame the ESC
// executed and each tick, 0 after a PDI access): a tick before it changes nothing, so the others are not
// touched. An ESC on a clock of its own has its due time on that clock: it is left to service().
void Runtime::tick_escs(uint64_t t) {
    ticked_ns_ = t;
    const int count = static_cast<int>(segment_.size());
    esc::EscSignals* sig = segment_.signals();
    for (int k = 0; k < count; ++k) {
        if (sig[k].clock != &clock_ || sig[k].due_ns > t || !segment_.powered(k)) continue;
        segment_.esc(k).tick(t);
    }
}

// Each frame from the master is walked through the segment at its arrival.
int Runtime::handle_frames() {
    int64_t offset = 0;
    bool offset_taken = false;
    int i = 0;
    for (; i < kMaxBurst; ++i) {
        const std::size_t len = link_.receive(buffer_);
        if (len == 0) break;
        const uint64_t rx_ns = clock_.now_ns();
        const uint64_t at = arrival_ns(link_, rx_ns, offset, offset_taken);
        ++stats_.frames_received;
        if (reply_count_ != 0 && rx_ns - reply_first_ns_ >= kReplyCoalesceNs) flush_replies();
        std::span<uint8_t> frame(buffer_.data(), len);
        if (capture_ != nullptr) std::memcpy(in_copy_.data(), buffer_.data(), len);
        if (at > ticked_ns_) tick_escs(at);
        const esc::Segment::Result result = segment_.walk(frame, at);
        const uint64_t done = clock_.now_ns();
        log_frame_time(done - rx_ns);
        stats_.frame_ns_total += done - rx_ns;
        stats_.frame_ns_max = std::max(stats_.frame_ns_max, done - rx_ns);
        segment_result(result, frame, done);
        if (capture_ != nullptr) {
            capture_->write(std::span<const uint8_t>(in_copy_.data(), len));
            if (result.kind == esc::Segment::Result::Kind::Reply) capture_->write(frame);
        }
    }
    flush_replies();
    return i;
}

void Runtime::log_frame_time(uint64_t ns) {
    if (frame_log_ == nullptr || !frame_log_->on.load(std::memory_order_relaxed)) return;
    const std::size_t k = frame_log_->count.load(std::memory_order_relaxed);
    if (k >= frame_log_->ns.size()) return;
    frame_log_->ns[k] = ns;
    frame_log_->count.store(k + 1, std::memory_order_release);
}

// Frames that come back on the out link (from the devices behind the external port).
int Runtime::handle_out_frames() {
    int64_t offset = 0;
    bool offset_taken = false;
    int i = 0;
    for (; i < kMaxBurst; ++i) {
        const std::size_t len = out_->receive(buffer_);
        if (len == 0) break;
        const uint64_t at = arrival_ns(*out_, clock_.now_ns(), offset, offset_taken);
        ++stats_.frames_resumed;
        std::span<uint8_t> frame(buffer_.data(), len);
        if (at > ticked_ns_) tick_escs(at);
        const esc::Segment::Result result = segment_.resume(frame, at);
        segment_result(result, frame, clock_.now_ns());
        if (capture_ != nullptr && result.kind == esc::Segment::Result::Kind::Reply) capture_->write(frame);
    }
    flush_replies();
    return i;
}

void Runtime::segment_result(const esc::Segment::Result& result, std::span<uint8_t> frame, uint64_t now) {
    using Kind = esc::Segment::Result::Kind;
    if (result.kind == Kind::External) {
        ++stats_.frames_external;
        return;
    }
    if (result.kind != Kind::Reply) {
        ++stats_.frames_dropped;
        return;
    }
    if (result.hold_ns != 0 || hold_count_ != 0) {  // behind held replies too: a cable keeps the order
        flush_replies();                            // and the replies before it go first
        if (hold_count_ < kHoldSlots) {
            const std::size_t slot = (hold_head_ + hold_count_) % kHoldSlots;
            std::memcpy(hold_buffer_.data() + slot * esc::kMaxFrameSize, frame.data(), frame.size());
            hold_slots_[slot] = HeldFrame{now + result.hold_ns, frame.size()};
            ++hold_count_;
            ++stats_.frames_held;
            return;
        }
        ++stats_.hold_overflows;
        send_reply(frame, now);
        flush_replies();
        return;
    }
    send_reply(frame, now);
}

// A reply joins the burst's batch; the batch goes out when the burst is done (flush_replies() at the end of
// handle_frames/handle_out_frames) or once its oldest reply has waited kReplyCoalesceNs.
void Runtime::send_reply(std::span<const uint8_t> frame, uint64_t now) {
    if (reply_count_ == reply_lengths_.size()) flush_replies();
    if (reply_count_ == 0) reply_first_ns_ = now;
    std::memcpy(reply_buffer_.data() + reply_count_ * esc::kMaxFrameSize, frame.data(), frame.size());
    reply_lengths_[reply_count_++] = frame.size();
    if (now - reply_first_ns_ >= kReplyCoalesceNs) flush_replies();
}

void Runtime::flush_replies() {
    if (reply_count_ == 0) return;
    for (std::size_t k = 0; k < reply_count_; ++k) {
        if (link_.send(
                std::span<const uint8_t>(reply_buffer_.data() + k * esc::kMaxFrameSize, reply_lengths_[k])))
            ++stats_.frames_sent;
        else
            ++stats_.send_errors;
    }
    reply_count_ = 0;
    ++stats_.reply_batches;
}

void Runtime::release_held(uint64_t now) {
    while (hold_count_ != 0 && hold_slots_[hold_head_].due_ns <= now) {
        const HeldFrame& h = hold_slots_[hold_head_];
        if (link_.send(
                std::span<const uint8_t>(hold_buffer_.data() + hold_head_ * esc::kMaxFrameSize, h.length)))
            ++stats_.frames_sent;
        else
            ++stats_.send_errors;
        hold_head_ = (hold_head_ + 1) % kHoldSlots;
        --hold_count_;
    }
}

void Runtime::poll_carrier(uint64_t now) {
    if (now < carrier_due_ns_) return;
    carrier_due_ns_ = now + kCarrierPollNs;
    const int up = carrier_check_() ? 1 : 0;
    if (up == carrier_state_) return;
    const bool first = carrier_state_ < 0;
    carrier_state_ = up;
    segment_.set_external_link(up != 0);
    if (!first) ++stats_.carrier_changes;
    if (carrier_log_ != nullptr && (!first || up == 0)) {
        const std::string what = up != 0 ? "carrier on, the external port is open"
                                         : "no carrier, the external port is closed (frames loop back)";
        carrier_log_->write(up != 0 ? LogLevel::Info : LogLevel::Warn,
                            "out link " + carrier_name_ + ": " + what);
    }
}

void Runtime::service() {
    ++stats_.services;
    // Frames before the firmware: one that came while the last work ran (a burst, the control socket, a
    // spin) is answered before the firmware runs (a look at the receive ring when none waits). Each is taken
    // at its arrival, the ESCs' timers ticked to it first (tick_escs()): a SYNC0 pulse due before the frame
    // arrived comes before it, as on hardware (answering the frame first put a cycle's LRW before the SYNC0
    // that precedes it, and a chain of two processes counted SM events missed, integration_segment_chain),
    // and one due after it comes after it.
    serve_frames();
    // Then the ESCs' timers to now, with one clock read for the segment: its ESCs count the runtime's clock
    // (each with its own drift).
    const uint64_t now = clock_.now_ns();
    tick_escs(now);
    const int count = static_cast<int>(segment_.size());
    const esc::EscSignals* sig = segment_.signals();
    for (int k = 0; k < count; ++k)
        if (sig[k].clock != &clock_ && segment_.powered(k)) segment_.esc(k).tick();
    if (hold_count_ != 0) release_held(now);
    if (carrier_check_) poll_carrier(now);
    if (firmware_ != nullptr) {
        firmware_->poll(now);
        // The ESCs the firmware accessed (PDI watchdog restarted, registers written): their next event
        // settled at the time they were ticked to, which fires nothing new (what was due by then has run).
        tick_escs(ticked_ns_);
    }
    // Capture: pushed to the file at most every kCaptureFlushNs, so a reader (or a SIGKILL) sees frames
    // that are at most that old, without a write() per frame.
    if (capture_ != nullptr && capture_->frames_written() != flushed_frames_ &&
        now >= capture_flush_due_ns_) {
        capture_->flush();
        flushed_frames_ = capture_->frames_written();
        capture_flush_due_ns_ = now + kCaptureFlushNs;
    }
    // `now` may be a little old by here: an event found due at it is due at once, which is what it is.
    deadline_ns_ = compute_deadline_ns(now);
}

void Runtime::arm_timer() {
    uint64_t deadline = next_deadline_ns();
    if (deadline != kNever && spin_ns_ != 0) deadline = deadline > spin_ns_ ? deadline - spin_ns_ : 0;
    // The timer is only ever moved earlier. A deadline that moved later (a watchdog re-triggered by every
    // process-data frame) or went away leaves the timer where it is: it then fires early once, service()
    // finds nothing due, and the timer is re-armed for the real deadline. This saves a timerfd_settime()
    // per frame, and on a shared CPU every microsecond after the reply delays the master too.
    if (deadline == kNever || (armed_ns_ != 0 && deadline >= armed_ns_)) return;
    itimerspec spec{};
    spec.it_value.tv_sec = static_cast<time_t>(deadline / 1000000000ull);
    spec.it_value.tv_nsec = static_cast<long>(deadline % 1000000000ull);
    if (spec.it_value.tv_sec == 0 && spec.it_value.tv_nsec == 0) spec.it_value.tv_nsec = 1;  // 0 would disarm
    if (::timerfd_settime(timer_fd_, TFD_TIMER_ABSTIME, &spec, nullptr) < 0)
        throw std::runtime_error(std::string("timerfd_settime: ") + std::strerror(errno));
    ++stats_.timer_arms;
    armed_ns_ = deadline == 0 ? 1 : deadline;
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

}  // namespace slave
