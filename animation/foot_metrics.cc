#include "animation/foot_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace gk {

void measure_contacts(std::span<const glm::vec3> toe, std::span<const glm::vec3> ankle,
                      std::span<uint8_t> out_contact) {
  float min_t = std::numeric_limits<float>::infinity();
  float min_a = std::numeric_limits<float>::infinity();
  for (const glm::vec3& p : toe) min_t = std::min(min_t, p.y);
  for (const glm::vec3& p : ankle) min_a = std::min(min_a, p.y);
  for (size_t i = 0; i < toe.size(); ++i) {
    out_contact[i] = toe[i].y <= min_t + kContactToeBandM && ankle[i].y <= min_a + kContactAnkleBandM;
  }
}

void SlideAccumulator::add_track(std::span<const glm::vec3> toe, std::span<const glm::vec3> ankle,
                                 float dt_s) {
  contact_scratch_.resize(toe.size());
  measure_contacts(toe, ankle, contact_scratch_);
  // Copy because add_track_with_contacts may be handed our own scratch by a caller.
  const std::vector<uint8_t> contact = contact_scratch_;
  add_track_with_contacts(toe, contact, dt_s);
}

void SlideAccumulator::add_track_with_contacts(std::span<const glm::vec3> toe,
                                               std::span<const uint8_t> contact, float dt_s) {
  auto horizontal = [](const glm::vec3& a, const glm::vec3& b) {
    return std::hypot(a.x - b.x, a.z - b.z);
  };
  size_t run_start = 0;
  bool in_run = false;
  for (size_t i = 0; i < toe.size(); ++i) {
    if (contact[i]) {
      if (!in_run) {
        in_run = true;
        run_start = i;
      }
      if (i > 0 && contact[i - 1]) {
        speeds_cm_s_.push_back(100.0f * horizontal(toe[i], toe[i - 1]) / dt_s);
      }
    }
    const bool run_ends = in_run && (!contact[i] || i + 1 == toe.size());
    if (run_ends) {
      const size_t last = contact[i] ? i : i - 1;
      if (last > run_start) {  // an interval is at least two consecutive contact frames
        drift_sum_cm_ += 100.0 * horizontal(toe[last], toe[run_start]);
        ++num_intervals_;
      }
      in_run = false;
    }
  }
}

SlideStats SlideAccumulator::finish() const {
  SlideStats s;
  s.num_samples = static_cast<int>(speeds_cm_s_.size());
  if (!speeds_cm_s_.empty()) {
    double sum = 0.0;
    int skating = 0;
    for (float v : speeds_cm_s_) {
      sum += v;
      skating += v > kSkateThresholdCmS;
    }
    s.mean_cm_s = static_cast<float>(sum / speeds_cm_s_.size());
    s.skate_ratio = static_cast<float>(skating) / speeds_cm_s_.size();
    std::vector<float> sorted = speeds_cm_s_;
    const size_t k = static_cast<size_t>(std::ceil(0.95 * sorted.size())) - 1;
    std::nth_element(sorted.begin(), sorted.begin() + k, sorted.end());
    s.p95_cm_s = sorted[k];
  }
  if (num_intervals_ > 0) s.drift_cm_per_step = static_cast<float>(drift_sum_cm_ / num_intervals_);
  return s;
}

}  // namespace gk
