#pragma once
// Foot-slide metrics exactly as defined in ../shared/docs/METRICS.md, over world-space toe and
// ankle tracks of one foot (one position per frame). Shared by clip analysis (the floor of a clip
// played with its own root motion) and the mediator's crowd metrics.

#include <span>
#include <vector>

#include <glm/vec3.hpp>

#include "animation/analysis.h"

namespace gk {

// METRICS.md v1's definitions (the metric's, not tuning): a foot is in contact while its toe is
// within kContactToeBandM and its ankle within kContactAnkleBandM of their lowest heights; a
// contact sample faster than kSkateThresholdCmS skates.
inline constexpr float kContactToeBandM = 0.025f;
inline constexpr float kContactAnkleBandM = 0.05f;
inline constexpr float kSkateThresholdCmS = 30.0f;

// Contact per METRICS.md v1, with the minima over the whole track. out_contact must have the
// tracks' length.
void measure_contacts(std::span<const glm::vec3> toe, std::span<const glm::vec3> ankle,
                      std::span<uint8_t> out_contact);

// Accumulates slide samples over any number of foot tracks, then reports mean, p95, skate ratio
// (> 30 cm/s) and drift per contact interval.
class SlideAccumulator {
 public:
  // toe/ankle: one foot's positions on consecutive frames dt_s apart.
  void add_track(std::span<const glm::vec3> toe, std::span<const glm::vec3> ankle, float dt_s);
  // Adds a track whose contact flags are already known.
  void add_track_with_contacts(std::span<const glm::vec3> toe, std::span<const uint8_t> contact,
                               float dt_s);
  SlideStats finish() const;
  size_t num_samples() const { return speeds_cm_s_.size(); }

 private:
  std::vector<float> speeds_cm_s_;
  std::vector<uint8_t> contact_scratch_;
  double drift_sum_cm_ = 0.0;
  int num_intervals_ = 0;
};

}  // namespace gk
