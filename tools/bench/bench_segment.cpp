// bench-segment: a segment of N soft drives in ONE process, driven by a master thread at 1 kHz with DC.
// For each N (default 1, 10, 100): a veth pair in a private network namespace; on one end the slave
// runtime (slave::Runtime over a device::Line of N drives, the segment of ecat-slave --slaves N) in its own
// thread; on the other the master library: the whole line scanned, DC delays and offsets measured, every
// drive's SM2/SM3 in one LRW image, SYNC0 on all at one start time, all to OP, every drive in CSP (mode 8,
// controlword 6 -> 7 -> 15, a target position ramp). Then --seconds of cycles at 1 kHz in blocks of 20,
// alternating with as many cycles of a bare echo in the runtime's place (TimedLink answers each frame itself,
// in the runtime's thread and wake-up path, unprocessed), so the cyclic frame and its baseline are measured
// side by side on the same veth pair and the same busy or idle machine. Afterwards the same frames against an
// echo in a thread of its own (poll(), no runtime), as a second baseline.
//
// Prints per N: the processing time of one frame through the whole segment (the runtime's walk, from the
// frame's receive to its reply being ready) and its latency in the slave (receive to send, with the wait
// for the other replies of a burst), the CPU time of the slave thread per cycle as % of one core at 1 kHz
// (CLOCK_THREAD_CPUTIME_ID of that thread over the cyclic blocks), the runtime's wake-ups, passes over the
// line and timer arms per cycle, missed cycles (the master loop woke a whole period late), lost frames and
// working-counter errors of the cyclic blocks, the round trips of the cyclic frame and of the echoes
// (median/p99 and their ratios) and the allocations per cycle of the whole process during the measured window
// (a counting global operator new). Asserts nothing. Needs root.
//
// --line SPEC (repeatable) and --mixed: a MIXED LINE of devices from ESIs instead of N MAXPOS drives. SPEC is
// a comma-separated list of KIND:COUNT in line order; the kinds are the example devices of esi/examples
// (found through --esi-dir, default the source tree's esi/examples):
//   coupler  EXK1100 (coupler.xml: no mailbox, no process data)
//   io       IO terminals in turn: EXD1008 rev 0x00110000 (8 digital inputs), EXD2008 (8 digital outputs),
//            both without mailbox, and EXA3104 (4 analog inputs, CoE)
//   drive    EXS7200-0010 (drive402.xml, a CiA 402 drive that is not a MAXPOS; its own PDO layout)
//   maxpos   the built-in MAXPOS drive
// The master side reads the layout of a slave without mailbox from its SII (discover_sii), of the others
// through CoE; a slave whose outputs map 0x6040/0x607A and inputs 0x6041/0x6064 is a drive and is driven in
// CSP like the N-drive line, the outputs of the other slaves get a counting byte. Per line it prints the same
// figures as for N drives, plus the drives enabled in CSP, faulted or not in OP at the end (a line that does
// not reach OP is reported and the next one runs). --mixed runs coupler:1,io:3 and coupler:1,io:60 (whose
// difference is the cost of one IO terminal per cycle), then coupler:1,io:60,drive:40 and
// coupler:1,io:60,maxpos:40.
#include <poll.h>
#include <pthread.h>
#include <sched.h>
#include <time.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "device/line.hpp"
#include "esc/clock.hpp"
#include "esc/link.hpp"
#include "esi/device/product.hpp"
#include "harness.hpp"
#include "master/bus.hpp"
#include "master/coe.hpp"
#include "master/mailbox.hpp"
#include "master/master.hpp"
#include "master/session.hpp"
#include "od/product.hpp"
#include "slave/netif.hpp"
#include "slave/runtime.hpp"
#include "slave/topology.hpp"
#include "stats.hpp"
#include "support/alloc_counter.hpp"
#include "util/le.hpp"
#include "util/strfmt.hpp"

namespace {

using master::Address;
using master::Error;

constexpr const char* kSlaveEnd = "seg-s0";
constexpr const char* kMasterEnd = "seg-m0";
constexpr auto kPeriod = std::chrono::microseconds(1000);

// The slave's link with a stopwatch and an echo switch.
// Stopwatch: a frame's receive() time is kept under its first datagram's index; when the reply with that
// index is sent, send - receive is the frame's latency through the slave: its walk through the segment and,
// in a burst, the wait for the burst's other replies (slave::Runtime coalesces them).
// Echo: while set, receive() sends each frame straight back (processed, as an ESC marks it) and hands nothing
// to the runtime: a bare echo in the runtime's own thread and wake-up path. Blocks of echo and of cyclic
// operation alternate, so both baselines see the same machine at the same time.
class TimedLink final : public esc::Link {
  public:
    explicit TimedLink(esc::Link& inner, std::size_t capacity) : inner_(inner), samples_(capacity) {}
    int fd() const override { return inner_.fd(); }
    std::size_t receive(std::span<uint8_t> buf) override {
        for (;;) {
            const std::size_t n = inner_.receive(buf);
            if (n == 0) return 0;
            if (echo_.load(std::memory_order_relaxed)) {
                if (n >= 12) buf[6] |= 0x02;  // source MAC: locally administered, as an ESC's port 0 sets it
                (void)inner_.send(std::span<const uint8_t>(buf.data(), n));
                continue;
            }
            if (n > kIndexOffset) {
                Pending& p = pending_[next_++ % kPending];
                p = Pending{bench::now_ns(), buf[kIndexOffset], true};
            }
            return n;
        }
    }
    bool send(std::span<const uint8_t> frame) override {
        if (frame.size() > kIndexOffset) {
            Pending* oldest = nullptr;
            for (Pending& p : pending_)
                if (p.valid && p.index == frame[kIndexOffset] && (!oldest || p.at < oldest->at)) oldest = &p;
            if (oldest != nullptr) {
                oldest->valid = false;
                if (recording_.load(std::memory_order_relaxed) && count_ < samples_.size())
                    samples_[count_++] = bench::now_ns() - oldest->at;
            }
        }
        return inner_.send(frame);
    }
    std::string describe() const override { return inner_.describe(); }
    void record(bool on) { recording_.store(on); }
    void echo(bool on) { echo_.store(on); }
    std::vector<uint64_t> samples() const { return {samples_.begin(), samples_.begin() + count_}; }

