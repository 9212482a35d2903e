#pragma once
// Level of detail for big crowds (issue #11): each agent gets a level from its distance to a focus
// point (the camera in the app, --lod-focus or the scenario's centre in `gaitkeeper bench`), and
// the level says how often it is planned and posed and how much of the pose is worked out:
//
//   level  period      pose                                   planned
//   0      every frame all joints, spine twist, foot locks + IK every frame (exactly as without LOD)
//   1      every 2nd   all joints, spine twist, no foot locks  every 2nd frame
//   2      every 4th   no spine twist, no foot locks           every 4th frame
//   3      every 8th   no spine twist, no foot locks           every 8th frame
//
// Between its updates an agent's gait phase and clip times still advance with its planned rate
// and its root follows the simulator every frame (Mediator::set_lod_due), and its drawn joints
// and palettes move with the root (PoseSynthesizer, PoseDetail::kHold). The agents of a level are
// spread over its period: an agent entering a level takes the next of the level's P frame offsets
// in turn (round robin) and is due when (offset + frame) % P == 0, so every frame costs about the
// same whatever the order of the slots. A level changes only once the agent is `hysteresis_m` past a boundary, so an
// agent walking along one does not flicker between two levels.

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glm/vec2.hpp>

#include "common/status.h"
#include "mediator/animation_plans.h"
#include "mediator/pose_synthesis.h"

namespace gk {

inline constexpr int kNumLodLevels = 4;
// Frames between two updates of an agent at each level.
inline constexpr std::array<int, kNumLodLevels> kLodPeriod = {1, 2, 4, 8};

struct LodParams {
  bool enabled = false;
  glm::vec2 focus{0.0f};  // (x, z) [m]: distances are measured from here
  // Level boundaries [m]: level 0 closer than distances_m[0], level 3 beyond distances_m[2].
  // [Limit: 0 <= d0 <= d1 <= d2, finite]
  std::array<float, kNumLodLevels - 1> distances_m = {15.0f, 30.0f, 60.0f};
  float hysteresis_m = 2.0f;  // a level changes this far past its boundary [m] [Limit: 0..100]
};

// Empty Status when the parameters are within their limits, else which one is not.
Status validate(const LodParams& params);
// "a,b,c" [m] into params->distances_m (checked with validate); the error names `option`.
Status parse_lod_distances(const std::string& text, const std::string& option, LodParams* params);

// Per-slot levels with hysteresis and the frame's due flags. Sized for the capacity; allocates
// nothing per frame.
class LodPolicy {
 public:
  explicit LodPolicy(size_t capacity);

  // Levels of the slots in use, from their drawn roots of the last plan (plans.root_xz: a frame
  // old, which moves a boundary by one frame's walk), and the due flags of `frame`. A slot not in
  // use last frame takes the level of its distance outright (a newcomer's, the frame after it
  // came: on its first frame it is planned and posed like every fresh agent, by Mediator and
  // PoseSynthesizer, whatever its flag says).
  void assign(const AnimationPlans& plans, const LodParams& params, int64_t frame);
  // Per slot: 1 when the slot is planned and posed this frame.
  std::span<const uint8_t> due() const { return due_; }
  std::span<const uint8_t> levels() const { return level_; }
  int level(int slot) const { return level_[slot]; }
  // The pose work of each slot this frame (PoseSynthesizer::run's `detail`).
  std::span<const uint8_t> pose_detail() const { return detail_; }
  // Per slot: 1 at level 0 (full detail: what the metrics measure with LOD on).
  std::span<const uint8_t> full_detail() const { return full_; }
  // Slots in use at each level after the last assign().
  const std::array<int64_t, kNumLodLevels>& counts() const { return counts_; }
  // Level of a distance [m] without hysteresis.
  static int level_of(float distance_m, const LodParams& params);
  // The level after `current` for a distance, with hysteresis.
  static int next_level(int current, float distance_m, const LodParams& params);

 private:
  std::vector<uint8_t> level_;
  std::vector<uint8_t> in_use_;  // slot held a live agent at the last assign()
  std::vector<uint8_t> offset_;  // frame offset within its level's period
  std::array<uint32_t, kNumLodLevels> next_offset_{};  // round robin per level
  std::vector<uint8_t> due_;
  std::vector<uint8_t> detail_;
  std::vector<uint8_t> full_;
  std::array<int64_t, kNumLodLevels> counts_{};
};

}  // namespace gk
