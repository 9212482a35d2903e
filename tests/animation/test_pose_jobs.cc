// Runtime jobs checked against closed-form expectations: interpolation, looping, blending, FK of a
// chain with known geometry, and two-bone IK reaching random targets with the knee toward the pole.

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/quaternion.hpp>

#include "animation/pose_jobs.h"
#include "animation/procedural.h"

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

// Random unit quaternions, about half of them in the far hemisphere of `near` (the same rotation
// with the other sign), so the shortest-arc sign flips are exercised.
std::vector<glm::quat> random_quats(int n, std::mt19937& rng, const std::vector<glm::quat>* near) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<glm::quat> q(n);
  for (int i = 0; i < n; ++i) {
    q[i] = glm::normalize(glm::quat(u(rng), u(rng), u(rng), u(rng)));
    if (near && glm::dot(q[i], (*near)[i]) > 0.0f && (i % 2)) q[i] = -q[i];
  }
  return q;
}

// Many joints (four at a time and a remainder): each one as the single-joint formula has it.
TEST(SampleClipJob, EveryJointIsTheShortestArcNlerpOfItsFrames) {
  const int n = 11;
  std::mt19937 rng(9);
  Clip c;
  c.name = "many";
  c.fps = 10.0f;
  c.num_frames = 2;
  c.num_joints = n;
  const std::vector<glm::quat> f0 = random_quats(n, rng, nullptr);
  const std::vector<glm::quat> f1 = random_quats(n, rng, &f0);
  c.rotations = f0;
  c.rotations.insert(c.rotations.end(), f1.begin(), f1.end());
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int i = 0; i < 2 * n; ++i) c.translations.push_back(glm::vec3(u(rng), u(rng), u(rng)));
  std::vector<glm::quat> r(n);
  std::vector<glm::vec3> t(n);
  const float w = 0.3f;
  SampleClipJob job{&c, w / c.fps, r, t};
  ASSERT_TRUE(job.validate());
  job.run();
  for (int j = 0; j < n; ++j) {
    const glm::quat b = glm::dot(f0[j], f1[j]) < 0.0f ? -f1[j] : f1[j];
    const glm::quat want = glm::normalize(f0[j] * (1.0f - w) + b * w);
    for (int k = 0; k < 4; ++k) EXPECT_NEAR(r[j][k], want[k], 1e-6f) << "joint " << j;
    const glm::vec3 want_t = glm::mix(c.translations[j], c.translations[n + j], w);
    EXPECT_NEAR(glm::length(t[j] - want_t), 0.0f, 1e-6f) << "joint " << j;
  }
}

TEST(BlendPosesJob, TwoLayersOfManyJointsEachAsTheFormula) {
  const int n = 10;
  std::mt19937 rng(4);
  const std::vector<glm::quat> a = random_quats(n, rng, nullptr);
  const std::vector<glm::quat> b = random_quats(n, rng, &a);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<glm::vec3> ta(n), tb(n);
  for (int i = 0; i < n; ++i) {
    ta[i] = glm::vec3(u(rng), u(rng), u(rng));
    tb[i] = glm::vec3(u(rng), u(rng), u(rng));
  }
  // A weightless layer between them is skipped.
  PoseLayer layers[3] = {{a, ta, 2.0f}, {b, tb, 0.0f}, {b, tb, 1.0f}};
  std::vector<glm::quat> r(n);
  std::vector<glm::vec3> t(n);
  BlendPosesJob job{layers, r, t};
  ASSERT_TRUE(job.validate());
  job.run();
  for (int j = 0; j < n; ++j) {
    const glm::quat bj = glm::dot(a[j], b[j]) < 0.0f ? -b[j] : b[j];
    const glm::quat want = glm::normalize(a[j] * (2.0f / 3.0f) + bj * (1.0f / 3.0f));
    for (int k = 0; k < 4; ++k) EXPECT_NEAR(r[j][k], want[k], 1e-6f) << "joint " << j;
    EXPECT_NEAR(glm::length(t[j] - (ta[j] * (2.0f / 3.0f) + tb[j] * (1.0f / 3.0f))), 0.0f, 1e-6f)
        << "joint " << j;
  }
}

