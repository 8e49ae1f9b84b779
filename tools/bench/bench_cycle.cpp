// bench-cycle: process data in step with the master. For each cycle time (default 1 ms, 250 us, 125 us)
// it starts the real ecat-slave on one end of a veth pair, brings it to OP with distributed clocks as SOEM
// and TwinCAT do (clock offset, SYNC0 on the cycle grid 100 ms ahead, sync mode 2), then runs the cyclic
// exchange for --seconds: one frame per cycle with the LRW of the process data and an FRMW of the reference
// clock's system time (0x0910), sent from an absolute-time clock_nanosleep loop whose phase is steered so
// that the frame passes the slave half a cycle away from SYNC0 (SOEM's ec_sync() idea).
//
// Master side it counts lost replies, working-counter errors, late replies (back after the next cycle
// should have started) and missed cycles (the loop woke a whole period or more late); slave side it reads
// the stack's statistics that ecat-slave writes at exit (--stats-file): SYNC0 periods without a cycle,
// SYNC0 without new outputs, and the lateness of the application cycle after its SYNC0 pulse measured
// against the DC system time (p50 / p99 / max). Prints one table; asserts nothing.
//
// Everything lives in a private network namespace (unshare) that disappears with this process; the slave
// is killed with us (PR_SET_PDEATHSIG); the temporary state directory is removed. Needs root.
#include <sched.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "ecat/latency.hpp"
#include "esc/link.hpp"
#include "harness.hpp"
#include "master/coe.hpp"
#include "master/mailbox.hpp"
#include "master/master.hpp"
#include "master/session.hpp"
#include "slave/netif.hpp"
#include "util/strfmt.hpp"

