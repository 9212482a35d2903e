#pragma once
// Internal to the procedural gait generator: the joints it drives (GaitRig) and the conversion of
// world-space targets (pelvis, ankles, foot pitch, trunk and arm angles) into a local pose through
// analytic two-bone leg IK.

#include <vector>

#include <glm/gtc/quaternion.hpp>
#include <glm/vec3.hpp>

#include "animation/clip.h"
#include "animation/gait_generator.h"
#include "animation/skeleton.h"

namespace gk::gait {

// Model-space rest positions by forward kinematics of the rest pose.
std::vector<glm::vec3> rest_positions(const Skeleton& skeleton);

struct GaitRig {
  explicit GaitRig(const Skeleton& skeleton);
  int root = 0;
  int hip[2], knee[2], ankle[2], toe[2];
  int upper_arm[2], forearm[2], hand[2];  // -1 when the skeleton has no arm chain
  int neck = -1, head = -1;
  std::vector<int> spine;
  glm::vec3 hip_offset[2];   // hip joint relative to the root in the rest pose [m]
  glm::vec3 ball_offset[2];  // toe joint relative to the ankle in the rest pose [m]
  float thigh_m[2], shank_m[2];
  glm::vec3 thigh_dir[2], shank_dir[2], upper_arm_dir[2], forearm_dir[2];  // rest directions
  FootShape foot[2];
};

struct FootTarget {
  glm::vec3 ball{0.0f};    // toe joint (ball of the foot) position [m]
  float pitch = 0.0f;      // foot pitch [rad], positive = toe up
  float toe_pitch = 0.0f;  // toe segment pitch relative to the ground [rad]
};

struct PoseTargets {
  glm::vec3 root_position{0.0f};
  float pelvis_yaw = 0.0f, pelvis_roll = 0.0f;  // [rad] about +y and about +z (left side up)
  FootTarget foot[2];
  glm::vec3 ankle[2];
  bool planted[2] = {true, true};  // stance feet are reached exactly; swing feet softly
  float thorax_yaw = 0.0f;         // [rad] world yaw of the chest
  float lean = 0.0f;               // [rad] forward trunk lean at the chest
  float head_yaw = 0.0f;
  float arm_forward[2] = {0.0f, 0.0f};  // [rad] shoulder flexion (+) / extension (-)
  float elbow[2] = {0.0f, 0.0f};        // [rad] elbow flexion
  float arm_abduction = 0.0f;           // [rad] upper arms away from the body
  float forearm_abduction = 0.0f;       // [rad] forearms away from the body (< 0: toward it)
};

glm::quat pelvis_rotation(float yaw, float roll);

// Left/right mirror of a clip in place (x -> -x, Left* <-> Right* joints).
void mirror_clip(const Skeleton& skeleton, Clip* clip);

// Fills the local pose (rotations for every joint, translations = rest offsets with the root at
// targets.root_position).
void build_local_pose(const Skeleton& skeleton, const GaitRig& rig, const PoseTargets& targets,
                      glm::quat* out_rot, glm::vec3* out_trans);

}  // namespace gk::gait
