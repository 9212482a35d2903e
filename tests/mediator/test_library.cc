// The mediator's clip library built from the built-in set, the real CMU pair (two actors) and the
// Quaternius glb: what it keeps, how it retargets, and its phase tables.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include <gtest/gtest.h>

#include "animation/clip_library.h"
#include "animation/pose_jobs.h"
#include "animation/procedural.h"
#include "tests/animation/clip_transforms.h"
#include "tests/animation/model_pose.h"
#include "tests/mediator/mediator_fixture.h"
#include "tests/test_data.h"

namespace gk {
namespace {

const LocomotionClip* find(const LocomotionLibrary& lib, const std::string& name) {
  for (const LocomotionClip& c : lib.clips) {
    if (c.clip.name == name) return &c;
  }
  return nullptr;
}

TEST(LocomotionLibrary, BuiltinBlendSpace) {
  const LocomotionLibrary& lib = test::builtin_library();
  ASSERT_EQ(lib.clips.size(), 9u);
  ASSERT_GE(lib.idle, 0);
  EXPECT_EQ(lib.clips[lib.idle].clip.name, "idle");
  // Forward, left, right and backward groups, each sorted by speed.
  ASSERT_EQ(lib.groups.size(), 4u);
  for (const DirectionGroup& g : lib.groups) {
    for (size_t k = 1; k < g.clips.size(); ++k) {
      EXPECT_LE(lib.clips[g.clips[k - 1]].speed_m_s, lib.clips[g.clips[k]].speed_m_s);
    }
  }
  EXPECT_EQ(lib.groups[lib.forward_group].clips.size(), 5u);
  // Phase tables run forward over exactly one cycle.
  for (const LocomotionClip& c : lib.clips) {
    if (!c.gait) continue;
    for (int k = 1; k <= kPhaseTableSize; ++k)
      EXPECT_GE(c.phase_to_time[k], c.phase_to_time[k - 1]);
    EXPECT_NEAR(c.phase_to_time[kPhaseTableSize] - c.phase_to_time[0], c.cycle_s, 1e-4f);
  }
}

// A loop played by phase comes round to its first frame as its phase does: its phase table spans
// a whole number of the loop's durations (one stride: the duration itself). Otherwise every wrap
// of the phase skips (or repeats) the frames between, and the legs jump each stride. Loops cut
// from captures have steps of unequal length, where the phase at the loop's end did not meet the
// phase at its start (the CMU run, subject 16's veer, turn and fast walk were a frame short).
TEST(LocomotionLibrary, LoopsPlayedByPhaseWrapWithoutSkippingFrames) {
  GK_REQUIRE_DATA("clips/bvh/more");
  auto cmu =
      test::load_data_library({"clips/bvh/cmu_07_01_walk.bvh", "clips/bvh/cmu_09_11_run.bvh"});
  auto more = test::subject16_library();
  auto mannequin = test::load_data_library({"clips/gltf/ual_mannequin_quaternius.glb"});
  ASSERT_TRUE(cmu.ok()) << cmu.message();
  ASSERT_TRUE(more.ok()) << more.message();
  ASSERT_TRUE(mannequin.ok()) << mannequin.message();
  int loops = 0;
  for (const LocomotionLibrary* lib : std::initializer_list<const LocomotionLibrary*>{
           &test::builtin_library(), &*cmu, &*more, &*mannequin}) {
    for (const LocomotionClip& c : lib->clips) {
      if (!c.gait || !c.clip.loops) continue;
      ++loops;
      const float duration = c.clip.duration_s();
      const float strides = std::max(1.0f, std::round(duration / c.cycle_s));
      // Within a tenth of a frame.
      EXPECT_NEAR(c.cycle_s * strides, duration, 0.1f / c.clip.fps) << c.clip.name;
      // The phase advances through the seam as it does on either side of it: its last table
      // step is no longer in clip time than twice the mean step.
      const float mean_step = c.cycle_s / kPhaseTableSize;
      EXPECT_LT(c.phase_to_time[kPhaseTableSize] - c.phase_to_time[kPhaseTableSize - 1],
                2.0f * mean_step + 1e-4f)
          << c.clip.name;
    }
  }
  EXPECT_GE(loops, 20);
}

// The same for a loop of any rig: the built-in walk, time-warped smoothly (the loop stays closed)
// so that one of its steps takes longer than the other, as a capture's may.
TEST(LocomotionLibrary, AnUnevenLoopWrapsWithoutSkippingFrames) {
  ClipSet set = make_builtin_clip_set();
  std::vector<Clip> kept;
  for (const Clip& c : set.clips) {
    if (c.name == "idle") kept.push_back(c);
    if (c.name == "walk") kept.push_back(test::unevenly_timed(c, 0.35f));
  }
  ASSERT_EQ(kept.size(), 2u);
  set.clips = std::move(kept);
  auto lib = build_locomotion_library({set});
  ASSERT_TRUE(lib.ok()) << lib.message();
  const LocomotionClip* walk = find(*lib, "walk");
  ASSERT_NE(walk, nullptr);
  ASSERT_TRUE(walk->gait);
  // Its two steps are uneven: one contact start is not halfway round from the other.
  const float l = walk->analysis.contacts[0][0].start_s, r = walk->analysis.contacts[1][0].start_s;
  const float apart = std::abs(r - l) / walk->clip.duration_s();
  EXPECT_GT(std::abs(apart - 0.5f), 0.05f);
  EXPECT_NEAR(walk->cycle_s, walk->clip.duration_s(), 0.1f / walk->clip.fps);
  // Across the seam the phase moves on as much as a frame either side of it does.
  const std::vector<float>& ph = walk->analysis.phase;
  const int n = walk->clip.num_frames;
  auto step = [&](int f) {
    float d = ph[(f + 1) % n] - ph[f];
    return d - std::floor(d);
  };
  const float around = 0.5f * (step(n - 2) + step(0));
  EXPECT_NEAR(step(n - 1), around, 0.25f * around);
}

TEST(LocomotionLibrary, InPlaceClipsKeepOnlyTheSway) {
  // The in-place walk's hips stay within a few centimetres of the origin horizontally.
  const LocomotionLibrary& lib = test::builtin_library();
  const LocomotionClip* walk = find(lib, "walk");
  ASSERT_NE(walk, nullptr);
  for (int f = 0; f < walk->clip.num_frames; ++f) {
    const glm::vec3 t = walk->clip.frame_translations(f)[0];
    EXPECT_LT(std::hypot(t.x, t.z), 0.06f) << f;
  }
}

TEST(LocomotionLibrary, TwoActorsOfTheCmuRetargetedOntoOne) {
  GK_REQUIRE_DATA("clips/bvh/cmu_09_11_run.bvh");
  auto loaded =
      test::load_data_clip_sets({"clips/bvh/cmu_07_01_walk.bvh", "clips/bvh/cmu_09_11_run.bvh"});
  ASSERT_TRUE(loaded.ok()) << loaded.message();
  std::vector<ClipSet>& sets = *loaded;
  // Leg lengths of the two actors, to predict the run's speed on the walker's body.
  auto leg = [](const Skeleton& sk) {
    std::vector<glm::mat4> m(sk.num_joints());
    LocalToModelJob{&sk, sk.rest_rotations, sk.rest_translations, glm::mat4(1.0f), m}.run();
    const Side s = Side::kLeft;
    return glm::length(translation_of(m[sk.knee(s)]) - translation_of(m[sk.hip(s)])) +
           glm::length(translation_of(m[sk.ankle(s)]) - translation_of(m[sk.knee(s)]));
  };
  const float ratio = leg(*sets[0].skeleton) / leg(*sets[1].skeleton);
  auto lib = build_locomotion_library(sets);
  ASSERT_TRUE(lib.ok()) << lib.message();
  EXPECT_EQ(lib->skeleton, sets[0].skeleton);
  const LocomotionClip* walk = find(*lib, "cmu_07_01_walk");
  const LocomotionClip* run = find(*lib, "cmu_09_11_run");
  ASSERT_TRUE(walk && run);
  // Clip analysis reports the takes' root speeds; the run's on the walker's body is scaled by
  // the legs.
  EXPECT_NEAR(walk->analysis.native_speed_m_s, 1.36f, 0.05f * 1.36f);
  EXPECT_NEAR(run->analysis.native_speed_m_s, 3.50f * ratio, 0.05f * 3.50f * ratio);
  // The library plays each at the speed its planted feet are carried under the body at: the
  // toe's way back over the middle halves of its runs of rest frames, sampled and posed here,
  // over their time (within 8%: the library takes a median over all of them), and no more than
  // 15% off the root's (the captures' feet slide a little in their own root motion).
  for (const LocomotionClip* c : {walk, run}) {
    const Skeleton& sk = *lib->skeleton;
    std::vector<glm::quat> rot(sk.num_joints());
    std::vector<glm::vec3> tr(sk.num_joints());
    std::vector<glm::mat4> m(sk.num_joints());
    auto toe_z = [&](int f, int s) {
      SampleClipJob{&c->clip, f / c->clip.fps, rot, tr}.run();
      LocalToModelJob{&sk, rot, tr, glm::mat4(1.0f), m}.run();
      return translation_of(m[sk.toe(static_cast<Side>(s))]).z;
    };
    double moved = 0.0, time = 0.0;
    const int n = c->clip.num_frames;
    for (int s = 0; s < 2; ++s) {
      for (int f = 0; f < n;) {
        if (!c->plant[s][f]) {
          ++f;
          continue;
        }
        int e = f;
        while (e + 1 < n && c->plant[s][e + 1]) ++e;
        const int a = f + (e - f) / 4, b = e - (e - f) / 4;
        if (b > a) {
          moved += toe_z(a, s) - toe_z(b, s);
          time += (b - a) / c->clip.fps;
        }
        f = e + 1;
      }
    }
    ASSERT_GT(time, 0.0) << c->clip.name;
    EXPECT_NEAR(c->speed_m_s, moved / time, 0.08 * moved / time) << c->clip.name;
    EXPECT_NEAR(c->speed_m_s, c->analysis.native_speed_m_s, 0.15f * c->analysis.native_speed_m_s)
        << c->clip.name;
  }
  // No idle clip in the pair: a standing pose is made from the walk, with both feet down.
  ASSERT_GE(lib->idle, 0);
  EXPECT_FALSE(lib->clips[lib->idle].gait);
  EXPECT_NE(lib->clips[lib->idle].clip.name.find("cmu_07_01_walk"), std::string::npos);
}

TEST(LocomotionLibrary, MannequinGlbKeepsLocomotionAndItsIdle) {
  GK_REQUIRE_DATA("clips/gltf/ual_mannequin_quaternius.glb");
  auto lib = test::load_data_library({"clips/gltf/ual_mannequin_quaternius.glb"});
  ASSERT_TRUE(lib.ok()) << lib.message();
  EXPECT_EQ(lib->clips[lib->idle].clip.name, "Idle_Loop");
  EXPECT_NE(find(*lib, "Walk_Loop"), nullptr);
  for (const LocomotionClip& c : lib->clips) {
    const std::string n = c.clip.name;
    EXPECT_EQ(n.find("Crouch"), std::string::npos) << n;
    EXPECT_EQ(n.find("Swim"), std::string::npos) << n;
    EXPECT_EQ(n.find("Driving"), std::string::npos) << n;
  }
  EXPECT_EQ(lib->skeleton->num_joints(), 53);
  ASSERT_TRUE(lib->mesh);  // the glb's own skinned mesh is kept for the renderer
}

// A steady cycle cut from a take keeps the contacts the take's analysis found in that stride
// (the loop alone has no before and after for its stances): in each walk of the subject-16 set,
// the loop's contacts alternate, one stance per foot, each foot down for about the same share of
// the cycle, a walk's 55-75% (GAIT.md: stance 60%, longer when slow), and both down together for
// a while twice (double support).
TEST(LocomotionLibrary, LoopsCutFromATakeKeepItsStances) {
  GK_REQUIRE_DATA("clips/bvh/more/cmu_16_15_walk_mrl30.bvh");
  for (const char* file : {"clips/bvh/more/cmu_16_15_walk_mrl30.bvh",
                           "clips/bvh/more/cmu_16_22_fast_walk_mrl30.bvh",
                           "clips/bvh/more/cmu_16_11_walk_veer_left.bvh"}) {
    auto lib = test::load_data_library({file});
    ASSERT_TRUE(lib.ok()) << lib.message();
    int loops = 0;
    for (const LocomotionClip& c : lib->clips) {
      if (!c.gait) continue;
      ++loops;
      const float cycle = c.clip.duration_s();
      float down[2] = {0.0f, 0.0f};
      for (int s = 0; s < 2; ++s) {
        ASSERT_EQ(c.analysis.contacts[s].size(), 1u) << c.clip.name << " side " << s;
        const TimeInterval& iv = c.analysis.contacts[s][0];
        down[s] = (iv.end_s - iv.start_s) / cycle;
        EXPECT_GT(down[s], 0.55f) << c.clip.name << " side " << s;
        EXPECT_LT(down[s], 0.75f) << c.clip.name << " side " << s;
      }
      EXPECT_NEAR(down[0], down[1], 0.1f) << c.clip.name;
      EXPECT_TRUE(c.double_support) << c.clip.name;
      EXPECT_TRUE(c.doubts.empty()) << c.clip.name;
    }
    EXPECT_GE(loops, 1) << file;
  }
}

// Retargeting between skeletons whose rest poses differ (the MRL subject-16 skeleton has its arms
// along the body, the cgspeed one out to the sides): every retargeted bone points where the
// source bone points, frame by frame, in model space (upper arms, forearms, thighs, shins).
TEST(LocomotionLibrary, RetargetedBonesPointWhereTheSourceBonesPoint) {
  const char* mrl = "clips/bvh/more/cmu_16_15_walk_mrl30.bvh";
  const char* cgspeed = "clips/bvh/more/cmu_16_11_walk_veer_left.bvh";
  GK_REQUIRE_DATA(mrl);
  GK_REQUIRE_DATA(cgspeed);
  Result<ClipSet> src = load_clip_file(test::data_path(mrl));
  Result<ClipSet> dst = load_clip_file(test::data_path(cgspeed));
  ASSERT_TRUE(src.ok() && dst.ok());
  const Skeleton& S = *src->skeleton;
  const Skeleton& D = *dst->skeleton;
  const Clip out = retarget_clip(src->clips[0], S, D, 1.0f);
  struct Bone {
    const char *src_from, *src_to, *dst_from, *dst_to;
  };
  const Bone bones[] = {{"lhumerus", "lradius", "LeftArm", "LeftForeArm"},
                        {"rhumerus", "rradius", "RightArm", "RightForeArm"},
                        {"lradius", "lhand", "LeftForeArm", "LeftHand"},
                        {"lfemur", "ltibia", "LeftUpLeg", "LeftLeg"},
                        {"rtibia", "rfoot", "RightLeg", "RightFoot"}};
  std::vector<glm::mat4> ms(S.num_joints()), md(D.num_joints());
  float worst = 0.0f;
  for (int f = 0; f < out.num_frames; f += 3) {
    LocalToModelJob{&S, {src->clips[0].frame_rotations(f), static_cast<size_t>(S.num_joints())},
                    {src->clips[0].frame_translations(f), static_cast<size_t>(S.num_joints())},
                    glm::mat4(1.0f), ms}
        .run();
    LocalToModelJob{&D, {out.frame_rotations(f), static_cast<size_t>(D.num_joints())},
                    {out.frame_translations(f), static_cast<size_t>(D.num_joints())},
                    glm::mat4(1.0f), md}
        .run();
    for (const Bone& b : bones) {
      const glm::vec3 ds = glm::normalize(translation_of(ms[S.find(b.src_to)]) -
                                          translation_of(ms[S.find(b.src_from)]));
      const glm::vec3 dd = glm::normalize(translation_of(md[D.find(b.dst_to)]) -
                                          translation_of(md[D.find(b.dst_from)]));
      worst = std::max(worst, glm::degrees(std::acos(std::clamp(glm::dot(ds, dd), -1.0f, 1.0f))));
    }
  }
  EXPECT_LT(worst, 5.0f);
}

}  // namespace
}  // namespace gk