namespace {

using master::Address;
using master::Error;

constexpr const char* kSlaveEnd = "cyc-s0";
constexpr const char* kMasterEnd = "cyc-m0";
constexpr uint16_t kStation = 0x1001;

std::atomic<bool> g_stop{false};
void on_signal(int) {
    g_stop.store(true);
}

// Sleeps until t - spin_ns, then spins on the clock until t (spin_ns 0: sleeps all the way).
void sleep_until_ns(uint64_t t, uint64_t spin_ns) {
    const uint64_t wake = t > spin_ns ? t - spin_ns : 0;
    timespec ts{};
    ts.tv_sec = static_cast<time_t>(wake / 1'000'000'000ull);
    ts.tv_nsec = static_cast<long>(wake % 1'000'000'000ull);
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
        if (g_stop.load()) return;
    }
    while (spin_ns != 0 && bench::now_ns() < t) {
    }
}

struct Options {
    unsigned seconds = 60;
    std::vector<unsigned> cycles_us{1000, 250, 125};
    std::string slave_path = BENCH_ECAT_SLAVE_PATH;
    std::string backend;
    int rt_priority = 80;  // 0: no SCHED_FIFO
    int master_cpu = 0;    // -1: not pinned
    int slave_cpu = 1;
    unsigned phase_percent = 50;    // where in the cycle (after SYNC0) the frame passes the slave
    unsigned master_spin_us = 0;    // the master loop wakes this early and spins to its deadline
    bool master_busy_poll = false;  // the master waits for replies by polling, not in ppoll()
    unsigned slave_spin_us = 0;     // ecat-slave --spin-us
    bool slave_busy_poll = false;   // ecat-slave --busy-poll
    bool rt_throttle_off = false;   // kernel.sched_rt_runtime_us = -1 for the run (restored at the end)
    unsigned probe_seconds = 10;    // platform stall probe before the runs (0: none)
    bool sm_sync = false;           // SM-synchronous (0x1C32:01 = 1) instead of DC SYNC0
    bool verbose = false;
    std::string keep_logs;  // copy the slave logs here
};

// The platform's floor, measured in the same run just before each cycle time: a thread pinned to each CPU
// the benchmark uses, at the benchmark's priority, spins on CLOCK_MONOTONIC (90 % of the time, in 18 ms
// chunks) and records every gap between two consecutive reads. Nothing else in the guest runs at that
// priority on those CPUs, so a long gap is the vCPU not running (the host preempted it) or an interrupt.
// Every cycle boundary that falls into such a gap is a cycle no software in the guest could have kept:
// `periods` counts them (gap / cycle, all CPUs together).
struct StallProbe {
    unsigned seconds = 0;
    uint64_t periods = 0;    // cycle periods inside gaps, all CPUs
    uint64_t over_20us = 0;  // gaps over 20 us
    uint64_t longest_ns = 0;
};

StallProbe probe_stalls(const Options& o, unsigned cycle_us) {
    StallProbe r;
    r.seconds = o.probe_seconds;
    if (o.probe_seconds == 0) return r;
    std::vector<int> cpus;
    for (int c : {o.master_cpu, o.slave_cpu})
        if (std::find(cpus.begin(), cpus.end(), c) == cpus.end()) cpus.push_back(c);
    std::vector<StallProbe> per(cpus.size());
    std::vector<std::thread> threads;
    const uint64_t period = cycle_us * 1000ull;
    const uint64_t end = bench::now_ns() + o.probe_seconds * 1'000'000'000ull;
    for (std::size_t i = 0; i < cpus.size(); ++i) {
        threads.emplace_back([&p = per[i], cpu = cpus[i], end, period] {
            if (cpu >= 0) {
                cpu_set_t set;
                CPU_ZERO(&set);
                CPU_SET(cpu, &set);
                (void)::pthread_setaffinity_np(pthread_self(), sizeof set, &set);
            }
            // Spins 18 ms, then sleeps 2 ms (not counted): a SCHED_FIFO loop that never sleeps would be
            // stopped for 50 ms in every second by the kernel's RT throttling, which is not the platform.
            constexpr uint64_t kSpinNs = 18'000'000;
            constexpr timespec kPause{0, 2'000'000};
            uint64_t last = bench::now_ns();
            uint64_t chunk_end = last + kSpinNs;
            while (last < end && !g_stop.load(std::memory_order_relaxed)) {
                uint64_t t = bench::now_ns();
                if (t >= chunk_end) {
                    ::nanosleep(&kPause, nullptr);
                    t = bench::now_ns();
                    last = t;
                    chunk_end = t + kSpinNs;
                }
                const uint64_t gap = t - last;
                last = t;
                if (gap < 20'000) continue;
                ++p.over_20us;
                p.longest_ns = std::max(p.longest_ns, gap);
                p.periods += gap / period;
            }
        });
    }
    for (auto& t : threads)
        t.join();
    for (const StallProbe& p : per) {
        r.periods += p.periods;
        r.over_20us += p.over_20us;
        r.longest_ns = std::max(r.longest_ns, p.longest_ns);
    }
    return r;
}

// Steal time of the benchmark's CPUs (/proc/stat, 8th value of each cpuN line): the time the hypervisor ran
// something else while these vCPUs wanted to run. Milliseconds, summed over the CPUs; -1 if unknown.
int64_t steal_ms(const Options& o) {
    std::ifstream in("/proc/stat");
    std::string line;
    const long hz = ::sysconf(_SC_CLK_TCK);
    int64_t total = 0;
    bool found = false;
    while (std::getline(in, line)) {
        if (line.rfind("cpu", 0) != 0 || line.size() < 4 || line[3] < '0' || line[3] > '9') continue;
        std::istringstream ls(line.substr(3));
        int cpu = -1;
        unsigned long long v[8] = {};
        if (!(ls >> cpu)) continue;
        for (auto& x : v)
            ls >> x;
        if (!ls || (cpu != o.master_cpu && cpu != o.slave_cpu)) continue;
        total += static_cast<int64_t>(v[7]);
        found = true;
    }
    if (!found || hz <= 0) return -1;
    return total * 1000 / hz;
}

// kernel.sched_rt_runtime_us = -1 while it lives, the previous value afterwards. A busy-polling SCHED_FIFO
// task on each CPU would otherwise be stopped for 50 ms of every second by the kernel's real-time throttling.
class RtThrottleOff {
  public:
    RtThrottleOff() {
        std::ifstream in(kPath);
        if (!(in >> saved_)) return;
        std::ofstream out(kPath);
        active_ = static_cast<bool>(out << -1 << '\n') && static_cast<bool>(out.flush());
    }
    ~RtThrottleOff() {
        if (!active_) return;
        std::ofstream out(kPath);
        out << saved_ << '\n';
    }
    RtThrottleOff(const RtThrottleOff&) = delete;
    RtThrottleOff& operator=(const RtThrottleOff&) = delete;
    bool active() const { return active_; }
    long saved() const { return saved_; }

  private:
    static constexpr const char* kPath = "/proc/sys/kernel/sched_rt_runtime_us";
    long saved_ = 0;
    bool active_ = false;
};

// "stack.cycles 123" lines of the slave's --stats-file (or of its --verbose output).
std::map<std::string, uint64_t> read_figures(const std::string& log) {
    std::map<std::string, uint64_t> m;
    std::ifstream in(log);
    std::string line;
    while (std::getline(in, line)) {
        if (line.rfind("stack.", 0) != 0 && line.rfind("runtime.", 0) != 0) continue;
        std::istringstream ls(line);
        std::string key;
        unsigned long long v = 0;
        if (ls >> key >> v) m[key] = v;
    }
    return m;
}

struct Result {
    unsigned cycle_us = 0;
    bool ok = false;  // reached OP and ran
    std::string failure;
    // Master side.
    uint64_t cycles = 0, lost = 0, wkc_errors = 0, late = 0, missed = 0;
    ecat::LatencyHistogram wake;   // clock_nanosleep wake-up lateness
    ecat::LatencyHistogram rtt;    // send to matched reply
    ecat::LatencyHistogram phase;  // |frame at the slave - target phase| (DC time, from the FRMW)
    std::string end_state;
    StallProbe probe;       // the platform just before this run
    uint64_t steal_ms = 0;  // time the host took from the benchmark's CPUs during the measured window
    bool steal_known = false;
    // Slave side (the stack.* lines of its --stats-file).
    std::map<std::string, uint64_t> slave;
};

std::string state_text(master::Master& m, Address a) {
    auto st = m.al_status(a);
    if (!st) return std::string("? (") + std::string(master::to_string(st.error())) + ")";
    std::string s(master::al_state_name(st->state));
    if (st->error) {
        s += util::strprintf("+ERR 0x%04x", st->code);
    }
    return s;
}

// Brings the slave to OP with DC and runs the measured loop. Fills r; throws on setup failures.
void run_master(const Options& o, unsigned cycle_us, Result& r) {
    auto link = esc::open_link(kMasterEnd, o.backend);
    master::MasterOptions mo;
    mo.timeout = std::chrono::milliseconds(100);
    mo.retries = 0;
    mo.busy_poll = o.master_busy_poll;
    master::Master m(*link, mo);
    // The slave needs a moment to open its end.
    uint16_t n = 0;
    for (int i = 0; i < 100 && n == 0 && !g_stop.load(); ++i) {
        auto c = m.count_slaves();
        if (c) n = *c;
        if (n == 0) std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    if (n == 0) throw std::runtime_error("the slave does not answer");
    m.set_timeout(std::chrono::milliseconds(100));
    auto check = [](Error e, const char* what) {
        if (e != Error::Ok)
            throw std::runtime_error(std::string(what) + ": " + std::string(master::to_string(e)));
    };
    check(m.assign_station_addresses(n), "assigning station addresses");
    const Address a = Address::station(kStation);
    master::Mailbox mbx(m, a);
    check(mbx.configure_from_sii(), "mailbox from SII");
    master::AlStatus final{};
    if (Error e = m.request_state(a, master::AlState::PreOp, &final); e != Error::Ok) {
        throw std::runtime_error("INIT -> PREOP: " + std::string(master::to_string(e)) +
                                 util::strprintf(" (AL status code 0x%04x)", final.code));
    }
    master::SdoClient sdo(mbx);
    master::ProcessDataSession pd(m, a, sdo);
    check(pd.discover(), "reading the process-data layout");
    master::DcConfig dc;
    dc.enable = !o.sm_sync;
    dc.cycle_ns = cycle_us * 1000u;
    check(pd.configure(dc), "configuring process data and DC");
    const auto period = std::chrono::microseconds(cycle_us);
    if (Error e = pd.request_state(master::AlState::SafeOp, period, &final); e != Error::Ok) {
        throw std::runtime_error(util::strprintf("requesting SAFEOP: %s (AL status code 0x%04x)",
                                                 std::string(master::to_string(e)).c_str(), final.code));
    }

    // The cyclic loop: first the phase is locked (Safe-Op), then OP is requested between cycles (as masters
    // do, the frames keep their phase), then the measured cycles. A reply that is not back within one period
    // counts as lost.
    m.set_timeout(period);
    const uint64_t p = cycle_us * 1000ull;
    const uint64_t target_phase = p * o.phase_percent / 100;
    const uint64_t total = static_cast<uint64_t>(o.seconds) * 1'000'000'000ull / p;
    constexpr uint64_t kLock = 200;  // cycles to lock the phase before asking for OP
    const uint64_t status_every = std::max<uint64_t>(1, 5'000'000 / p);  // AL status polls while waiting
    const uint64_t op_deadline = bench::now_ns() + 10'000'000'000ull;
    uint64_t counting_from = UINT64_MAX;
    int64_t steal_at_start = -1;
    uint64_t t = bench::now_ns() + p;
    for (uint64_t i = 0; !g_stop.load(); ++i) {
        if (counting_from != UINT64_MAX && i >= counting_from + total) break;
        const bool counted = i >= counting_from;
        sleep_until_ns(t, std::min<uint64_t>(o.master_spin_us * 1000ull, p));
        const uint64_t woke = bench::now_ns();
        const uint64_t late_by = woke > t ? woke - t : 0;
        if (counted) r.wake.add(late_by);
        if (late_by >= p) {
            // Whole periods slept through: those cycles are gone; continue on the grid.
            const uint64_t skipped = late_by / p;
            if (counted) r.missed += skipped;
            t += skipped * p;
        }
        const uint64_t sent = bench::now_ns();
        const Error e = pd.cycle();
        const uint64_t done = bench::now_ns();
        if (counted) {
            ++r.cycles;
            if (e == Error::Timeout) {
                ++r.lost;
            } else {
                r.rtt.add(done - sent);
                if (e == Error::WorkingCounter) ++r.wkc_errors;
                if (done > t + p) ++r.late;
            }
        }
        // Phase control on the DC time the FRMW brought back: where in the SYNC0 cycle the frame passed.
        int64_t correction = 0;
        if (!o.sm_sync && e != Error::Timeout && e != Error::SendFailed) {
            int64_t delta = static_cast<int64_t>((pd.reference_time() + p - target_phase) % p);
            if (delta > static_cast<int64_t>(p / 2)) delta -= static_cast<int64_t>(p);
            if (counted) r.phase.add(static_cast<uint64_t>(delta < 0 ? -delta : delta));
            // Jump once the first replies are in, then a gentle proportional pull (both clocks are the same
            // oscillator here, so only the wake-up noise is left to average out).
            correction = i == 20 ? -delta : -delta / 32;
        }
        t = static_cast<uint64_t>(static_cast<int64_t>(t + p) + correction);
        if (counting_from != UINT64_MAX) continue;
        if (i == kLock) {
            if (Error e2 = m.write_reg<uint16_t>(a, master::reg::AlControl,
                                                 static_cast<uint8_t>(master::AlState::Op));
                e2 != Error::Ok)
                throw std::runtime_error("requesting OP: " + std::string(master::to_string(e2)));
        } else if (i > kLock && (i - kLock) % status_every == 0) {
            auto st = m.al_status(a);
            if (st && st->error) {
                throw std::runtime_error(
                    util::strprintf("OP refused: AL status code 0x%04x (%s)", st->code,
                                    std::string(master::al_status_code_name(st->code)).c_str()));
            }
            if (st && st->state == static_cast<uint8_t>(master::AlState::Op)) {
                counting_from = i + 1;
                steal_at_start = steal_ms(o);
            }
            if (bench::now_ns() > op_deadline) throw std::runtime_error("OP not reached within 10 s");
        }
    }
    m.set_timeout(std::chrono::milliseconds(100));
    const int64_t steal_at_end = steal_ms(o);
    if (steal_at_start >= 0 && steal_at_end >= steal_at_start) {
        r.steal_ms = static_cast<uint64_t>(steal_at_end - steal_at_start);
        r.steal_known = true;
    }
    r.end_state = state_text(m, a);
    (void)m.request_state(a, master::AlState::Init);
    r.ok = !g_stop.load();
}

Result run_one(const Options& o, unsigned cycle_us, const std::filesystem::path& dir) {
    Result r;
    r.cycle_us = cycle_us;
    const std::string log = (dir / ("slave-" + std::to_string(cycle_us) + "us.log")).string();
    const std::string stats = (dir / ("slave-" + std::to_string(cycle_us) + "us.stats")).string();
    std::vector<std::string> args = {o.slave_path, "--verbose", "--stats-file", stats,
                                     "--iface",    kSlaveEnd,   "--state-dir",  (dir / "state").string()};
    if (!o.backend.empty()) args.insert(args.end(), {"--backend", o.backend});
    if (o.rt_priority > 0) args.insert(args.end(), {"--rt-priority", std::to_string(o.rt_priority)});
    if (o.slave_cpu >= 0) args.insert(args.end(), {"--cpu", std::to_string(o.slave_cpu)});
    if (o.slave_spin_us > 0) args.insert(args.end(), {"--spin-us", std::to_string(o.slave_spin_us)});
    if (o.slave_busy_poll) args.push_back("--busy-poll");
    if (o.probe_seconds > 0)
        std::fprintf(stderr, "bench-cycle: platform stall probe for %u s ...\n", o.probe_seconds);
    r.probe = probe_stalls(o, cycle_us);
    {
        bench::Child slave(args, log);
        try {
            run_master(o, cycle_us, r);
        } catch (const std::exception& e) {
            r.failure = e.what();
        }
        if (!slave.alive())
            r.failure += (r.failure.empty() ? "" : "; ") + std::string("ecat-slave exited early");
        const int status = slave.stop();
        if (status != -1 && !(WIFEXITED(status) && WEXITSTATUS(status) == 0))
            r.failure += (r.failure.empty() ? "" : "; ") + std::string("ecat-slave did not exit cleanly");
    }
    r.slave = read_figures(std::filesystem::exists(stats) ? stats : log);
    if (!r.failure.empty() || o.verbose) {
        std::ifstream in(log);
        std::fprintf(stderr, "---- ecat-slave log (%u us) ----\n%s", cycle_us,
                     std::string(std::istreambuf_iterator<char>(in), {}).c_str());
    }
    if (!o.keep_logs.empty()) {
        std::error_code ec;
        std::filesystem::create_directories(o.keep_logs, ec);
        std::filesystem::copy_file(log,
                                   std::filesystem::path(o.keep_logs) / std::filesystem::path(log).filename(),
                                   std::filesystem::copy_options::overwrite_existing, ec);
    }
    return r;
}

double us(uint64_t ns) {
    return static_cast<double>(ns) / 1000.0;
}

std::string slave_figure(const Result& r, const std::string& key, bool in_us) {
    auto it = r.slave.find("stack." + key);
    if (it == r.slave.end()) return "n/a";
    char b[32];
    if (in_us)
        std::snprintf(b, sizeof b, "%.1f", us(it->second));
    else
        std::snprintf(b, sizeof b, "%llu", static_cast<unsigned long long>(it->second));
    return b;
}

void print_table(const Options& o, const std::vector<Result>& results, const std::string& sched) {
    std::printf("\nbench-cycle: %u s per cycle time, backend %s, %s; ", o.seconds,
                o.backend.empty() ? esc::default_link_backend() : o.backend.c_str(), sched.c_str());
    if (o.sm_sync)
        std::printf("SM-synchronous: the application cycle runs on each SM2 write\n");
    else
        std::printf("DC: frame at %u%% of the cycle after SYNC0\n", o.phase_percent);
    const std::string lat = o.sm_sync ? "sm2_latency" : "sync0_latency";
    std::printf("%-7s | %-9s %5s %5s %5s %6s | %-9s %8s %8s | %-22s | %-22s | %-16s | %s\n", "", "master",
                "lost", "wkc", "late", "missed", "slave", "exceeded", "no-outp",
                o.sm_sync ? "frame->cycle us" : "SYNC0->cycle us", "master wake us", "rtt us", "floor");
    std::printf("%-7s | %-9s %5s %5s %5s %6s | %-9s %8s %8s | %6s %7s %7s | %6s %7s %7s | %7s %8s | %s\n",
                "cycle", "cycles", "", "err", "", "", "cycles", "", "", "p50", "p99", "max", "p50", "p99",
                "max", "p50", "p99", "stalls");
    for (std::size_t i = 0; i < results.size(); ++i) {
        const Result& r = results[i];
        // The probe's lost periods scaled to the measured time: cycles no software could have kept.
        std::string floor = "-";
        if (r.probe.seconds > 0) {
            char b[32];
            std::snprintf(b, sizeof b, "%.0f",
                          static_cast<double>(r.probe.periods) * o.seconds / r.probe.seconds);
            floor = b;
        }
        std::printf(
            "%4u us | %-9llu %5llu %5llu %5llu %6llu | %-9s %8s %8s | %6s %7s %7s | %6.1f %7.1f %7.1f | "
            "%7.1f %8.1f | %6s\n",
            r.cycle_us, static_cast<unsigned long long>(r.cycles), static_cast<unsigned long long>(r.lost),
            static_cast<unsigned long long>(r.wkc_errors), static_cast<unsigned long long>(r.late),
            static_cast<unsigned long long>(r.missed), slave_figure(r, "cycles", false).c_str(),
            slave_figure(r, "cycles_exceeded", false).c_str(),
            slave_figure(r, "sm_events_missed", false).c_str(),
            slave_figure(r, lat + ".p50_ns", true).c_str(), slave_figure(r, lat + ".p99_ns", true).c_str(),
            slave_figure(r, lat + ".max_ns", true).c_str(), us(r.wake.percentile_ns(0.5)),
            us(r.wake.percentile_ns(0.99)), us(r.wake.max_ns()), us(r.rtt.percentile_ns(0.5)),
            us(r.rtt.percentile_ns(0.99)), floor.c_str());
    }
    std::printf(
        "lost: no reply within one cycle; late: reply after the next cycle was due; missed: cycles the "
        "master "
        "slept through;\nexceeded: SYNC0 periods without a slave cycle; no-outp: SYNC0 without new outputs "
        "(sm_events_missed);\nSYNC0->cycle: DC system time at the start of the slave's application cycle "
        "minus "
        "its SYNC0 pulse;\nframe->cycle (--sm-sync): from the start of the frame that wrote SM2 (0x09F0) to "
        "the start of "
        "the application cycle, slave local time;\nfloor stalls: cycle periods inside the gaps of a busy "
        "loop on each CPU (platform "
        "probe "
        "just before the run), scaled to the measured time.\n");
    for (const Result& r : results) {
        std::printf("%4u us: end state %s", r.cycle_us, r.end_state.empty() ? "?" : r.end_state.c_str());
        if (!o.sm_sync)
            std::printf(", phase error p99 %.1f us (max %.1f)", us(r.phase.percentile_ns(0.99)),
                        us(r.phase.max_ns()));
        if (r.steal_known)
            std::printf(", host steal on the two CPUs %llu ms (%.2f %%)",
                        static_cast<unsigned long long>(r.steal_ms),
                        100.0 * static_cast<double>(r.steal_ms) /
                            (o.seconds * 1000.0 * (o.master_cpu == o.slave_cpu ? 1 : 2)));
        if (r.probe.seconds > 0)
            std::printf(", platform probe %u s: %llu gaps over 20 us, longest %.1f us", r.probe.seconds,
                        static_cast<unsigned long long>(r.probe.over_20us), us(r.probe.longest_ns));
        auto gaps = r.slave.find("runtime.loop_gaps_over_50us");
        if (gaps != r.slave.end() && (o.slave_busy_poll || o.slave_spin_us > 0))
            std::printf(
                ", slave's busy loop kept from running %llu times over 50 us, %llu over 1 ms, longest %.1f "
                "us",
                static_cast<unsigned long long>(gaps->second),
                static_cast<unsigned long long>(r.slave.at("runtime.loop_gaps_over_1ms")),
                us(r.slave.at("runtime.loop_gap_max_ns")));
        if (!r.failure.empty()) std::printf(", FAILED: %s", r.failure.c_str());
        if (r.slave.empty()) std::printf(", no slave figures (ecat-slave printed no stack.* lines)");
        std::printf("\n");
    }
}

void usage() {
    std::fprintf(
        stderr,
        "usage: bench-cycle [--seconds N] [--cycles-us LIST] [--slave PATH] [--backend pcap|packet]\n"
        "                   [--rt-priority N | --no-rt] [--master-cpu N] [--slave-cpu N] "
        "[--phase PERCENT]\n"
        "                   [--master-spin-us N] [--master-busy-poll] [--slave-spin-us N | "
        "--slave-busy-poll]\n"
        "                   [--spin] [--no-rt-throttle] [--probe-seconds N] [--sm-sync] [--keep-logs DIR] "
        "[--verbose]\n"
        "  --seconds N        measured time per cycle time (default 60; 5 is a quick check)\n"
        "  --slave PATH       the slave program (default: the ecat-slave of this build)\n"
        "  --cycles-us LIST   cycle times in microseconds (default 1000,250,125)\n"
        "  --rt-priority N    SCHED_FIFO priority of master and slave (default 80), --no-rt: none\n"
        "  --master-cpu/--slave-cpu N  pin to a CPU (default 0 / 1; -1: not pinned)\n"
        "  --phase PERCENT    where the frame passes the slave, in %% of the cycle after SYNC0 (50)\n"
        "  --master-spin-us N the master wakes N us early and spins to its deadline (default 0; a cycle or\n"
        "                     more: it never sleeps)\n"
        "  --master-busy-poll the master polls for its replies instead of sleeping in ppoll()\n"
        "  --slave-spin-us N  ecat-slave --spin-us N: the slave wakes N us before SYNC0 and spins to it\n"
        "  --slave-busy-poll  ecat-slave --busy-poll: the slave never sleeps\n"
        "  --no-rt-throttle   kernel.sched_rt_runtime_us = -1 for the run, restored afterwards (busy loops\n"
        "                     at SCHED_FIFO are otherwise stopped 50 ms in every second)\n"
        "  --spin             all of it: neither side ever sleeps (--master-spin-us 1000000\n"
        "                     --master-busy-poll --slave-busy-poll --no-rt-throttle)\n"
        "  --sm-sync          SM-synchronous instead of DC: the slave's cycle runs on each SM2 write\n"
        "  --probe-seconds N  platform stall probe before each cycle time (default 10, 0: none)\n"
        "  default: both sides sleep on timers and in poll, as a plain SOEM loop and ecat-slave do\n");
}

bool parse_list(const std::string& s, std::vector<unsigned>& out) {
    out.clear();
    std::stringstream ss(s);
    std::string item;
    while (std::getline(ss, item, ',')) {
        char* end = nullptr;
        const unsigned long v = std::strtoul(item.c_str(), &end, 10);
        if (item.empty() || *end != '\0' || v < 20 || v > 1'000'000) return false;
        out.push_back(static_cast<unsigned>(v));
    }
    return !out.empty();
}

}  // namespace

int main(int argc, char** argv) {
    Options o;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto next = [&] { return bench::option_value(argc, argv, i, usage); };
        auto number = [&](long lo, long hi) -> long {
            const std::string v = next();
            char* end = nullptr;
            const long n = std::strtol(v.c_str(), &end, 10);
            if (v.empty() || *end != '\0' || n < lo || n > hi) {
                std::fprintf(stderr, "bench-cycle: bad value '%s' for %s\n", v.c_str(), a.c_str());
                std::exit(2);
            }
            return n;
        };
        if (a == "--seconds") {
            o.seconds = static_cast<unsigned>(number(1, 86400));
        } else if (a == "--cycles-us") {
            if (!parse_list(next(), o.cycles_us)) {
                std::fprintf(stderr,
                             "bench-cycle: --cycles-us wants a list like 1000,250,125 (20..1000000)\n");
                return 2;
            }
        } else if (a == "--slave") {
            o.slave_path = next();
        } else if (a == "--backend") {
            o.backend = next();
        } else if (a == "--rt-priority") {
            o.rt_priority = static_cast<int>(number(1, 99));
        } else if (a == "--no-rt") {
            o.rt_priority = 0;
        } else if (a == "--master-cpu") {
            o.master_cpu = static_cast<int>(number(-1, 1023));
        } else if (a == "--slave-cpu") {
            o.slave_cpu = static_cast<int>(number(-1, 1023));
        } else if (a == "--master-spin-us") {
            o.master_spin_us = static_cast<unsigned>(number(0, 1'000'000));
        } else if (a == "--master-busy-poll") {
            o.master_busy_poll = true;
        } else if (a == "--slave-spin-us") {
            o.slave_spin_us = static_cast<unsigned>(number(1, 100'000));
        } else if (a == "--slave-busy-poll") {
            o.slave_busy_poll = true;
        } else if (a == "--spin") {
            o.master_spin_us = 1'000'000;
            o.master_busy_poll = true;
            o.slave_busy_poll = true;
            o.rt_throttle_off = true;
        } else if (a == "--sm-sync") {
            o.sm_sync = true;
        } else if (a == "--no-rt-throttle") {
            o.rt_throttle_off = true;
        } else if (a == "--probe-seconds") {
            o.probe_seconds = static_cast<unsigned>(number(0, 3600));
        } else if (a == "--phase") {
            o.phase_percent = static_cast<unsigned>(number(0, 99));
        } else if (a == "--keep-logs") {
            o.keep_logs = next();
        } else if (a == "--verbose") {
            o.verbose = true;
        } else if (a == "--help" || a == "-h") {
            usage();
            return 0;
        } else {
            usage();
            return 2;
        }
    }
    if (!bench::require_root("(network namespace, veth pair, raw sockets, SCHED_FIFO); run it with sudo"))
        return 2;
    if (::access(o.slave_path.c_str(), X_OK) != 0) {
        std::fprintf(stderr, "bench-cycle: cannot run the slave %s\n", o.slave_path.c_str());
        return 2;
    }
    const long cpus = ::sysconf(_SC_NPROCESSORS_ONLN);
    if (o.master_cpu >= cpus) o.master_cpu = -1;
    if (o.slave_cpu >= cpus) o.slave_cpu = -1;
    if (!bench::enter_network_namespace()) return 2;
    struct sigaction sa {};
    sa.sa_handler = on_signal;
    ::sigaction(SIGINT, &sa, nullptr);
    ::sigaction(SIGTERM, &sa, nullptr);

    // The master's own scheduling; if SCHED_FIFO is refused, neither side gets it (a fair comparison).
    std::string sched = "SCHED_OTHER";
    if (o.master_cpu >= 0) {
        cpu_set_t set;
        CPU_ZERO(&set);
        CPU_SET(o.master_cpu, &set);
        if (::sched_setaffinity(0, sizeof set, &set) != 0) o.master_cpu = -1;
    }
    if (o.rt_priority > 0) {
        sched_param sp{};
        sp.sched_priority = o.rt_priority;
        if (::sched_setscheduler(0, SCHED_FIFO, &sp) != 0) {
            std::fprintf(stderr, "bench-cycle: SCHED_FIFO refused (%s); running without real-time priority\n",
                         std::strerror(errno));
            o.rt_priority = 0;
        } else {
            (void)::mlockall(MCL_CURRENT | MCL_FUTURE);
            sched = "SCHED_FIFO " + std::to_string(o.rt_priority);
        }
    }
    sched += ", master CPU " + (o.master_cpu >= 0 ? std::to_string(o.master_cpu) : std::string("any")) +
             ", slave CPU " + (o.slave_cpu >= 0 ? std::to_string(o.slave_cpu) : std::string("any"));
    if (o.master_spin_us > 0) sched += ", master spins the last " + std::to_string(o.master_spin_us) + " us";
    if (o.master_busy_poll) sched += ", master busy-polls for replies";
    if (o.slave_spin_us > 0) sched += ", slave --spin-us " + std::to_string(o.slave_spin_us);
    if (o.slave_busy_poll) sched += ", slave --busy-poll";
    if (o.slave_spin_us > 0 && o.slave_busy_poll) {
        std::fprintf(stderr, "bench-cycle: --slave-spin-us and --slave-busy-poll exclude each other\n");
        return 2;
    }

    std::unique_ptr<RtThrottleOff> throttle;
    if (o.rt_throttle_off && o.rt_priority > 0) {
        throttle = std::make_unique<RtThrottleOff>();
        if (throttle->active())
            sched += ", RT throttling off (kernel.sched_rt_runtime_us -1, restored to " +
                     std::to_string(throttle->saved()) + ")";
        else
            std::fprintf(stderr, "bench-cycle: could not switch RT throttling off; busy loops will stall\n");
    }

    int rc = 0;
    try {
        const bench::TempDir tmp("bench-cycle");
        const std::filesystem::path& dir = tmp.path();
        slave::VethPair pair(kSlaveEnd, kMasterEnd);
        std::vector<Result> results;
        for (unsigned c : o.cycles_us) {
            if (g_stop.load()) break;
            std::fprintf(stderr, "bench-cycle: %u us for %u s ...\n", c, o.seconds);
            results.push_back(run_one(o, c, dir));
            if (!results.back().ok || !results.back().failure.empty()) rc = 1;
        }
        print_table(o, results, sched);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench-cycle: %s\n", e.what());
        rc = 1;
    }
    return rc;
}
