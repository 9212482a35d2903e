#pragma once
// A generated IK-style rig for the tests (no such rig is in the shared data): the built-in walking
// character written as a skinned GLB whose feet hang from a root joint on the ground (and, on
// request, whose toes do too), in centimetres or inches, with known (Unreal-style) or meaningless
// joint names. What the file shows is known independently of the loader: the built-in clips'
// model-space poses on the built-in skeleton, two strides per clip.

#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "animation/clip.h"

namespace gk::test {

struct IkRigOptions {
  bool known_names = true;       // thigh_l/calf_l/foot_l/ball_l...; false: bone_00, bone_01, ...
  float units_per_m = 100.0f;    // 100: centimetres; 1 / 0.0254: inches
  bool toes_under_root = false;  // the toes hang from the root as well as the feet
  bool feet_under_root = true;   // false: an ordinary rig (feet under the shins), to compare
  std::vector<std::string> clips = {"idle", "walk_slow", "walk", "walk_fast", "jog"};
};

// The hard case: meaningless joint names, inches, toes hanging from the root as well.
inline IkRigOptions meaningless_inch_rig() {
  IkRigOptions o;
  o.known_names = false;
  o.units_per_m = 1.0f / 0.0254f;
  o.toes_under_root = true;
  return o;
}

struct IkRig {
  std::string glb;  // the file's bytes
  // The built-in clips (metres, on the built-in skeleton) that the file holds, in its order.
  ClipSet authored;
  // File joint name of each built-in joint (built-in joint order).
  std::vector<std::string> names;
  // Per clip, per frame of the file (two strides: frame k shows built-in frame k mod n, moved on
  // by the clip's travel per stride), the model-space position [m] of each built-in joint.
  std::vector<std::vector<std::vector<glm::vec3>>> positions;
  // A role manifest naming the file's joints ({"roles": {...}}).
  std::string roles_json;
};

IkRig make_ik_rig(const IkRigOptions& options = {});

// Writes bytes to `path`; false when it cannot.
bool write_file(const std::string& path, const std::string& bytes);

}  // namespace gk::test
