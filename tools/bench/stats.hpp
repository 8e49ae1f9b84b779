#pragma once
// Median / percentiles of a sample of durations (ns), for the benchmark printouts.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <numeric>
#include <vector>

namespace bench {

struct Summary {
    double median = 0, p99 = 0, p999 = 0, mean = 0, min = 0, max = 0;
    std::size_t n = 0;
    // The tail a master with a short link timeout sees (KickCAT's tools: 500 us): samples above each limit.
    std::size_t over_500us = 0, over_1ms = 0;
};

inline Summary summarize(std::vector<uint64_t> v) {
    Summary s;
    s.n = v.size();
    if (v.empty()) return s;
    std::sort(v.begin(), v.end());
    auto pct = [&](double p) {
        return static_cast<double>(v[static_cast<std::size_t>(p * static_cast<double>(v.size() - 1))]);
    };
    s.median = pct(0.5);
    s.p99 = pct(0.99);
    s.p999 = pct(0.999);
    s.min = static_cast<double>(v.front());
    s.max = static_cast<double>(v.back());
    s.over_500us =
        static_cast<std::size_t>(v.end() - std::upper_bound(v.begin(), v.end(), uint64_t{500'000}));
    s.over_1ms =
        static_cast<std::size_t>(v.end() - std::upper_bound(v.begin(), v.end(), uint64_t{1'000'000}));
    s.mean =
        static_cast<double>(std::accumulate(v.begin(), v.end(), uint64_t{0})) / static_cast<double>(v.size());
    return s;
}

inline void print(const char* label, const Summary& s, const char* unit_name = "ns", double unit = 1.0) {
    std::printf("%-28s n=%zu  median %.2f %s  p99 %.2f %s  p99.9 %.2f %s  mean %.2f %s  min %.2f  max %.2f\n",
                label, s.n, s.median / unit, unit_name, s.p99 / unit, unit_name, s.p999 / unit, unit_name,
                s.mean / unit, unit_name, s.min / unit, s.max / unit);
}

// The tail of a sample of round trips or latencies: p99.9, maximum and the counts over 500 us and 1 ms.
inline void print_tail(const char* label, const Summary& s) {
    std::printf("%-28s p99.9 %.2f us  max %.2f us  over 500 us: %zu  over 1 ms: %zu  (of %zu)\n", label,
                s.p999 / 1000.0, s.max / 1000.0, s.over_500us, s.over_1ms, s.n);
}

}  // namespace bench
