#pragma once
// Clip analysis, done once at load: native speed and travel direction, foot contacts, the gait
// cycle and a normalised gait phase, and the foot-slide floor of ../shared/docs/METRICS.md.

#include <algorithm>
#include <string>
#include <vector>

#include "animation/clip.h"
#include "animation/skeleton.h"

namespace gk {

struct TimeInterval {
  float start_s = 0.0f;
  float end_s = 0.0f;
};

// Contact detection, velocity first: a foot is down while its ball or heel is nearly still over the
// ground and low. Speeds are relative to the clip's own travel speed so that a walk and a sprint
// are judged alike; heights relative to the joint's own range over the fitted ground.
struct ContactThresholds {
  float still_fraction_of_travel = 0.5f;  // [ratio] "still": slower than half the travel speed
  float min_still_speed_m_s = 0.2f;       // [m/s] and never a stricter limit than this (capture
                                          // jitter; standing clips)
  float height_gate_fraction = 0.3f;      // [ratio] low: within this share of the joint's range
  float min_height_gate_m = 0.02f;        // [m] of its lowest heights, and at least this
  float min_duration_s = 0.04f;           // [s] shorter contacts and gaps are jitter: dropped
};

// The speed over the ground below which a point counts as still [m/s], for a body travelling at
// travel_m_s: the larger of its share of the travel and the jitter floor.
inline float still_speed_m_s(float travel_m_s, const ContactThresholds& th = {}) {
  return std::max(th.min_still_speed_m_s, th.still_fraction_of_travel * travel_m_s);
}

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
  // [m/s] loops: per loop; takes: along the root's path (sampled every 0.5 s), which a take that
  // turns or stops covers faster than its net displacement; in place: from the stance foot
  float native_speed_m_s = 0.0f;
  float direction_rad = 0.0f;  // travel direction relative to the character's facing (0 = forward)
  TimeInterval cycle;          // one gait cycle (the loop points of a one-stride loop)
  std::vector<TimeInterval> contacts[2];  // [Side] foot contact intervals, in clip time
  // Per frame: gait phase in [0, 1), 0 at the left foot's contact start (linear between contacts;
  // a loop's contacts come round again after its duration, so its phase runs on across the seam).
  std::vector<float> phase;
  SlideStats floor;  // foot-slide metrics of the clip played with its own root motion
  // Ground under the feet, fitted to the lowest toe heights: y = ground_y0_m + ground_slope_m_s *
  // t. Mocap floors are rarely level (the CMU walk rises 5 cm over 2.6 s); contacts are measured
  // against this line rather than one global minimum, and then, in a take, against the floor of
  // each stance (a tilted floor is level under a planted foot, which a line in time is not).
  float ground_y0_m = 0.0f;
  float ground_slope_m_s = 0.0f;
};

ClipAnalysis analyze_clip(const Clip& clip, const Skeleton& skeleton,
                          const ContactThresholds& thresholds = {});

}  // namespace gk
