// bench-walk: in-process cost of a cyclic frame's walk through a line of ESCs (esc::Segment::walk), per ESC,
// with the ESCs' state in the cache (frames back to back) and evicted between frames (a sweep over a buffer
// larger than the core's L2 cache, as the kernel, the master and other processes leave it on a shared host
// between two cycles of a line). No firmware, no link: the ESC side of bench-segment's per-device figure.
//
// The line: C couplers (station address only, no process data), then T terminals, each with 1 byte of
// outputs (SM2 3-buffer at 0x1000, FMMU0 write) and 1 byte of inputs (SM3 3-buffer at 0x1100, FMMU1 read)
// at logical 2k and 2k + 1. The cyclic frame is the master's: LRW over the whole image and FRMW of the DC
// system time (0x0910) of the first ESC, which every other ESC takes as a write (drift compensation).
// Prints the median per frame and per ESC of each mode; asserts nothing.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "esc/esc.hpp"
#include "esc/segment.hpp"
#include "frame.hpp"
#include "harness.hpp"
#include "stats.hpp"

using bench::now_ns;

namespace {

uint16_t station_of(std::size_t k) {
    return static_cast<uint16_t>(0x1001 + k);
}

// Station address, and for a terminal its SMs and FMMUs, as a master configures them (frames at port 0).
bool configure(esc::Esc& e, std::size_t k, bool terminal, std::size_t terminal_index) {
    using bench::FrameBuilder;
    const uint16_t st = station_of(k);
    const uint8_t addr[2] = {static_cast<uint8_t>(st), static_cast<uint8_t>(st >> 8)};
    std::vector<std::vector<uint8_t>> frames;
    frames.push_back(FrameBuilder().add(bench::APWR, 1, 0, 0x0010, addr).build());
    if (terminal) {
        const uint8_t sm2[8] = {0x00, 0x10, 1, 0, 0x64, 0, 1, 0};
        const uint8_t sm3[8] = {0x00, 0x11, 1, 0, 0x20, 0, 1, 0};
        frames.push_back(
            FrameBuilder().add(bench::FPWR, 2, st, 0x0810, sm2).add(bench::FPWR, 3, st, 0x0818, sm3).build());
        const uint32_t la = static_cast<uint32_t>(2 * terminal_index);
        const uint8_t fmmu0[16] = {static_cast<uint8_t>(la),
                                   static_cast<uint8_t>(la >> 8),
                                   0,
                                   0,
                                   1,
                                   0,
                                   0,
                                   7,
                                   0x00,
                                   0x10,
                                   0,
                                   2,
                                   1,
                                   0,
                                   0,
                                   0};
        const uint8_t fmmu1[16] = {static_cast<uint8_t>(la + 1),
                                   static_cast<uint8_t>((la + 1) >> 8),
                                   0,
                                   0,
                                   1,
                                   0,
                                   0,
                                   7,
                                   0x00,
                                   0x11,
                                   0,
                                   1,
                                   1,
                                   0,
                                   0,
                                   0};
        frames.push_back(FrameBuilder()
                             .add(bench::FPWR, 4, st, 0x0600, fmmu0)
                             .add(bench::FPWR, 5, st, 0x0610, fmmu1)
                             .build());
    }
    for (auto& f : frames)
        if (!e.process_frame(f)) return false;
    return true;
}

}  // namespace

