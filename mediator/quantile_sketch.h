#pragma once
// Streaming statistics in fixed memory, for runs of any length: exact count, sum, min and max,
// and order statistics (p95, p99, median) from a fixed logarithmic histogram.
//
// QuantileSketch: bins a ratio gamma = (1 + a) / (1 - a) apart over [kMinValue, kMaxValue), each
// answered by the point 2 gamma / (1 + gamma) times its lower edge, which is within a relative
// error a = kRelativeError of every value of the bin (the bound of DDSketch, Masson, Rim and Lee,
// VLDB 2019). Any order statistic x (the k-th smallest sample) is therefore returned:
//   - within kRelativeError * x when kMinValue <= x < kMaxValue,
//   - exactly when x <= 0 (samples are non-negative here: a negative one counts as 0),
//   - within kMinValue when 0 < x < kMinValue,
//   - as the exact maximum when x >= kMaxValue,
// and never outside the exact [min, max] of the samples. The histogram has 17,270 64-bit counters
// (135 KiB), whatever the number of samples; add() allocates nothing.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace gk {

struct Summary {
  double mean = 0.0, p95 = 0.0, max = 0.0, min = 0.0;
  size_t count = 0;
};

class QuantileSketch {
 public:
  static constexpr double kRelativeError = 1e-3;
  static constexpr double kMinValue = 1e-6;  // in the samples' own unit
  static constexpr double kMaxValue = 1e9;

  QuantileSketch();
  // A NaN is counted in num_nan() only.
  void add(double x) {
    if (std::isnan(x)) {
      ++nan_;
      return;
    }
    ++count_;
    if (x <= 0.0) {
      ++zero_;
    } else if (x < kMinValue) {
      ++tiny_;
    } else if (x >= kMaxValue) {
      ++huge_;
    } else {
      ++bins_[bin_of(x)];
    }
    min_ = std::min(min_, x);
    max_ = std::max(max_, x);
  }
  void merge(const QuantileSketch& other);

  uint64_t count() const { return count_; }
  uint64_t num_nan() const { return nan_; }
  double min() const { return count_ ? min_ : 0.0; }
  double max() const { return count_ ? max_ : 0.0; }
  // The k-th smallest sample (k = 0 is the minimum), within the error above; 0 when empty.
  double value_at_rank(uint64_t k) const;
  // Nearest rank: the ceil(q n)-th smallest (METRICS.md's p95 of summaries and of stage times).
  double nearest_rank(double q) const;
  // The sample at index floor(q n) of the sorted samples (common/stats.h's percentile()).
  double floor_rank(double q) const;

  static int num_bins();

 private:
  static size_t bin_of(double x);
  std::vector<uint64_t> bins_;
  uint64_t count_ = 0, nan_ = 0, zero_ = 0, tiny_ = 0, huge_ = 0;
  double min_ = std::numeric_limits<double>::infinity();
  double max_ = -std::numeric_limits<double>::infinity();
};

// Exact count, mean, min and max, and a sketched p95, of a stream of samples.
class StreamSummary {
 public:
  void add(double x) {
    sum_ += x;  // a NaN makes the mean NaN, as it would over stored samples
    sketch_.add(x);
  }
  void merge(const StreamSummary& other);
  Summary summary() const;
  const QuantileSketch& sketch() const { return sketch_; }

 private:
  double sum_ = 0.0;
  QuantileSketch sketch_;
};

}  // namespace gk
