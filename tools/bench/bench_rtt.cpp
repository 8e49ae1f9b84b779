// bench-rtt: round-trip time over veth pairs as a master-side raw socket sees it,
//   (a) through a bare echo (bench-echo: receive, send back; same link backend), and
//   (b) through ecat-slave (the ESC processes every datagram),
// measured in the same run, interleaved frame by frame so both see the same machine load.
// Everything lives in a private network namespace created at start (unshare), which the kernel removes with
// the two veth pairs when this program and its children exit, however they exit. Needs root.
// Prints median / p99 / p99.9 / max for both, their ratio and the tail (replies later than 500 us and
// 1 ms); asserts nothing.
#include <poll.h>

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "esc/link.hpp"
#include "esc/link_packet.hpp"
#include "frame.hpp"
#include "harness.hpp"
#include "slave/netif.hpp"
#include "stats.hpp"

namespace {

using bench::Child;
using bench::now_ns;

// Sends frame (datagram 0 index = seq) and waits for the processed reply. Returns the round trip in ns,
// 0 if no reply came within timeout_ms.
uint64_t exchange(esc::Link& link, std::vector<uint8_t>& frame, uint8_t seq, std::vector<uint8_t>& rx,
                  int timeout_ms) {
    frame[17] = seq;
    const uint64_t t0 = now_ns();
    if (!link.send(frame)) return 0;
    const uint64_t deadline = t0 + static_cast<uint64_t>(timeout_ms) * 1000000ull;
    for (;;) {
        const std::size_t n = link.receive(rx);
        if (n > 17 && rx[17] == seq && (rx[6] & 0x02) != 0) return now_ns() - t0;
        if (n > 0) continue;  // a stale reply of an earlier, timed-out frame
        const uint64_t t = now_ns();
        if (t >= deadline) return 0;
        pollfd p{link.fd(), POLLIN, 0};
        ::poll(&p, 1, static_cast<int>((deadline - t) / 1000000ull) + 1);
    }
}

bool wait_until_answering(esc::Link& link, std::vector<uint8_t>& frame, std::vector<uint8_t>& rx) {
    for (int i = 0; i < 100; ++i)
        if (exchange(link, frame, static_cast<uint8_t>(0xF0 + i % 8), rx, 100) != 0) return true;
    return false;
}

// Measures `count` exchanges on link (after a short warm-up); lost frames are counted, not sampled.
void measure(esc::Link& link, std::vector<uint8_t>& frame, std::vector<uint8_t>& rx, std::size_t count,
             std::vector<uint64_t>& out, std::size_t& lost) {
    for (std::size_t i = 0; i < 100 + count; ++i) {
        const uint64_t t = exchange(link, frame, static_cast<uint8_t>(i), rx, 200);
        if (i < 100) continue;
        if (t != 0)
            out.push_back(t);
        else
            ++lost;
    }
}

// The figures of (a) the bare echo and (b) ecat-slave: each distribution, its tail, the losses, the ratio.
void print_echo_vs_slave(const std::vector<uint64_t>& rtt_echo, std::size_t lost_echo,
                         const std::vector<uint64_t>& rtt_slave, std::size_t lost_slave) {
    const bench::Summary se = bench::summarize(rtt_echo);
    const bench::Summary ss = bench::summarize(rtt_slave);
    bench::print("(a) bare echo", se, "us", 1000.0);
    bench::print("(b) ecat-slave", ss, "us", 1000.0);
    bench::print_tail("tail (a) bare echo", se);
    bench::print_tail("tail (b) ecat-slave", ss);
    std::printf("lost: echo %zu, slave %zu\n", lost_echo, lost_slave);
    if (se.median > 0 && se.p99 > 0)
        std::printf("ratio slave/echo: median %.3f  p99 %.3f  (target < 1.2)\n", ss.median / se.median,
                    ss.p99 / se.p99);
}

// --same-pair: (a) and (b) on the same veth pair, one after the other, in alternating blocks (the echo and
// the slave are restarted for each block) so that both see the same load on average.
int run_same_pair(std::size_t frames, const std::string& backend, const std::string& slave_path,
                  const std::string& echo_path, bool verbose) {
    slave::VethPair pair("rtt-s0", "rtt-m0");
    esc::PacketLink master("rtt-m0");
    std::vector<uint8_t> rx(esc::kMaxFrameSize);
    const uint16_t station = 0x1001;
    std::vector<uint8_t> frame = bench::cyclic_frame(station, 0);
    std::vector<uint64_t> rtt_echo, rtt_slave;
    std::size_t lost_echo = 0, lost_slave = 0;
    constexpr std::size_t kBlocks = 4;
    int wkc_lrw = -1;
    for (std::size_t block = 0; block < kBlocks; ++block) {
        const std::size_t n = frames / kBlocks + (block < frames % kBlocks ? 1 : 0);
        {
            Child echo({echo_path, "--iface", "rtt-s0", "--backend", backend}, verbose ? "" : "/dev/null",
                       2000);
            if (!wait_until_answering(master, frame, rx))
                throw std::runtime_error("bench-echo does not answer");
            measure(master, frame, rx, n, rtt_echo, lost_echo);
        }
        {
            std::vector<std::string> args = {slave_path, "--iface", "rtt-s0", "--backend", backend};
            if (verbose) args.push_back("--verbose");
            Child slave(args, verbose ? "" : "/dev/null", 2000);
            if (!wait_until_answering(master, frame, rx))
                throw std::runtime_error("ecat-slave does not answer");
            for (auto cfg : bench::configuration_frames(station))
                if (exchange(master, cfg, 0xE0, rx, 500) == 0)
                    throw std::runtime_error("configuration frame lost");
            measure(master, frame, rx, n, rtt_slave, lost_slave);
            wkc_lrw = bench::datagram_wkc(rx, 0);
        }
    }
    std::printf(
        "bench-rtt: backend %s, same veth pair, %zu frames of %zu bytes in %zu alternating blocks; "
        "last slave reply LRW wkc %d\n",
        backend.c_str(), frames, frame.size(), kBlocks, wkc_lrw);
    print_echo_vs_slave(rtt_echo, lost_echo, rtt_slave, lost_slave);
    return 0;
}

void usage() {
    std::fprintf(stderr,
                 "usage: bench-rtt [--frames N] [--backend pcap|packet] [--slave PATH] [--echo PATH] "
                 "[--eeprom FILE] [--verbose] [--compare-backends | --same-pair]\n");
}

}  // namespace

