#pragma once
// The slave runtime: a single-threaded event loop that owns the link and a segment of ESCs (esc::Segment)
// and runs the firmware. One ESC alone on its wire (ecat-slave with one drive) is a segment of one device:
// there is one loop and one frame path, whatever the number of devices.
//
//   epoll_wait(link fd, out link fd, timerfd, stop eventfd, firmware control fd)
//   for each frame waiting (a burst, at most kMaxBurst):  rx time = when it arrived (the link's receive
//       time stamp on the clock, else clock now); tick every powered ESC to it (a SYNC0 pulse or a watchdog
//       due before the frame comes before it); segment.walk(frame, rx time); a reply joins the burst's
//       batch; record in/out to the capture
//   send the batch; then tick every powered ESC to now and firmware.poll(now) (after the replies: the
//   firmware never delays a frame); re-arm the timerfd (CLOCK_MONOTONIC, TFD_TIMER_ABSTIME) for the earliest
//   of the ESCs' events, the firmware's deadline, a held reply and the carrier poll
//
// How it waits for a timed event (a SYNC0 pulse, the application cycle, a watchdog) is a choice:
//   default        sleeps on the timerfd to the deadline: the wake-up is as late as the platform's timer
//                  latency (tens of microseconds on a virtual machine, docs/benchmarks.md); a deadline
//                  that comes within kChainNs after a service is waited for awake (the SYNC0 pulses of a
//                  line of drives come microseconds apart: one wake-up serves them all);
//   set_spin(N)    sleeps to N ns before the deadline, then busy-waits on the clock to it, serving frames
//                  that come meanwhile: the event runs within a microsecond or two of its time, for at most
//                  N ns of CPU per event;
//   set_busy_poll  never sleeps: the link, the clock and the descriptors are polled in a loop, so frames are
//                  answered and events run without any wake-up latency, for a whole CPU.
//
// One receive buffer, allocated at construction; nothing is allocated per frame or per cycle.
// The clock must count CLOCK_MONOTONIC nanoseconds (esc::SystemClock) because the timer runs on it.
//
// A frame from the link is walked through the segment (Segment::walk) (ecat-slave --slaves N, --topology,
// --out-iface, or one drive); a reply goes back out on the link, held back HopFaults::hold_ns in a
// preallocated queue when a hop is delayed; a frame the segment sent out of its external port (the `out`
// link) comes back on that link and finishes its walk (Segment::resume). The carrier of the out link is
// polled every kCarrierPollNs and given to Segment::set_external_link() (no carrier: the port is closed and
// loops back). The timers of every ESC of the segment are ticked after each burst; the firmware (all the
// devices' firmware in one) runs after it. Replies of one burst are coalesced: they go out together when the
// burst has been walked, or as soon as the oldest has waited kReplyCoalesceNs (docs/decisions/segment.md
// "Replies of a burst"), so a master that sent several frames is woken once for them instead of once per
// reply.
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "esc/clock.hpp"
#include "esc/esc.hpp"
#include "esc/link.hpp"
#include "esc/link_capture.hpp"
#include "esc/segment.hpp"
#include "slave/firmware.hpp"
#include "slave/log.hpp"

