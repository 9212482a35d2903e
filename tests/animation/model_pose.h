#pragma once
// Model-space pose of one frame (LocalToModelJob), for the animation tests.

#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/quaternion.hpp>
#include <glm/mat4x4.hpp>

#include "animation/pose_jobs.h"
#include "animation/skeleton.h"

namespace gk::test {

inline std::vector<glm::mat4> model_pose(const Skeleton& s, const glm::quat* r,
                                         const glm::vec3* t) {
  std::vector<glm::mat4> model(s.num_joints());
  LocalToModelJob job;
  job.skeleton = &s;
  job.rotations = {r, static_cast<size_t>(s.num_joints())};
  job.translations = {t, static_cast<size_t>(s.num_joints())};
  job.out_model = model;
  EXPECT_TRUE(job.validate());
  job.run();
  return model;
}

}  // namespace gk::test
