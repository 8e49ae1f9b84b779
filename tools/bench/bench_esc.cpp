// bench-esc: in-process cost of esc::Esc::process_frame() for a typical cyclic frame (LRW 32 bytes onto
// configured FMMUs + FRMW 0x0910 + FPRD 0x0130). The slave is configured first through frames, as a master
// does. Between frames the "firmware" side refreshes the inputs and takes the outputs through the PDI, so the
// 3-buffer SyncManagers rotate as in operation. Prints median / p99 per call; asserts nothing.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "esc/esc.hpp"
#include "frame.hpp"
#include "harness.hpp"
#include "stats.hpp"

using bench::now_ns;

int main(int argc, char** argv) {
    std::size_t iterations = 200000;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--iterations" && i + 1 < argc) {
            iterations = std::strtoull(argv[++i], nullptr, 10);
        } else {
            std::fprintf(stderr, "usage: bench-esc [--iterations N]\n");
            return 2;
        }
    }
    if (iterations == 0) iterations = 1;

    esc::SystemClock clock;
    esc::Esc esc(esc::EscConfig{}, clock);
    const uint16_t station = 0x1001;
    for (auto f : bench::configuration_frames(station)) {
        if (!esc.process_frame(f)) {
            std::fprintf(stderr, "bench-esc: configuration frame was not returned\n");
            return 1;
        }
    }

    const std::vector<uint8_t> tmpl = bench::cyclic_frame(station, 0x10);
    std::vector<uint8_t> frame(tmpl.size());
    std::vector<uint64_t> samples;
    samples.reserve(iterations);
    uint8_t inputs[16] = {};
    uint8_t outputs[16] = {};
    int wkc_lrw = -1, wkc_frmw = -1, wkc_fprd = -1;

    const std::size_t warmup = iterations / 10 + 100;
    for (std::size_t i = 0; i < warmup + iterations; ++i) {
        inputs[0] = static_cast<uint8_t>(i);
        esc.write(0x1180, inputs);  // firmware publishes inputs (SM3)
        std::memcpy(frame.data(), tmpl.data(), tmpl.size());
        const uint64_t t0 = now_ns();
        esc.process_frame(frame);
        const uint64_t t1 = now_ns();
        esc.read(0x1100, outputs);  // firmware takes outputs (SM2)
        esc.tick();
        if (i >= warmup) samples.push_back(t1 - t0);
        if (i == warmup) {
            wkc_lrw = bench::datagram_wkc(frame, 0);
            wkc_frmw = bench::datagram_wkc(frame, 1);
            wkc_fprd = bench::datagram_wkc(frame, 2);
        }
    }
    // Back-to-back throughput without per-call time stamps (clock_gettime costs ~20 ns itself): batches of
    // 1000 frames, the median batch (a preempted batch on a loaded machine does not count).
    const std::size_t batch = 1000;
    std::vector<uint64_t> batches;
    for (std::size_t k = 0; k < std::max<std::size_t>(iterations / batch, 1); ++k) {
        const uint64_t b0 = now_ns();
        for (std::size_t i = 0; i < batch; ++i) {
            std::memcpy(frame.data(), tmpl.data(), tmpl.size());
            esc.process_frame(frame);
        }
        batches.push_back(now_ns() - b0);
    }
    const bench::Summary bs = bench::summarize(batches);

    std::printf("bench-esc: cyclic frame of %zu bytes (LRW 32 B + FRMW 0x0910 8 B + FPRD 0x0130 2 B)\n",
                tmpl.size());
    std::printf("working counters: LRW %d (3 expected with both FMMUs), FRMW %d, FPRD %d\n", wkc_lrw,
                wkc_frmw, wkc_fprd);
    bench::print("process_frame", bench::summarize(samples));
    std::printf("%-28s median %.1f ns/frame, best %.1f ns/frame (%zu batches of %zu, incl. frame memcpy)\n",
                "back-to-back", bs.median / static_cast<double>(batch), bs.min / static_cast<double>(batch),
                bs.n, batch);
    return 0;
}
