#pragma once
// The metrics of ../shared/docs/METRICS.md, computed from the synthesised world-space joints of
// every agent on every frame (after all mediator adjustments, exactly as rendered), streamed in
// memory that depends on the crowd's capacity, never on the number of frames:
//   - counts, means, minima and maxima are exact (sums in double precision);
//   - percentiles (p95, p99) come from QuantileSketch: within 0.1% of the exact order statistic
//     (mediator/quantile_sketch.h);
//   - each live agent keeps a few frames for its finite differences (heading, jerk, limb
//     accelerations) and 2 s of its feet, to apply the v1 foot-slide metric's own contact
//     definition (measurement only: no pose or planning code reads it; see
//     mediator/foot_slide_stream.h for its documented error);
//   - an agent's track is folded into the totals and released when the agent leaves.
// docs/metrics.md gives the error of every figure in METRICS.md's terms.

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include <glm/vec2.hpp>

#include "animation/analysis.h"
#include "crowd/crowd_source.h"
#include "mediator/foot_slide_stream.h"
#include "mediator/mediator.h"
#include "mediator/pose_synthesis.h"
#include "mediator/quantile_sketch.h"
#include "mediator/viewer_metrics.h"

namespace gk {

struct MetricsReport {
  SlideStats slide;
  int64_t slide_samples = 0;  // the exact count (slide.num_samples saturates at INT_MAX)
  // The measurement's own error against the v1 foot-slide definition: how far above that
  // definition's contact height, at most, a frame counted in contact lay because its foot went
  // lower more than FootSlideStream::kLag_s later [m]; 0: exact. (Reported, never steered by.)
  float slide_toe_band_excess_m = 0.0f;
  float slide_ankle_band_excess_m = 0.0f;
  Summary torsion_deg, facing_error_deg, heading_error_deg, root_error_cm, playback_rate;
  // Facing error over the agent-frames whose asked twist (theta against the pelvis) is within the
  // torsion limit: what the upper body could have reached.
  Summary facing_error_within_limit_deg;
  double playback_outside_limits = 0.0;         // fraction of agent-frames
  std::optional<double> feedback_speed_change;  // null when the mediator never changed v
  int64_t pop_count = 0;
  double max_root_jerk = 0.0;  // [m/s^3]
  int64_t agent_frames = 0;
  // Joint coordinates and samples that were NaN or infinite (0 in a sound run).
  int64_t non_finite = 0;
  // METRICS.md v2: the feet against the floor the clips were authored on, and the same figures of
  // the library's own clips (its floor).
  FeetReference feet_reference;
  ViewerFeetStats feet;
  ViewerFeetStats feet_floor;
};

class MetricsRecorder {
 public:
  // capacity: the most agents live at once (the mediator's capacity); per-agent state is sized
  // for it here, and record() allocates nothing.
  MetricsRecorder(const LocomotionLibrary& library, float frame_time_s, size_t capacity);
  // Records one frame after plan() and synthesis; `frame` is the crowd's frame the plan was for.
  // Agents of the previous frame that are missing from this one have left: their tracks end.
  // With `include_by_slot` (capacity long, level of detail: pipeline/lod.h) only the agents whose
  // slot is flagged are recorded; an agent left out ends its track, as if it had left.
  void record(const AgentFrame& frame, const Mediator& mediator, const PoseSynthesizer& poses,
              std::span<const uint8_t> include_by_slot = {});
  // The figures so far, as if every live agent's track ended now; recording may go on.
  MetricsReport finish() const;
  // Agents followed now (tracks not yet ended).
  size_t num_live_tracks() const;
  int64_t num_non_finite() const { return non_finite_; }

 private:
  // One agent's track in the slot the mediator gave it.
  struct Track {
    uint32_t id = 0;
    int64_t last_frame = -1;  // -1: no track in this slot
    int64_t frames = 0;
    glm::vec2 roots[3]{};  // the last three roots, newest last (heading, jerk)
  };
  void end_track(size_t slot);

  const LocomotionLibrary& library_;
  float dt_;
  size_t capacity_;
  FeetReference feet_reference_;
  ViewerFeetStats feet_floor_;
  int64_t frame_ = 0;
  std::vector<Track> tracks_;             // [slot]
  std::vector<ViewerTrack> feet_tracks_;  // [slot]
  FootSlideStream slide_;                 // feet [slot * 2 + side]
  ViewerFeetAccumulator feet_;
  StreamSummary torsion_, facing_, facing_within_, heading_, root_error_, rate_;
  double feedback_change_sum_ = 0.0;
  int64_t feedback_changes_ = 0;
  int64_t rate_outside_ = 0;
  int64_t pops_ = 0;
  int64_t agent_frames_ = 0;
  int64_t non_finite_ = 0;
  double max_jerk_ = 0.0;
};

}  // namespace gk
