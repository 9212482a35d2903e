// upsample_clip: a capture below the crowd's frame rate played from a monotone cubic through its
// frames. Checked against motions whose values between the frames are known (smooth curves
// sampled at 30 and 24 fps): the new frames lie nearer the curve than straight segments do, the
// captured frames stay exact, the joints' world velocity no longer jumps at every captured frame,
// a landing does not overshoot through the floor, and a loop with root travel wraps forward.

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/quaternion.hpp>

#include "animation/clip.h"
#include "animation/pose_jobs.h"
#include "animation/skeleton.h"
#include "tests/animation/model_pose.h"

namespace gk {
namespace {

constexpr float kTwoPi = 2.0f * std::numbers::pi_v<float>;

// A root (with root motion) and one bone 0.4 m long hanging from it.
Skeleton two_joints() {
  Skeleton sk;
  sk.names = {"root", "bone"};
  sk.parents = {-1, 0};
  sk.rest_translations = {glm::vec3(0.0f), glm::vec3(0.0f, -0.4f, 0.0f)};
  sk.rest_rotations = {glm::quat(1, 0, 0, 0), glm::quat(1, 0, 0, 0)};
  return sk;
}

// The motion as a function of time: the root travels forward and bobs, turns to and fro; the bone
// swings about x like a leg.
glm::vec3 root_at(float t) {
  return {0.05f * std::sin(kTwoPi * 0.9f * t), 0.9f + 0.03f * std::sin(kTwoPi * 2.0f * t),
          1.3f * t};
}
glm::quat root_rot_at(float t) {
  return glm::angleAxis(0.4f * std::sin(kTwoPi * t), glm::vec3(0, 1, 0));
}
glm::quat bone_rot_at(float t) {
  return glm::angleAxis(0.8f * std::sin(kTwoPi * 1.2f * t), glm::vec3(1, 0, 0));
}

Clip sampled(float fps, int frames, bool loops = false) {
  Clip c;
  c.name = "sampled";
  c.fps = fps;
  c.num_frames = frames;
  c.num_joints = 2;
  c.loops = loops;
  c.sampled_capture = true;
  for (int f = 0; f < frames; ++f) {
    const float t = static_cast<float>(f) / fps;
    c.rotations.push_back(root_rot_at(t));
    c.translations.push_back(root_at(t));
    c.rotations.push_back(bone_rot_at(t));
    c.translations.push_back(glm::vec3(0.0f, -0.4f, 0.0f));
  }
  return c;
}

float angle_between(const glm::quat& a, const glm::quat& b) {
  return 2.0f * std::acos(std::min(1.0f, std::abs(glm::dot(a, b))));
}

TEST(Upsample, KeepsTheCapturedFramesAndTheDuration) {
  const Skeleton sk = two_joints();
  for (const auto& [fps, factor] : {std::pair{30.0f, 2}, std::pair{24.0f, 3}}) {
    const Clip c = sampled(fps, 31);
    const Clip u = upsample_clip(c, factor, sk);
    EXPECT_TRUE(validate_clip(u, sk).ok()) << validate_clip(u, sk).message();
    EXPECT_EQ(u.num_frames, 30 * factor + 1);
    EXPECT_FLOAT_EQ(u.fps, fps * static_cast<float>(factor));
    EXPECT_FLOAT_EQ(u.duration_s(), c.duration_s());
    EXPECT_TRUE(u.sampled_capture);
    for (int f = 0; f < c.num_frames; ++f) {
      for (int j = 0; j < 2; ++j) {
        EXPECT_EQ(u.frame_rotations(f * factor)[j], c.frame_rotations(f)[j]) << f;
        EXPECT_EQ(u.frame_translations(f * factor)[j], c.frame_translations(f)[j]) << f;
      }
    }
    // The bone's offset is the same on every frame, exactly (a constant track stays constant).
    for (int f = 0; f < u.num_frames; ++f) {
      EXPECT_EQ(u.frame_translations(f)[1], glm::vec3(0.0f, -0.4f, 0.0f)) << f;
    }
  }
  // Nothing to do: the clip as it is.
  const Clip c = sampled(30.0f, 10);
  EXPECT_EQ(upsample_clip(c, 1, sk).num_frames, 10);
  Skeleton other = sk;
  other.names.push_back("extra");
  other.parents.push_back(1);
  other.rest_translations.push_back(glm::vec3(0.0f));
  other.rest_rotations.push_back(glm::quat(1, 0, 0, 0));
  EXPECT_EQ(upsample_clip(c, 2, other).num_frames, 10);
}

// Between the captured frames the new ones lie nearer the motion than the straight segments that
// linear sampling draws, by the root's position and both joints' rotations.
TEST(Upsample, NewFramesLieNearerTheMotionThanStraightSegments) {
  const Skeleton sk = two_joints();
  for (const auto& [fps, factor] : {std::pair{30.0f, 2}, std::pair{24.0f, 3}}) {
    const Clip c = sampled(fps, 49);
    const Clip u = upsample_clip(c, factor, sk);
    double up_pos = 0.0, lin_pos = 0.0, up_rot = 0.0, lin_rot = 0.0;
    float up_pos_max = 0.0f, lin_pos_max = 0.0f;
    std::vector<glm::quat> rot(2);
    std::vector<glm::vec3> trans(2);
    // Interior frames only: beyond a take's ends the true motion is not known to either.
    for (int f = 2 * factor; f < u.num_frames - 2 * factor; ++f) {
      if (f % factor == 0) continue;
      const float t = static_cast<float>(f) / u.fps;
      SampleClipJob{&c, t, rot, trans}.run();  // straight segments between the captured frames
      const float ep_u = glm::length(u.frame_translations(f)[0] - root_at(t));
      const float ep_l = glm::length(trans[0] - root_at(t));
      up_pos += ep_u * ep_u;
      lin_pos += ep_l * ep_l;
      up_pos_max = std::max(up_pos_max, ep_u);
      lin_pos_max = std::max(lin_pos_max, ep_l);
      for (int j = 0; j < 2; ++j) {
        const glm::quat want = j == 0 ? root_rot_at(t) : bone_rot_at(t);
        const float er_u = angle_between(u.frame_rotations(f)[j], want);
        const float er_l = angle_between(rot[j], want);
        up_rot += er_u * er_u;
        lin_rot += er_l * er_l;
      }
    }
    EXPECT_LT(up_pos, 0.25 * lin_pos) << fps;
    EXPECT_LT(up_rot, 0.25 * lin_rot) << fps;
    EXPECT_LE(up_pos_max, lin_pos_max) << fps;
  }
}

// The bone's tip, sampled at 60 Hz: straight segments between 30 fps frames change its velocity
// in a jump at every captured frame (a spike in the second difference, about twice the motion's
// own acceleration); the upsampled clip's does not.
TEST(Upsample, TheJointsVelocityNoLongerJumpsAtEveryCapturedFrame) {
  const Skeleton sk = two_joints();
  const Clip c = sampled(30.0f, 61);
  const Clip u = upsample_clip(c, 2, sk);
  ASSERT_FLOAT_EQ(u.fps, 60.0f);
  std::vector<glm::vec3> tip_lin, tip_up, tip_true;
  std::vector<glm::quat> rot(2);
  std::vector<glm::vec3> trans(2);
  auto tip = [&](const std::vector<glm::quat>& r, const std::vector<glm::vec3>& t) {
    return glm::vec3(test::model_pose(sk, r.data(), t.data())[1] *
                     glm::vec4(0.0f, -0.4f, 0.0f, 1.0f));
  };
  for (int f = 0; f < u.num_frames; ++f) {
    const float t = static_cast<float>(f) / 60.0f;
    SampleClipJob{&c, t, rot, trans}.run();
    tip_lin.push_back(tip(rot, trans));
    rot.assign(u.frame_rotations(f), u.frame_rotations(f) + 2);
    trans.assign(u.frame_translations(f), u.frame_translations(f) + 2);
    tip_up.push_back(tip(rot, trans));
    tip_true.push_back(tip({root_rot_at(t), bone_rot_at(t)}, {root_at(t), trans[1]}));
  }
  auto max_accel = [](const std::vector<glm::vec3>& p) {
    float worst = 0.0f;
    for (size_t i = 4; i + 5 < p.size(); ++i) {
      worst = std::max(worst, glm::length(p[i + 1] - 2.0f * p[i] + p[i - 1]) * 3600.0f);
    }
    return worst;
  };
  const float a_true = max_accel(tip_true), a_lin = max_accel(tip_lin), a_up = max_accel(tip_up);
  // Straight segments: the velocity jumps, spikes well above the motion's own acceleration.
  EXPECT_GT(a_lin, 1.5f * a_true);
  // Upsampled: no spike, within half again the motion's own (a monotone cubic flattens the
  // slope at a captured turning point, and bends a little harder beside it).
  EXPECT_LT(a_up, 1.5f * a_true) << a_true;
  EXPECT_LT(a_up, 0.7f * a_lin) << a_lin;
}

// A foot that comes down onto the floor and stays (a landing: heights 10, 5, 1, 0, 0, 0 cm) and
// lifts again: between any two captured frames the new ones stay between those two, so the foot
// never dips through the floor and back; a bone's bend that stops does not swing past either.
TEST(Upsample, ALandingDoesNotOvershootTheCapturedFrames) {
  const Skeleton sk = two_joints();
  const std::vector<float> height = {0.10f, 0.05f, 0.01f, 0.0f, 0.0f, 0.0f, 0.02f, 0.06f, 0.12f};
  const std::vector<float> bend = {0.9f, 0.5f, 0.1f, 0.0f, 0.0f, 0.0f, 0.3f, 0.6f, 0.7f};
  Clip c;
  c.fps = 30.0f;
  c.num_frames = static_cast<int>(height.size());
  c.num_joints = 2;
  c.loops = false;
  for (size_t f = 0; f < height.size(); ++f) {
    c.rotations.push_back(glm::quat(1, 0, 0, 0));
    c.translations.push_back(glm::vec3(0.0f, height[f], 0.3f * static_cast<float>(f) / 30.0f));
    c.rotations.push_back(glm::angleAxis(bend[f], glm::vec3(1, 0, 0)));
    c.translations.push_back(glm::vec3(0.0f, -0.4f, 0.0f));
  }
  for (int factor : {2, 3, 4}) {
    const Clip u = upsample_clip(c, factor, sk);
    for (int f = 0; f < u.num_frames; ++f) {
      const int i = f / factor;
      const int k = std::min(i + 1, c.num_frames - 1);
      const float y = u.frame_translations(f)[0].y;
      EXPECT_GE(y, std::min(height[i], height[k]) - 1e-7f) << factor << " frame " << f;
      EXPECT_LE(y, std::max(height[i], height[k]) + 1e-7f) << factor << " frame " << f;
      const glm::quat q = u.frame_rotations(f)[1];
      const float angle = 2.0f * std::atan2(q.x, q.w);
      EXPECT_GE(angle, std::min(bend[i], bend[k]) - 1e-5f) << factor << " frame " << f;
      EXPECT_LE(angle, std::max(bend[i], bend[k]) + 1e-5f) << factor << " frame " << f;
    }
  }
}

// A loop whose root travels: after its last captured frame it goes on to the first one moved on
// by the loop's travel, never back to where the loop began; and it joins there as smoothly as
// anywhere else.
TEST(Upsample, ALoopWithRootTravelWrapsForward) {
  const Skeleton sk = two_joints();
  const float fps = 24.0f;
  const int n = 24;  // one second: the bob and the swing (2 and 1.2 Hz) are not whole cycles, but
                     // the travel is what this is about
  const Clip c = sampled(fps, n, /*loops=*/true);
  const Clip u = upsample_clip(c, 3, sk);
  EXPECT_EQ(u.num_frames, 3 * n);
  EXPECT_FLOAT_EQ(u.duration_s(), c.duration_s());
  for (int f = 1; f < u.num_frames; ++f) {
    EXPECT_GT(u.frame_translations(f)[0].z, u.frame_translations(f - 1)[0].z) << f;
  }
  // The last new frames head for frame 0 one loop on (1.3 m/s for n / fps seconds).
  const float next_z = c.frame_translations(0)[0].z + 1.3f * static_cast<float>(n) / fps;
  const float last_z = u.frame_translations(u.num_frames - 1)[0].z;
  EXPECT_NEAR(next_z - last_z, 1.3f / (3.0f * fps), 2e-3f);
}

}  // namespace
}  // namespace gk
