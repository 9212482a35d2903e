// Invariance of clip analysis on the real clips: each take is changed in memory the way a clip
// nobody has seen may differ (frame rate, travel direction, root off the travel line, an extra
// root, a drifting or tilted floor, units, a mirrored body, capture jitter, other joint names,
// position channels on every joint), and what analysis finds must stay the same or change the
// same way. The reference is always the analysis of the unchanged clip, never a stored number.

#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/quaternion.hpp>

#include "animation/analysis.h"
#include "animation/bvh_loader.h"
#include "animation/bvh_writer.h"
#include "animation/clip_library.h"
#include "animation/pose_jobs.h"
#include "animation/segmentation.h"
#include "tests/animation/clip_transforms.h"
#include "tests/test_data.h"

namespace gk {
namespace {

using test::authored_turned;
using test::jittered;
using test::kDeg;
using test::kPi;
using test::load_rig;
using test::mirrored;
using test::move_take;
using test::raise_over_take;
using test::resampled;
using test::Rig;
using test::with_parent_root;

// A naming convention: the name of each role-bearing joint (side: "L" or "R").
struct Convention {
  const char* label;
  std::string (*hips)();
  std::string (*spine)(int i, int count);  // i-th joint of the spine chain, bottom first
  std::string (*neck)();
  std::string (*head)();
  std::string (*leg)(int part, char side);  // part 0 thigh, 1 shin, 2 foot, 3 toe
  std::string (*arm)(char side);            // the upper arm
};

std::string sided(char side, const char* l, const char* r) { return side == 'L' ? l : r; }

const Convention kConventions[] = {
    {"ASF lfemur/ltibia/lfoot/ltoes", [] { return std::string("root"); },
     [](int i, int n) {
       return std::string(i + 1 == n ? "thorax" : (i == 0 ? "lowerback" : "upperback")) +
              (i > 0 && i + 1 < n ? std::to_string(i) : "");
     },
     [] { return std::string("lowerneck"); }, [] { return std::string("head"); },
     [](int p, char s) {
       const char* w[] = {"femur", "tibia", "foot", "toes"};
       return std::string(1, s == 'L' ? 'l' : 'r') + w[p];
     },
     [](char s) { return std::string(s == 'L' ? "lhumerus" : "rhumerus"); }},
    {"Unity UpperLeg_L", [] { return std::string("Hips"); },
     [](int i, int n) {
       return i + 1 == n ? std::string("UpperChest")
                         : (i == 0 ? "Spine" : "Chest" + std::to_string(i));
     },
     [] { return std::string("Neck"); }, [] { return std::string("Head"); },
     [](int p, char s) {
       const char* w[] = {"UpperLeg_", "LowerLeg_", "Foot_", "Toes_"};
       return std::string(w[p]) + s;
     },
     [](char s) { return std::string("UpperArm_") + s; }},
    {"Blender UpperLeg.L", [] { return std::string("Hips"); },
     [](int i, int) { return "Spine." + std::to_string(i); }, [] { return std::string("Neck"); },
     [] { return std::string("Head"); },
     [](int p, char s) {
       const char* w[] = {"UpperLeg.", "LowerLeg.", "Foot.", "Toes."};
       return std::string(w[p]) + s;
     },
     [](char s) { return std::string("UpperArm.") + s; }},
    {"Mixamo mixamorig:LeftUpLeg", [] { return std::string("mixamorig:Hips"); },
     [](int i, int) { return "mixamorig:Spine" + (i == 0 ? std::string() : std::to_string(i)); },
     [] { return std::string("mixamorig:Neck"); }, [] { return std::string("mixamorig:Head"); },
     [](int p, char s) {
       const char* w[] = {"UpLeg", "Leg", "Foot", "ToeBase"};
       return "mixamorig:" + sided(s, "Left", "Right") + w[p];
     },
     [](char s) { return "mixamorig:" + sided(s, "Left", "Right") + "Arm"; }},
    {"Blender thigh.L", [] { return std::string("pelvis"); },
     [](int i, int) { return std::string("spine") + (i == 0 ? "" : ".00" + std::to_string(i)); },
     [] { return std::string("neck"); }, [] { return std::string("head"); },
     [](int p, char s) {
       const char* w[] = {"thigh.", "shin.", "foot.", "toe."};
       return std::string(w[p]) + s;
     },
     [](char s) { return std::string("upper_arm.") + s; }},
    {"L_Thigh", [] { return std::string("Pelvis"); },
     [](int i, int) { return "Spine" + std::to_string(i + 1); }, [] { return std::string("Neck"); },
     [] { return std::string("Head"); },
     [](int p, char s) {
       const char* w[] = {"_Thigh", "_Calf", "_Foot", "_Toe"};
       return std::string(1, s) + w[p];
     },
     [](char s) { return std::string(1, s) + "_UpperArm"; }},
    {"3ds Max Biped \"Bip01 L Thigh\"", [] { return std::string("Bip01 Pelvis"); },
     [](int i, int) { return "Bip01 Spine" + (i == 0 ? std::string() : std::to_string(i)); },
     [] { return std::string("Bip01 Neck"); }, [] { return std::string("Bip01 Head"); },
     [](int p, char s) {
       const char* w[] = {" Thigh", " Calf", " Foot", " Toe0"};
       return std::string("Bip01 ") + s + w[p];
     },
     [](char s) { return std::string("Bip01 ") + s + " UpperArm"; }},
    {"VRM J_Bip_L_UpperLeg", [] { return std::string("J_Bip_C_Hips"); },
     [](int i, int n) {
       return std::string(i + 1 == n ? "J_Bip_C_UpperChest"
                                     : (i == 0 ? "J_Bip_C_Spine" : "J_Bip_C_Chest"));
     },
     [] { return std::string("J_Bip_C_Neck"); }, [] { return std::string("J_Bip_C_Head"); },
     [](int p, char s) {
       const char* w[] = {"_UpperLeg", "_LowerLeg", "_Foot", "_ToeBase"};
       return std::string("J_Bip_") + s + w[p];
     },
     [](char s) { return std::string("J_Bip_") + s + "_UpperArm"; }},
    {"SMPL L_Hip/L_Knee/L_Ankle/L_Foot", [] { return std::string("Pelvis"); },
     [](int i, int) { return "Spine" + std::to_string(i + 1); }, [] { return std::string("Neck"); },
     [] { return std::string("Head"); },
     [](int p, char s) {
       const char* w[] = {"_Hip", "_Knee", "_Ankle", "_Foot"};
       return std::string(1, s) + w[p];
     },
     [](char s) { return std::string(1, s) + "_Shoulder"; }},
};

// The rig with its role-bearing joints renamed to `conv` and every other joint named "joint<i>"
// (names that say nothing), roles detected afresh.
Rig renamed(const Rig& in, const Convention& conv) {
  const Skeleton& s = *in.sk;
  auto sk = std::make_shared<Skeleton>(s);
  for (int j = 0; j < sk->num_joints(); ++j) sk->names[j] = "joint" + std::to_string(j);
  sk->names[s.role(JointRole::kHips)] = conv.hips();
  const int n = static_cast<int>(s.spine_chain.size());
  for (int i = 0; i < n; ++i) sk->names[s.spine_chain[i]] = conv.spine(i, n);
  if (s.has(JointRole::kNeck)) sk->names[s.role(JointRole::kNeck)] = conv.neck();
  if (s.has(JointRole::kHead)) sk->names[s.role(JointRole::kHead)] = conv.head();
  for (Side side : {Side::kLeft, Side::kRight}) {
    const char c = side == Side::kLeft ? 'L' : 'R';
    const int leg[] = {s.hip(side), s.knee(side), s.ankle(side), s.toe(side)};
    for (int p = 0; p < 4; ++p) sk->names[leg[p]] = conv.leg(p, c);
    const int arm =
        s.role(side == Side::kLeft ? JointRole::kLeftShoulder : JointRole::kRightShoulder);
    if (arm >= 0) sk->names[arm] = conv.arm(c);
  }
  detect_joint_roles(sk.get());
  return {sk, in.clip};
}

// --- Comparison -----------------------------------------------------------------------------

struct Tolerance {
  float contact_s = 0.0f;  // each touchdown and lift-off [s]
  float speed = 0.02f;     // [ratio]
  float direction_rad = 3.0f * kDeg;
  float cycle = 0.02f;      // [ratio], or one frame of the coarser rate if that is more
  float cycle_s = 0.0f;     // [s] or this if it is more (a take's cycle runs landing to landing)
  bool swap_sides = false;  // mirrored: left contacts are the original's right ones
};

// The same speed, direction, contacts and cycle.
void expect_same(const ClipAnalysis& want, const ClipAnalysis& got, const Tolerance& tol,
                 const std::string& what) {
  EXPECT_NEAR(got.native_speed_m_s, want.native_speed_m_s, tol.speed * want.native_speed_m_s)
      << what << ": speed";
  EXPECT_EQ(got.in_place, want.in_place) << what;
  const float dir_want = tol.swap_sides ? -want.direction_rad : want.direction_rad;
  float d = got.direction_rad - dir_want;
  d = std::remainder(d, 2.0f * kPi);
  if (want.native_speed_m_s > 0.3f) {
    EXPECT_LT(std::abs(d), tol.direction_rad) << what << ": direction";
  }
  // A contact cut by the take's first or last frame to less than 0.15 s (a few frames of a foot
  // arriving or leaving) may come or go with the edge; a longer one is compared at its other end.
  const float edge = tol.contact_s;
  const float dur = std::min(want.duration_s, got.duration_s);
  for (int s = 0; s < 2; ++s) {
    auto inner = [&](const std::vector<TimeInterval>& cs, const ClipAnalysis& a) {
      std::vector<TimeInterval> out;
      const float last = (a.num_frames - 1) / a.fps;
      for (const TimeInterval& c : cs) {
        const bool cut = c.start_s < 0.5f / a.fps || c.end_s > last - 0.5f / a.fps;
        if (cut && c.end_s - c.start_s < 0.15f) continue;
        out.push_back(c);
      }
      return out;
    };
    const auto w = inner(want.contacts[tol.swap_sides ? 1 - s : s], want);
    const auto g = inner(got.contacts[s], got);
    auto list = [](const std::vector<TimeInterval>& cs) {
      std::string out;
      for (const TimeInterval& c : cs) {
        out += " " + std::to_string(c.start_s) + "-" + std::to_string(c.end_s);
      }
      return out;
    };
    ASSERT_EQ(g.size(), w.size()) << what << ": contacts of side " << s << ": want" << list(w)
                                  << ", got" << list(g);
    for (size_t i = 0; i < w.size(); ++i) {
      if (w[i].start_s > edge) {
        EXPECT_NEAR(g[i].start_s, w[i].start_s, tol.contact_s)
            << what << ": side " << s << " contact " << i << " touchdown";
      }
      if (w[i].end_s < dur - edge) {
        EXPECT_NEAR(g[i].end_s, w[i].end_s, tol.contact_s)
            << what << ": side " << s << " contact " << i << " lift-off";
      }
    }
  }
  // One frame (and a hair: two times that differ by exactly one frame are not exact in float).
  const float cw = want.cycle.end_s - want.cycle.start_s, cg = got.cycle.end_s - got.cycle.start_s;
  EXPECT_NEAR(cg, cw,
              std::max({tol.cycle * cw, 1.01f / std::min(want.fps, got.fps), tol.cycle_s}))
      << what << ": cycle";
}

// Left and right contact starts take turns (a contact cut by the first frame starts no step).
void expect_alternating(const ClipAnalysis& a, const std::string& what) {
  std::vector<std::pair<float, int>> starts;
  for (int s = 0; s < 2; ++s) {
    for (const TimeInterval& c : a.contacts[s]) {
      if (c.start_s > 0.5f / a.fps) starts.push_back({c.start_s, s});
    }
  }
  std::sort(starts.begin(), starts.end());
  ASSERT_GE(starts.size(), 3u) << what;
  for (size_t k = 1; k < starts.size(); ++k) {
    EXPECT_NE(starts[k].second, starts[k - 1].second)
        << what << ": contact start " << starts[k].first;
  }
}

ClipAnalysis analyze(const Rig& r) { return analyze_clip(r.clip, *r.sk); }

// The takes every invariance runs on: a 30 fps retargeted walk (hand-labelled), a 120 fps walk
// that veers left, a 30 fps jog, the 90-degree turn, and an in-place keyframed loop.
struct Case {
  const char* file;
  const char* clip;
};
constexpr Case kTakes[] = {{"clips/bvh/more/cmu_16_15_walk_mrl30.bvh", ""},
                           {"clips/bvh/more/cmu_16_11_walk_veer_left.bvh", ""},
                           {"clips/bvh/more/cmu_16_36_run_jog_mrl30.bvh", ""},
                           {"clips/bvh/more/cmu_16_17_walk_90_left_turn_mrl30.bvh", ""}};
constexpr Case kLoop = {"clips/bvh/ual_walk_loop.bvh", ""};
constexpr Case kGlbWalk = {"clips/gltf/ual_mannequin_quaternius.glb", "Walk_Loop"};

// 1. Frame rate: 24, 60 and 120 fps -> the same speed, contacts within one frame of the coarser
// rate, the same cycle (within 2%, or one frame of the coarser rate where that is more).
TEST(Invariance, FrameRate) {
  for (const Case& c : kTakes) {
    GK_REQUIRE_DATA(c.file);
    const Rig r = load_rig(c.file);
    const ClipAnalysis base = analyze(r);
    for (float fps : {24.0f, 60.0f, 120.0f}) {
      if (fps == r.clip.fps) continue;
      Rig t = r;
      t.clip = resampled(r.clip, fps);
      // Within one frame of the coarser rate: a 24 fps copy of a 120 fps take cannot place a
      // touchdown closer than its own frames.
      Tolerance tol;
      tol.contact_s = 1.01f / std::min(fps, r.clip.fps);
      expect_same(base, analyze(t), tol,
                  std::string(c.file) + " at " + std::to_string(static_cast<int>(fps)) + " fps");
    }
  }
}

// 2. Travel direction: the whole take turned about the vertical.
TEST(Invariance, TravelDirection) {
  for (const Case& c : kTakes) {
    GK_REQUIRE_DATA(c.file);
    const Rig r = load_rig(c.file);
    const ClipAnalysis base = analyze(r);
    for (float deg : {37.0f, -120.0f}) {
      Rig t = r;
      move_take(&t.clip, *t.sk, glm::angleAxis(deg * kDeg, glm::vec3(0, 1, 0)), glm::vec3(0.0f));
      Tolerance tol;
      tol.contact_s = 1.01f / r.clip.fps;
      expect_same(base, analyze(t), tol, std::string(c.file) + " turned " + std::to_string(deg));
    }
  }
}

// 3. Root off the travel line: the body moved sideways by 0.5 m, and an extra root above the hips
// with an offset of its own and a Z-up turn.
TEST(Invariance, RootOffTheTravelLine) {
  for (const Case& c : kTakes) {
    GK_REQUIRE_DATA(c.file);
    const Rig r = load_rig(c.file);
    const ClipAnalysis base = analyze(r);
    Tolerance tol;
    tol.contact_s = 1.01f / r.clip.fps;
    Rig side = r;
    move_take(&side.clip, *side.sk, glm::quat(1, 0, 0, 0), glm::vec3(0.5f, 0.0f, 0.0f));
    expect_same(base, analyze(side), tol, std::string(c.file) + " moved 0.5 m sideways");
    const Rig extra = with_parent_root(r, glm::vec3(0.3f, 0.0f, -0.4f),
                                       glm::angleAxis(-90.0f * kDeg, glm::vec3(1, 0, 0)));
    ASSERT_TRUE(extra.sk->has_locomotion_roles()) << c.file;
    EXPECT_EQ(extra.sk->role(JointRole::kHips), r.sk->role(JointRole::kHips) + 1) << c.file;
    expect_same(base, analyze(extra), tol, std::string(c.file) + " under an extra root");
  }
}

struct FloorChange {
  const char* what;
  glm::quat q;
  glm::vec3 d;
  float rise_m;
};

void expect_floor_invariance(const FloorChange& ch) {
  for (const Case& c : kTakes) {
    GK_REQUIRE_DATA(c.file);
    const Rig r = load_rig(c.file);
    const ClipAnalysis base = analyze(r);
    Tolerance tol;
    tol.contact_s = 2.01f / r.clip.fps;
    tol.speed = 0.03f;
    Rig t = r;
    move_take(&t.clip, *t.sk, ch.q, ch.d);
    raise_over_take(&t.clip, ch.rise_m);
    const ClipAnalysis a = analyze(t);
    const std::string what = std::string(c.file) + ": " + ch.what;
    expect_same(base, a, tol, what);
    expect_alternating(a, what);
  }
}

// 4. Floor: rising 6 cm over the take, 3 cm lower or higher.
TEST(Invariance, FloorDriftAndHeight) {
  const glm::quat id(1, 0, 0, 0);
  expect_floor_invariance({"floor rising 6 cm", id, glm::vec3(0.0f), 0.06f});
  expect_floor_invariance({"floor 3 cm lower", id, glm::vec3(0.0f, 0.03f, 0.0f), 0.0f});
  expect_floor_invariance({"floor 3 cm higher", id, glm::vec3(0.0f, -0.03f, 0.0f), 0.0f});
}

// 4b. A tilted capture floor (the take turned 1.5 deg about x, or 2 deg about z): contacts within
// two frames, alternating.
TEST(Invariance, FloorTilt) {
  expect_floor_invariance({"floor tilted 1.5 deg along x",
                           glm::angleAxis(1.5f * kDeg, glm::vec3(1, 0, 0)), glm::vec3(0.0f), 0.0f});
  expect_floor_invariance({"floor tilted 2 deg along z",
                           glm::angleAxis(2.0f * kDeg, glm::vec3(0, 0, 1)), glm::vec3(0.0f), 0.0f});
}

// 5 and 8b. Units and channels: written as BVH in centimetres, in inches, and with position
// channels on every joint, then loaded: the unit is detected and the analysis is the same in
// metres.
TEST(Invariance, UnitsAndPositionChannelsThroughBvh) {
  for (const Case& c : {kTakes[0], kTakes[1], kLoop}) {
    GK_REQUIRE_DATA(c.file);
    const Rig r = load_rig(c.file);
    const ClipAnalysis base = analyze(r);
    struct Form {
      const char* what;
      BvhWriteOptions options;
      float m_per_unit;
    };
    for (const Form& form : {Form{"centimetres", {100.0f, false}, 0.01f},
                             Form{"inches", {1.0f / 0.0254f, false}, 0.0254f},
                             Form{"metres, 6 channels per joint", {1.0f, true}, 1.0f}}) {
      const std::string text = format_bvh(*r.sk, r.clip, form.options);
      Result<ClipSet> set = parse_bvh(text, std::string(c.file) + " in " + form.what);
      ASSERT_TRUE(set.ok()) << set.message();
      EXPECT_FLOAT_EQ(set->scale_m_per_unit, form.m_per_unit)
          << c.file << ": " << set->scale_reason;
      const Rig back{std::make_shared<Skeleton>(*set->skeleton), set->clips.at(0)};
      EXPECT_EQ(back.clip.loops, r.clip.loops) << c.file;
      EXPECT_EQ(back.clip.num_frames, r.clip.num_frames) << c.file;
      Tolerance tol;
      tol.contact_s = 0.5f / r.clip.fps;
      tol.speed = 0.005f;
      expect_same(base, analyze(back), tol, std::string(c.file) + " in " + form.what);
    }
  }
}

// The rig without toe joints: each toe removed, the foot ending at an End Site where the toe's own
// bone ended in the rest pose, its tip (a rig whose feet end a chain, as many BVH exports have).
glm::vec3 rest_tip(const Skeleton& sk, Side s) {
  const int toe = sk.toe(s);
  const glm::vec3 end =
      toe < static_cast<int>(sk.end_sites.size()) ? sk.end_sites[toe] : glm::vec3(0.0f);
  return sk.rest_translations[toe] + sk.rest_rotations[toe] * end;
}
Rig without_toes(const Rig& r) {
  const Skeleton& sk = *r.sk;
  const int n = sk.num_joints();
  std::vector<int> new_of_old(n, -1);
  std::vector<bool> drop(n, false);
  for (Side s : {Side::kLeft, Side::kRight}) drop[sk.toe(s)] = true;
  auto out = std::make_shared<Skeleton>();
  for (int j = 0; j < n; ++j) {
    if (drop[j]) continue;
    new_of_old[j] = out->num_joints();
    out->names.push_back(sk.names[j]);
    out->parents.push_back(static_cast<int16_t>(sk.parents[j] < 0 ? -1 : new_of_old[sk.parents[j]]));
    out->rest_translations.push_back(sk.rest_translations[j]);
    out->rest_rotations.push_back(sk.rest_rotations[j]);
    out->end_sites.push_back(j < static_cast<int>(sk.end_sites.size()) ? sk.end_sites[j]
                                                                        : glm::vec3(0.0f));
  }
  for (Side s : {Side::kLeft, Side::kRight}) {
    out->end_sites[new_of_old[sk.ankle(s)]] = rest_tip(sk, s);
  }
  detect_joint_roles(out.get());
  Rig back{out, r.clip};
  back.clip.num_joints = out->num_joints();
  back.clip.rotations.clear();
  back.clip.translations.clear();
  for (int f = 0; f < r.clip.num_frames; ++f) {
    for (int j = 0; j < n; ++j) {
      if (drop[j]) continue;
      back.clip.rotations.push_back(r.clip.frame_rotations(f)[j]);
      back.clip.translations.push_back(r.clip.frame_translations(f)[j]);
    }
  }
  return back;
}

// 5a. Feet without toes, through BVH: loaded, each foot gets a toe joint at its End Site, on
// every frame where the removed toe's tip would be with the toe held straight; the analysis finds
// the same speed, contacts (within two frames: the foot rolls off its rigid end, not off a toe
// that bends) and cycle.
TEST(Invariance, FeetWithoutToesThroughBvh) {
  for (const Case& c : {kTakes[0], kTakes[1], kTakes[2], kLoop}) {
    GK_REQUIRE_DATA(c.file);
    const Rig r = load_rig(c.file);
    const Rig bare = without_toes(r);
    ASSERT_LT(bare.sk->toe(Side::kLeft), 0) << c.file;
    const std::string text = format_bvh(*bare.sk, bare.clip, {1.0f, false});
    Result<ClipSet> set = parse_bvh(text, std::string(c.file) + " without toes");
    ASSERT_TRUE(set.ok()) << set.message();
    EXPECT_NE(set->rig_reason.find("feet without toes"), std::string::npos) << set->rig_reason;
    const Rig back{std::make_shared<Skeleton>(*set->skeleton), set->clips.at(0)};
    ASSERT_TRUE(back.sk->has_locomotion_roles()) << c.file;
    ASSERT_EQ(back.clip.num_frames, r.clip.num_frames);
    std::vector<glm::mat4> m0(r.sk->num_joints()), m1(back.sk->num_joints());
    float worst = 0.0f;
    for (int f = 0; f < r.clip.num_frames; ++f) {
      clip_frame_model(r.clip, *r.sk, f, m0);
      clip_frame_model(back.clip, *back.sk, f, m1);
      for (Side s : {Side::kLeft, Side::kRight}) {
        const glm::vec3 tip(m0[r.sk->ankle(s)] * glm::vec4(rest_tip(*r.sk, s), 1.0f));
        worst = std::max(worst, glm::length(tip - translation_of(m1[back.sk->toe(s)])));
      }
    }
    EXPECT_LT(worst, 1e-3f) << c.file << ": the toe joint is not at the foot's end";
    Tolerance tol;
    tol.contact_s = 2.0f / r.clip.fps;
    tol.cycle_s = 2.0f / r.clip.fps;
    expect_same(analyze(r), analyze(back), tol, std::string(c.file) + " without toes");
  }
}

// 5b. Up axis: written as BVH by a tool whose up is +z (Blender, 3ds Max), +x or -z, rest
// offsets and all, then loaded: the body is stood up along +y again and the analysis is the same.
TEST(Invariance, UpAxisThroughBvh) {
  for (const Case& c : {kTakes[0], kTakes[2], kLoop}) {
    GK_REQUIRE_DATA(c.file);
    const Rig r = load_rig(c.file);
    const ClipAnalysis base = analyze(r);
    struct Form {
      const char* what;
      glm::quat up;
      const char* axis;
    };
    for (const Form& form :
         {Form{"Z-up", glm::angleAxis(90.0f * kDeg, glm::vec3(1, 0, 0)), "+z"},
          Form{"X-up", glm::angleAxis(-90.0f * kDeg, glm::vec3(0, 0, 1)), "+x"},
          Form{"-Z-up", glm::angleAxis(-90.0f * kDeg, glm::vec3(1, 0, 0)), "-z"}}) {
      const Rig turned = authored_turned(r, form.up);
      const std::string what = std::string(c.file) + " " + form.what;
      Result<ClipSet> set = parse_bvh(format_bvh(*turned.sk, turned.clip, {100.0f, false}), what);
      ASSERT_TRUE(set.ok()) << set.message();
      EXPECT_FLOAT_EQ(set->scale_m_per_unit, 0.01f) << what << ": " << set->scale_reason;
      EXPECT_NE(set->up_reason.find(form.axis), std::string::npos)
          << what << ": " << set->up_reason;
      const Rig back{std::make_shared<Skeleton>(*set->skeleton), set->clips.at(0)};
      EXPECT_EQ(back.clip.loops, r.clip.loops) << what;
      Tolerance tol;
      tol.contact_s = 0.5f / r.clip.fps;
      tol.speed = 0.005f;
      expect_same(base, analyze(back), tol, what);
      // Stood up exactly: every joint where the original has it, on every 10th frame.
      std::vector<glm::mat4> m0(r.sk->num_joints()), m1(r.sk->num_joints());
      float worst = 0.0f;
      for (int f = 0; f < back.clip.num_frames; f += 10) {
        clip_frame_model(r.clip, *r.sk, f, m0);
        clip_frame_model(back.clip, *back.sk, f, m1);
        for (int j = 0; j < r.sk->num_joints(); ++j) {
          worst = std::max(worst, glm::length(translation_of(m0[j]) - translation_of(m1[j])));
        }
      }
      EXPECT_LT(worst, 1e-3f) << what;
    }
    // Y-up as it was: nothing turned, and the reason says so.
    Result<ClipSet> same = parse_bvh(format_bvh(*r.sk, r.clip, {100.0f, false}), c.file);
    ASSERT_TRUE(same.ok()) << same.message();
    EXPECT_NE(same->up_reason.find("+y"), std::string::npos) << same->up_reason;
  }
}

// 6. Mirror: the mirror image walks the same, its feet swapped and its direction mirrored.
TEST(Invariance, MirrorSwapsTheFeet) {
  for (const Case& c : {kTakes[0], kTakes[1], kTakes[3], kLoop}) {
    GK_REQUIRE_DATA(c.file);
    const Rig r = load_rig(c.file);
    const Rig m = mirrored(r);
    ASSERT_TRUE(m.sk->has_locomotion_roles()) << c.file;
    // The joint that was the left thigh is now the right one.
    EXPECT_EQ(m.sk->hip(Side::kRight), r.sk->hip(Side::kLeft)) << c.file;
    Tolerance tol;
    tol.contact_s = 1.01f / r.clip.fps;
    tol.swap_sides = true;
    expect_same(analyze(r), analyze(m), tol, std::string(c.file) + " mirrored");
  }
}

void expect_jitter_invariance(const Case& c, float fps = 0.0f) {
  GK_REQUIRE_DATA(c.file);
  Rig r = load_rig(c.file);
  if (fps > 0.0f) r.clip = resampled(r.clip, fps);  // the same take captured at another rate
  const ClipAnalysis base = analyze(r);
  for (uint32_t seed : {1u, 2u}) {
    Rig t = r;
    t.clip = jittered(r.clip, seed, 2.0f, 0.5f);
    Tolerance tol;
    // Two frames, and at a high frame rate two frames at 30 fps, as the hand labels: velocities
    // are taken over 1/30 s at any rate, so an edge moved by jitter is found within that span.
    tol.contact_s = std::max(2.01f / r.clip.fps, 2.01f / 30.0f);
    // A take's cycle is a stride from one landing to the next: as exact as its landings.
    tol.cycle_s = tol.contact_s;
    const std::string what = std::string(c.file) + " at " + std::to_string(r.clip.fps) +
                             " fps jittered, seed " + std::to_string(seed);
    const ClipAnalysis a = analyze(t);
    expect_same(base, a, tol, what);
    expect_alternating(a, what);
  }
}

// 7. Capture jitter: 2 mm on the root, 0.5 deg on every joint, on every frame, seeded.
TEST(Invariance, CaptureJitter) {
  expect_jitter_invariance(kTakes[0]);  // straight walk, 30 fps
  expect_jitter_invariance(kTakes[2]);  // jog, 30 fps
}

TEST(Invariance, CaptureJitterTurnAnd120Fps) {
  expect_jitter_invariance(kTakes[1]);
  expect_jitter_invariance(kTakes[3]);
  // The same per-frame jitter on the straight walk taken at 60 and 120 fps.
  expect_jitter_invariance(kTakes[0], 60.0f);
  expect_jitter_invariance(kTakes[0], 120.0f);
}

// 8. Names: the role-bearing joints renamed to other conventions, every other joint to a name
// that says nothing: the same roles, so the same analysis.
TEST(Invariance, NamingConventions) {
  for (const Case& c : {kTakes[0], kTakes[1], kLoop, kGlbWalk}) {
    GK_REQUIRE_DATA(c.file);
    const Rig r = load_rig(c.file, c.clip);
    const ClipAnalysis base = analyze(r);
    for (const Convention& conv : kConventions) {
      const Rig t = renamed(r, conv);
      const std::string what = std::string(c.file) + " named " + conv.label;
      for (int k = 0; k < kNumJointRoles; ++k) {
        EXPECT_EQ(t.sk->roles[k], r.sk->roles[k])
            << what << ": role " << joint_role_name(static_cast<JointRole>(k));
      }
      EXPECT_EQ(t.sk->spine_chain, r.sk->spine_chain) << what;
      if (!t.sk->has_locomotion_roles()) continue;
      Tolerance tol;
      tol.contact_s = 0.5f / r.clip.fps;
      tol.speed = 1e-4f;
      expect_same(base, analyze(t), tol, what);
    }
  }
}

// The writer's round trip: every joint's model-space position on every frame comes back within
// 0.1 mm, in any unit and channel layout.
TEST(BvhWriter, RoundTripKeepsEveryJoint) {
  for (const Case& c : {kTakes[1], kLoop, kGlbWalk}) {
    GK_REQUIRE_DATA(c.file);
    const Rig r = load_rig(c.file, c.clip);
    for (const BvhWriteOptions& o : {BvhWriteOptions{1.0f, false}, BvhWriteOptions{100.0f, true}}) {
      LoadOptions lo;
      lo.scale_m_per_unit = 1.0f / o.units_per_m;
      Result<ClipSet> set = parse_bvh(format_bvh(*r.sk, r.clip, o), "round trip", lo);
      ASSERT_TRUE(set.ok()) << set.message();
      const Skeleton& sk = *set->skeleton;
      const Clip& back = set->clips.at(0);
      ASSERT_EQ(sk.num_joints(), r.sk->num_joints()) << c.file;
      ASSERT_EQ(back.num_frames, r.clip.num_frames) << c.file;
      EXPECT_EQ(back.loops, r.clip.loops) << c.file;
      EXPECT_EQ(sk.names, r.sk->names) << c.file;
      EXPECT_EQ(sk.parents, r.sk->parents) << c.file;
      std::vector<glm::mat4> m0(sk.num_joints()), m1(sk.num_joints());
      float worst = 0.0f;
      for (int f = 0; f < back.num_frames; ++f) {
        clip_frame_model(r.clip, *r.sk, f, m0);
        clip_frame_model(back, sk, f, m1);
        for (int j = 0; j < sk.num_joints(); ++j) {
          worst = std::max(worst, glm::length(translation_of(m0[j]) - translation_of(m1[j])));
        }
      }
      EXPECT_LT(worst, 1e-4f) << c.file;
    }
  }
}

}  // namespace
}  // namespace gk