// Three or more layers go four joints at a time: the same bits as the plain loop (sums from 0
// in layer order, each layer's weight negated outside the first's hemisphere), any joint count.
TEST(BlendPosesJob, ManyLayersFourJointsAtATimeEqualThePlainLoopBitForBit) {
  std::mt19937 rng(8);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), weight(0.01f, 2.0f);
  for (const int n : {1, 3, 4, 7, 25}) {
    for (const int num_layers : {3, 4}) {
      std::vector<std::vector<glm::quat>> r(num_layers);
      std::vector<std::vector<glm::vec3>> t(num_layers);
      std::vector<PoseLayer> layers;
      for (int l = 0; l < num_layers; ++l) {
        r[l] = random_quats(n, rng, nullptr);
        for (int j = 0; j < n; ++j) t[l].push_back(glm::vec3(u(rng), u(rng), u(rng)));
        layers.push_back({r[l], t[l], l == 1 ? 0.0f : weight(rng)});  // one weightless layer
      }
      if (num_layers == 3) layers[1].weight = weight(rng);  // three weighted
      float total = 0.0f;
      for (const PoseLayer& l : layers) total += l.weight > 0.0f ? l.weight : 0.0f;
      const float inv_total = 1.0f / total;
      std::vector<glm::quat> got_r(n);
      std::vector<glm::vec3> got_t(n);
      BlendPosesJob{layers, got_r, got_t}.run();
      int first = 0;
      while (!(layers[first].weight > 0.0f)) ++first;
      for (int j = 0; j < n; ++j) {
        glm::quat q(0, 0, 0, 0);
        glm::vec3 p(0.0f);
        for (const PoseLayer& l : layers) {
          if (l.weight <= 0.0f) continue;
          const float w = l.weight * inv_total;
          q += (glm::dot(layers[first].rotations[j], l.rotations[j]) < 0.0f ? -w : w) *
               l.rotations[j];
          p += w * l.translations[j];
        }
        const glm::quat want = glm::normalize(q);
        for (int k = 0; k < 4; ++k) ASSERT_EQ(got_r[j][k], want[k]) << "n " << n << " joint " << j;
        for (int k = 0; k < 3; ++k) ASSERT_EQ(got_t[j][k], p[k]) << "n " << n << " joint " << j;
      }
    }
  }
}

TEST(BlendPosesJob, OneWeightedLayerIsCopied) {
  const glm::quat a = glm::angleAxis(glm::radians(20.0f), glm::vec3(0, 0, 1));
  const glm::quat b = glm::angleAxis(glm::radians(70.0f), glm::vec3(1, 0, 0));
  glm::vec3 ta(0.3f, 0.2f, 0.1f), tb(4, 0, 0);
  PoseLayer layers[2] = {{{&a, 1}, {&ta, 1}, 0.0f}, {{&b, 1}, {&tb, 1}, 0.7f}};
  glm::quat r;
  glm::vec3 t;
  BlendPosesJob{layers, {&r, 1}, {&t, 1}}.run();
  EXPECT_EQ(r, b);
  EXPECT_EQ(t, tb);
  layers[1].weight = 0.0f;  // nothing weighted: the first layer
  BlendPosesJob{layers, {&r, 1}, {&t, 1}}.run();
  EXPECT_EQ(r, a);
  EXPECT_EQ(t, ta);
}

// A random looping clip of n joints and `frames` frames whose root travels (so a wrap moves it on).
Clip random_clip(int n, int frames, std::mt19937& rng) {
  Clip c;
  c.name = "random";
  c.fps = 30.0f;
  c.num_frames = frames;
  c.num_joints = n;
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<glm::quat> previous;
  for (int f = 0; f < frames; ++f) {
    const std::vector<glm::quat> q = random_quats(n, rng, f > 0 ? &previous : nullptr);
    c.rotations.insert(c.rotations.end(), q.begin(), q.end());
    previous = q;
    for (int j = 0; j < n; ++j) {
      c.translations.push_back(j == 0 ? glm::vec3(0.1f * f, 0.9f + 0.01f * u(rng), 0.05f * u(rng))
                                      : glm::vec3(u(rng), u(rng), u(rng)));
    }
  }
  return c;
}

