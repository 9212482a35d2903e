#pragma once
// The metrics of ../shared/docs/METRICS.md, computed from the synthesised world-space joints of
// every agent on every frame (after all mediator adjustments, exactly as rendered).

#include <cstdint>
#include <optional>
#include <unordered_map>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "animation/analysis.h"
#include "crowd/crowd_source.h"
#include "mediator/mediator.h"
#include "mediator/pose_synthesis.h"
#include "mediator/viewer_metrics.h"

namespace gk {

struct Summary {
  double mean = 0.0, p95 = 0.0, max = 0.0, min = 0.0;
  size_t count = 0;
};

struct MetricsReport {
  SlideStats slide;
  Summary torsion_deg, facing_error_deg, heading_error_deg, root_error_cm, playback_rate;
  // Facing error over the agent-frames whose asked twist (theta against the pelvis) is within the
  // torsion limit: what the upper body could have reached.
  Summary facing_error_within_limit_deg;
  double playback_outside_limits = 0.0;         // fraction of agent-frames
  std::optional<double> feedback_speed_change;  // null when the mediator never changed v
  int64_t pop_count = 0;
  double max_root_jerk = 0.0;  // [m/s^3]
  int64_t agent_frames = 0;
  // METRICS.md v2: the feet against the floor the clips were authored on, and the same figures of
  // the library's own clips (its floor).
  FeetReference feet_reference;
  ViewerFeetStats feet;
  ViewerFeetStats feet_floor;
};

// Summary of samples: mean, nearest-rank p95, min, max.
Summary summarize(std::vector<float>& samples);

class MetricsRecorder {
 public:
  // frames_hint: expected frames (storage is reserved for it).
  MetricsRecorder(const LocomotionLibrary& library, float frame_time_s, size_t capacity,
                  size_t frames_hint);
  // Records one frame after plan() and synthesis; `frame` is the crowd's frame the plan was for.
  void record(const AgentFrame& frame, const Mediator& mediator, const PoseSynthesizer& poses);
  MetricsReport finish() const;

 private:
  struct Track {
    std::vector<glm::vec3> toe[2], ankle[2], knee[2];
    std::vector<glm::vec2> root;
    int last_frame = -1;
  };
  const LocomotionLibrary& library_;
  float dt_;
  size_t frames_hint_;
  FeetReference feet_reference_;
  ViewerFeetStats feet_floor_;
  int frame_ = 0;
  std::unordered_map<uint32_t, Track> tracks_;
  std::vector<Track> finished_;
  std::vector<float> torsion_, facing_, facing_within_, heading_, root_error_, rate_,
      feedback_change_;
  int64_t rate_outside_ = 0;
  int64_t pops_ = 0;
  int64_t agent_frames_ = 0;
};

}  // namespace gk
