// bench-sdo: CoE from the master's side over a veth pair with the real ecat-slave, in a private network
// namespace created at start (unshare; the kernel removes the pair with the namespace however we exit):
//   (1) the whole object dictionary through SDO information: the object list, every object description and
//       every entry description, as `ecatctl sdos` reads it (time per run, per request);
//   (2) expedited SDO upload round trips (0x6041:00, 2 bytes): median, p99;
//   (3) segmented SDO upload of a string (0x1008, a 255-character device name given to the slave through
//       --config, so it needs an initiate plus segments with the default 128-byte mailbox);
//   (0) the bare frame round trip on the same pair (one APRD of the AL status register), interleaved with
//       (2) and (3) so every figure sees the same machine load; ratios against it.
// Needs root. Prints figures; asserts nothing (docs/benchmarks-coe.md).

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "esc/link.hpp"
#include "harness.hpp"
#include "master/coe.hpp"
#include "master/mailbox.hpp"
#include "master/master.hpp"
#include "slave/netif.hpp"
#include "stats.hpp"

namespace {

using bench::Child;
using bench::now_ns;

void check(master::Error e, const char* what) {
    if (e != master::Error::Ok)
        throw std::runtime_error(std::string(what) + ": " + std::string(master::to_string(e)));
}

struct DictionaryRun {
    uint64_t ns = 0;
    std::size_t objects = 0;
    std::size_t entries = 0;
    std::size_t requests = 0;
};

// The whole dictionary through SDO information, as `ecatctl sdos` reads it.
DictionaryRun read_dictionary(master::SdoClient& sdo) {
    DictionaryRun r;
    const uint64_t t0 = now_ns();
    auto list = sdo.od_list(1);
    ++r.requests;
    if (!list) throw std::runtime_error("object list: " + std::string(master::to_string(list.error())));
    for (uint16_t index : *list) {
        auto od = sdo.object_description(index);
        ++r.requests;
        if (!od)
            throw std::runtime_error("object description: " + std::string(master::to_string(od.error())));
        ++r.objects;
        const unsigned last = od->object_code == 7 ? 0 : od->max_subindex;
        for (unsigned sub = 0; sub <= last; ++sub) {
            auto e = sdo.entry_description(index, static_cast<uint8_t>(sub), 0);
            ++r.requests;
            if (!e) {
                if (e.error() == master::Error::SdoAbort) continue;  // a gap in the subindices
                throw std::runtime_error("entry description: " + std::string(master::to_string(e.error())));
            }
            ++r.entries;
        }
    }
    r.ns = now_ns() - t0;
    return r;
}

void usage() {
    std::fprintf(
        stderr,
        "usage: bench-sdo [--requests N] [--segmented N] [--dictionary-runs N] [--backend pcap|packet] "
        "[--slave PATH] [--verbose]\n");
}

}  // namespace

