// The mediator on an IK-style rig (feet parented to the root, tests/ik_rig_fixture.h): its clips
// analysed as the built-in clips they were written from (contacts alternate, a cycle of one
// stride), feet planted by apm as on the built-in rig; refused with a way out when the roles
// cannot be found. And libraries of several skeletons: every clip of every file is in the library
// or named with the reason it is not (never dropped silently), and a skeleton that cannot be
// retargeted is refused naming both.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "animation/gltf_loader.h"
#include "animation/procedural.h"
#include "tests/ik_rig_fixture.h"
#include "tests/mediator/mediator_fixture.h"

namespace gk {
namespace {

using test::Script;
using test::straight;

const LocomotionClip* find(const LocomotionLibrary& lib, const std::string& name) {
  for (const LocomotionClip& c : lib.clips) {
    if (c.clip.name == name) return &c;
  }
  return nullptr;
}

// True when contacts start left, right, left, ... (each foot's next contact begins after the
// other's has begun).
bool contacts_alternate(const ClipAnalysis& a) {
  std::vector<std::pair<float, int>> starts;
  for (int s = 0; s < 2; ++s) {
    for (const TimeInterval& c : a.contacts[s]) starts.push_back({c.start_s, s});
  }
  std::sort(starts.begin(), starts.end());
  for (size_t i = 1; i < starts.size(); ++i) {
    if (starts[i].second == starts[i - 1].second) return false;
  }
  return starts.size() >= 4;
}

MediatorParams with_mode(MediatorMode mode) {
  MediatorParams p;
  p.mode = mode;
  return p;
}

TEST(IkRigLibrary, AnalysedAndPlantedAsTheClipsItWasWrittenFrom) {
  const test::IkRig rig = test::make_ik_rig();
  Result<ClipSet> set = parse_gltf(rig.glb, "ik_rig_cm.glb");
  ASSERT_TRUE(set.ok()) << set.message();
  std::vector<ClipSet> sets{*set};
  Result<LocomotionLibrary> lib = build_locomotion_library(sets);
  ASSERT_TRUE(lib.ok()) << lib.message();
  std::vector<ClipSet> ref_sets{rig.authored};
  Result<LocomotionLibrary> ref = build_locomotion_library(ref_sets);
  ASSERT_TRUE(ref.ok()) << ref.message();
  EXPECT_TRUE(lib->left_out.empty()) << describe_left_out(*lib).front();
  for (const char* name : {"walk_slow", "walk", "walk_fast", "jog"}) {
    const LocomotionClip* c = find(*lib, name);
    const LocomotionClip* r = find(*ref, name);
    ASSERT_TRUE(c && r) << name;
    ASSERT_TRUE(c->gait) << name;
    EXPECT_TRUE(contacts_alternate(c->analysis)) << name;
    // Two strides in the file: the cycle is one, as long as the built-in clip's.
    EXPECT_NEAR(c->cycle_s, r->cycle_s, 0.02f * r->cycle_s) << name;
    EXPECT_NEAR(c->cycle_s, 0.5f * c->clip.duration_s(), 0.02f * r->cycle_s) << name;
    EXPECT_NEAR(c->speed_m_s, r->speed_m_s, 0.02f * r->speed_m_s) << name;
  }
  // Walkers between the clips' speeds: apm keeps the feet planted on this rig as on the built-in
  // one, where naive playback skates.
  std::vector<Script> s;
  for (int i = 0; i < 6; ++i) s.push_back(straight({2.0f * i, 0.0f}, {0.0f, 1.05f + 0.1f * i}));
  const auto apm = test::run_scripted(*lib, s, with_mode(MediatorMode::kApm));
  const auto naive = test::run_scripted(*lib, s, with_mode(MediatorMode::kNaive));
  const auto ref_apm = test::run_scripted(*ref, s, with_mode(MediatorMode::kApm));
  std::printf("foot slide [cm/s]: IK rig apm %.3f, naive %.3f; built-in rig apm %.3f\n",
              apm.report.slide.mean_cm_s, naive.report.slide.mean_cm_s,
              ref_apm.report.slide.mean_cm_s);
  EXPECT_GT(apm.report.slide.num_samples, 1000);
  EXPECT_LE(apm.report.slide.mean_cm_s, 2.0f);
  EXPECT_GE(naive.report.slide.mean_cm_s, 10.0f * apm.report.slide.mean_cm_s);
  EXPECT_NEAR(apm.report.slide.mean_cm_s, ref_apm.report.slide.mean_cm_s,
              0.25f * ref_apm.report.slide.mean_cm_s + 0.1f);
  EXPECT_EQ(apm.report.non_finite, 0);
}

TEST(IkRigLibrary, MeaninglessNamesAreRefusedSayingHowToGiveRoles) {
  const test::IkRig rig = test::make_ik_rig(test::meaningless_inch_rig());
  Result<ClipSet> bare = parse_gltf(rig.glb, "ik_rig_in.glb");
  ASSERT_TRUE(bare.ok()) << bare.message();
  std::vector<ClipSet> sets{*bare};
  Result<LocomotionLibrary> refused = build_locomotion_library(sets);
  ASSERT_FALSE(refused.ok());
  for (const char* part : {"ik_rig_in.glb: ", "no joint found for hips, chest, left_hip",
                           "--roles FILE.json", "{\"roles\": {\"hips\": "}) {
    EXPECT_NE(refused.message().find(part), std::string::npos) << refused.message();
  }
  // Beside a skeleton that has them, the file is refused naming both.
  std::vector<ClipSet> mixed{make_builtin_clip_set(), *bare};
  Result<LocomotionLibrary> both = build_locomotion_library(mixed);
  ASSERT_FALSE(both.ok());
  EXPECT_EQ(both.message().rfind("ik_rig_in.glb: cannot retarget its clips onto the library "
                                 "skeleton (builtin)",
                                 0),
            0u)
      << both.message();

  const std::string dir = test::scratch_dir("ik_rig_library");
  ASSERT_TRUE(test::write_file(dir + "/roles.json", rig.roles_json));
  LoadOptions load;
  load.role_manifest = dir + "/roles.json";
  Result<ClipSet> set = parse_gltf(rig.glb, "ik_rig_in.glb", load);
  ASSERT_TRUE(set.ok()) << set.message();
  sets = {*set};
  Result<LocomotionLibrary> lib = build_locomotion_library(sets);
  ASSERT_TRUE(lib.ok()) << lib.message();
  const LocomotionClip* walk = find(*lib, "walk");
  ASSERT_TRUE(walk && walk->gait);
  EXPECT_TRUE(contacts_alternate(walk->analysis));
}

// Clips of another skeleton are retargeted by role (the IK rig's onto the built-in skeleton);
// every clip given ends up in the library or in left_out with its reason.
TEST(IkRigLibrary, EveryClipOfEverySkeletonIsUsedOrReported) {
  const test::IkRig rig = test::make_ik_rig();
  Result<ClipSet> ik = parse_gltf(rig.glb, "ik_rig_cm.glb");
  ASSERT_TRUE(ik.ok()) << ik.message();
  ClipSet builtin = make_builtin_clip_set();
  // Clips the library does not use: a name that says it is no locomotion, a walk whose legs stay
  // in the rest pose while the hips travel (the feet glide: no contacts), a second standing clip.
  Clip crouch = builtin.clips[2];
  crouch.name = "crouch_walk";
  Clip gliding = builtin.clips[2];
  gliding.name = "gliding_walk";
  for (int f = 0; f < gliding.num_frames; ++f) {
    for (int j = 1; j < gliding.num_joints; ++j) {
      gliding.rotations[static_cast<size_t>(f) * gliding.num_joints + j] =
          builtin.skeleton->rest_rotations[j];
    }
  }
  // The same as a take (not a loop): segmented, it has no stride to loop and nowhere it stands.
  Clip gliding_take = gliding;
  gliding_take.name = "gliding_take";
  gliding_take.loops = false;
  builtin.clips.push_back(crouch);
  builtin.clips.push_back(gliding);
  builtin.clips.push_back(gliding_take);
  std::vector<ClipSet> sets{builtin, *ik};
  Result<LocomotionLibrary> lib = build_locomotion_library(sets);
  ASSERT_TRUE(lib.ok()) << lib.message();
  size_t accounted = 0, given = 0;
  for (const ClipSet& set : sets) {
    for (const Clip& c : set.clips) {
      ++given;
      const std::string tag = c.name + " (" + set.source + ")";
      auto is_it = [&](const LocomotionLibrary::LeftOut& l) {
        return l.clip == c.name && l.file == set.source;
      };
      const bool used = std::any_of(lib->clips.begin(), lib->clips.end(), [&](const auto& l) {
        return l.clip.name == c.name && l.clip.source == set.source;
      });
      const bool reported = std::any_of(lib->left_out.begin(), lib->left_out.end(), is_it);
      EXPECT_NE(used, reported) << tag;
      accounted += used || reported;
    }
  }
  EXPECT_EQ(accounted, given);
  for (const std::string& l : describe_left_out(*lib)) std::printf("left out: %s\n", l.c_str());
  auto reason = [&](const std::string& clip, const std::string& file) {
    for (const LocomotionLibrary::LeftOut& l : lib->left_out) {
      if (l.clip == clip && l.file == file) return l.why;
    }
    return std::string();
  };
  EXPECT_NE(reason("crouch_walk", "builtin").find("not walking or running"), std::string::npos);
  EXPECT_NE(reason("gliding_walk", "builtin").find("no foot contact on either foot"),
            std::string::npos)
      << reason("gliding_walk", "builtin");
  EXPECT_NE(reason("gliding_take", "builtin").find("a take with no stride to loop"),
            std::string::npos)
      << reason("gliding_take", "builtin");
  // Of the two (identical) standing clips one stands for the library, the other is reported.
  const std::string idle_out = reason("idle", "ik_rig_cm.glb") + reason("idle", "builtin");
  EXPECT_NE(idle_out.find("standing; the library stands with idle"), std::string::npos) << idle_out;
  // The IK rig's walk, retargeted by role onto the built-in skeleton, walks as the built-in one.
  const LocomotionClip *ik_walk = nullptr, *builtin_walk = nullptr;
  for (const LocomotionClip& c : lib->clips) {
    if (c.clip.name == "walk") (c.clip.source == "builtin" ? builtin_walk : ik_walk) = &c;
  }
  ASSERT_TRUE(ik_walk && builtin_walk);
  EXPECT_TRUE(ik_walk->gait);
  EXPECT_NEAR(ik_walk->speed_m_s, builtin_walk->speed_m_s, 0.02f * builtin_walk->speed_m_s);
  EXPECT_NEAR(ik_walk->cycle_s, builtin_walk->cycle_s, 0.02f * builtin_walk->cycle_s);
}

}  // namespace
}  // namespace gk
