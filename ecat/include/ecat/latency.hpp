#pragma once
// A latency histogram of fixed size: adding a sample allocates nothing and costs a few instructions, so
// it can run in every process-data cycle. 100 ns bins up to 100 us, 10 us bins up to 10 ms, one bin for
// everything longer; count, sum, min and max are exact. Percentiles are the upper edge of the bin that
// holds them (never above the exact max), i.e. at most one bin width pessimistic.
#include <array>
#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <string_view>

namespace ecat {

class LatencyHistogram {
  public:
    static constexpr uint64_t kFineBinNs = 100;
    static constexpr std::size_t kFineBins = 1000;  // [0, 100 us)
    static constexpr uint64_t kCoarseBinNs = 10'000;
    static constexpr std::size_t kCoarseBins = 990;  // [100 us, 10 ms)
    static constexpr uint64_t kFineRangeNs = kFineBinNs * kFineBins;
    static constexpr uint64_t kRangeNs = kFineRangeNs + kCoarseBinNs * kCoarseBins;

    void add(uint64_t ns) {
        std::size_t bin;
        if (ns < kFineRangeNs) {
            bin = static_cast<std::size_t>(ns / kFineBinNs);
        } else if (ns < kRangeNs) {
            bin = kFineBins + static_cast<std::size_t>((ns - kFineRangeNs) / kCoarseBinNs);
        } else {
            bin = kFineBins + kCoarseBins;
        }
        ++bins_[bin];
        ++count_;
        sum_ += ns;
        if (ns < min_) min_ = ns;
        if (ns > max_) max_ = ns;
    }
    void clear() { *this = LatencyHistogram{}; }
    // Adds every sample of another histogram (statistics of a whole run across firmware restarts).
    void merge(const LatencyHistogram& o) {
        for (std::size_t i = 0; i < bins_.size(); ++i)
            bins_[i] += o.bins_[i];
        count_ += o.count_;
        sum_ += o.sum_;
        if (o.count_ != 0 && o.min_ < min_) min_ = o.min_;
        if (o.max_ > max_) max_ = o.max_;
    }

    uint64_t count() const { return count_; }
    uint64_t min_ns() const { return count_ ? min_ : 0; }
    uint64_t max_ns() const { return max_; }
    uint64_t mean_ns() const { return count_ ? sum_ / count_ : 0; }
    // Samples of kRangeNs or more (counted, with their exact max, but not placed).
    uint64_t overflow() const { return bins_[kFineBins + kCoarseBins]; }
    // The p-quantile, p in [0, 1] (0.5: median, 0.99: p99); 0 when empty.
    uint64_t percentile_ns(double p) const;

    // "<prefix>.count N", ".min_ns", ".p50_ns", ".p99_ns", ".max_ns", ".mean_ns" lines.
    void print(std::ostream& out, std::string_view prefix) const;

  private:
    std::array<uint64_t, kFineBins + kCoarseBins + 1> bins_{};
    uint64_t count_ = 0;
    uint64_t sum_ = 0;
    uint64_t min_ = UINT64_MAX;
    uint64_t max_ = 0;
};

}  // namespace ecat
