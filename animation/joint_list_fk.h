#pragma once
// Forward kinematics over a list of joints rather than a range: the joints a pose pass changes
// are often two or three short runs (both legs, both feet), which LocalToModelJob would take one
// call and one four-joint group each; a list takes them four at a time across the runs.

#include <cstdint>
#include <span>

#include <glm/gtc/quaternion.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "animation/skeleton.h"

namespace gk {

// out_model[j] = out_model[parent] * T(t_j) * R(q_j) for each j of `joints` in order (the roots'
// parent is *root_transform): LocalToModelJob's arithmetic, so the same bits as running it over
// the same joints in the same order. Every parent of a listed joint must be current when the
// joint comes (listed before it, or not changed since it was last computed).
struct LocalToModelListJob {
  const Skeleton* skeleton = nullptr;
  std::span<const glm::quat> rotations;     // num_joints
  std::span<const glm::vec3> translations;  // num_joints
  const glm::mat4* root_transform = nullptr;
  std::span<glm::mat4> out_model;   // num_joints
  std::span<const int16_t> joints;  // indices into the above, each < num_joints
  bool validate() const;
  void run() const;
};

}  // namespace gk
