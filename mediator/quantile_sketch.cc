#include "mediator/quantile_sketch.h"

#include <algorithm>

namespace gk {
namespace {

// ln(gamma) = 2 atanh(a), by its series (constant-initialised: no static-order question for
// sketches built during static initialisation).
constexpr double atanh_series(double a) {
  double term = a, sum = 0.0;
  for (int k = 1; k < 40; k += 2, term *= a * a) sum += term / k;
  return sum;
}
constexpr double kLogGamma = 2.0 * atanh_series(QuantileSketch::kRelativeError);
constexpr double kLn10 = 2.302585092994045684;
// ln(kMaxValue / kMinValue) = 15 ln 10.
constexpr double kDecadesSpanned = 15.0;
static_assert(QuantileSketch::kMaxValue / QuantileSketch::kMinValue > 0.999e15 &&
              QuantileSketch::kMaxValue / QuantileSketch::kMinValue < 1.001e15);
constexpr int kNumBins = static_cast<int>(kDecadesSpanned * kLn10 / kLogGamma) + 1;

// The point of bin i within the relative error of both its edges: 2 gamma / (1 + gamma) times the
// lower edge (|r - x| / x <= (gamma - 1) / (gamma + 1) = kRelativeError for x in the bin).
double representative(int i) {
  const double gamma = std::exp(kLogGamma);
  return QuantileSketch::kMinValue * std::exp(i * kLogGamma) * (2.0 * gamma / (1.0 + gamma));
}

}  // namespace

QuantileSketch::QuantileSketch() : bins_(static_cast<size_t>(kNumBins), 0) {}

int QuantileSketch::num_bins() { return kNumBins; }

size_t QuantileSketch::bin_of(double x) {
  const int i = static_cast<int>(std::log(x / kMinValue) / kLogGamma);
  return static_cast<size_t>(std::clamp(i, 0, kNumBins - 1));
}

void QuantileSketch::merge(const QuantileSketch& o) {
  for (size_t i = 0; i < bins_.size(); ++i) bins_[i] += o.bins_[i];
  count_ += o.count_;
  nan_ += o.nan_;
  zero_ += o.zero_;
  tiny_ += o.tiny_;
  huge_ += o.huge_;
  min_ = std::min(min_, o.min_);
  max_ = std::max(max_, o.max_);
}

double QuantileSketch::value_at_rank(uint64_t k) const {
  if (count_ == 0) return 0.0;
  if (k + 1 >= count_) return max_;
  if (k == 0) return min_;
  double v = max_;  // in the overflow bin
  uint64_t seen = zero_;
  if (k < seen) {
    v = 0.0;
  } else if (k < (seen += tiny_)) {
    v = 0.5 * kMinValue;
  } else {
    for (int i = 0; i < kNumBins; ++i) {
      seen += bins_[static_cast<size_t>(i)];
      if (k < seen) {
        v = representative(i);
        break;
      }
    }
  }
  return std::clamp(v, min_, max_);
}

double QuantileSketch::nearest_rank(double q) const {
  if (count_ == 0) return 0.0;
  const auto k = static_cast<uint64_t>(std::ceil(q * static_cast<double>(count_)));
  return value_at_rank(std::clamp<uint64_t>(k, 1, count_) - 1);
}

double QuantileSketch::floor_rank(double q) const {
  if (count_ == 0) return 0.0;
  const auto k = static_cast<uint64_t>(std::clamp(q, 0.0, 1.0) * static_cast<double>(count_));
  return value_at_rank(std::min(k, count_ - 1));
}

void StreamSummary::merge(const StreamSummary& o) {
  sum_ += o.sum_;
  sketch_.merge(o.sketch_);
}

Summary StreamSummary::summary() const {
  Summary s;
  s.count = static_cast<size_t>(sketch_.count());
  if (s.count == 0) return s;
  s.mean = sum_ / static_cast<double>(s.count);
  s.min = sketch_.min();
  s.max = sketch_.max();
  s.p95 = sketch_.nearest_rank(0.95);
  return s;
}

}  // namespace gk