int main(int argc, char** argv) {
    std::size_t requests = 5000;
    std::size_t segmented = 1000;
    std::size_t dict_runs = 5;
    std::string backend = esc::default_link_backend();
    std::string slave_path = BENCH_ECAT_SLAVE_PATH;
    bool verbose = false;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto next = [&] { return bench::option_value(argc, argv, i, usage); };
        if (a == "--requests") {
            requests = std::strtoull(next().c_str(), nullptr, 10);
        } else if (a == "--segmented") {
            segmented = std::strtoull(next().c_str(), nullptr, 10);
        } else if (a == "--dictionary-runs") {
            dict_runs = std::strtoull(next().c_str(), nullptr, 10);
        } else if (a == "--backend") {
            backend = next();
        } else if (a == "--slave") {
            slave_path = next();
        } else if (a == "--verbose") {
            verbose = true;
        } else {
            usage();
            return 2;
        }
    }
    if (requests == 0) requests = 1;
    if (segmented == 0) segmented = 1;
    if (dict_runs == 0) dict_runs = 1;
    if (!bench::require_root("(network namespace, veth pair, raw sockets)")) return 2;
    if (!bench::enter_network_namespace()) return 2;
    try {
        bench::TempDir tmp("bench-sdo");
        const std::filesystem::path& dir = tmp.path();
        // A device name of 255 characters (the SII string limit): 0x1008 then needs segments.
        std::string name = "bench-sdo device name ";
        while (name.size() < 255)
            name += static_cast<char>('a' + name.size() % 26);
        {
            std::ofstream conf(dir / "device.conf");
            conf << "[identity]\ndevice_name = \"" << name << "\"\n";
            if (!conf) throw std::runtime_error("cannot write the device configuration");
        }
        slave::VethPair pair("sdo-s0", "sdo-m0");
        std::vector<std::string> args = {slave_path,
                                         "--iface",
                                         "sdo-s0",
                                         "--backend",
                                         backend,
                                         "--config",
                                         (dir / "device.conf").string(),
                                         "--state-dir",
                                         (dir / "state").string()};
        if (verbose) args.push_back("--verbose");
        Child slave(args, verbose ? "" : "/dev/null", 2000);

        auto link = esc::open_link("sdo-m0", backend);
        master::MasterOptions opt;
        opt.timeout = std::chrono::milliseconds(100);
        master::Master m(*link, opt);
        const auto a = master::Address::position(0);
        uint8_t al[2];
        bool up = false;
        for (int i = 0; i < 100 && !up; ++i) {
            up = m.read(a, esc::reg::kAlStatus, al) == master::Error::Ok;
            if (!up) std::this_thread::sleep_for(std::chrono::milliseconds(50));
        }
        if (!up) throw std::runtime_error("ecat-slave does not answer");
        master::Mailbox mbx(m, a);
        check(mbx.configure_from_sii(), "mailbox from the SII");
        check(m.request_state(a, master::AlState::PreOp), "INIT -> PREOP");
        master::SdoClient sdo(mbx);

        // (1) the dictionary.
        std::vector<uint64_t> dict_ns;
        DictionaryRun last;
        for (std::size_t i = 0; i < dict_runs; ++i) {
            last = read_dictionary(sdo);
            dict_ns.push_back(last.ns);
        }

        // (0), (2), (3) interleaved.
        std::vector<uint64_t> frame_ns, exp_ns, seg_ns;
        frame_ns.reserve(requests + segmented);
        exp_ns.reserve(requests);
        seg_ns.reserve(segmented);
        std::vector<uint8_t> buf(1024);
        std::size_t failed = 0;
        auto frame_rtt = [&] {
            const uint64_t t0 = now_ns();
            if (m.read(a, esc::reg::kAlStatus, al) == master::Error::Ok) return now_ns() - t0;
            ++failed;
            return uint64_t{0};
        };
        const std::size_t warmup = 100;
        uint64_t exp_frames = 0, seg_frames = 0;
        for (std::size_t i = 0; i < warmup + requests; ++i) {
            const uint64_t f = frame_rtt();
            const uint64_t sent = m.stats().frames_sent;
            const uint64_t t0 = now_ns();
            auto n = sdo.upload(0x6041, 0, buf);
            const uint64_t t = now_ns() - t0;
            if (i >= warmup) exp_frames += m.stats().frames_sent - sent;
            if (!n || *n != 2) {
                ++failed;
                continue;
            }
            if (i < warmup) continue;
            if (f != 0) frame_ns.push_back(f);
            exp_ns.push_back(t);
        }
        for (std::size_t i = 0; i < segmented; ++i) {
            const uint64_t f = frame_rtt();
            const uint64_t sent = m.stats().frames_sent;
            const uint64_t t0 = now_ns();
            auto n = sdo.upload(0x1008, 0, buf);
            const uint64_t t = now_ns() - t0;
            seg_frames += m.stats().frames_sent - sent;
            if (!n || *n != name.size() || std::memcmp(buf.data(), name.data(), name.size()) != 0) {
                ++failed;
                continue;
            }
            if (f != 0) frame_ns.push_back(f);
            seg_ns.push_back(t);
        }

        const bench::Summary sd = bench::summarize(dict_ns);
        const bench::Summary sf = bench::summarize(frame_ns);
        const bench::Summary se = bench::summarize(exp_ns);
        const bench::Summary ss = bench::summarize(seg_ns);
        std::printf(
            "bench-sdo: backend %s, veth pair in a private netns, ecat-slave in PREOP, mailbox SM0 %u / "
            "SM1 %u bytes\n",
            backend.c_str(), mbx.config().out_size, mbx.config().in_size);
        std::printf("(1) dictionary via SDO info: %zu objects, %zu entries, %zu requests per run, %zu runs\n",
                    last.objects, last.entries, last.requests, dict_runs);
        bench::print("    whole dictionary", sd, "ms", 1e6);
        std::printf("    per SDO info request: median %.1f us\n",
                    sd.median / 1e3 / static_cast<double>(last.requests));
        bench::print("(0) bare frame (APRD 0x0130)", sf, "us", 1e3);
        bench::print("(2) expedited upload 0x6041", se, "us", 1e3);
        bench::print("(3) segmented upload 0x1008", ss, "us", 1e3);
        std::printf("    0x1008 is %zu bytes\n", name.size());
        std::printf("frames per transfer (mailbox writes, SM1 polls): expedited %.2f, segmented %.2f\n",
                    static_cast<double>(exp_frames) / static_cast<double>(requests),
                    static_cast<double>(seg_frames) / static_cast<double>(segmented));
        if (sf.median > 0 && sf.p99 > 0) {
            std::printf("ratio expedited/frame: median %.2f  p99 %.2f\n", se.median / sf.median,
                        se.p99 / sf.p99);
            std::printf("ratio segmented/frame: median %.2f  p99 %.2f\n", ss.median / sf.median,
                        ss.p99 / sf.p99);
            std::printf("ratio SDO info request/frame: median %.2f\n",
                        sd.median / static_cast<double>(last.requests) / sf.median);
        }
        std::printf("failed requests: %zu, mailbox repeat requests: %llu, emergencies seen: %llu\n", failed,
                    static_cast<unsigned long long>(mbx.repeats()),
                    static_cast<unsigned long long>(sdo.emergencies()));
        if (!slave.alive()) std::printf("warning: ecat-slave exited during the run\n");
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench-sdo: %s\n", e.what());
        return 1;
    }
    return 0;
}
