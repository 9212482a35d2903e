#pragma once
// Skeleton: the joint hierarchy as plain arrays (structure of arrays), translations in metres,
// rotations as unit quaternions. Built once by a loader or builder and then treated as immutable
// (modules share it as std::shared_ptr<const Skeleton>).
//
// Conventions used everywhere in Gaitkeeper: y is up, the ground is y = 0, a character in its rest
// pose faces +z and has its left side at +x. A heading angle theta [rad] about +y maps +z to
// (sin theta, 0, cos theta).

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <glm/gtc/quaternion.hpp>
#include <glm/vec3.hpp>

#include "common/status.h"

namespace gk {

// Semantic roles the mediator and analysis need, detected from joint names.
enum class JointRole : uint8_t {
  kHips,
  kSpine,  // first spine joint above the hips
  kChest,  // upper chest / neck base: the "upper body" of METRICS.md
  kNeck,
  kHead,
  kLeftHip,
  kLeftKnee,
  kLeftAnkle,
  kLeftToe,
  kRightHip,
  kRightKnee,
  kRightAnkle,
  kRightToe,
  kLeftShoulder,  // the upper-arm joint (shoulder rotation centre), not the clavicle
  kRightShoulder,
  kCount
};
inline constexpr int kNumJointRoles = static_cast<int>(JointRole::kCount);
std::string_view joint_role_name(JointRole role);  // "hips", "left_knee", ...
bool joint_role_from_name(std::string_view name, JointRole* out_role);

enum class Side : uint8_t { kLeft = 0, kRight = 1 };

struct Skeleton {
  std::vector<std::string> names;
  // parents[i] < i for every joint but the root(s), whose parent is -1 (topological order).
  std::vector<int16_t> parents;
  // Rest pose, local to the parent [m].
  std::vector<glm::vec3> rest_translations;
  std::vector<glm::quat> rest_rotations;
  // Per joint, the tip of its bone where the file gives one (BVH End Site), local to the joint
  // [m]; empty, or zero for a joint without one.
  std::vector<glm::vec3> end_sites;
  // Joint index per role, -1 if absent.
  std::array<int16_t, kNumJointRoles> roles;
  // Joints from the first spine joint above the hips up to and including the chest, bottom first:
  // the joints the torso twist is spread over.
  std::vector<int16_t> spine_chain;

  Skeleton() { roles.fill(-1); }
  int num_joints() const { return static_cast<int>(parents.size()); }
  int role(JointRole r) const { return roles[static_cast<int>(r)]; }
  bool has(JointRole r) const { return role(r) >= 0; }
  int find(std::string_view name) const;  // -1 if absent
  // Hip, knee, ankle, toe of one side.
  int hip(Side s) const {
    return role(s == Side::kLeft ? JointRole::kLeftHip : JointRole::kRightHip);
  }
  int knee(Side s) const {
    return role(s == Side::kLeft ? JointRole::kLeftKnee : JointRole::kRightKnee);
  }
  int ankle(Side s) const {
    return role(s == Side::kLeft ? JointRole::kLeftAnkle : JointRole::kRightAnkle);
  }
  int toe(Side s) const {
    return role(s == Side::kLeft ? JointRole::kLeftToe : JointRole::kRightToe);
  }
  // True when every role the mediator needs for locomotion (hips, chest, both legs) is present.
  bool has_locomotion_roles() const;
};

// Fills roles and spine_chain from the joint names, recognising CMU/cgspeed (LeftUpLeg/LeftLeg/
// LeftFoot/LeftToeBase and LeftHip/LeftKnee/LeftAnkle/LeftToe), Rigify (DEF-thigh.L), Mixamo
// (mixamorig:LeftUpLeg), Unreal (thigh_l/calf_l/foot_l/ball_l), ASF (lfemur/ltibia/lfoot/ltoes),
// Unity (UpperLeg_L), RobotExpressive (UpperLegL) and plain (l_hip, left_knee) names, and word by
// word names with a rig prefix and a side word anywhere (Bip01 L Thigh, J_Bip_L_UpperLeg,
// CC_Base_L_Calf); a foot word below the ankle is the toe (SMPL's L_Ankle -> L_Foot). With
// topology checks (a knee must be below its hip, ...). A leg word without a side ("Foot.001") takes
// the side it stands on in the rest pose (left at +x). IK-style rigs, whose feet (or toes) are not
// below the shins (or feet) but hang from the root or the hips, are matched by the rest pose: the
// foot is the same-side foot joint that sits a plausible shin length below the knee, nearest under
// it (the loaders then re-parent it, attach_ik_feet). Unrecognised roles stay -1.
void detect_joint_roles(Skeleton* skeleton);

// The locomotion roles (those of has_locomotion_roles) the skeleton lacks, comma-separated
// ("left_ankle, right_ankle"); empty when it has them all.
std::string missing_locomotion_roles(const Skeleton& skeleton);
// For error messages: how roles are found and how to give them (--roles FILE.json, its format).
std::string role_manifest_hint();

// Overrides roles from a JSON manifest: {"roles": {"left_knee": "Knee_L", ...}}. Errors name the
// manifest file and the field.
Status apply_role_manifest(const std::string& manifest_path, Skeleton* skeleton);
Status apply_role_manifest_text(std::string_view json_text, const std::string& source_name,
                                Skeleton* skeleton);

// Validates structure (sizes agree, parents topological, finite numbers, unit quaternions).
Status validate_skeleton(const Skeleton& skeleton, const std::string& source_name);

// Subtree ranges, per joint j the end e of the joint range [j, e) that forward kinematics has to
// recompute after j's local transform changed. Where j's descendants follow it contiguously (a
// depth-first order: BVH files, the built-in rig) the range holds exactly j and its descendants;
// otherwise (or with parents out of order) it runs to the last joint, which in a parents-first
// order also covers them. Made once by the user (it is not kept in Skeleton, which loaders build
// and edit joint by joint).
std::vector<int> subtree_ends(const Skeleton& skeleton);

}  // namespace gk
