// The coarse joint set of far agents (mediator/coarse_pose.h): found from the rest pose's
// geometry, it leaves out exactly the small end chains (fingers, toes) of the real rigs, and its
// world pose equals forward kinematics of the full pose when the detail joints are in the
// reference pose.

#include <algorithm>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "animation/pose_jobs.h"
#include "mediator/coarse_pose.h"
#include "tests/mediator/mediator_fixture.h"
#include "tests/test_data.h"

namespace gk {
namespace {

std::vector<std::string> detail_names(const LocomotionLibrary& lib) {
  const CoarseRig rig = make_coarse_rig(lib);
  std::vector<std::string> out;
  for (int j = 0; j < lib.skeleton->num_joints(); ++j) {
    if (rig.index[j] < 0) out.push_back(lib.skeleton->names[j]);
  }
  return out;
}

bool contains(const std::string& s, const char* word) { return s.find(word) != std::string::npos; }

// The 53-joint mannequin: its 30 finger joints and 2 toes are detail, nothing else (hands,
// forearms, head, spine and legs are sampled).
TEST(CoarseRig, MannequinLeavesOutFingersAndToes) {
  GK_REQUIRE_DATA("clips/gltf/ual_mannequin_quaternius.glb");
  auto lib = test::load_data_library({"clips/gltf/ual_mannequin_quaternius.glb"});
  ASSERT_TRUE(lib.ok()) << lib.message();
  const std::vector<std::string> detail = detail_names(*lib);
  int fingers = 0, toes = 0;
  for (const std::string& n : detail) {
    fingers += contains(n, "f_") || contains(n, "thumb");
    toes += contains(n, "toe");
  }
  EXPECT_EQ(fingers, 30);
  EXPECT_EQ(toes, 2);
  EXPECT_EQ(detail.size(), 32u) << ::testing::PrintToString(detail);
  const CoarseRig rig = make_coarse_rig(*lib);
  EXPECT_EQ(rig.num_coarse, 21);
  for (int role = 0; role < kNumJointRoles; ++role) {
    const int j = lib->skeleton->roles[role];
    if (j < 0 || role == static_cast<int>(JointRole::kLeftToe) ||
        role == static_cast<int>(JointRole::kRightToe)) {
      continue;
    }
    EXPECT_GE(rig.index[j], 0) << lib->skeleton->names[j];
  }
}

// The CMU rig: the finger joints under each hand are detail; hands and head are not.
TEST(CoarseRig, CmuLeavesOutFingers) {
  GK_REQUIRE_DATA("clips/bvh/cmu_07_01_walk.bvh");
  auto lib = test::load_data_library({"clips/bvh/cmu_07_01_walk.bvh"});
  ASSERT_TRUE(lib.ok()) << lib.message();
  const Skeleton& sk = *lib->skeleton;
  const CoarseRig rig = make_coarse_rig(*lib);
  for (const char* name : {"LeftFingerBase", "RightFingerBase", "LThumb", "RThumb"}) {
    const int j = sk.find(name);
    ASSERT_GE(j, 0) << name;
    EXPECT_LT(rig.index[j], 0) << name;
  }
  for (const char* name : {"LeftHand", "RightHand", "LeftForeArm", "Head", "LeftLeg"}) {
    const int j = sk.find(name);
    ASSERT_GE(j, 0) << name;
    EXPECT_GE(rig.index[j], 0) << name;
  }
}

// Detail needs a parent; a rig without a usable leg length has none.
TEST(CoarseRig, DetailJointsNeedALegLength) {
  const LocomotionLibrary& lib = test::builtin_library();
  const std::vector<uint8_t> none = detail_joints(*lib.skeleton, 0.0f);
  EXPECT_EQ(std::count(none.begin(), none.end(), 1), 0);
  const std::vector<uint8_t> some = detail_joints(*lib.skeleton, lib.leg_length_m[0]);
  EXPECT_EQ(some[0], 0);  // the root never is
}

// With every detail joint in its reference pose (the standing clip's first frame), the coarse
// world pose is the full forward kinematics of that frame, joint for joint.
TEST(CoarseRig, CoarseWorldPoseIsFullFkInTheReferencePose) {
  GK_REQUIRE_DATA("clips/gltf/ual_mannequin_quaternius.glb");
  auto lib = test::load_data_library({"clips/gltf/ual_mannequin_quaternius.glb"});
  ASSERT_TRUE(lib.ok()) << lib.message();
  const CoarseRig rig = make_coarse_rig(*lib);
  ASSERT_TRUE(rig.useful());
  const Clip& idle = lib->clips[lib->idle].clip;
  const Clip& coarse_idle = rig.clips[lib->idle];
  const int J = lib->skeleton->num_joints();
  ASSERT_EQ(coarse_idle.num_joints, rig.num_coarse);
  glm::mat4 root = glm::translate(glm::mat4(1.0f), glm::vec3(3.0f, 0.1f, -2.0f));
  root = glm::rotate(root, 0.7f, glm::vec3(0, 1, 0));
  std::vector<glm::mat4> full(J), coarse(J);
  LocalToModelJob{lib->skeleton.get(),
                  {idle.frame_rotations(0), static_cast<size_t>(J)},
                  {idle.frame_translations(0), static_cast<size_t>(J)},
                  root,
                  full}
      .run();
  coarse_to_world(
      rig, *lib->skeleton, {coarse_idle.frame_rotations(0), static_cast<size_t>(rig.num_coarse)},
      {coarse_idle.frame_translations(0), static_cast<size_t>(rig.num_coarse)}, root, coarse);
  for (int j = 0; j < J; ++j) {
    for (int c = 0; c < 4; ++c) {
      for (int r = 0; r < 4; ++r) {
        ASSERT_NEAR(coarse[j][c][r], full[j][c][r], 1e-4f) << lib->skeleton->names[j];
      }
    }
  }
}

}  // namespace
}  // namespace gk
