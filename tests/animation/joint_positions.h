#pragma once
// Every joint's model-space position on one frame of a clip (its root motion included).

#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "animation/clip.h"
#include "animation/pose_jobs.h"
#include "animation/skeleton.h"

namespace gk::test {

inline std::vector<glm::vec3> joint_positions(const Clip& c, const Skeleton& sk, int frame) {
  std::vector<glm::mat4> model(sk.num_joints());
  clip_frame_model(c, sk, frame, model);
  std::vector<glm::vec3> out;
  for (const glm::mat4& m : model) out.push_back(translation_of(m));
  return out;
}

}  // namespace gk::test
