#pragma once
// Clip analysis, done once at load: native speed and travel direction, foot contacts, the gait
// cycle and a normalised gait phase, and the foot-slide floor of ../shared/docs/METRICS.md.

#include <string>
#include <vector>

#include "animation/clip.h"
#include "animation/skeleton.h"

namespace gk {

struct TimeInterval {
  float start_s = 0.0f;
  float end_s = 0.0f;
};

struct ContactThresholds {
  float height_above_min_m = 0.025f;  // toe height above its lowest point (METRICS.md)
  float ankle_above_min_m = 0.05f;    // ankle height above its lowest point (METRICS.md)
  float max_speed_m_s = 0.6f;         // horizontal toe speed relative to the ground
  float min_duration_s = 0.04f;       // shorter contacts and gaps are capture jitter: dropped
};

struct SlideStats {
  float mean_cm_s = 0.0f;
  float p95_cm_s = 0.0f;
  float skate_ratio = 0.0f;
  float drift_cm_per_step = 0.0f;
  int num_samples = 0;
};

struct ClipAnalysis {
  std::string name;
  float fps = 0.0f;
  int num_frames = 0;
  float duration_s = 0.0f;
  bool in_place = false;  // no horizontal root motion: speed inferred from the stance foot
  float native_speed_m_s = 0.0f;
  float direction_rad = 0.0f;  // travel direction relative to the character's facing (0 = forward)
  TimeInterval cycle;          // one gait cycle (loop points)
  std::vector<TimeInterval> contacts[2];  // [Side] foot contact intervals, in clip time
  // Per frame: gait phase in [0, 1), 0 at the left foot's contact start (linear between contacts).
  std::vector<float> phase;
  SlideStats floor;  // foot-slide metrics of the clip played with its own root motion
  // Ground under the feet, fitted to the lowest toe heights: y = ground_y0_m + ground_slope_m_s *
  // t. Mocap floors are rarely level (the CMU walk rises 5 cm over 2.6 s); contacts are measured
  // against this line rather than one global minimum.
  float ground_y0_m = 0.0f;
  float ground_slope_m_s = 0.0f;
};

ClipAnalysis analyze_clip(const Clip& clip, const Skeleton& skeleton,
                          const ContactThresholds& thresholds = {});

}  // namespace gk