  private:
    static constexpr std::size_t kIndexOffset = 14 + 2 + 1;  // Ethernet header, EtherCAT header, command
    static constexpr std::size_t kPending = 16;
    struct Pending {
        uint64_t at = 0;
        uint8_t index = 0;
        bool valid = false;
    };
    esc::Link& inner_;
    std::vector<uint64_t> samples_;
    std::size_t count_ = 0;
    Pending pending_[kPending];
    std::size_t next_ = 0;
    std::atomic<bool> recording_{false};
    std::atomic<bool> echo_{false};
};

uint64_t thread_cpu_ns(clockid_t id) {
    timespec ts{};
    clock_gettime(id, &ts);
    return static_cast<uint64_t>(ts.tv_sec) * 1'000'000'000ull + static_cast<uint64_t>(ts.tv_nsec);
}

// Byte offset of object (index, sub) in the PDOs the assignment object lists, -1 if it is not mapped.
int pdo_offset(master::SdoClient& sdo, uint16_t assign, uint16_t index, uint8_t sub) {
    uint8_t b[4] = {};
    if (!sdo.upload(assign, 0, b)) return -1;
    const uint8_t pdos = b[0];
    uint32_t bits = 0;
    for (uint8_t p = 1; p <= pdos; ++p) {
        if (!sdo.upload(assign, p, b)) return -1;
        const uint16_t pdo = util::get16(b);
        if (!sdo.upload(pdo, 0, b)) return -1;
        const uint8_t entries = b[0];
        for (uint8_t e = 1; e <= entries; ++e) {
            if (!sdo.upload(pdo, e, b)) return -1;
            const uint32_t entry = util::get32(b);
            if ((entry >> 16) == index && ((entry >> 8) & 0xFF) == sub) return static_cast<int>(bits / 8);
            bits += entry & 0xFF;
        }
    }
    return -1;
}

struct DriveIo {
    int cw = -1, mode = -1, target = -1;  // outputs
    int sw = -1, pos = -1;                // inputs
    bool drive() const { return cw >= 0 && target >= 0 && sw >= 0 && pos >= 0; }
};

// The devices of one line, in order: the product of each (null: the built-in MAXPOS drive).
struct Plan {
    std::string label;  // "coupler:1,io:60,drive:40"; empty: N MAXPOS drives (the classic output)
    std::vector<std::shared_ptr<const od::Product>> products;
    std::vector<std::string> names;  // topology names ("io12"); empty: line_topology's
};

struct Figures {
    std::size_t drives = 0;
    std::string label;                                   // the plan's
    std::size_t devices = 0, no_mailbox = 0, in_op = 0;  // mixed line: slaves, without mailbox, in OP at end
    std::string not_op;    // the first of the others: position, AL state and AL status code
    uint64_t faulted = 0;  // drives with statusword bit 3 (fault) at the end
    double followed_min = 0, followed_max = 0;  // mixed line: position actual's advance over the ramp's, 0..1
    bench::Summary walk, latency, rtt, echo, echo_thread;
    double cpu_percent = 0, cpu_us_per_cycle = 0, allocs_per_cycle = 0;
    double polls_per_cycle = 0;  // device firmware polls (device::LineStats::polls)
    double wakeups_per_cycle = 0, services_per_cycle = 0, timer_arms_per_cycle = 0, frames_per_wakeup = 0,
           replies_per_batch = 0;
    uint64_t frames_before_work = 0;  // frames found waiting before the timers/firmware or between devices
    double spin_us_per_cycle = 0;     // awake waiting for a deadline microseconds away (kChainNs)
    uint64_t cycles = 0, missed = 0, lost = 0, wkc_errors = 0, enabled = 0;
    std::size_t frames_per_cycle = 0;
};

void sleep_until_ns(uint64_t t) {
    timespec ts{static_cast<time_t>(t / 1'000'000'000ull), static_cast<long>(t % 1'000'000'000ull)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
    }
}

// Cycles at 1 kHz on an absolute-time grid; each_cycle fills the outputs. Round trips into rtt (reserved).
template <typename Fill>
void run_cycles(master::ProcessDataSession& pd, uint64_t cycles, std::vector<uint64_t>& rtt, uint64_t& missed,
                Fill fill) {
    const uint64_t period = static_cast<uint64_t>(std::chrono::nanoseconds(kPeriod).count());
    uint64_t next = bench::now_ns();
    for (uint64_t i = 0; i < cycles; ++i) {
        const uint64_t t0 = bench::now_ns();
        if (t0 >= next + period) {
            ++missed;
            next = t0;  // start again from now
        }
        fill(i);
        (void)pd.cycle();
        const uint64_t t1 = bench::now_ns();
        if (rtt.size() < rtt.capacity()) rtt.push_back(t1 - t0);
        next += period;
        sleep_until_ns(next);
    }
}

Figures run_segment(const Plan& plan, double seconds, const std::string& backend) {
    Figures f;
    f.label = plan.label;
    const std::size_t devices = plan.products.size();
    f.devices = devices;
    const uint64_t cycles = static_cast<uint64_t>(seconds * 1000.0);
    slave::VethPair pair(kSlaveEnd, kMasterEnd);
    bench::TempDir dir("bench-segment");

    // ---- the slave side: N drives in a Runtime, in its own thread ---------------------------------------
    esc::SystemClock clock;
    device::LineOptions lo;
    lo.topology = slave::line_topology(static_cast<int>(devices));
    for (std::size_t k = 0; k < devices; ++k) {
        slave::TopologyDevice& d = lo.topology.devices[k];
        if (k < plan.names.size()) d.name = plan.names[k];
        d.state_dir = (dir.path() / d.name).string();
    }
    lo.base.state_dir = dir.path();
    lo.products = plan.products;
    auto slave_link = esc::open_link(kSlaveEnd, backend);
    TimedLink timed(*slave_link, cycles + 1000);
    auto line = std::make_unique<device::Line>(clock, lo);
    auto runtime = std::make_unique<slave::Runtime>(timed, line->segment(), clock);
    runtime->set_firmware(line.get());
    slave::FrameTimeLog walk_log(cycles * 8 + 1000);
    runtime->set_frame_time_log(&walk_log);
    // The runtime's statistics are copied by its own thread on request (snapshot()), never read across.
    std::atomic<int> snap_state{0};
    slave::RuntimeStats snap;
    uint64_t snap_polls = 0;
    std::thread slave_thread([&] {
        pthread_setname_np(pthread_self(), "segment-slave");  // for perf and top
        while (runtime->run_once(2)) {
            if (snap_state.load(std::memory_order_acquire) == 1) {
                snap = runtime->stats();
                snap_polls = line->stats().polls;
                snap_state.store(2, std::memory_order_release);
            }
        }
    });
    auto snapshot = [&] {
        snap_state.store(1, std::memory_order_release);
        while (snap_state.load(std::memory_order_acquire) != 2)
            std::this_thread::sleep_for(std::chrono::microseconds(100));
        snap_state.store(0);
        return snap;
    };
    clockid_t slave_cpu{};
    pthread_getcpuclockid(slave_thread.native_handle(), &slave_cpu);

    // ---- the master side ---------------------------------------------------------------------------------
    auto master_link = esc::open_link(kMasterEnd, backend);
    master::MasterOptions mo;
    mo.timeout = std::chrono::milliseconds(50);
    mo.al_timeout = std::chrono::milliseconds(10'000);
    master::Master m(*master_link, mo);
    auto fail = [&](const std::string& what, Error e) {
        // What the slave side saw, to tell a frame that never reached it from a reply that never came back
        // (or a slave thread that did not run): the master's frames sent against the runtime's counts.
        const slave::RuntimeStats rs = snapshot();
        const master::MasterStats& ms = m.stats();
        char seen[320];
        std::snprintf(
            seen, sizeof seen,
            " (master: frames sent %llu, replies %llu, ignored %llu, timeouts %llu; slave: frames "
            "received %llu, replies sent %llu, send errors %llu, wake-ups %llu)",
            static_cast<unsigned long long>(ms.frames_sent),
            static_cast<unsigned long long>(ms.frames_received),
            static_cast<unsigned long long>(ms.frames_ignored), static_cast<unsigned long long>(ms.timeouts),
            static_cast<unsigned long long>(rs.frames_received),
            static_cast<unsigned long long>(rs.frames_sent), static_cast<unsigned long long>(rs.send_errors),
            static_cast<unsigned long long>(rs.wakeups));
        runtime->request_stop();
        slave_thread.join();
        throw std::runtime_error(what + ": " + std::string(master::to_string(e)) + seen);
    };
    auto bus = master::scan_bus(m, {.first_station = 0x1001, .identity = true});
    if (!bus) fail("scan", bus.error());
    if (bus->size() != devices)
        fail("scan found " + std::to_string(bus->size()) + " slaves", Error::WorkingCounter);
    std::vector<Address> addresses;
    for (const master::SlaveInfo& s : *bus)
        addresses.push_back(Address::station(s.station));
    // Slaves without mailbox (SII words 0x18-0x1B all zero: couplers, digital IO terminals) get their layout
    // from the SII alone and no SDO client (as ecatctl pd --all).
    std::vector<bool> mailbox(devices, true);
    for (std::size_t k = 0; k < devices; ++k) {
        uint8_t words[8] = {};
        if (Error e = m.sii_read(addresses[k], 0x18, words); e != Error::Ok)
            fail("SII of slave " + std::to_string(k), e);
        mailbox[k] = std::any_of(std::begin(words), std::end(words), [](uint8_t b) { return b != 0; });
        f.no_mailbox += mailbox[k] ? 0 : 1;
    }
    master::SdoClients clients;
    const Error opened = clients.open(m, addresses, [&](master::Mailbox& mbx, Address a) {
        if (mailbox[a.value - 0x1001u])
            if (Error e = mbx.configure_from_sii(); e != Error::Ok) return e;
        return m.request_state(a, master::AlState::PreOp);
    });
    if (opened != Error::Ok)
        fail("mailbox / PREOP of " + std::string(plan.label.empty() ? "drive " : "slave ") +
                 std::to_string(clients.failed() + 1),
             opened);
    std::vector<master::SdoClient*> sdos(clients.clients().begin(), clients.clients().end());
    for (std::size_t k = 0; k < devices; ++k)
        if (!mailbox[k]) sdos[k] = nullptr;
    // The drives and where their CSP objects are: the default mapping of the first slave of an identity holds
    // for all slaves of that identity.
    std::vector<DriveIo> io(devices);
    std::vector<std::size_t> drive_slaves;
    for (std::size_t k = 0; k < devices; ++k) {
        if (sdos[k] == nullptr) continue;
        const master::SlaveInfo& s = (*bus)[k];
        std::size_t same = k;
        for (std::size_t j = 0; j < k; ++j)
            if (sdos[j] != nullptr && (*bus)[j].vendor_id == s.vendor_id &&
                (*bus)[j].product_code == s.product_code && (*bus)[j].revision == s.revision) {
                same = j;
                break;
            }
        if (same != k) {
            io[k] = io[same];
        } else {
            io[k].cw = pdo_offset(*sdos[k], 0x1C12, 0x6040, 0);
            io[k].mode = pdo_offset(*sdos[k], 0x1C12, 0x6060, 0);
            io[k].target = pdo_offset(*sdos[k], 0x1C12, 0x607A, 0);
            io[k].sw = pdo_offset(*sdos[k], 0x1C13, 0x6041, 0);
            io[k].pos = pdo_offset(*sdos[k], 0x1C13, 0x6064, 0);
        }
        if (!io[k].drive()) continue;
        drive_slaves.push_back(k);
        if (io[k].mode < 0) {
            const uint8_t csp[1] = {8};
            if (Error e = sdos[k]->download(0x6060, 0, csp); e != Error::Ok) fail("0x6060 = 8", e);
        }
    }
    const std::size_t drives = drive_slaves.size();
    f.drives = drives;
    if (plan.label.empty() && drives != devices) fail("CSP objects not mapped", Error::InvalidArgument);
    master::ProcessDataSession pd(m, addresses, sdos);
    if (Error e = pd.discover(); e != Error::Ok) fail("discover", e);
    for (std::size_t k = 0; k < devices; ++k)
        if (!mailbox[k])
            if (Error e = pd.discover_sii(k); e != Error::Ok)
                fail("SII layout of slave " + std::to_string(k), e);
    master::DcConfig dc;
    dc.enable = true;
    dc.cycle_ns = 1'000'000;
    dc.start_delay = std::chrono::milliseconds(100 + 5 * static_cast<int64_t>(devices));
    dc.measure_options.drift_frames = 1000;
    if (Error e = pd.configure(dc); e != Error::Ok) fail("configure", e);
    f.frames_per_cycle = pd.frames_per_cycle();

    std::vector<int32_t> target(devices, 0);
    std::vector<std::size_t> other_slaves;  // not drives, with outputs: a counting byte
    for (std::size_t k = 0; k < devices; ++k)
        if (!io[k].drive() && !pd.outputs(k).empty()) other_slaves.push_back(k);
    uint16_t controlword = 0;
    auto fill = [&](uint64_t i) {
        for (std::size_t k : drive_slaves) {
            const auto o = pd.outputs(k);
            util::put16(o.data() + io[k].cw, controlword);
            if (io[k].mode >= 0) o[static_cast<std::size_t>(io[k].mode)] = 8;
            util::put32(o.data() + io[k].target, static_cast<uint32_t>(target[k]));
        }
        for (std::size_t k : other_slaves) {
            const auto o = pd.outputs(k);
            std::fill(o.begin(), o.end(), static_cast<uint8_t>(i >> 4));
        }
    };
    auto hold = [&] {  // target = actual position
        for (std::size_t k : drive_slaves)
            target[k] = static_cast<int32_t>(util::get32(pd.inputs(k).data() + io[k].pos));
    };
    auto fill_state = [&] { fill(0); };
    if (Error e = pd.request_state(master::AlState::SafeOp, kPeriod, nullptr, fill_state); e != Error::Ok)
        fail("SAFEOP", e);
    if (Error e = pd.request_state(master::AlState::Op, kPeriod, nullptr, fill_state); e != Error::Ok)
        fail("OP", e);
    // CiA 402 enable: shutdown, switch on, enable operation, holding the actual position.
    std::vector<uint64_t> scratch;
    scratch.reserve(1000);
    uint64_t ignored = 0;
    for (uint16_t cw : {0x0006, 0x0007, 0x000F}) {
        controlword = cw;
        run_cycles(pd, 100, scratch, ignored, [&](uint64_t) {
            hold();
            fill(0);
        });
    }

    // ---- the measured window: a position ramp on every drive, in blocks of cyclic operation that alternate
    // with blocks of the bare echo in the runtime's place (TimedLink)
    // ------------------------------------------
    constexpr uint64_t kBlock = 20;  // cycles; well inside the process-data watchdog (100 ms)
    std::vector<uint64_t> rtt, echo_rtt;
    rtt.reserve(cycles);
    echo_rtt.reserve(cycles);
    uint64_t cpu = 0, echo_missed = 0;
    std::vector<int32_t> pos0(devices, 0), target0(devices, 0);
    for (std::size_t k : drive_slaves) {
        pos0[k] = static_cast<int32_t>(util::get32(pd.inputs(k).data() + io[k].pos));
        target0[k] = target[k];
    }
    const slave::RuntimeStats rs0 = snapshot();
    const uint64_t polls0 = snap_polls;
    const alloc_counter::Scope allocs;
    walk_log.on.store(true);
    for (uint64_t done = 0; done < cycles; done += kBlock) {
        const uint64_t n = std::min(kBlock, cycles - done);
        timed.echo(true);
        run_cycles(pd, n, echo_rtt, echo_missed, [&](uint64_t) { fill(done); });
        timed.echo(false);
        const master::CycleStats before = pd.stats();
        timed.record(true);
        const uint64_t cpu0 = thread_cpu_ns(slave_cpu);
        run_cycles(pd, n, rtt, f.missed, [&](uint64_t i) {
            for (std::size_t k : drive_slaves)
                target[k] += 20;  // 20 increments per ms
            fill(done + i);
        });
        cpu += thread_cpu_ns(slave_cpu) - cpu0;
        timed.record(false);
        const master::CycleStats after = pd.stats();
        f.cycles += after.cycles - before.cycles;
        f.lost += after.lost - before.lost;
        f.wkc_errors += after.wkc_errors - before.wkc_errors;
    }
    walk_log.on.store(false);
    const uint64_t alloc_count = allocs.count();
    const slave::RuntimeStats rs1 = snapshot();
    const uint64_t polls1 = snap_polls;
    for (std::size_t k : drive_slaves) {
        const uint16_t sw = util::get16(pd.inputs(k).data() + io[k].sw);
        if ((sw & 0x006F) == 0x0027) ++f.enabled;
        if (sw & 0x0008) ++f.faulted;
        // How far the actual position followed the ramp (the drive lags its target by a cycle or two).
        const double ramp = static_cast<double>(target[k] - target0[k]);
        const double moved =
            static_cast<double>(static_cast<int32_t>(util::get32(pd.inputs(k).data() + io[k].pos)) - pos0[k]);
        const double followed = ramp > 0 ? moved / ramp : 0.0;
        f.followed_min = k == drive_slaves.front() ? followed : std::min(f.followed_min, followed);
        f.followed_max = k == drive_slaves.front() ? followed : std::max(f.followed_max, followed);
    }
    if (!plan.label.empty()) {
        std::vector<master::AlStatus> states(devices);
        if (pd.read_states(states) == Error::Ok)
            for (const master::AlStatus& st : states)
                f.in_op += st.state == static_cast<uint8_t>(master::AlState::Op) && !st.error;
    }
    // CPU and allocations over the cyclic blocks; the runtime's counters over the whole window (both kinds of
    // block: its timers run in the echo blocks as well).
    const double window_cycles = static_cast<double>(2 * cycles);
    f.cpu_us_per_cycle =
        static_cast<double>(cpu) / 1000.0 / static_cast<double>(std::max<uint64_t>(1, f.cycles));
    f.cpu_percent = f.cpu_us_per_cycle / 10.0;  // of the 1000 us period
    f.allocs_per_cycle = static_cast<double>(alloc_count) / window_cycles;
    f.wakeups_per_cycle = static_cast<double>(rs1.wakeups - rs0.wakeups) / window_cycles;
    f.timer_arms_per_cycle = static_cast<double>(rs1.timer_arms - rs0.timer_arms) / window_cycles;
    f.services_per_cycle = static_cast<double>(rs1.services - rs0.services) / window_cycles;
    f.polls_per_cycle = static_cast<double>(polls1 - polls0) / window_cycles;
    f.spin_us_per_cycle = static_cast<double>(rs1.spin_ns_total - rs0.spin_ns_total) / 1000.0 / window_cycles;
    f.frames_per_wakeup = static_cast<double>(rs1.frames_received - rs0.frames_received) /
                          static_cast<double>(std::max<uint64_t>(1, rs1.wakeups - rs0.wakeups));
    f.replies_per_batch = static_cast<double>(rs1.frames_sent - rs0.frames_sent) /
                          static_cast<double>(std::max<uint64_t>(1, rs1.reply_batches - rs0.reply_batches));
    f.frames_before_work = rs1.frames_before_work - rs0.frames_before_work;
    f.rtt = bench::summarize(rtt);
    f.echo = bench::summarize(echo_rtt);
    f.latency = bench::summarize(timed.samples());
    f.walk = bench::summarize(
        std::vector<uint64_t>(walk_log.ns.begin(), walk_log.ns.begin() + walk_log.count.load()));

    // ---- the bare echo in a thread of its own (poll(), no runtime), after the slave stopped
    // ----------------
    runtime->request_stop();
    slave_thread.join();
    runtime.reset();
    std::atomic<bool> echo_stop{false};
    std::thread echo([&] {
        std::vector<uint8_t> buf(esc::kMaxFrameSize);
        while (!echo_stop.load(std::memory_order_relaxed)) {
            const std::size_t n = slave_link->receive(buf);
            if (n == 0) {
                pollfd p{slave_link->fd(), POLLIN, 0};
                (void)::poll(&p, 1, 10);
                continue;
            }
            if (n >= 12) buf[6] |= 0x02;  // as an ESC marks the frame processed
            slave_link->send(std::span<const uint8_t>(buf.data(), n));
        }
    });
    std::vector<uint64_t> thread_rtt;
    thread_rtt.reserve(cycles);
    uint64_t thread_missed = 0;
    run_cycles(pd, cycles, thread_rtt, thread_missed, [&](uint64_t) { fill(0); });
    echo_stop.store(true);
    echo.join();
    f.echo_thread = bench::summarize(thread_rtt);
    return f;
}

void usage() {
    std::fprintf(stderr,
                 "usage: bench-segment [--seconds S] [--drives N[,N...]] [--backend pcap|packet]\n"
                 "       bench-segment [--seconds S] (--mixed | --line KIND:COUNT[,...]...) [--esi-dir DIR]\n"
                 "                     KIND: coupler, io, drive (ESI examples), maxpos (built-in)\n");
}

// A line of the examples from SPEC ("coupler:1,io:60,drive:40"); throws std::runtime_error (a bad SPEC or an
// ESI that cannot be served).
// loaded: the products made so far (file/device -> product), shared by the lines of a run.
using Loaded = std::vector<std::pair<std::string, std::shared_ptr<const od::Product>>>;
Plan make_plan(const std::string& spec, const std::string& esi_dir, Loaded& loaded) {
    struct Kind {
        const char* name;
        std::vector<std::pair<const char*, const char*>> devices;  // file, device spec; cycled through
    };
    static const Kind kinds[] = {
        {"coupler", {{"coupler.xml", "EXK1100"}}},
        {"io",
         {{"digital-io.xml", "0x03f03052:0x00110000"},
          {"digital-io.xml", "EXD2008"},
          {"analog-in.xml", "EXA3104"}}},
        {"drive", {{"drive402.xml", "EXS7200-0010"}}},
        {"maxpos", {{nullptr, nullptr}}},
    };
    Plan plan;
    plan.label = spec;
    for (std::size_t pos = 0; pos < spec.size();) {
        const std::size_t comma = std::min(spec.find(',', pos), spec.size());
        const std::string item = spec.substr(pos, comma - pos);
        pos = comma + 1;
        const std::size_t colon = item.find(':');
        const std::string name = item.substr(0, colon);
        const unsigned long count =
            colon == std::string::npos ? 1 : std::strtoul(item.substr(colon + 1).c_str(), nullptr, 10);
        const Kind* kind = nullptr;
        for (const Kind& k : kinds)
            if (name == k.name) kind = &k;
        if (kind == nullptr || count == 0 || count > 1000)
            throw std::runtime_error("bad line item '" + item + "' in '" + spec + "'");
        for (unsigned long i = 0; i < count; ++i) {
            const auto& [file, device] = kind->devices[i % kind->devices.size()];
            std::shared_ptr<const od::Product> product;
            if (file != nullptr) {
                const std::string key = std::string(file) + "/" + device;
                for (const auto& [k, p] : loaded)
                    if (k == key) product = p;
                if (!product) {
                    product =
                        std::make_shared<const od::Product>(esi::load_product(esi_dir + "/" + file, device));
                    loaded.emplace_back(key, product);
                }
            }
            plan.names.push_back(name + std::to_string(i));
            plan.products.push_back(std::move(product));
        }
    }
    if (plan.products.empty() || plan.products.size() > 1000)
        throw std::runtime_error("a line of 1 to 1000 devices: '" + spec + "'");
    return plan;
}

void print_figures(const Figures& f) {
    const bool mixed = !f.label.empty();
    if (mixed)
        std::printf(
            "\nline %s: %zu devices (%zu without mailbox, %zu drives), %zu frame%s per cycle, %llu cycles\n"
            "  drives enabled in CSP %llu of %zu, faulted %llu, position actual followed the ramp "
            "%.3f..%.3f; "
            "slaves in OP at the end %zu of %zu\n",
            f.label.c_str(), f.devices, f.no_mailbox, f.drives, f.frames_per_cycle,
            f.frames_per_cycle == 1 ? "" : "s", static_cast<unsigned long long>(f.cycles),
            static_cast<unsigned long long>(f.enabled), f.drives, static_cast<unsigned long long>(f.faulted),
            f.followed_min, f.followed_max, f.in_op, f.devices);
    if (mixed && !f.not_op.empty())
        std::printf("  not in OP at the end (position:AL status/AL status code, the first 8):%s\n",
                    f.not_op.c_str());
    if (!mixed)
        std::printf("\n%zu drive%s (%zu frame%s per cycle), %llu cycles, %llu enabled in CSP\n", f.drives,
                    f.drives == 1 ? "" : "s", f.frames_per_cycle, f.frames_per_cycle == 1 ? "" : "s",
                    static_cast<unsigned long long>(f.cycles), static_cast<unsigned long long>(f.enabled));
    bench::print("  frame through segment", f.walk, "us", 1000.0);
    bench::print("  frame latency in slave", f.latency, "us", 1000.0);
    bench::print("  round trip, cyclic", f.rtt, "us", 1000.0);
    bench::print("  round trip, bare echo", f.echo, "us", 1000.0);
    bench::print("  round trip, echo thread", f.echo_thread, "us", 1000.0);
    bench::print_tail("  tail: latency in slave", f.latency);
    bench::print_tail("  tail: round trip, cyclic", f.rtt);
    std::printf(
        "  ratio cyclic/echo: median %.3f  p99 %.3f   (against the echo thread run after it: %.3f / "
        "%.3f)\n",
        f.rtt.median / std::max(1.0, f.echo.median), f.rtt.p99 / std::max(1.0, f.echo.p99),
        f.rtt.median / std::max(1.0, f.echo_thread.median), f.rtt.p99 / std::max(1.0, f.echo_thread.p99));
    if (mixed)
        std::printf(
            "  slave thread CPU: %.1f us per cycle (%.3f us per device) = %.1f %% of one core at 1 kHz\n",
            f.cpu_us_per_cycle, f.cpu_us_per_cycle / static_cast<double>(f.devices), f.cpu_percent);
    else
        std::printf(
            "  slave thread CPU: %.1f us per cycle (%.2f us per drive) = %.1f %% of one core at 1 kHz\n",
            f.cpu_us_per_cycle, f.cpu_us_per_cycle / static_cast<double>(f.drives), f.cpu_percent);
    std::printf(
        "  slave wake-ups per cycle %.2f, passes over the line per cycle %.2f, timer arms per cycle %.2f, "
        "frames per wake-up %.2f, replies per batch %.2f, awake waiting for deadlines %.1f us per cycle, "
        "device polls per cycle %.1f\n",
        f.wakeups_per_cycle, f.services_per_cycle, f.timer_arms_per_cycle, f.frames_per_wakeup,
        f.replies_per_batch, f.spin_us_per_cycle, f.polls_per_cycle);
    std::printf("  frames answered before the firmware's work or between devices: %llu\n",
                static_cast<unsigned long long>(f.frames_before_work));
    std::printf("  missed cycles %llu, lost frames %llu, wkc errors %llu, allocations per cycle %.3f\n",
                static_cast<unsigned long long>(f.missed), static_cast<unsigned long long>(f.lost),
                static_cast<unsigned long long>(f.wkc_errors), f.allocs_per_cycle);
}

}  // namespace

int main(int argc, char** argv) {
    double seconds = 5.0;
    std::vector<std::size_t> counts = {1, 10, 100};
    std::vector<std::string> lines;  // --line / --mixed
    std::string esi_dir = BENCH_ESI_EXAMPLES;
    std::string backend = esc::default_link_backend();
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto next = [&] { return bench::option_value(argc, argv, i, usage); };
        if (a == "--seconds") {
            seconds = std::max(0.1, std::atof(next().c_str()));
        } else if (a == "--drives") {
            counts.clear();
            const std::string list = next();
            for (std::size_t pos = 0; pos < list.size();) {
                const std::size_t comma = std::min(list.find(',', pos), list.size());
                const unsigned long n = std::strtoul(list.substr(pos, comma - pos).c_str(), nullptr, 10);
                if (n == 0 || n > 1000) {
                    usage();
                    return 2;
                }
                counts.push_back(n);
                pos = comma + 1;
            }
        } else if (a == "--line") {
            lines.push_back(next());
        } else if (a == "--mixed") {
            for (const char* l : {"coupler:1,io:3", "coupler:1,io:60", "coupler:1,io:60,drive:40",
                                  "coupler:1,io:60,maxpos:40"})
                lines.emplace_back(l);
        } else if (a == "--esi-dir") {
            esi_dir = next();
        } else if (a == "--backend") {
            backend = next();
        } else {
            usage();
            return 2;
        }
    }
    std::vector<Plan> plans;
    if (lines.empty()) {
        for (std::size_t n : counts)
            plans.push_back(Plan{{}, std::vector<std::shared_ptr<const od::Product>>(n), {}});
    } else {
        try {
            Loaded loaded;
            for (const std::string& l : lines)
                plans.push_back(make_plan(l, esi_dir, loaded));
        } catch (const std::exception& e) {
            std::fprintf(stderr, "bench-segment: %s\n", e.what());
            return 2;
        }
    }
    if (!bench::require_root("(network namespace, veth pair, raw sockets)")) return 2;
    if (!bench::enter_network_namespace()) return 2;
    if (lines.empty())
        std::printf(
            "bench-segment: %zu drive line(s), 1 kHz DC, CSP ramp, %.1f s per configuration, backend %s, %u "
            "CPUs\n",
            counts.size(), seconds, backend.c_str(), std::thread::hardware_concurrency());
    else
        std::printf(
            "bench-segment: %zu mixed line(s) from the ESIs of %s, 1 kHz DC, CSP ramp on the drives, %.1f s "
            "per line, backend %s, %u CPUs\n",
            lines.size(), esi_dir.c_str(), seconds, backend.c_str(), std::thread::hardware_concurrency());
    std::vector<Figures> all;
    std::vector<std::string> failed;  // mixed lines that did not run: what went wrong
    for (const Plan& plan : plans) {
        try {
            all.push_back(run_segment(plan, seconds, backend));
        } catch (const std::exception& e) {
            if (plan.label.empty()) {
                std::fprintf(stderr, "bench-segment: %zu drives: %s\n", plan.products.size(), e.what());
                return 1;
            }
            // A mixed line that does not come up is a figure too: say so and measure the next one.
            std::printf("\nline %s: not measured: %s\n", plan.label.c_str(), e.what());
            failed.push_back(plan.label + ": " + e.what());
            continue;
        }
        print_figures(all.back());
    }
    if (!lines.empty()) {
        std::printf("\n%-28s %-8s %-34s %-10s %-7s %-5s %-5s %-7s %-9s\n", "line", "devices",
                    "segment med/p99/p99.9/max us", "cpu %core", "missed", "lost", "wkc", "allocs",
                    "CSP/drives");
        for (const Figures& f : all)
            std::printf(
                "%-28s %-8zu %6.2f / %6.2f / %6.2f / %-8.2f %-10.1f %-7llu %-5llu %-5llu %-7.3f %llu/%zu\n",
                f.label.c_str(), f.devices, f.walk.median / 1000.0, f.walk.p99 / 1000.0, f.walk.p999 / 1000.0,
                f.walk.max / 1000.0, f.cpu_percent, static_cast<unsigned long long>(f.missed),
                static_cast<unsigned long long>(f.lost), static_cast<unsigned long long>(f.wkc_errors),
                f.allocs_per_cycle, static_cast<unsigned long long>(f.enabled), f.drives);
        for (const std::string& l : failed)
            std::printf("not measured: %s\n", l.c_str());
        // The cost of a device without drive: the smallest and the largest line of devices without drive
        // (a line without process data at all does not run: configure() has no LRW to make).
        const Figures* small = nullptr;
        const Figures* large = nullptr;
        for (const Figures& f : all)
            if (f.drives == 0) {
                if (small == nullptr || f.devices < small->devices) small = &f;
                if (large == nullptr || f.devices > large->devices) large = &f;
            }
        // The frames' walk per cycle (median per frame times frames per cycle), line a less line b, in us.
        auto walk_us = [](const Figures& a, const Figures& b) {
            return (a.walk.median * static_cast<double>(a.frames_per_cycle) -
                    b.walk.median * static_cast<double>(b.frames_per_cycle)) /
                   1000.0;
        };
        if (small != nullptr && large->devices > small->devices) {
            const double n = static_cast<double>(large->devices - small->devices);
            const double cpu = large->cpu_us_per_cycle - small->cpu_us_per_cycle;
            const double walk = walk_us(*large, *small);
            std::printf(
                "per device without drive (%s against %s): slave CPU %.3f us per cycle, of which the frame "
                "walk %.3f us (median) and outside the walk %.3f us; allocations per cycle %.3f (whole "
                "line)\n",
                large->label.c_str(), small->label.c_str(), cpu / n, walk / n, (cpu - walk) / n,
                large->allocs_per_cycle);
        }
        return 0;
    }
    std::printf("\n%-7s %-22s %-10s %-8s %-22s %-8s\n", "drives", "segment med/p99 us", "cpu %core", "missed",
                "rtt ratio med/p99", "allocs");
    for (const Figures& f : all)
        std::printf("%-7zu %8.2f / %-11.2f %-10.1f %-8llu %8.3f / %-11.3f %-8.3f\n", f.drives,
                    f.walk.median / 1000.0, f.walk.p99 / 1000.0, f.cpu_percent,
                    static_cast<unsigned long long>(f.missed), f.rtt.median / std::max(1.0, f.echo.median),
                    f.rtt.p99 / std::max(1.0, f.echo.p99), f.allocs_per_cycle);
    return 0;
}