namespace slave {

struct RuntimeStats {
    uint64_t frames_received = 0;
    uint64_t frames_sent = 0;
    uint64_t frames_dropped = 0;  // process_frame() said "do not send"
    uint64_t send_errors = 0;
    uint64_t link_errors = 0;  // POLLERR on the link (interface went down, ...)
    uint64_t wakeups = 0;
    uint64_t services = 0;  // passes over the segment's timers and the firmware (service())
    uint64_t timer_expiries = 0;
    uint64_t timer_arms = 0;      // timerfd_settime() calls
    uint64_t frame_ns_total = 0;  // sum over frames of (reply ready to send - frame received), clock ns
    uint64_t frame_ns_max = 0;
    uint64_t spin_waits = 0;     // busy-waits to a deadline (set_spin)
    uint64_t spin_ns_total = 0;  // time spent in them, clock ns
    // Busy-poll and spin loops: gaps between two consecutive passes, i.e. times the loop was kept from
    // running (preempted, interrupted, a slow system call). Show what the platform takes from a busy loop.
    uint64_t loop_gaps_over_50us = 0;
    uint64_t loop_gaps_over_1ms = 0;
    uint64_t loop_gap_max_ns = 0;
    // Segments with faults or an external port:
    uint64_t frames_external = 0;  // walks that left through the external port (sent on the out link)
    uint64_t frames_resumed = 0;   // frames received on the out link (Segment::resume)
    uint64_t frames_held = 0;      // replies held back by a delayed hop
    uint64_t hold_overflows = 0;   // replies sent at once because the hold queue was full
    uint64_t out_send_errors = 0;  // not used by the Runtime itself: the external send callback counts here
    uint64_t carrier_changes = 0;  // carrier of the out link gained or lost
    uint64_t reply_batches = 0;    // coalesced replies sent together (a batch of one counts too)
    // Frames found waiting when other work was about to start or between devices' firmware (they are
    // answered first): they arrived while the runtime was busy, not asleep.
    uint64_t frames_before_work = 0;
};

// Optional record of each frame's processing time (receive to reply ready, clock ns), for benchmarks: a
// buffer the caller allocates; the runtime fills it while `on` is set and stops when it is full.
struct FrameTimeLog {
    explicit FrameTimeLog(std::size_t capacity) : ns(capacity) {}
    std::vector<uint64_t> ns;
    std::atomic<std::size_t> count{0};
    std::atomic<bool> on{false};
};

class Runtime final : private FrameService {
  public:
    static constexpr int kMaxBurst = 64;
    // Longest time a captured frame stays in the capture's buffer before it is written to the file.
    static constexpr uint64_t kCaptureFlushNs = 200'000'000;

    // Replies held back by a delayed hop (HopFaults::hold_ns): at most this many at once.
    static constexpr std::size_t kHoldSlots = 256;
    // Longest time the first reply of a burst waits for the others: well below the time a
    // full frame takes on a 100 Mbit/s wire (123 us), so replies never come later than on real cables.
    static constexpr uint64_t kReplyCoalesceNs = 100'000;
    // A deadline this close after a service is waited for awake instead of asleep (see run_once()).
    static constexpr uint64_t kChainNs = 20'000;
    // How often the out link's carrier is polled (with an out link).
    static constexpr uint64_t kCarrierPollNs = 100'000'000;

    // Frames from `link` are walked through `segment`; `out` (may be null) is the link of the segment's
    // external port, whose send callback the owner set (Segment::set_external).
    Runtime(esc::Link& link, esc::Segment& segment, const esc::Clock& clock, esc::Link* out = nullptr);
    // One ESC alone on its wire: the runtime runs it as a segment of one device, which it owns.
    Runtime(esc::Link& link, esc::Esc& esc, const esc::Clock& clock);
    ~Runtime();
    Runtime(const Runtime&) = delete;
    Runtime& operator=(const Runtime&) = delete;

    // Also watches the firmware's control_fd(), if it has one.
    void set_firmware(Firmware* firmware);
    void set_capture(esc::PcapWriter* capture) { capture_ = capture; }
    void set_frame_time_log(FrameTimeLog* log) { frame_log_ = log; }
    // Called when poll() reports an error on the link (interface down or removed); returns whether the link
    // is still usable. If it returns false, run() ends and link_lost() is true. Not called per frame.
    void set_link_check(std::function<bool()> check) { link_check_ = std::move(check); }
    bool link_lost() const { return link_lost_; }
    // With an out link: whether the out interface has a carrier, polled every kCarrierPollNs
    // (not per frame); each change is given to Segment::set_external_link() and logged to `log`.
    void set_carrier_check(std::function<bool()> check, Log* log = nullptr, std::string name = {});
    // Wake spin_ns before each timed event and busy-wait to it (0: sleep all the way, the default).
    void set_spin(uint64_t spin_ns) { spin_ns_ = spin_ns; }
    // Never sleep (see above). run_once() then returns after one pass, whatever its timeout.
    void set_busy_poll(bool on) { busy_poll_ = on; }

    // Runs until request_stop().
    void run();
    // One wait and what follows it; waits at most timeout_ms (-1: no limit). Returns false once stop was
    // requested. For tests and for callers that interleave other work.
    bool run_once(int timeout_ms);
    // Asks run() to return. Async-signal-safe and callable from any thread.
    void request_stop();
    bool stop_requested() const;

    const RuntimeStats& stats() const { return stats_; }
    RuntimeStats& stats() { return stats_; }
    // Replies waiting in the hold queue.
    std::size_t held() const { return hold_count_; }