int main(int argc, char** argv) {
    std::size_t couplers = 1, terminals = 60, frames = 2000, evict_kib = 4096;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto next = [&]() { return i + 1 < argc ? std::strtoull(argv[++i], nullptr, 10) : 0ull; };
        if (a == "--couplers") {
            couplers = next();
        } else if (a == "--terminals") {
            terminals = next();
        } else if (a == "--frames") {
            frames = std::max<std::size_t>(next(), 10);
        } else if (a == "--evict-kib") {
            evict_kib = next();
        } else {
            std::fprintf(stderr,
                         "usage: bench-walk [--couplers C] [--terminals T] [--frames F] [--evict-kib K]\n");
            return 2;
        }
    }
    const std::size_t n = couplers + terminals;
    if (n == 0 || n > 1000 || terminals > 700) {
        std::fprintf(stderr, "bench-walk: 1 to 1000 ESCs, at most 700 terminals\n");
        return 2;
    }

    esc::SystemClock clock;
    esc::EscConfig config;
    config.thread_safe = false;  // as device::Line builds them
    std::vector<std::unique_ptr<esc::Esc>> escs;
    esc::Segment segment;
    for (std::size_t k = 0; k < n; ++k) {
        escs.push_back(std::make_unique<esc::Esc>(config, clock));
        // Configured alone on its wire (the frames come back at port 0), then wired into the line.
        if (!configure(*escs.back(), k, k >= couplers, k - std::min(k, couplers))) {
            std::fprintf(stderr, "bench-walk: a configuration frame was not returned\n");
            return 1;
        }
        segment.add(*escs.back());
        if (k > 0) segment.connect(static_cast<int>(k - 1), 1, static_cast<int>(k), 0);
    }

    std::vector<uint8_t> image(2 * terminals, 0);
    const std::vector<uint8_t> tmpl = bench::FrameBuilder()
                                          .add_logical(bench::LRW, 0x10, 0, image)
                                          .add_zero(bench::FRMW, 0x11, station_of(0), 0x0910, 8)
                                          .build();
    std::vector<uint8_t> frame(tmpl.size());
    std::vector<uint8_t> sweep(evict_kib * 1024, 1);
    uint64_t sink = 0;
    int wkc_lrw = -1;

    auto run = [&](bool evict) {
        std::vector<uint64_t> samples;
        samples.reserve(frames);
        for (std::size_t i = 0; i < frames + frames / 10; ++i) {
            if (evict) {
                for (std::size_t b = 0; b < sweep.size(); b += 64) {
                    sweep[b] = static_cast<uint8_t>(sweep[b] + 1);
                    sink += sweep[b];
                }
            }
            std::memcpy(frame.data(), tmpl.data(), tmpl.size());
            const uint64_t t0 = now_ns();
            const esc::Segment::Result r = segment.walk(frame, clock.now_ns());
            const uint64_t t1 = now_ns();
            if (r.kind != esc::Segment::Result::Kind::Reply) {
                std::fprintf(stderr, "bench-walk: the frame did not come back\n");
                std::exit(1);
            }
            // The firmware side of each terminal: new inputs, the outputs taken (the 3-buffer SMs rotate).
            for (std::size_t k = couplers; k < n; ++k) {
                uint8_t b = static_cast<uint8_t>(i);
                escs[k]->write(0x1100, std::span<const uint8_t>(&b, 1));
                escs[k]->read(0x1000, std::span<uint8_t>(&b, 1));
                escs[k]->tick();
            }
            if (i >= frames / 10) samples.push_back(t1 - t0);
            wkc_lrw = bench::datagram_wkc(frame, 0);
        }
        return bench::summarize(samples);
    };

    std::printf(
        "bench-walk: %zu couplers + %zu terminals, frame of %zu bytes (LRW %zu B + FRMW 0x0910 8 B), "
        "%zu frames per mode, eviction sweep %zu KiB\n",
        couplers, terminals, tmpl.size(), image.size(), frames, evict_kib);
    const bench::Summary hot = run(false);
    const bench::Summary cold = run(true);
    std::printf("working counter of the LRW %d (%zu expected)\n", wkc_lrw, 3 * terminals);
    for (const auto& [label, s] : {std::pair{"hot (back to back)", hot}, std::pair{"cold (evicted)", cold}})
        std::printf("%-20s median %8.0f ns per frame, %6.1f ns per ESC; p99 %8.0f ns\n", label, s.median,
                    s.median / static_cast<double>(n), s.p99);
    return sink == 42 ? 3 : 0;
}