namespace gk {
namespace {

// The released foot's speed limit: the peak speed of a swinging toe over the ground, which is at
// least its mean over the swing (a stride's length over the time the foot is off the ground)
// and, for a smooth swing, less than three times it.
TEST(LocomotionLibrary, SwingSpeedPeaksAboveTheMeanSpeedOfTheSwing) {
  std::vector<LocomotionLibrary> libs;
  libs.push_back(test::builtin_library());
  for (const char* f : {"clips/bvh/cmu_07_01_walk.bvh", "clips/gltf/ual_mannequin_quaternius.glb",
                        "clips/bvh/more/cmu_16_15_walk_mrl30.bvh"}) {
    if (!std::filesystem::exists(test::data_path(f))) continue;
    auto lib = test::load_data_library({f});
    ASSERT_TRUE(lib.ok()) << lib.message();
    libs.push_back(std::move(*lib));
  }
  for (const LocomotionLibrary& lib : libs) {
    const LocomotionClip& slow = lib.clips[lib.groups[lib.forward_group].clips.front()];
    // The share of its frames on which the left foot is off the ground, by the plant flags the
    // swing speed was measured between (the clip is a loop of one stride).
    ASSERT_TRUE(slow.clip.loops) << slow.clip.name;
    const int cycle = slow.clip.num_frames;
    const int off = static_cast<int>(std::count(slow.plant[0].begin(), slow.plant[0].end(), 0));
    ASSERT_GT(off, 0) << slow.clip.name;
    const float mean_swing = slow.speed_m_s * cycle / static_cast<float>(off);
    EXPECT_GE(lib.swing_speed_m_s, mean_swing) << slow.clip.name;
    EXPECT_LE(lib.swing_speed_m_s, 3.0f * mean_swing) << slow.clip.name;
  }
}

}  // namespace
}  // namespace gk