  private:
    Runtime(esc::Link& link, std::unique_ptr<esc::Segment> own, esc::Esc& esc, const esc::Clock& clock);
    int handle_frames();          // returns the number of frames received
    int serve_frames() override;  // FrameService: frames that came while other work ran
    int handle_out_frames();
    // When the frame link.receive() returned last arrived, on clock_: its receive time stamp converted with
    // `offset` (clock_ minus the link's time base, taken once per burst into *offset_taken), kept within
    // [ticked_ns_, now]; now if the link has no stamps.
    uint64_t arrival_ns(const esc::Link& link, uint64_t now, int64_t& offset, bool& offset_taken) const;
    void tick_escs(uint64_t t);  // every powered ESC on clock_ to t
    void segment_result(const esc::Segment::Result& result, std::span<uint8_t> frame, uint64_t now);
    void release_held(uint64_t now);
    void send_reply(std::span<const uint8_t> frame, uint64_t now);
    void flush_replies();
    void log_frame_time(uint64_t ns);
    void poll_carrier(uint64_t now);
    void add_watch(int fd, uint32_t tag);
    void service();
    uint64_t next_deadline_ns() const;  // as computed at the end of the last service()
    uint64_t compute_deadline_ns(uint64_t now) const;
    bool spin_to_deadline(uint64_t window_ns);  // false: stop was requested meanwhile
    void note_loop_pass(uint64_t now);
    void arm_timer();
    void close_fds();
    static constexpr uint32_t kTagLink = 1, kTagTimer = 2, kTagStop = 3, kTagControl = 4, kTagOut = 5;

    esc::Link& link_;
    esc::Segment& segment_;
    std::unique_ptr<esc::Segment> own_segment_;  // the segment of one ESC (the Esc constructor), else null
    esc::Link* out_ = nullptr;                   // the segment's external port, may be null
    const esc::Clock& clock_;
    Firmware* firmware_ = nullptr;
    esc::PcapWriter* capture_ = nullptr;
    FrameTimeLog* frame_log_ = nullptr;
    std::function<bool()> link_check_;
    bool link_lost_ = false;
    int timer_fd_ = -1;
    int stop_fd_ = -1;
    int epoll_fd_ = -1;
    uint64_t spin_ns_ = 0;
    bool busy_poll_ = false;
    uint64_t last_pass_ns_ = 0;           // clock at the last pass of a busy loop, 0: not in one
    std::atomic<bool> stop_flag_{false};  // set with the stop eventfd, cheap to test while spinning
    int control_fd_ = -1;                 // the firmware's control descriptor registered with epoll, -1: none
    uint64_t ticked_ns_ = 0;              // clock time the ESCs were last ticked to
    uint64_t deadline_ns_ = 0;            // next deadline, computed by service() (and when the parts change)
    uint64_t armed_ns_ = 0;               // deadline the timerfd is armed for; 0 = not armed or expired
    uint64_t flushed_frames_ = 0;         // capture frames already pushed to the file
    uint64_t capture_flush_due_ns_ = 0;   // earliest time of the next capture flush
    std::vector<uint8_t> buffer_;         // the receive buffer (frame processed in place)
    std::vector<uint8_t> in_copy_;        // the frame as received, kept for the capture
    RuntimeStats stats_;
    // Hold queue: a ring of kHoldSlots frames, released in order when due.
    struct HeldFrame {
        uint64_t due_ns = 0;
        std::size_t length = 0;
    };
    std::vector<uint8_t> hold_buffer_;  // kHoldSlots * kMaxFrameSize, allocated at construction
    std::vector<HeldFrame> hold_slots_;
    std::size_t hold_head_ = 0;
    std::size_t hold_count_ = 0;
    // Replies of the current burst, sent together by flush_replies().
    std::vector<uint8_t> reply_buffer_;  // kMaxBurst * kMaxFrameSize, allocated at construction
    std::vector<std::size_t> reply_lengths_;
    std::size_t reply_count_ = 0;
    uint64_t reply_first_ns_ = 0;  // when the oldest waiting reply was ready
    // Carrier of the out link.
    std::function<bool()> carrier_check_;
    Log* carrier_log_ = nullptr;
    std::string carrier_name_;
    uint64_t carrier_due_ns_ = 0;
    int carrier_state_ = -1;  // -1: not polled yet, 0: no carrier, 1: carrier
};

// SIGINT / SIGTERM handling: install_stop_signals() makes both signals set a flag (stop_signalled()) and
// stop the runtime registered with set_signal_target(), if any. SA_RESTART is not set, so a blocking call
// returns with EINTR. Registering a target after a signal arrived stops it at once.
void install_stop_signals();
void set_signal_target(Runtime* runtime);
bool stop_signalled();

}  // namespace slave
