#pragma once
// The mediator's output for one frame, per slot (structure of arrays sized for the crowd's
// capacity): what pose synthesis and the metrics read. Its own header so that pose synthesis
// depends on the plans, not on the Mediator that makes them.

#include <cstdint>
#include <vector>

#include <glm/vec2.hpp>

namespace gk {

inline constexpr int kMaxBlendLayers = 4;
// From this share of gait clips (and transitions) in the blend on, they vote the foot flags (plant,
// hold, swing) and the feet walk; below it the standing clip's flags hold both feet down.
inline constexpr float kGaitVoteWeight = 0.25f;

// Where a foot that carries the body alone (pinned, the other foot not) lets the root go, as pose
// synthesis found it on the last frame (per slot): the root more than `radius` from `centre`
// would stretch the leg beyond its reach with the heel as high as it rises. The other foot takes
// the weight over in `landing_s` (< 0: not known; no landing is coming soon).
struct SupportReach {
  glm::vec2 centre{0.0f};  // (x, z) [m]
  float radius = -1.0f;    // [m]; < 0: no such foot
  float landing_s = -1.0f;  // [s]
  bool replanting =
      false;  // the other foot is in a re-planting step (its own clock, not the clips')
};

// Per-slot plan for one frame, read by the pose synthesis pass and the metrics.
struct AnimationPlans {
  // Frame agent index -> slot, and slot -> frame agent index (-1 when the slot is free).
  std::vector<int32_t> slot_of_agent;
  std::vector<int32_t> agent_of_slot;
  // Blend layers: clip index and weight (weights sum to 1; unused layers have weight 0).
  std::vector<int16_t> layer_clip;   // [slot * kMaxBlendLayers + k]
  std::vector<float> layer_weight;   // [slot * kMaxBlendLayers + k]
  std::vector<float> layer_time_s;   // clip time to sample (0 in a layer of weight 0)
  std::vector<glm::vec2> root_xz;    // rendered root placement on the ground [m]
  std::vector<float> lower_yaw;      // lower-body facing psi [rad]
  std::vector<float> upper_yaw;      // desired upper-body facing (filtered theta) [rad]
  std::vector<float> travel_yaw;     // travel direction implied by the played clips [rad]
  std::vector<float> playback_rate;  // clip-time step / real time step
  std::vector<float> speed_m_s;      // filtered speed
  std::vector<float> plant[2];       // blended "a foot lock may start" of each foot, 0..1
  std::vector<float> hold[2];        // blended "keep the lock" of each foot, 0..1
  // Toe height [m] (model space, ground at 0) the gait clips alone have at this phase: a walk
  // blended with a standing pose swings lower, and pose synthesis gives a foot that is not pinned
  // the gait clips' own swing height back.
  std::vector<float> gait_toe_y[2];
  // Toe height [m] (model space) the standing clips have at their time, or lowest() where none of
  // them has toe heights; and 1 where they vote the feet (the gait clips and a start or stop carry
  // under kGaitVoteWeight of the blend): a pinned toe then stands where they have it.
  std::vector<float> stand_toe_y[2];
  std::vector<uint8_t> standing_votes;
  // The voting clips' own ball speed over the ground at this frame's rate [m/s] (< 0: not known):
  // a foot has landed once its ball rests in the clips, though a blend's changing weights may
  // still move the drawn foot.
  std::vector<float> clip_toe_speed[2];
  std::vector<float> gait_weight;        // share of gait clips (not standing) in the blend, 0..1
  std::vector<float> swing_progress[2];  // blended swing progress of each foot, 0..1
  // When the voting clips that have this foot in the air bring it down [s]: the mean of each one's
  // remaining swing at its playback rate (< 0: none has it in the air). Measured in clip time at
  // the gait phase's rate; while a start or stop transition plays, the gait layers' phase follows
  // the transition's clock instead and their share of this is approximate.
  std::vector<float> landing_s[2];
  std::vector<float> double_support;     // share of the voting clips that walk (0..1)
  std::vector<float> phase;              // gait phase [0, 1)
  std::vector<float> blend_progress;     // b: 0 when the chosen clips just changed, 1 when settled
  std::vector<uint8_t> standing;         // 1 when below the stop speed
  std::vector<uint8_t> fresh;            // 1 on the agent's first frame
};

}  // namespace gk
