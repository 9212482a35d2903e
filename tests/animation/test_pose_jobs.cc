// Runtime jobs checked against closed-form expectations: interpolation, looping, blending, FK of a
// chain with known geometry, and two-bone IK reaching random targets with the knee toward the pole.

#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/quaternion.hpp>

#include "animation/pose_jobs.h"

namespace gk {
namespace {

Skeleton make_chain(int n, float bone) {
  Skeleton s;
  for (int i = 0; i < n; ++i) {
    s.names.push_back("j" + std::to_string(i));
    s.parents.push_back(static_cast<int16_t>(i - 1));
    s.rest_translations.push_back(i == 0 ? glm::vec3(0) : glm::vec3(0, -bone, 0));
    s.rest_rotations.push_back(glm::quat(1, 0, 0, 0));
  }
  return s;
}

Clip make_two_frame_clip(bool loops) {
  Clip c;
  c.name = "t";
  c.fps = 10.0f;
  c.num_frames = 2;
  c.num_joints = 1;
  c.loops = loops;
  c.rotations = {glm::quat(1, 0, 0, 0), glm::angleAxis(glm::radians(90.0f), glm::vec3(0, 1, 0))};
  c.translations = {glm::vec3(0), glm::vec3(1, 0, 0)};
  return c;
}

TEST(SampleClipJob, InterpolatesBetweenFrames) {
  const Clip c = make_two_frame_clip(false);
  glm::quat r[1];
  glm::vec3 t[1];
  SampleClipJob job{&c, 0.025f, r, t};  // a quarter of the way from frame 0 to frame 1
  ASSERT_TRUE(job.validate());
  job.run();
  EXPECT_NEAR(t[0].x, 0.25f, 1e-6f);
  // nlerp of 0 and 90 deg at 1/4 gives atan2(0.25 sin45, 0.75 + 0.25 cos45) * 2.
  const float expect = 2.0f * std::atan2(0.25f * std::sin(glm::radians(45.0f)),
                                         0.75f + 0.25f * std::cos(glm::radians(45.0f)));
  EXPECT_NEAR(glm::angle(r[0]), expect, 1e-5f);
}

TEST(SampleClipJob, ClampsOrWraps) {
  const Clip clamped = make_two_frame_clip(false);
  glm::quat r[1];
  glm::vec3 t[1];
  SampleClipJob{&clamped, 5.0f, r, t}.run();
  EXPECT_NEAR(t[0].x, 1.0f, 1e-6f);
}

TEST(SampleClipJob, LoopWrapKeepsRootMotionAndWrapsOtherJoints) {
  // Two joints moving +1 per frame. A loop of 2 frames at 10 fps lasts 0.2 s; at 0.15 s we are half
  // way from frame 1 back to frame 0: the root keeps travelling (1.5), the child wraps back (0.5).
  Clip c = make_two_frame_clip(true);
  c.num_joints = 2;
  c.rotations = {glm::quat(1, 0, 0, 0), glm::quat(1, 0, 0, 0), glm::quat(1, 0, 0, 0),
                 glm::quat(1, 0, 0, 0)};
  c.translations = {glm::vec3(0), glm::vec3(0), glm::vec3(1, 0, 0), glm::vec3(1, 0, 0)};
  glm::quat r[2];
  glm::vec3 t[2];
  for (float time : {0.15f + 0.2f * 3, -0.05f}) {
    SampleClipJob{&c, time, r, t}.run();
    EXPECT_NEAR(t[0].x, 1.5f, 1e-4f) << time;
    EXPECT_NEAR(t[1].x, 0.5f, 1e-4f) << time;
  }
}

TEST(BlendPosesJob, WeightedMeanAndHemisphere) {
  const glm::quat a = glm::angleAxis(glm::radians(20.0f), glm::vec3(0, 0, 1));
  const glm::quat b =
      -glm::angleAxis(glm::radians(60.0f), glm::vec3(0, 0, 1));  // same rotation, other sign
  glm::vec3 ta(0), tb(4, 0, 0);
  PoseLayer layers[2] = {{{&a, 1}, {&ta, 1}, 3.0f}, {{&b, 1}, {&tb, 1}, 1.0f}};
  glm::quat r;
  glm::vec3 t;
  BlendPosesJob job{layers, {&r, 1}, {&t, 1}};
  ASSERT_TRUE(job.validate());
  job.run();
  EXPECT_NEAR(t.x, 1.0f, 1e-6f);  // 3:1 weights
  // Angle must lie between 20 and 60 degrees (close to 30), proving the sign flip was handled.
  const float deg = glm::degrees(glm::angle(r));
  EXPECT_GT(deg, 25.0f);
  EXPECT_LT(deg, 35.0f);
}

TEST(LocalToModelJob, ChainGeometry) {
  const Skeleton s = make_chain(3, 0.5f);
  std::vector<glm::quat> r(3, glm::quat(1, 0, 0, 0));
  r[1] = glm::angleAxis(glm::radians(90.0f), glm::vec3(1, 0, 0));  // bend the second joint
  std::vector<glm::mat4> m(3);
  LocalToModelJob job{&s, r, s.rest_translations, glm::translate(glm::mat4(1), glm::vec3(0, 2, 0)),
                      m};
  ASSERT_TRUE(job.validate());
  job.run();
  // j1 at (0, 1.5, 0); its child's offset (0,-0.5,0) rotated 90 deg about x gives (0, 0, -0.5).
  EXPECT_NEAR(translation_of(m[1]).y, 1.5f, 1e-6f);
  EXPECT_NEAR(translation_of(m[2]).y, 1.5f, 1e-6f);
  EXPECT_NEAR(translation_of(m[2]).z, -0.5f, 1e-6f);
}

TEST(TwoBoneIKJob, ReachesRandomTargetsWithKneeTowardPole) {
  const Skeleton s = make_chain(3, 0.45f);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  int reached = 0;
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<glm::quat> r(3);
    for (auto& q : r)
      q = glm::normalize(glm::quat(1.0f, 0.3f * u(rng), 0.3f * u(rng), 0.3f * u(rng)));
    std::vector<glm::mat4> m(3);
    LocalToModelJob fk{&s, r, s.rest_translations, glm::mat4(1), m};
    fk.run();
    // Targets inside the reachable shell (0.05 .. 0.85 m from the hip), below the hip.
    glm::vec3 dir = glm::normalize(glm::vec3(0.5f * u(rng), -1.0f, 0.5f * u(rng)));
    const float dist = 0.3f + 0.5f * (0.5f + 0.5f * u(rng));
    const glm::vec3 target = translation_of(m[0]) + dir * dist;
    const glm::vec3 pole(0, 0, 1);
    glm::quat c0, c1;
    bool ok = false;
    TwoBoneIKJob ik;
    ik.start_model = m[0];
    ik.mid_model = m[1];
    ik.end_model = m[2];
    ik.target = target;
    ik.pole = pole;
    ik.out_start_correction = &c0;
    ik.out_mid_correction = &c1;
    ik.out_reached = &ok;
    ASSERT_TRUE(ik.validate());
    ik.run();
    r[0] = r[0] * c0;
    r[1] = r[1] * c1;
    fk.run();
    const glm::vec3 end = translation_of(m[2]);
    ASSERT_LT(glm::length(end - target), 1e-3f) << "trial " << trial;
    reached += ok;
    // The knee lies on the pole side of the hip-target line.
    const glm::vec3 axis = glm::normalize(target - translation_of(m[0]));
    glm::vec3 knee = translation_of(m[1]) - translation_of(m[0]);
    knee -= axis * glm::dot(knee, axis);
    glm::vec3 pole_p = pole - axis * glm::dot(pole, axis);
    if (glm::length(knee) > 1e-3f) {
      EXPECT_GT(glm::dot(knee, pole_p), 0.0f) << "trial " << trial;
    }
  }
  EXPECT_EQ(reached, 200);
}

TEST(TwoBoneIKJob, OutOfReachStretchesTowardTarget) {
  const Skeleton s = make_chain(3, 0.4f);
  std::vector<glm::quat> r(3, glm::quat(1, 0, 0, 0));
  r[1] = glm::angleAxis(glm::radians(30.0f), glm::vec3(1, 0, 0));
  std::vector<glm::mat4> m(3);
  LocalToModelJob fk{&s, r, s.rest_translations, glm::mat4(1), m};
  fk.run();
  const glm::vec3 target(0.0f, -2.0f, 0.5f);
  glm::quat c0, c1;
  bool ok = true;
  TwoBoneIKJob ik;
  ik.start_model = m[0];
  ik.mid_model = m[1];
  ik.end_model = m[2];
  ik.target = target;
  ik.out_start_correction = &c0;
  ik.out_mid_correction = &c1;
  ik.out_reached = &ok;
  ik.run();
  EXPECT_FALSE(ok);
  r[0] = r[0] * c0;
  r[1] = r[1] * c1;
  fk.run();
  const glm::vec3 end = translation_of(m[2]);
  EXPECT_NEAR(glm::length(end), 0.8f * ik.max_extension, 1e-3f);
  EXPECT_GT(glm::dot(glm::normalize(end), glm::normalize(target)), 0.9999f);
}

// Soft IK: a target pulled straight away from the hip through full reach, 1 mm per step. The
// hard clamp moves the knee by far more in the last millimetres than anywhere else (the knee's
// distance from the hip-target line is l*sin(acos(d/2l)), whose slope is unbounded at d = 2l);
// softened, the knee's step stays near its step well inside the reach, the foot lands exactly
// where asked below the soft zone and never goes past the limb's length.
TEST(TwoBoneIKJob, SoftenedKneeStraightensWithoutASnap) {
  const float bone = 0.4f;
  const Skeleton s = make_chain(3, bone);
  auto knee_and_end = [&](float dist, float soften, glm::vec3* end) {
    std::vector<glm::quat> r(3, glm::quat(1, 0, 0, 0));
    r[1] = glm::angleAxis(glm::radians(40.0f), glm::vec3(1, 0, 0));
    std::vector<glm::mat4> m(3);
    LocalToModelJob fk{&s, r, s.rest_translations, glm::mat4(1), m};
    fk.run();
    const glm::vec3 dir = glm::normalize(translation_of(m[2]) - translation_of(m[0]));
    glm::quat c0, c1;
    TwoBoneIKJob ik;
    ik.start_model = m[0];
    ik.mid_model = m[1];
    ik.end_model = m[2];
    ik.target = translation_of(m[0]) + dir * dist;
    ik.pole = glm::vec3(0, 0, 1);
    ik.soften = soften;
    ik.out_start_correction = &c0;
    ik.out_mid_correction = &c1;
    ik.run();
    r[0] = r[0] * c0;
    r[1] = r[1] * c1;
    fk.run();
    *end = translation_of(m[2]) - translation_of(m[0]);
    return translation_of(m[1]);
  };
  auto largest_knee_step = [&](float soften, float from, float to) {
    float worst = 0.0f;
    glm::vec3 end;
    glm::vec3 prev = knee_and_end(from, soften, &end);
    for (float d = from + 0.001f; d <= to; d += 0.001f) {
      const glm::vec3 k = knee_and_end(d, soften, &end);
      worst = std::max(worst, glm::length(k - prev));
      prev = k;
      EXPECT_LE(glm::length(end), 2.0f * bone + 1e-4f);
    }
    return worst;
  };
  const float inside = largest_knee_step(1.0f, 0.5f, 0.6f);  // well within reach
  const float hard = largest_knee_step(1.0f, 0.70f, 0.85f);
  const float soft = largest_knee_step(0.95f, 0.70f, 0.85f);
  EXPECT_GT(hard, 4.0f * inside) << hard << " " << inside;
  EXPECT_LT(soft, 3.0f * inside) << soft << " " << inside;
  EXPECT_LT(soft, 0.25f * hard) << soft << " " << hard;
  // Below the soft zone the end joint is exactly where asked.
  glm::vec3 end;
  knee_and_end(0.7f, 0.95f, &end);
  EXPECT_NEAR(glm::length(end), 0.7f, 1e-4f);
}

TEST(SkinningPaletteJob, BindPoseGivesIdentity) {
  const Skeleton s = make_chain(4, 0.3f);
  std::vector<glm::mat4> m(4), inv(4), pal(4);
  LocalToModelJob{&s, s.rest_rotations, s.rest_translations, glm::mat4(1), m}.run();
  for (int i = 0; i < 4; ++i) inv[i] = glm::inverse(m[i]);
  SkinningPaletteJob job{m, inv, pal};
  ASSERT_TRUE(job.validate());
  job.run();
  for (int i = 0; i < 4; ++i)
    for (int c = 0; c < 4; ++c)
      for (int k = 0; k < 4; ++k) EXPECT_NEAR(pal[i][c][k], c == k ? 1.0f : 0.0f, 1e-5f);
}

}  // namespace
}  // namespace gk
