// bench-foe: firmware download through the real ecat-slave over a veth pair, as a master sees it.
//
//  1. FoE write throughput for each bootstrap mailbox size (default 1024 bytes, the seed's layout, and 1486,
//     the largest mailbox a master can write in one datagram): the slave gets a device configuration file
//     with that [bootstrap_mailbox]; the master goes INIT -> BOOT with the bootstrap mailbox from the SII and
//     writes a valid image of --bytes. Reported per run: the data phase (write request to the moment the last
//     DATA is answered BUSY, i.e. everything sent and the slave storing), the commit (BUSY until the final
//     ACK: fsync, rename, read-back, pointer switch) and the whole write; MB/s = image bytes / time (10^6
//     bytes per s).
//  2. The time of a whole firmware update of a --update-bytes image (default 1 MiB) with the default mailbox:
//     `ecatctl firmware-update` (identity check, BOOT, write, INIT, restart, revision checked in SII,
//     0x1018:03 and 0x100A) run as a program and timed from start to exit, with its own step times.
//
// Everything lives in a private network namespace (unshare) that disappears with this process; the slave is
// killed with us (PR_SET_PDEATHSIG); the temporary state directories are removed. Needs root. Prints figures;
// asserts nothing (a failed step is reported and the exit code is 1).
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "esc/link.hpp"
#include "foe/image.hpp"
#include "harness.hpp"
#include "master/foe.hpp"
#include "master/mailbox.hpp"
#include "master/master.hpp"
#include "slave/netif.hpp"
#include "util/le.hpp"
#include "util/strfmt.hpp"