// The fused job is an optimisation of these two: the same bits, at any times (a loop's wrap and
// its root's step included) and weights, four joints at a time and the remainder.
TEST(SampleBlendJob, EqualsTwoSamplesAndTheirBlendBitForBit) {
  std::mt19937 rng(21);
  for (const int n : {1, 4, 11, 25}) {
    const Clip a = random_clip(n, 7, rng), b = random_clip(n, 9, rng);
    std::uniform_real_distribution<float> time(-0.5f, 0.7f), weight(0.01f, 3.0f);
    for (int trial = 0; trial < 200; ++trial) {
      // Every third trial at a frame pair across the loop's wrap.
      const float ta = trial % 3 == 0 ? (a.num_frames - 0.4f) / a.fps : time(rng);
      const float tb = trial % 3 == 0 ? (b.num_frames - 0.7f) / b.fps : time(rng);
      const float wa = weight(rng), wb = weight(rng);
      std::vector<glm::quat> ra(n), rb(n), want_r(n), got_r(n);
      std::vector<glm::vec3> pa(n), pb(n), want_t(n), got_t(n);
      SampleClipJob{&a, ta, ra, pa}.run();
      SampleClipJob{&b, tb, rb, pb}.run();
      const PoseLayer layers[2] = {{ra, pa, wa}, {rb, pb, wb}};
      BlendPosesJob{layers, want_r, want_t}.run();
      SampleBlendJob job;
      job.a = {&a, ta, wa};
      job.b = {&b, tb, wb};
      job.out_rotations = got_r;
      job.out_translations = got_t;
      ASSERT_TRUE(job.validate());
      job.run();
      for (int j = 0; j < n; ++j) {
        for (int k = 0; k < 4; ++k) {
          ASSERT_EQ(got_r[j][k], want_r[j][k]) << "n " << n << " trial " << trial << " joint " << j;
        }
        for (int k = 0; k < 3; ++k) {
          ASSERT_EQ(got_t[j][k], want_t[j][k]) << "n " << n << " trial " << trial << " joint " << j;
        }
      }
    }
  }
}

// With a list of translated joints, the jobs write those joints' translations as they would
// without it (the same bits; the root's step across a wrap too) and leave the others alone.
TEST(PoseJobs, TranslatedJointsOnlyAreWrittenAsWithoutTheList) {
  std::mt19937 rng(33);
  const int n = 11;
  const Clip a = random_clip(n, 7, rng), b = random_clip(n, 9, rng);
  const std::vector<int16_t> lists[] = {{0}, {0, 3, 10}, {2, 5}};
  const glm::vec3 kept(7.0f, -7.0f, 7.0f);
  for (const std::vector<int16_t>& list : lists) {
    for (const float time : {0.05f, (a.num_frames - 0.4f) / a.fps}) {
      std::vector<glm::quat> r(n), r_all(n), rb(n);
      std::vector<glm::vec3> t(n, kept), t_all(n), tb(n, kept), tb_all(n);
      SampleClipJob all{&a, time, r_all, t_all};
      all.run();
      SampleClipJob some{&a, time, r, t, list};
      ASSERT_TRUE(some.validate());
      some.run();
      SampleClipJob{&b, 0.5f * time, rb, tb_all}.run();
      SampleClipJob{&b, 0.5f * time, rb, tb, list}.run();
      SampleBlendJob blend;
      blend.a = {&a, time, 0.7f};
      blend.b = {&b, 0.5f * time, 1.3f};
      blend.out_rotations = r_all;
      blend.out_translations = t_all;
      std::vector<glm::vec3> blend_all(n), blend_some(n, kept);
      blend.out_translations = blend_all;
      blend.run();
      blend.out_translations = blend_some;
      blend.translated_joints = list;
      ASSERT_TRUE(blend.validate());
      blend.run();
      std::vector<glm::vec3> layers_all(n), layers_some(n, kept);
      const PoseLayer layers[3] = {{r_all, t_all, 0.5f}, {rb, tb_all, 0.25f}, {rb, tb_all, 1.0f}};
      BlendPosesJob{layers, r, layers_all}.run();
      BlendPosesJob{layers, r, layers_some, list}.run();
      std::vector<glm::vec3> two_all(n), two_some(n, kept);  // two layers: the four-wide path
      BlendPosesJob{{layers, 2}, r, two_all}.run();
      BlendPosesJob{{layers, 2}, r, two_some, list}.run();
      for (int j = 0; j < n; ++j) {
        const bool listed = std::find(list.begin(), list.end(), j) != list.end();
        EXPECT_EQ(t[j], listed ? t_all[j] : kept) << "joint " << j;
        EXPECT_EQ(blend_some[j], listed ? blend_all[j] : kept) << "joint " << j;
        EXPECT_EQ(layers_some[j], listed ? layers_all[j] : kept) << "joint " << j;
        EXPECT_EQ(two_some[j], listed ? two_all[j] : kept) << "joint " << j;
      }
    }
  }
  std::vector<glm::quat> r(n);
  std::vector<glm::vec3> t(n);
  const std::vector<int16_t> unordered = {3, 1}, outside = {0, 11};
  EXPECT_FALSE((SampleClipJob{&a, 0.0f, r, t, unordered}.validate()));
  EXPECT_FALSE((SampleClipJob{&a, 0.0f, r, t, outside}.validate()));
}

