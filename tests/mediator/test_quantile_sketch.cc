// QuantileSketch against sorted samples: every order statistic within the documented error, over
// samples spanning many decades, with zeros, tiny values, duplicates and values beyond the range.

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "mediator/quantile_sketch.h"

namespace gk {
namespace {

// The documented bound of the k-th smallest sample x (mediator/quantile_sketch.h), with a margin
// of 1e-9 relative for the rounding of the bin index at a bin's edge.
void expect_within_bound(double estimate, double x, double max, uint64_t k) {
  if (x <= 0.0) {
    EXPECT_EQ(estimate, 0.0) << "rank " << k;
  } else if (x < QuantileSketch::kMinValue) {
    EXPECT_NEAR(estimate, x, QuantileSketch::kMinValue) << "rank " << k;
  } else if (x >= QuantileSketch::kMaxValue) {
    EXPECT_EQ(estimate, max) << "rank " << k;
  } else {
    EXPECT_NEAR(estimate, x, x * (QuantileSketch::kRelativeError + 1e-9)) << "rank " << k;
  }
}

std::vector<double> mixed_samples(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::lognormal_distribution<double> wide(0.0, 6.0);  // about 1e-8 .. 1e8
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<double> v;
  v.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    const double u = unit(rng);
    if (u < 0.1) {
      v.push_back(0.0);
    } else if (u < 0.15) {
      v.push_back(2.5);  // many equal values
    } else if (u < 0.16) {
      v.push_back(3e9 * (1.0 + u));  // beyond kMaxValue
    } else {
      v.push_back(wide(rng));
    }
  }
  return v;
}

TEST(QuantileSketch, EveryRankWithinTheDocumentedError) {
  const std::vector<double> samples = mixed_samples(200'000, 7);
  QuantileSketch sketch;
  for (double x : samples) sketch.add(x);
  std::vector<double> sorted = samples;
  std::sort(sorted.begin(), sorted.end());
  ASSERT_EQ(sketch.count(), sorted.size());
  EXPECT_EQ(sketch.min(), sorted.front());
  EXPECT_EQ(sketch.max(), sorted.back());
  for (uint64_t k = 0; k < sorted.size(); k += 97) {
    expect_within_bound(sketch.value_at_rank(k), sorted[k], sorted.back(), k);
  }
  for (double q : {0.5, 0.9, 0.95, 0.99, 0.999}) {
    const auto nearest = static_cast<size_t>(std::ceil(q * sorted.size())) - 1;
    expect_within_bound(sketch.nearest_rank(q), sorted[nearest], sorted.back(), nearest);
    const auto floor_k = static_cast<size_t>(q * sorted.size());
    expect_within_bound(sketch.floor_rank(q), sorted[floor_k], sorted.back(), floor_k);
  }
  // Not better than documented by accident of the data: a value at a bin's far edge is off by
  // nearly the whole bound.
  double worst = 0.0;
  for (uint64_t k = 0; k < sorted.size(); k += 97) {
    const double x = sorted[k];
    if (x >= QuantileSketch::kMinValue && x < QuantileSketch::kMaxValue) {
      worst = std::max(worst, std::abs(sketch.value_at_rank(k) - x) / x);
    }
  }
  EXPECT_GT(worst, 0.5 * QuantileSketch::kRelativeError);
}

TEST(QuantileSketch, MergeEqualsOneSketchOfAllSamples) {
  const std::vector<double> a = mixed_samples(50'000, 1), b = mixed_samples(30'000, 2);
  QuantileSketch sa, sb, all;
  for (double x : a) sa.add(x), all.add(x);
  for (double x : b) sb.add(x), all.add(x);
  sa.merge(sb);
  ASSERT_EQ(sa.count(), all.count());
  for (uint64_t k = 0; k < all.count(); k += 101) {
    EXPECT_EQ(sa.value_at_rank(k), all.value_at_rank(k)) << k;
  }
}

TEST(QuantileSketch, SummaryMeanIsExactAndNanIsCounted) {
  StreamSummary s;
  for (double x : {1.0, 2.0, 3.0, 4.0}) s.add(x);
  Summary r = s.summary();
  EXPECT_EQ(r.count, 4u);
  EXPECT_DOUBLE_EQ(r.mean, 2.5);
  EXPECT_EQ(r.min, 1.0);
  EXPECT_EQ(r.max, 4.0);
  EXPECT_EQ(r.p95, 4.0);  // nearest rank ceil(0.95 * 4) = 4th: the maximum, exactly
  s.add(std::nan(""));
  r = s.summary();
  EXPECT_EQ(r.count, 4u);
  EXPECT_EQ(s.sketch().num_nan(), 1u);
  EXPECT_TRUE(std::isnan(r.mean));  // a NaN is not hidden from the mean
}

TEST(QuantileSketch, EmptyAndFixedSize) {
  QuantileSketch s;
  EXPECT_EQ(s.count(), 0u);
  EXPECT_EQ(s.nearest_rank(0.95), 0.0);
  EXPECT_EQ(s.value_at_rank(0), 0.0);
  // 15 decades at a bin ratio of (1 + 0.001) / (1 - 0.001).
  const double expected = std::log(1e15) / std::log(1.001 / 0.999);
  EXPECT_NEAR(QuantileSketch::num_bins(), expected, 1.0);
}

}  // namespace
}  // namespace gk