namespace gk {
namespace {

// Toe positions (model space, the clip in place) of `side` sampled at 60 Hz over the clip.
std::vector<glm::vec3> toe_at_60hz(const Clip& c, const Skeleton& sk, Side side) {
  const int J = sk.num_joints();
  std::vector<glm::quat> rot(J);
  std::vector<glm::vec3> trans(J);
  std::vector<glm::vec3> out;
  for (int f = 0; f / 60.0f <= c.duration_s(); ++f) {
    SampleClipJob{&c, f / 60.0f, rot, trans}.run();
    out.push_back(translation_of(test::model_pose(sk, rot.data(), trans.data())[sk.toe(side)]));
  }
  return out;
}

// Captures below 60 fps (the subject-16 set but its veer, 30 fps) are played from their upsampling:
// at every captured frame's time it samples that frame, and between them the toes' velocity changes
// smoothly (sampled linearly at 60 Hz, it jumps at every captured frame: the second difference
// spikes). Authored glTF keys (24 fps) and 120 fps captures are played as they are.
TEST(LocomotionLibrary, CapturesBelow60FpsArePlayedFromTheirUpsampling) {
  GK_REQUIRE_DATA("clips/bvh/more/cmu_16_36_run_jog_mrl30.bvh");
  auto lib = test::subject16_library();
  ASSERT_TRUE(lib.ok()) << lib.message();
  const Skeleton& sk = *lib->skeleton;
  const int J = sk.num_joints();
  int upsampled = 0;
  for (const LocomotionClip& lc : lib->clips) {
    if (!lc.clip.sampled_capture) continue;  // a synthesised standing pose
    if (lc.clip.fps >= 60.0f) {              // the veer, captured at 120 fps
      EXPECT_EQ(&lc.playback(), &lc.clip) << lc.clip.name;
      continue;
    }
    ++upsampled;
    EXPECT_FLOAT_EQ(lc.clip.fps, 30.0f) << lc.clip.name;
    ASSERT_FLOAT_EQ(lc.playback().fps, 60.0f) << lc.clip.name;
    EXPECT_FLOAT_EQ(lc.playback().duration_s(), lc.clip.duration_s()) << lc.clip.name;
    std::vector<glm::quat> ra(J), rb(J);
    std::vector<glm::vec3> ta(J), tb(J);
    for (int f = 0; f < lc.clip.num_frames; ++f) {
      SampleClipJob{&lc.clip, f / lc.clip.fps, ra, ta}.run();
      SampleClipJob{&lc.playback(), f / lc.clip.fps, rb, tb}.run();
      for (int j = 0; j < J; ++j) {
        ASSERT_NEAR(std::abs(glm::dot(ra[j], rb[j])), 1.0f, 1e-5f) << lc.clip.name << " " << f;
        ASSERT_NEAR(glm::length(ta[j] - tb[j]), 0.0f, 1e-5f) << lc.clip.name << " " << f;
      }
    }
  }
  EXPECT_GE(upsampled, 10);
  // The jog's toes, 60 Hz: the largest second difference of the upsampled clip's is smaller than
  // that of the captured frames' straight segments (measured: 98 and 62 m/s^2 against 126 and
  // 72; not half: the capture's own landings are that sharp).
  const LocomotionClip* jog = nullptr;
  for (const LocomotionClip& lc : lib->clips) {
    if (lc.gait && lc.clip.name.find("run_jog_mrl30") != std::string::npos) jog = &lc;
  }
  ASSERT_NE(jog, nullptr);
  for (Side side : {Side::kLeft, Side::kRight}) {
    // Away from the loop's seam (the cut cycle's last frame to its first), where both join the
    // same two captured frames.
    auto worst = [](const std::vector<glm::vec3>& p) {
      float w = 0.0f;
      for (size_t i = 4; i + 5 < p.size(); ++i) {
        w = std::max(w, glm::length(p[i + 1] - 2.0f * p[i] + p[i - 1]) * 3600.0f);
      }
      return w;
    };
    const float lin = worst(toe_at_60hz(jog->clip, sk, side));
    const float up = worst(toe_at_60hz(jog->playback(), sk, side));
    EXPECT_LT(up, lin) << static_cast<int>(side) << ": " << up << " against " << lin;
  }
  // Authored keys and captures at 60 fps or more: played as they are.
  for (const char* file :
       {"clips/gltf/ual_mannequin_quaternius.glb", "clips/bvh/cmu_09_11_run.bvh"}) {
    auto other = test::load_data_library({file});
    ASSERT_TRUE(other.ok()) << other.message();
    for (const LocomotionClip& lc : other->clips) {
      EXPECT_EQ(lc.played.num_frames, 0) << file << " " << lc.clip.name;
      EXPECT_EQ(&lc.playback(), &lc.clip);
    }
  }
}

}  // namespace
}  // namespace gk