// With runs of sampled joints, the jobs write those joints' rotations and translations as they
// would without them (the same bits: runs of one to three joints through the padded path, longer
// ones with their last four again; the root's step across a wrap too) and leave the others alone.
TEST(PoseJobs, SampledRunsOnlyAreWrittenAsWithoutThem) {
  std::mt19937 rng(35);
  const int n = 25;
  const Clip a = random_clip(n, 7, rng), b = random_clip(n, 9, rng);
  const std::vector<JointRun> run_sets[] = {
      {{0, 11}, {13, 14}, {18, 25}}, {{0, 3}, {5, 9}}, {{2, 25}}, {{0, 25}}};
  const glm::quat kept_r(0.5f, 0.5f, -0.5f, 0.5f);
  const glm::vec3 kept_t(7.0f, -7.0f, 7.0f);
  for (const std::vector<JointRun>& runs : run_sets) {
    auto in_runs = [&](int j) {
      for (const JointRun& r : runs) {
        if (j >= r.from && j < r.to) return true;
      }
      return false;
    };
    for (const float time : {0.05f, (a.num_frames - 0.4f) / a.fps}) {
      std::vector<glm::quat> r_all(n), r_some(n, kept_r), br_all(n), br_some(n, kept_r);
      std::vector<glm::vec3> t_all(n), t_some(n, kept_t), bt_all(n), bt_some(n, kept_t);
      SampleClipJob{&a, time, r_all, t_all}.run();
      SampleClipJob some{&a, time, r_some, t_some, {}, runs};
      ASSERT_TRUE(some.validate());
      some.run();
      SampleBlendJob blend;
      blend.a = {&a, time, 0.7f};
      blend.b = {&b, 0.5f * time + 0.1f, 1.3f};
      blend.out_rotations = br_all;
      blend.out_translations = bt_all;
      blend.run();
      blend.out_rotations = br_some;
      blend.out_translations = bt_some;
      blend.sampled_runs = runs;
      ASSERT_TRUE(blend.validate());
      blend.run();
      for (int j = 0; j < n; ++j) {
        const bool sampled = in_runs(j);
        EXPECT_EQ(r_some[j], sampled ? r_all[j] : kept_r) << "joint " << j;
        EXPECT_EQ(t_some[j], sampled ? t_all[j] : kept_t) << "joint " << j;
        EXPECT_EQ(br_some[j], sampled ? br_all[j] : kept_r) << "joint " << j;
        EXPECT_EQ(bt_some[j], sampled ? bt_all[j] : kept_t) << "joint " << j;
      }
    }
  }
  std::vector<glm::quat> r(n);
  std::vector<glm::vec3> t(n);
  const std::vector<JointRun> overlapping = {{0, 5}, {4, 8}}, outside = {{20, 26}}, empty = {{3, 3}};
  EXPECT_FALSE((SampleClipJob{&a, 0.0f, r, t, {}, overlapping}.validate()));
  EXPECT_FALSE((SampleClipJob{&a, 0.0f, r, t, {}, outside}.validate()));
  EXPECT_FALSE((SampleClipJob{&a, 0.0f, r, t, {}, empty}.validate()));
}

