#pragma once
// The coarse joint set of a rig, for agents far from the camera (level of detail,
// PoseDetail::kLight): fingers, toes, face joints and the like are neither sampled nor blended;
// each follows its parent rigidly in a fixed reference pose (its local transform in the library's
// standing clip). Found once from the rest pose's geometry, not from joint names, so it holds for
// any rig: a joint is "detail" when its parent's whole subtree is small against the legs (a hand
// and its fingers, a foot and its toe, a head and its face), or when its parent is detail; the
// joints of the skeleton's roles but the toes (hips, spine, chest, neck, head, legs, shoulders)
// and their ancestors never are.

#include <cstdint>
#include <span>
#include <vector>

#include <glm/gtc/quaternion.hpp>
#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>

#include "animation/clip.h"
#include "animation/skeleton.h"

namespace gk {

struct LocomotionLibrary;

// A subtree spanning less than this fraction of the leg length (hip to ankle) in the rest pose
// is detail below its root joint: a hand with its fingers (about 0.2 of a leg), a foot with its
// toe; a forearm with its hand (about 0.5) or a neck with its head is not.
inline constexpr float kDetailSpanOfLeg = 0.3f;

struct CoarseRig {
  // Per joint: its index among the coarse joints (sampled, blended, posed), or -1 for a detail
  // joint that follows its parent rigidly. Joint 0 (the root) is always coarse.
  std::vector<int16_t> index;
  int num_coarse = 0;
  // Per library clip: the clip with the coarse joints' tracks only (SampleClipJob over them).
  std::vector<Clip> clips;
  // Per joint: a detail joint's local rotation and translation in the reference pose (identity
  // and zero for the coarse joints).
  std::vector<glm::mat3> rigid_rotation;
  std::vector<glm::vec3> rigid_translation;
  // True when some joints are detail (else the coarse pose is the full pose: not worth it).
  bool useful() const { return num_coarse > 0 && num_coarse < static_cast<int>(index.size()); }
};

// Per joint: true for a detail joint (see above), from the rest pose; leg_length_m is the rig's
// hip-to-ankle length [m] (<= 0: no joint is detail).
std::vector<uint8_t> detail_joints(const Skeleton& skeleton, float leg_length_m);

// The coarse rig of a library: its detail joints, the coarse clips and the reference pose (the
// standing clip's first frame, else the first clip's, else the rest pose).
CoarseRig make_coarse_rig(const LocomotionLibrary& library);

// World transforms of every joint from the coarse joints' local pose (num_coarse rotations and
// translations, in coarse order) placed at root: coarse joints by forward kinematics, detail
// joints as parent * their reference local transform.
void coarse_to_world(const CoarseRig& rig, const Skeleton& skeleton,
                     std::span<const glm::quat> rotations, std::span<const glm::vec3> translations,
                     const glm::mat4& root, std::span<glm::mat4> out_world);

}  // namespace gk