int main(int argc, char** argv) {
    std::size_t frames = 20000;
    std::string backend = esc::default_link_backend();
    std::string slave_path = BENCH_ECAT_SLAVE_PATH;
    std::string echo_path = BENCH_ECHO_PATH;
    std::string eeprom;
    bool verbose = false;
    bool compare_backends = false;
    bool same_pair = false;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto next = [&] { return bench::option_value(argc, argv, i, usage); };
        if (a == "--frames") {
            frames = std::strtoull(next().c_str(), nullptr, 10);
        } else if (a == "--backend") {
            backend = next();
        } else if (a == "--slave") {
            slave_path = next();
        } else if (a == "--echo") {
            echo_path = next();
        } else if (a == "--eeprom") {
            eeprom = next();
        } else if (a == "--verbose") {
            verbose = true;
        } else if (a == "--compare-backends") {
            compare_backends = true;
        } else if (a == "--same-pair") {
            same_pair = true;
        } else {
            usage();
            return 2;
        }
    }
    if (frames == 0) frames = 1;
    if (!bench::require_root("(network namespace, veth pairs, raw sockets)")) return 2;
    if (!bench::enter_network_namespace()) return 2;
    try {
        if (same_pair) return run_same_pair(frames, backend, slave_path, echo_path, verbose);
        slave::VethPair echo_pair("rtt-s0", "rtt-m0");
        slave::VethPair slave_pair("rtt-s1", "rtt-m1");
        // (a) on pair 0, (b) on pair 1. With --compare-backends: (a) echo over pcap, (b) echo over packet.
        const std::string backend_a = compare_backends ? std::string("pcap") : backend;
        Child echo({echo_path, "--iface", "rtt-s0", "--backend", backend_a}, verbose ? "" : "/dev/null",
                   2000);
        std::vector<std::string> slave_args = {slave_path, "--iface", "rtt-s1", "--backend", backend};
        if (compare_backends) {
            slave_args = {echo_path, "--iface", "rtt-s1", "--backend", "packet"};
        } else {
            if (!eeprom.empty()) {
                slave_args.push_back("--eeprom");
                slave_args.push_back(eeprom);
            }
            if (verbose) slave_args.push_back("--verbose");
        }
        Child slave(slave_args, verbose ? "" : "/dev/null", 2000);

        esc::PacketLink to_echo("rtt-m0");
        esc::PacketLink to_slave("rtt-m1");
        std::vector<uint8_t> rx(esc::kMaxFrameSize);
        std::vector<uint8_t> rx_slave(esc::kMaxFrameSize);
        const uint16_t station = 0x1001;
        std::vector<uint8_t> frame = bench::cyclic_frame(station, 0);
        if (!wait_until_answering(to_echo, frame, rx)) throw std::runtime_error("bench-echo does not answer");
        if (!wait_until_answering(to_slave, frame, rx))
            throw std::runtime_error(std::string(compare_backends ? "bench-echo (packet)" : "ecat-slave") +
                                     " does not answer");
        // Configure the slave as a master would, so the LRW really moves process data.
        for (auto cfg : bench::configuration_frames(station)) {
            for (auto* link : {&to_echo, &to_slave}) {
                cfg[17] = 0xE0;
                if (exchange(*link, cfg, 0xE0, rx, 500) == 0)
                    throw std::runtime_error("configuration frame lost");
            }
        }

        std::vector<uint64_t> rtt_echo, rtt_slave;
        rtt_echo.reserve(frames);
        rtt_slave.reserve(frames);
        std::size_t lost_echo = 0, lost_slave = 0;
        const std::size_t warmup = 500;
        for (std::size_t i = 0; i < warmup + frames; ++i) {
            const uint8_t seq = static_cast<uint8_t>(i);
            // Alternate which goes first so neither always runs on a freshly woken CPU.
            uint64_t a = 0, b = 0;
            if (i % 2 == 0) {
                a = exchange(to_echo, frame, seq, rx, 200);
                b = exchange(to_slave, frame, seq, rx_slave, 200);
            } else {
                b = exchange(to_slave, frame, seq, rx_slave, 200);
                a = exchange(to_echo, frame, seq, rx, 200);
            }
            if (i < warmup) continue;
            if (a != 0)
                rtt_echo.push_back(a);
            else
                ++lost_echo;
            if (b != 0)
                rtt_slave.push_back(b);
            else
                ++lost_slave;
        }
        const int wkc_lrw = bench::datagram_wkc(rx_slave, 0);
        const bench::Summary se = bench::summarize(rtt_echo);
        const bench::Summary ss = bench::summarize(rtt_slave);
        if (compare_backends) {
            std::printf(
                "bench-rtt: bare echo, pcap vs packet backend, %zu frames of %zu bytes, interleaved\n",
                frames, frame.size());
            bench::print("(a) echo, pcap", se, "us", 1000.0);
            bench::print("(b) echo, packet", ss, "us", 1000.0);
            std::printf("lost: pcap %zu, packet %zu\n", lost_echo, lost_slave);
            if (se.median > 0 && se.p99 > 0)
                std::printf("ratio packet/pcap: median %.3f  p99 %.3f\n", ss.median / se.median,
                            ss.p99 / se.p99);
            return 0;
        }
        std::printf(
            "bench-rtt: backend %s, %zu frames of %zu bytes, interleaved; last slave reply LRW wkc %d\n",
            backend.c_str(), frames, frame.size(), wkc_lrw);
        print_echo_vs_slave(rtt_echo, lost_echo, rtt_slave, lost_slave);
        if (!slave.alive()) std::printf("warning: ecat-slave exited during the run\n");
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench-rtt: %s\n", e.what());
        return 1;
    }
    return 0;
}
