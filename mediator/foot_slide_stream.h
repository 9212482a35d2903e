#pragma once
// METRICS.md v1 foot slide (foot_slide_cm_s, its p95, skate_ratio, foot_drift_cm_per_step) over
// any number of feet and tracks of any length, in fixed memory per foot.
//
// METRICS.md puts a foot in contact on frame t when its toe is within 2.5 cm and its ankle within
// 5 cm of the lowest heights they reach over the agent's whole run: known only when the run ends.
// Here frame t is decided kLag_s later, against the lowest heights of the track up to t + kLag_s
// (and the last kLag_s of a track, when it ends, against the lowest of the whole track), so a foot
// holds kLag_s of frames (16 bytes each). The result is METRICS.md's exactly unless a foot reaches
// a new lowest height more than kLag_s after a frame it was in contact on; then the frames already
// decided were measured against a band higher by that drop. finish() reports by how much at most:
// `toe_band_excess_m` and `ankle_band_excess_m`, the largest height above METRICS.md's band of any
// frame counted in contact. The samples then lie between METRICS.md's (band of 2.5 cm and 5 cm)
// and those of a band wider by the excess: count, sum of speeds and skating samples between the
// two. kLag_s covers the settling of a new track (its first stride; a slow walk's stride takes
// about 1.2 s).
//
// The slide speeds' p95 comes from a QuantileSketch (within its relative error of 0.1%); means,
// counts and drift are summed exactly.

#include <cstdint>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "animation/analysis.h"
#include "animation/foot_metrics.h"
#include "mediator/quantile_sketch.h"

namespace gk {

struct FootSlideResult {
  SlideStats stats;                // num_samples saturates at INT_MAX; `samples` is the count
  int64_t samples = 0;             // slide samples (pairs of contact frames)
  int64_t intervals = 0;           // contact intervals (drift)
  float toe_band_excess_m = 0.0f;  // see above; 0 when the result is METRICS.md's exactly
  float ankle_band_excess_m = 0.0f;
};

class FootSlideStream {
 public:
  static constexpr float kLag_s = 2.0f;
  // METRICS.md v1's definitions, shared with the exact measure (animation/foot_metrics.h).
  static constexpr float kToeBandM = kContactToeBandM;
  static constexpr float kAnkleBandM = kContactAnkleBandM;
  static constexpr float kSkateCmS = kSkateThresholdCmS;

  // num_feet: feet that can be followed at once (2 x agents); dt_s: the frame time.
  FootSlideStream(size_t num_feet, float dt_s);

  // Begins a new track on `foot` (ending any open one first).
  void start(size_t foot);
  // The foot's toe position and ankle height on the track's next frame.
  void add(size_t foot, const glm::vec3& toe, float ankle_y);
  // Ends the foot's track: its last kLag_s are decided against the track's lowest heights.
  void end(size_t foot);
  bool active(size_t foot) const { return feet_[foot].active; }
  int lag_frames() const { return lag_frames_; }

  // The figures as if every open track ended now (the open tracks themselves are not changed).
  FootSlideResult finish() const;

 private:
  struct Frame {
    glm::vec3 toe;
    float ankle_y;
  };
  // One foot's track: the frames not yet decided are in the ring, the decided ones in the rest.
  struct Foot {
    bool active = false;
    bool prev_contact = false, in_run = false;
    int64_t added = 0, decided = 0;
    int64_t run_frames = 0;
    float min_toe_y = 0.0f, min_ankle_y = 0.0f;                      // over every frame added
    float max_contact_toe_y = -1e30f, max_contact_ankle_y = -1e30f;  // over decided contacts
    glm::vec2 prev_xz{0.0f}, run_start_xz{0.0f};  // toe (x, z) of the last decided frame
  };
  struct Totals {
    QuantileSketch speeds_cm_s;
    double speed_sum_cm_s = 0.0;
    int64_t skating = 0;
    double drift_sum_cm = 0.0;
    int64_t intervals = 0;
    float toe_excess_m = 0.0f, ankle_excess_m = 0.0f;
  };
  const Frame& ring_at(size_t foot, int64_t frame) const {
    return ring_[foot * ring_size_ + static_cast<size_t>(frame % ring_size_)];
  }
  void decide(Foot& f, const Frame& x, Totals& t) const;
  // Decides the frames left in the ring against the track's lowest heights and closes the run.
  void finish_foot(size_t foot, Foot& f, Totals& t) const;

  float dt_s_;
  int lag_frames_;
  int64_t ring_size_;
  std::vector<Foot> feet_;
  std::vector<Frame> ring_;  // [foot * ring_size_ + frame % ring_size_]
  Totals totals_;
};

}  // namespace gk