TEST(SampleBlendJob, ValidateRefusesUnweightedOrMismatchedInputs) {
  std::mt19937 rng(5);
  const Clip a = random_clip(4, 3, rng), b = random_clip(4, 3, rng), c = random_clip(5, 3, rng);
  std::vector<glm::quat> r(5);
  std::vector<glm::vec3> t(5);
  SampleBlendJob job;
  job.a = {&a, 0.0f, 1.0f};
  job.b = {&b, 0.0f, 1.0f};
  job.out_rotations = r;
  job.out_translations = t;
  EXPECT_TRUE(job.validate());
  job.b.weight = 0.0f;
  EXPECT_FALSE(job.validate());
  job.b = {&c, 0.0f, 1.0f};  // another skeleton
  EXPECT_FALSE(job.validate());
  job.b = {nullptr, 0.0f, 1.0f};
  EXPECT_FALSE(job.validate());
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

// A random local pose: rest translations, rotations within about 45 degrees of identity.
void random_pose(const Skeleton& s, std::mt19937& rng, std::vector<glm::quat>* r,
                 std::vector<glm::vec3>* t) {
  std::uniform_real_distribution<float> u(-0.4f, 0.4f);
  r->resize(s.num_joints());
  for (glm::quat& q : *r) q = glm::normalize(glm::quat(1.0f, u(rng), u(rng), u(rng)));
  *t = s.rest_translations;
}

bool same(const glm::mat4& a, const glm::mat4& b) { return a == b; }

TEST(LocalToModelJob, EqualsThePlainMatrixProduct) {
  const auto s = make_humanoid_skeleton();
  std::mt19937 rng(11);
  std::vector<glm::quat> r;
  std::vector<glm::vec3> t;
  random_pose(*s, rng, &r, &t);
  const glm::mat4 root = glm::translate(glm::mat4(1), glm::vec3(3, 0.1f, -2)) *
                         glm::mat4_cast(glm::angleAxis(0.7f, glm::vec3(0, 1, 0)));
  std::vector<glm::mat4> m(s->num_joints());
  LocalToModelJob{s.get(), r, t, root, m}.run();
  for (int j = 0; j < s->num_joints(); ++j) {
    glm::mat4 local = glm::mat4_cast(r[j]);
    local[3] = glm::vec4(t[j], 1.0f);
    const int p = s->parents[j];
    EXPECT_TRUE(same(m[j], (p < 0 ? root : m[p]) * local)) << s->names[j];
  }
}

TEST(LocalToModelJob, RangeRecomputesOnlyItsJoints) {
  const Skeleton s = make_chain(5, 0.5f);
  std::vector<glm::quat> r(5, glm::angleAxis(0.3f, glm::vec3(1, 0, 0)));
  std::vector<glm::mat4> full(5), part(5);
  LocalToModelJob{&s, r, s.rest_translations, glm::mat4(1), full}.run();
  const glm::mat4 sentinel(2.0f);
  part = full;
  part[1] = part[2] = part[3] = sentinel;
  LocalToModelJob job{&s, r, s.rest_translations, glm::mat4(1), part, 1, 3};
  ASSERT_TRUE(job.validate());
  job.run();
  EXPECT_TRUE(same(part[1], full[1]));
  EXPECT_TRUE(same(part[2], full[2]));
  EXPECT_TRUE(same(part[3], sentinel));  // past the range: untouched
  EXPECT_FALSE((LocalToModelJob{&s, r, s.rest_translations, glm::mat4(1), part, 3, 2}.validate()));
  EXPECT_FALSE((LocalToModelJob{&s, r, s.rest_translations, glm::mat4(1), part, 0, 6}.validate()));
}

// After one joint's local transform changes, recomputing its subtree range gives the full pass's
// pose to the bit, on every joint of the built-in rig, which is depth-first (every range is exactly
// the joint's subtree, so the update is partial).
TEST(LocalToModelJob, SubtreeUpdateAfterOneJointChangedEqualsFullPass) {
  const auto s = make_humanoid_skeleton();
  const int n = s->num_joints();
  const std::vector<int> ends = subtree_ends(*s);
  ASSERT_EQ(static_cast<int>(ends.size()), n);
  std::mt19937 rng(5);
  std::vector<glm::quat> r;
  std::vector<glm::vec3> t;
  random_pose(*s, rng, &r, &t);
  const glm::mat4 root = glm::translate(glm::mat4(1), glm::vec3(1, 0.05f, 2));
  std::vector<glm::mat4> before(n), full(n), part(n);
  LocalToModelJob{s.get(), r, t, root, before}.run();
  for (int j = 0; j < n; ++j) {
    int descendants = 0;
    for (int k = j + 1; k < n; ++k) {
      for (int a = s->parents[k]; a >= 0; a = s->parents[a]) descendants += a == j;
    }
    EXPECT_EQ(ends[j] - j, descendants + 1) << s->names[j];
    std::vector<glm::quat> r2 = r;
    std::vector<glm::vec3> t2 = t;
    r2[j] = glm::normalize(r2[j] * glm::angleAxis(0.5f, glm::normalize(glm::vec3(1, 0.5f, 0.2f))));
    t2[j] += glm::vec3(0.02f, -0.01f, 0.0f);
    LocalToModelJob{s.get(), r2, t2, root, full}.run();
    part = before;
    LocalToModelJob job{s.get(), r2, t2, root, part, j, ends[j]};
    ASSERT_TRUE(job.validate());
    job.run();
    for (int k = 0; k < n; ++k) {
      EXPECT_TRUE(same(part[k], full[k])) << "changed " << s->names[j] << ", joint " << s->names[k];
    }
  }
}

// A two-bone IK job on the first three model matrices of a chain (hip, knee, ankle), writing its
// corrections to c0 and c1.
TwoBoneIKJob chain_ik(const std::vector<glm::mat4>& m, const glm::vec3& target,
                      const glm::vec3& pole, glm::quat* c0, glm::quat* c1) {
  TwoBoneIKJob ik;
  ik.start_model = m[0];
  ik.mid_model = m[1];
  ik.end_model = m[2];
  ik.target = target;
  ik.pole = pole;
  ik.out_start_correction = c0;
  ik.out_mid_correction = c1;
  return ik;
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
    TwoBoneIKJob ik = chain_ik(m, target, pole, &c0, &c1);
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

// A limb within a hair of straight (bent half a degree either way, as a captured stance leg at
// push-off) bends toward the pole: its own bend plane is no guide, and taking it turned the limb
// about itself by up to half a turn whenever the hair's bend pointed away from the pole.
TEST(TwoBoneIKJob, NearlyStraightLimbBendsTowardThePole) {
  const Skeleton s = make_chain(3, 0.4f);
  for (const float bend_deg : {0.5f, -0.5f}) {
    std::vector<glm::quat> r(3, glm::quat(1, 0, 0, 0));
    r[1] = glm::angleAxis(glm::radians(bend_deg), glm::vec3(1, 0, 0));
    std::vector<glm::mat4> m(3);
    LocalToModelJob fk{&s, r, s.rest_translations, glm::mat4(1), m};
    fk.run();
    const glm::vec3 hip = translation_of(m[0]);
    const glm::vec3 target = hip + glm::normalize(translation_of(m[2]) - hip) * 0.7f;
    const glm::vec3 pole(0, 0, 1);
    glm::quat c0, c1;
    chain_ik(m, target, pole, &c0, &c1).run();
    r[0] = r[0] * c0;
    r[1] = r[1] * c1;
    fk.run();
    EXPECT_LT(glm::length(translation_of(m[2]) - target), 1e-3f) << bend_deg;
    const glm::vec3 axis = glm::normalize(target - hip);
    glm::vec3 knee = translation_of(m[1]) - hip;
    knee -= axis * glm::dot(knee, axis);
    EXPECT_GT(glm::dot(knee, pole), 0.0f) << bend_deg;
    // The hip turns by about the knee's bend (30 deg at 0.7 of 0.8 m), not about the limb.
    EXPECT_LT(2.0f * std::acos(std::min(1.0f, std::abs(c0.w))), glm::radians(45.0f)) << bend_deg;
  }
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

TEST(SkinningPaletteJob, AffineProductEqualsTheFullOne) {
  const auto s = make_humanoid_skeleton();
  const int n = s->num_joints();
  std::mt19937 rng(2);
  std::vector<glm::quat> r;
  std::vector<glm::vec3> t;
  std::vector<glm::mat4> rest(n), m(n), inv(n), full(n), affine(n);
  LocalToModelJob{s.get(), s->rest_rotations, s->rest_translations, glm::mat4(1), rest}.run();
  for (int i = 0; i < n; ++i) {
    inv[i] = glm::mat4(glm::inverse(glm::mat3(rest[i])));
    inv[i][3] = glm::vec4(-(glm::mat3(inv[i]) * glm::vec3(rest[i][3])), 1.0f);
  }
  random_pose(*s, rng, &r, &t);
  LocalToModelJob{s.get(), r, t, glm::translate(glm::mat4(1), glm::vec3(4, 0, 1)), m}.run();
  ASSERT_TRUE(is_affine(inv));
  SkinningPaletteJob{m, inv, full, false}.run();
  SkinningPaletteJob{m, inv, affine, true}.run();
  for (int i = 0; i < n; ++i) EXPECT_TRUE(same(full[i], affine[i])) << s->names[i];
  std::vector<glm::mat4> streamed(n);
  SkinningPaletteJob{m, inv, streamed, true, true}.run();
  for (int i = 0; i < n; ++i) EXPECT_TRUE(same(full[i], streamed[i])) << s->names[i];
  // The model matrices copied in the same pass (streamed, or not: not affine, not streamed).
  for (const bool affine_path : {true, false}) {
    for (const bool stream : {true, false}) {
      std::vector<glm::mat4> pal(n), copy(n);
      SkinningPaletteJob job{m, inv, pal, affine_path, stream};
      job.out_model_copy = copy;
      ASSERT_TRUE(job.validate());
      job.run();
      for (int i = 0; i < n; ++i) {
        EXPECT_TRUE(same(full[i], pal[i])) << s->names[i];
        EXPECT_TRUE(same(m[i], copy[i])) << s->names[i];
      }
    }
  }
  // The humanoid's rest rotations are the identity: its inverse binds are translations, and the
  // palette's first three columns the model's own (equal to the product's, -0 == 0).
  ASSERT_TRUE(is_translation(inv));
  for (const bool stream : {true, false}) {
    for (const bool with_copy : {true, false}) {
      std::vector<glm::mat4> pal(n), copy(n);
      SkinningPaletteJob job{m, inv, pal, true, stream};
      if (with_copy) job.out_model_copy = copy;
      job.translation_inverse_bind = true;
      ASSERT_TRUE(job.validate());
      job.run();
      for (int i = 0; i < n; ++i) {
        EXPECT_TRUE(same(full[i], pal[i])) << s->names[i];
        if (with_copy) {
          EXPECT_TRUE(same(m[i], copy[i])) << s->names[i];
        }
      }
    }
  }
  inv[2][0][1] = 1e-7f;  // a rotation: not a translation, still affine
  EXPECT_FALSE(is_translation(inv));
  EXPECT_TRUE(is_affine(inv));
  inv[3][1][3] = 1e-7f;  // not affine any more
  EXPECT_FALSE(is_affine(inv));
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
