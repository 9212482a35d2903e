#pragma once
// METRICS.md v2, "What a viewer sees of the feet": the feet measured against the floor the clips
// were authored on. The constants below are that document's definitions (a measurement, not a
// motion parameter: no motion code reads them). One accumulator serves the crowd
// (MetricsRecorder) and the library's own clips played with their root motion (the floor every
// figure is reported beside), streaming every track frame by frame in fixed memory.

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glm/ext/vector_double3.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "mediator/locomotion_library.h"
#include "mediator/quantile_sketch.h"

namespace gk {

// The leg joints the v2 metrics follow, per side: toe (ball), ankle, knee.
enum class LimbJoint : uint8_t { kToe = 0, kAnkle = 1, kKnee = 2 };
inline constexpr int kNumLimbJoints = 3;

// What the library says about its feet, for a run at one frame rate.
struct FeetReference {
  // Floor height of each toe and ankle [m]: median height over the frames clip analysis marks as
  // contact, over every locomotion clip of the library, as drawn (library scale and ground).
  float toe_floor_m[2] = {0.0f, 0.0f};
  float ankle_floor_m[2] = {0.0f, 0.0f};
  // 99.9th percentile of each limb joint's world acceleration over the locomotion clips played
  // with their own root motion at native rate, resampled to the run's frame rate [m/s^2];
  // [LimbJoint][Side].
  float accel_m_s2[kNumLimbJoints][2] = {};
};

// Computes the reference of a library for a run with frame time dt_s.
FeetReference make_feet_reference(const LocomotionLibrary& library, float dt_s);

// One agent's consecutive frames (all spans of one length).
struct LimbTrack {
  std::span<const glm::vec3> joint[kNumLimbJoints][2];  // [LimbJoint][Side]
  std::span<const glm::vec2> root;                      // pelvis projected on the ground
};

// One frame of one agent: its limb joints and root.
struct LimbFrame {
  glm::vec3 joint[kNumLimbJoints][2];  // [LimbJoint][Side]
  glm::vec2 root;
};

// What one agent's track carries from frame to frame: its last two frames (an acceleration needs
// the frames before and after) and where the 20 fps resampling has got to. A plain value: a
// default-constructed one starts a track.
struct ViewerTrack {
  LimbFrame last[2]{};  // frames n - 2 and n - 1
  int64_t frames = 0;
  int64_t next_gmd = 1;      // next 20 fps sample
  glm::dvec3 gmd_prev[2]{};  // both toes on the last 20 fps sample
};

struct ViewerFeetStats {
  // Support foot (the lower toe relative to its floor) slide over frame pairs on which it stays
  // the support foot within 5 cm of its floor.
  double support_slide_cm_s = 0.0, support_slide_p95_cm_s = 0.0, support_skate_ratio = 0.0;
  int64_t support_samples = 0;
  // Agent-frames at walking speed (0.1-2.2 m/s) with neither toe within 5 cm of its floor.
  double float_ratio = 0.0;
  int64_t float_samples = 0;
  // Depth of a foot (its toe or ankle, the deeper) below its floor, over all foot-frames [cm].
  double penetration_p99_cm = 0.0, penetration_max_cm = 0.0, penetration_ratio = 0.0;
  int64_t penetration_samples = 0;
  // Agent-frames on which a knee, ankle or toe accelerates beyond twice its reference, per
  // agent-minute.
  double limb_pop_rate = 0.0;
  int64_t limb_pops = 0;
  // Foot-skating ratio of the motion-generation literature (20 fps, 5 cm, 0.5 m/s).
  double gmd_skate_ratio = 0.0;
  int64_t gmd_frames = 0;
  int64_t agent_frames = 0;
};

// Streams tracks frame by frame in fixed memory: counts, sums and the maximum are exact; the
// percentiles (support slide p95, penetration p99) come from QuantileSketch, within 0.1% of the
// exact order statistic (see mediator/quantile_sketch.h).
class ViewerFeetAccumulator {
 public:
  // METRICS.md v2 definitions:
  static constexpr float kNearFloorM = 0.05f;         // [m] "within 5 cm of its floor height"
  static constexpr float kSkateCmS = 30.0f;           // [cm/s] support samples counted as skating
  static constexpr float kFloatMinSpeed = 0.1f;       // [m/s] walking, no flight phase
  static constexpr float kFloatMaxSpeed = 2.2f;       // [m/s]
  static constexpr float kPenetrationCountM = 0.01f;  // ratio counts feet deeper than this
  static constexpr float kGmdRateHz = 20.0f;
  static constexpr float kGmdSkateM_S = 0.5f;

  explicit ViewerFeetAccumulator(const FeetReference& reference) : ref_(reference) {}
  // The next frame of a track (frames dt_s apart; one dt_s for all tracks).
  void add_frame(ViewerTrack& track, const LimbFrame& frame, float dt_s);
  // Ends a track: its last 20 fps samples. The track may then start again from ViewerTrack().
  void end_track(const ViewerTrack& track, float dt_s);
  // A whole track: add_frame for each frame, then end_track.
  void add_track(const LimbTrack& track, float dt_s);
  ViewerFeetStats finish() const;

 private:
  void add_gmd_sample(ViewerTrack& t, const glm::dvec3 toe[2]);
  FeetReference ref_;
  StreamSummary support_cm_s_;
  QuantileSketch depth_cm_;
  int64_t support_skates_ = 0;
  int64_t float_frames_ = 0, float_samples_ = 0;
  int64_t deep_ = 0;
  int64_t pops_ = 0;
  int64_t gmd_skates_ = 0, gmd_frames_ = 0;
  int64_t agent_frames_ = 0;
  double seconds_ = 0.0;
};

// The v2 figures of the library's own locomotion clips, each played once with its own root motion
// at dt_s: the floor a crowd run is compared with.
ViewerFeetStats library_feet_floor(const LocomotionLibrary& library, const FeetReference& ref,
                                   float dt_s);

// Joint names of the toe, ankle and knee of one side, for the report.
std::string limb_joint_name(const Skeleton& skeleton, LimbJoint joint, Side side);

}  // namespace gk
