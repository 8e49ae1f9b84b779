#include "ecat/latency.hpp"

#include <algorithm>
#include <cmath>
#include <ostream>

namespace ecat {

uint64_t LatencyHistogram::percentile_ns(double p) const {
    if (count_ == 0) return 0;
    if (p <= 0.0) return min_;  // the smallest sample, exact
    p = std::min(p, 1.0);
    // Nearest rank: the smallest sample with at least p * count samples at or below it.
    uint64_t rank = static_cast<uint64_t>(std::ceil(p * static_cast<double>(count_)));
    rank = std::clamp<uint64_t>(rank, 1, count_);
    uint64_t seen = 0;
    for (std::size_t i = 0; i < bins_.size(); ++i) {
        seen += bins_[i];
        if (seen < rank) continue;
        uint64_t upper;
        if (i < kFineBins) {
            upper = (i + 1) * kFineBinNs - 1;
        } else if (i < kFineBins + kCoarseBins) {
            upper = kFineRangeNs + (i - kFineBins + 1) * kCoarseBinNs - 1;
        } else {
            upper = max_;
        }
        return std::clamp(upper, min_, max_);
    }
    return max_;
}

void LatencyHistogram::print(std::ostream& out, std::string_view prefix) const {
    out << prefix << ".count " << count_ << '\n'
        << prefix << ".min_ns " << min_ns() << '\n'
        << prefix << ".p50_ns " << percentile_ns(0.5) << '\n'
        << prefix << ".p99_ns " << percentile_ns(0.99) << '\n'
        << prefix << ".max_ns " << max_ns() << '\n'
        << prefix << ".mean_ns " << mean_ns() << '\n';
}

}  // namespace ecat