namespace {

using bench::Child;
using master::Address;
using master::AlState;
using master::Error;
using Clock = std::chrono::steady_clock;

constexpr const char* kSlaveEnd = "foe-s0";
constexpr const char* kMasterEnd = "foe-m0";
const Address kSlave = Address::position(0);

struct Options {
    std::vector<unsigned> mailbox_sizes{1024, 1486};
    std::size_t bytes = 4u << 20;
    unsigned runs = 5;
    std::size_t update_bytes = 1u << 20;
    unsigned update_runs = 5;
    std::string slave_path = BENCH_ECAT_SLAVE_PATH;
    std::string ecatctl_path = BENCH_ECATCTL_PATH;
    std::string backend;
};

double seconds(Clock::duration d) {
    return std::chrono::duration<double>(d).count();
}

std::string read_text(const std::filesystem::path& p) {
    std::ifstream f(p);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
}

void write_text(const std::filesystem::path& p, const std::string& text) {
    std::ofstream f(p, std::ios::trunc);
    f << text;
    if (!f) throw std::runtime_error("cannot write " + p.string());
}

// The slave's device configuration: the default model with this bootstrap mailbox (SM0 at 0x1000, SM1 after
// it, both of `size` bytes).
std::string device_config(unsigned size) {
    return util::strprintf(
        "[bootstrap_mailbox]\nout_start = 0x1000\nout_size = %u\nin_start = 0x%04x\nin_size = %u\n", size,
        0x1000 + ((size + 0xFF) & ~0xFFu), size);
}

struct Stats {
    std::vector<double> v;
    void add(double x) { v.push_back(x); }
    double median() const {
        if (v.empty()) return 0;
        std::vector<double> s = v;
        std::sort(s.begin(), s.end());
        return s.size() % 2 ? s[s.size() / 2] : (s[s.size() / 2 - 1] + s[s.size() / 2]) / 2;
    }
    double min() const { return v.empty() ? 0 : *std::min_element(v.begin(), v.end()); }
    double max() const { return v.empty() ? 0 : *std::max_element(v.begin(), v.end()); }
};

const char* err(Error e) {
    return master::to_string(e).data();
}

// Waits until the slave answers a register read (it has just been started).
bool wait_for_slave(master::Master& m) {
    const auto deadline = Clock::now() + std::chrono::seconds(10);
    while (Clock::now() < deadline) {
        uint8_t b[1];
        if (m.read(kSlave, esc::reg::kType, b) == Error::Ok) return true;
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return false;
}

// B -> I (the device restarts from the stored image) or any state -> I; waits out the restart.
bool to_init(master::Master& m) {
    const auto deadline = Clock::now() + std::chrono::seconds(20);
    // Not from INIT: AL control is a mailbox the slave must read before it takes the next write (ESC with
    // device emulation off), and "INIT reached" would not wait for that read: the BOOT request that follows
    // could be dropped.
    auto now = m.al_status(kSlave);
    if (now && now->state == static_cast<uint8_t>(AlState::Init) && !now->error) return true;
    (void)m.request_state(kSlave, AlState::Init);
    while (Clock::now() < deadline) {
        auto st = m.al_status(kSlave);
        if (st && st->state == static_cast<uint8_t>(AlState::Init) && !st->error) return true;
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return false;
}

// Waits for the slave, then reads its identity (vendor, product) from the SII: "" or why not.
std::string slave_identity(master::Master& m, const std::filesystem::path& log, foe::ImageIdentity& who) {
    if (!wait_for_slave(m)) return "the slave does not answer: " + read_text(log);
    uint8_t id[8];
    if (Error e = m.sii_read(kSlave, master::sii::VendorId, id); e != Error::Ok)
        return std::string("SII identity: ") + err(e);
    who = {util::get32(id), util::get32(id + 4)};
    return {};
}

struct Throughput {
    unsigned mailbox = 0;
    std::size_t bytes = 0;
    Stats data_s, commit_s, total_s;
    uint64_t busy = 0, repeats = 0;
    uint64_t frames = 0, packets = 0;  // EtherCAT frames the master sent, FoE DATA packets
    std::string failure;
};

void measure_throughput(const Options& o, unsigned size, const std::filesystem::path& dir, Throughput& r) {
    r.mailbox = size;
    const std::filesystem::path conf = dir / ("mailbox-" + std::to_string(size) + ".conf");
    const std::filesystem::path state = dir / ("state-" + std::to_string(size));
    const std::filesystem::path log = dir / ("slave-" + std::to_string(size) + ".log");
    write_text(conf, device_config(size));
    Child slave(
        {o.slave_path, "--iface", kSlaveEnd, "--state-dir", state.string(), "--config", conf.string()},
        log.string());
    auto link = esc::open_link(kMasterEnd, o.backend);
    master::Master m(*link);
    foe::ImageIdentity who{};
    if (r.failure = slave_identity(m, log, who); !r.failure.empty()) return;
    std::vector<uint8_t> payload(o.bytes > foe::kImageHeaderSize ? o.bytes - foe::kImageHeaderSize : 1);
    for (std::size_t i = 0; i < payload.size(); ++i)
        payload[i] = static_cast<uint8_t>(i * 7 + (i >> 9));
    for (unsigned run = 0; run < o.runs; ++run) {
        const std::vector<uint8_t> image = foe::build_image(payload, who, 0x01300000 + (run + 1) * 0x10000);
        r.bytes = image.size();
        if (!to_init(m)) {
            r.failure = "the slave does not reach INIT";
            return;
        }
        master::Mailbox mbx(m, kSlave);
        if (Error e = mbx.configure_from_sii(true); e != Error::Ok) {
            r.failure = std::string("bootstrap mailbox: ") + err(e);
            return;
        }
        if (mbx.config().out_size != size) {
            r.failure =
                "the SII says a bootstrap mailbox of " + std::to_string(mbx.config().out_size) + " bytes";
            return;
        }
        master::AlStatus st;
        if (Error e = m.request_state(kSlave, AlState::Boot, &st); e != Error::Ok) {
            auto now = m.al_status(kSlave);
            r.failure =
                "run " + std::to_string(run + 1) + ": BOOT: " + err(e) + ", AL status " +
                (now ? std::string(master::al_state_name(now->state)) : std::string(err(now.error()))) +
                " code " + std::to_string(st.code) + "; slave log:\n" + read_text(log);
            return;
        }
        master::FoeClient foe(mbx);
        Clock::time_point sent{};
        foe.set_progress([&](const master::FoeProgress& p) {
            if (p.busy && sent == Clock::time_point{}) sent = Clock::now();
        });
        const uint64_t frames0 = m.stats().frames_sent;
        const auto t0 = Clock::now();
        const Error e = foe.write("MAXPOS", image);
        const auto t1 = Clock::now();
        if (e != Error::Ok) {
            r.failure = std::string("FoE write: ") + err(e) + " " + std::to_string(foe.last_error()) + " " +
                        foe.last_error_text();
            return;
        }
        if (sent == Clock::time_point{}) sent = t1;  // stored without a BUSY answer
        r.data_s.add(seconds(sent - t0));
        r.commit_s.add(seconds(t1 - sent));
        r.total_s.add(seconds(t1 - t0));
        r.busy += foe.busy_answers();
        r.frames += m.stats().frames_sent - frames0;
        r.packets += image.size() / (mbx.max_out_payload() - 6) + 1;
        r.repeats += mbx.repeats();
    }
    (void)to_init(m);
    slave.stop();
}

struct UpdateTimes {
    std::size_t bytes = 0;
    Stats total_s, boot_s, written_s, restarted_s, checked_s;
    std::string failure;
};

// The time stamp of the first line of ecatctl's step output that contains `what` ("[  0.123 s] ...").
double step_time(const std::string& out, const std::string& what) {
    std::istringstream in(out);
    std::string line;
    while (std::getline(in, line)) {
        if (line.find(what) == std::string::npos) continue;
        const auto b = line.find('[');
        if (b != std::string::npos) return std::atof(line.c_str() + b + 1);
    }
    return -1;
}

void measure_update(const Options& o, const std::filesystem::path& dir, UpdateTimes& r) {
    const std::filesystem::path state = dir / "state-update";
    const std::filesystem::path log = dir / "slave-update.log";
    Child slave({o.slave_path, "--iface", kSlaveEnd, "--state-dir", state.string()}, log.string());
    foe::ImageIdentity who{};
    {
        auto link = esc::open_link(kMasterEnd, o.backend);
        master::Master m(*link);
        if (r.failure = slave_identity(m, log, who); !r.failure.empty()) return;
    }
    std::vector<uint8_t> payload(o.update_bytes - foe::kImageHeaderSize);
    for (std::size_t i = 0; i < payload.size(); ++i)
        payload[i] = static_cast<uint8_t>(i * 13 + (i >> 10));
    for (unsigned run = 0; run < o.update_runs; ++run) {
        const std::vector<uint8_t> image = foe::build_image(payload, who, 0x01300000 + (run + 1) * 0x10000);
        r.bytes = image.size();
        const std::filesystem::path file = dir / "update.bin";
        {
            std::ofstream f(file, std::ios::binary | std::ios::trunc);
            f.write(reinterpret_cast<const char*>(image.data()), static_cast<std::streamsize>(image.size()));
        }
        const std::filesystem::path out = dir / "ecatctl.log";
        const auto t0 = Clock::now();
        Child ctl({o.ecatctl_path, "--iface", kMasterEnd, "firmware-update", file.string()}, out.string());
        const int rc = bench::exit_code(ctl.wait());
        const auto t1 = Clock::now();
        const std::string text = read_text(out);
        if (rc != 0) {
            r.failure = "ecatctl firmware-update exit " + std::to_string(rc) + ":\n" + text;
            return;
        }
        r.total_s.add(seconds(t1 - t0));
        r.boot_s.add(step_time(text, "] BOOT"));
        r.written_s.add(step_time(text, "bytes written to"));
        r.restarted_s.add(step_time(text, "device restarted"));
        r.checked_s.add(step_time(text, "firmware updated"));
    }
    slave.stop();
}

void usage() {
    std::fprintf(stderr,
                 "usage: bench-foe [--mailbox N[,N...]] [--bytes N] [--runs N] [--update-bytes N] "
                 "[--update-runs N] [--slave PATH] [--ecatctl PATH] [--backend pcap|packet]\n"
                 "  FoE write throughput through the real ecat-slave for each bootstrap mailbox size\n"
                 "  (default 1024,1486; image of --bytes, default 4 MiB) and the time of a whole\n"
                 "  `ecatctl firmware-update` of an --update-bytes image (default 1 MiB). Needs root.\n");
}

}  // namespace

int main(int argc, char** argv) {
    Options o;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto next = [&] { return bench::option_value(argc, argv, i, usage); };
        auto number = [&](unsigned long long lo, unsigned long long hi) {
            const std::string t = next();
            char* end = nullptr;
            const unsigned long long v = std::strtoull(t.c_str(), &end, 0);
            if (t.empty() || *end != '\0' || v < lo || v > hi) {
                std::fprintf(stderr, "bench-foe: bad number '%s' for %s\n", t.c_str(), a.c_str());
                std::exit(2);
            }
            return v;
        };
        if (a == "--mailbox") {
            o.mailbox_sizes.clear();
            std::stringstream s(next());
            std::string part;
            while (std::getline(s, part, ',')) {
                const unsigned long v = std::strtoul(part.c_str(), nullptr, 0);
                if (v < 16 || v > 1486) {
                    std::fprintf(stderr, "bench-foe: mailbox size %s not in 16..1486\n", part.c_str());
                    return 2;
                }
                o.mailbox_sizes.push_back(static_cast<unsigned>(v));
            }
        } else if (a == "--bytes") {
            o.bytes = static_cast<std::size_t>(number(64, 256ull << 20));
        } else if (a == "--runs") {
            o.runs = static_cast<unsigned>(number(1, 1000));
        } else if (a == "--update-bytes") {
            o.update_bytes = static_cast<std::size_t>(number(64, 256ull << 20));
        } else if (a == "--update-runs") {
            o.update_runs = static_cast<unsigned>(number(0, 1000));
        } else if (a == "--slave") {
            o.slave_path = next();
        } else if (a == "--ecatctl") {
            o.ecatctl_path = next();
        } else if (a == "--backend") {
            o.backend = next();
        } else if (a == "--help" || a == "-h") {
            usage();
            return 0;
        } else {
            usage();
            return 2;
        }
    }
    if (!bench::require_root("(network namespace, veth pair, raw sockets); run it with sudo")) return 2;
    for (const std::string& p : {o.slave_path, o.ecatctl_path}) {
        if (::access(p.c_str(), X_OK) != 0) {
            std::fprintf(stderr, "bench-foe: cannot run %s\n", p.c_str());
            return 2;
        }
    }
    if (!bench::enter_network_namespace()) return 2;
    int rc = 0;
    try {
        const bench::TempDir tmp("bench-foe");
        const std::filesystem::path& dir = tmp.path();
        slave::VethPair pair(kSlaveEnd, kMasterEnd);
        std::printf("FoE write through ecat-slave over a veth pair (%u runs each; MB = 10^6 bytes)\n",
                    o.runs);
        std::printf("%-8s %-10s %-24s %-22s %-24s %s\n", "mailbox", "image", "data phase s / MB/s (med)",
                    "commit s (min-max)", "whole write s / MB/s", "BUSY/run");
        for (unsigned size : o.mailbox_sizes) {
            std::fprintf(stderr, "bench-foe: bootstrap mailbox %u bytes ...\n", size);
            Throughput t;
            measure_throughput(o, size, dir, t);
            if (!t.failure.empty()) {
                std::printf("%-8u failed: %s\n", size, t.failure.c_str());
                rc = 1;
                continue;
            }
            const double mb = static_cast<double>(t.bytes) / 1e6;
            char c1[64], c2[64], c3[64];
            std::snprintf(c1, sizeof c1, "%.3f / %.2f", t.data_s.median(), mb / t.data_s.median());
            std::snprintf(c2, sizeof c2, "%.3f (%.3f-%.3f)", t.commit_s.median(), t.commit_s.min(),
                          t.commit_s.max());
            std::snprintf(c3, sizeof c3, "%.3f / %.2f", t.total_s.median(), mb / t.total_s.median());
            std::printf("%-8u %-10zu %-24s %-22s %-24s %.0f\n", size, t.bytes, c1, c2, c3,
                        static_cast<double>(t.busy) / o.runs);
            std::printf(
                "         data phase MB/s min-max %.2f-%.2f; %.0f us and %.1f frames per DATA packet (%u "
                "data bytes); mailbox repeat requests %llu\n",
                mb / t.data_s.max(), mb / t.data_s.min(),
                1e6 * t.data_s.median() / (static_cast<double>(t.packets) / o.runs),
                static_cast<double>(t.frames) / static_cast<double>(t.packets), size - 12,
                static_cast<unsigned long long>(t.repeats));
        }
        if (o.update_runs > 0) {
            std::fprintf(stderr, "bench-foe: whole firmware update ...\n");
            UpdateTimes u;
            measure_update(o, dir, u);
            if (!u.failure.empty()) {
                std::printf("firmware update failed: %s\n", u.failure.c_str());
                rc = 1;
            } else {
                std::printf(
                    "\nWhole update, `ecatctl firmware-update` of a %zu-byte image, default mailbox (%u "
                    "runs):\n",
                    u.bytes, o.update_runs);
                std::printf("  program start to exit: median %.3f s (min %.3f, max %.3f)\n",
                            u.total_s.median(), u.total_s.min(), u.total_s.max());
                std::printf(
                    "  step times since ecatctl's start (median): BOOT %.3f s, written %.3f s, "
                    "restarted %.3f s, revision checked %.3f s\n",
                    u.boot_s.median(), u.written_s.median(), u.restarted_s.median(), u.checked_s.median());
            }
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench-foe: %s\n", e.what());
        rc = 1;
    }
    return rc;
}
