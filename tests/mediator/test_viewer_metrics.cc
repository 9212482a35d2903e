// METRICS.md v2 ("what a viewer sees of the feet") on small hand-built tracks whose every figure
// is derived on paper in the comments, then the reference of real libraries.

#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "animation/pose_jobs.h"
#include "mediator/viewer_metrics.h"
#include "tests/mediator/mediator_fixture.h"
#include "tests/test_data.h"

namespace gk {
namespace {

constexpr float kDt = 1.0f / 60.0f;
constexpr int kToe = static_cast<int>(LimbJoint::kToe);
constexpr int kAnkle = static_cast<int>(LimbJoint::kAnkle);
constexpr int kKnee = static_cast<int>(LimbJoint::kKnee);

// Toe floors 2 cm (left) and 3 cm (right), ankles 8 and 9 cm; accelerations never pop unless a
// test lowers them.
FeetReference reference() {
  FeetReference r;
  r.toe_floor_m[0] = 0.02f;
  r.toe_floor_m[1] = 0.03f;
  r.ankle_floor_m[0] = 0.08f;
  r.ankle_floor_m[1] = 0.09f;
  for (auto& j : r.accel_m_s2) j[0] = j[1] = 1e9f;
  return r;
}

// n frames of one agent: toes on their floors, ankles 2 cm above theirs, knees at 0.5 m, all
// still, the root still; tests edit what they need.
struct Track {
  std::vector<glm::vec3> joint[kNumLimbJoints][2];
  std::vector<glm::vec2> root;
  explicit Track(int n) : root(n, glm::vec2(0.0f)) {
    const FeetReference r = reference();
    for (int s = 0; s < 2; ++s) {
      joint[kToe][s].assign(n, glm::vec3(0.3f * s, r.toe_floor_m[s], 0.0f));
      joint[kAnkle][s].assign(n, glm::vec3(0.3f * s, r.ankle_floor_m[s] + 0.02f, -0.1f));
      joint[kKnee][s].assign(n, glm::vec3(0.3f * s, 0.5f, 0.0f));
    }
  }
  LimbTrack view() const {
    LimbTrack t;
    for (int j = 0; j < kNumLimbJoints; ++j) {
      for (int s = 0; s < 2; ++s) t.joint[j][s] = joint[j][s];
    }
    t.root = root;
    return t;
  }
};

ViewerFeetStats measure(const std::vector<Track>& tracks, const FeetReference& ref = reference()) {
  ViewerFeetAccumulator acc(ref);
  for (const Track& t : tracks) acc.add_track(t.view(), kDt);
  return acc.finish();
}

TEST(ViewerMetrics, SupportFootCreepAndSkate) {
  // Left toe on its floor creeps 1 mm per frame (6 cm/s at 60 Hz) twice, then 1 cm per frame
  // (60 cm/s) twice. The right foot swings 20 cm up at 1.2 m/s: not the support foot.
  Track t(5);
  const float x[5] = {0.0f, 0.001f, 0.002f, 0.012f, 0.022f};
  for (int f = 0; f < 5; ++f) {
    t.joint[kToe][0][f].x = x[f];
    t.joint[kToe][1][f] = glm::vec3(0.3f + 0.02f * f, 0.03f + 0.2f, 0.0f);
  }
  const ViewerFeetStats s = measure({t});
  // Speeds 6, 6, 60, 60: mean 33, p95 the 4th of 4 (nearest rank) = 60, 2 of 4 above 30.
  ASSERT_EQ(s.support_samples, 4);
  EXPECT_NEAR(s.support_slide_cm_s, 33.0, 1e-3);
  // The largest sample: the sketch returns the exact maximum.
  EXPECT_NEAR(s.support_slide_p95_cm_s, 60.0, 1e-3);
  EXPECT_DOUBLE_EQ(s.support_skate_ratio, 0.5);
}

TEST(ViewerMetrics, SupportFootIsTheLowerRelativeToItsOwnFloor) {
  // Left toe at 3.5 cm (1.5 cm above its 2 cm floor), still; right toe at 4 cm (1 cm above its
  // 3 cm floor) gliding 1 cm per frame. The right one is lower relative to its floor although
  // higher in the world: it is the support foot, sliding at 60 cm/s on all 3 pairs.
  Track t(4);
  for (int f = 0; f < 4; ++f) {
    t.joint[kToe][0][f].y = 0.035f;
    t.joint[kToe][1][f] = glm::vec3(0.3f, 0.04f, 0.01f * f);
  }
  const ViewerFeetStats s = measure({t});
  ASSERT_EQ(s.support_samples, 3);
  EXPECT_NEAR(s.support_slide_cm_s, 60.0, 1e-3);
  EXPECT_DOUBLE_EQ(s.support_skate_ratio, 1.0);
}

TEST(ViewerMetrics, SupportSamplesNeedTheSameFootNearTheFloorOnBothFrames) {
  // Frames 0-2: left toe on its floor, right 10 cm up. Frames 3-5: the other way round. Pair
  // (2,3) changes the support foot: 4 samples of 6 pairs. Then frames 6-7 lift the right toe,
  // still the lower, 6 cm (the left 7 cm): (5,6) is near the floor on one frame only, (6,7) on
  // none. 4 samples of 7 pairs.
  Track t(8);
  for (int f = 0; f < 8; ++f) {
    const bool left_down = f < 3, right_down = f >= 3 && f < 6;
    t.joint[kToe][0][f].y = 0.02f + (left_down ? 0.0f : f < 6 ? 0.1f : 0.07f);
    t.joint[kToe][1][f].y = 0.03f + (right_down ? 0.0f : f < 3 ? 0.1f : 0.06f);
  }
  const ViewerFeetStats s = measure({t});
  EXPECT_EQ(s.support_samples, 4);
  EXPECT_NEAR(s.support_slide_cm_s, 0.0, 1e-9);
}

TEST(ViewerMetrics, FloatCountsWalkingFramesWithBothToesUp) {
  // Walking at 1 m/s (1/60 m per frame): frames 1-3 have a root speed, frame 2 has both toes more
  // than 5 cm above their floors (8 and 6 cm): 1 of 3. A running track (3 m/s) and a standing
  // one (0 m/s) with both toes up all the time are outside 0.1-2.2 m/s and count nowhere.
  Track walk(4), run(4), stand(4);
  for (int f = 0; f < 4; ++f) {
    walk.root[f] = glm::vec2(f / 60.0f, 0.0f);
    run.root[f] = glm::vec2(0.0f, 3.0f * f / 60.0f);
    for (Track* t : {&run, &stand}) {
      t->joint[kToe][0][f].y = 0.2f;
      t->joint[kToe][1][f].y = 0.2f;
    }
  }
  walk.joint[kToe][0][2].y = 0.02f + 0.08f;
  walk.joint[kToe][1][2].y = 0.03f + 0.06f;
  const ViewerFeetStats s = measure({walk, run, stand});
  EXPECT_EQ(s.float_samples, 3);
  EXPECT_NEAR(s.float_ratio, 1.0 / 3.0, 1e-12);
  EXPECT_EQ(s.agent_frames, 12);
}

TEST(ViewerMetrics, PenetrationIsTheDeeperOfToeAndAnkleBelowTheirFloors) {
  // 60 frames, 120 foot-frames. Left toe 2 cm below its floor on frame 1; left toe 1.5 cm and
  // left ankle 3 cm below on frame 10 (the foot is 3 cm deep, not 4.5); right ankle 0.5 cm below
  // on frame 2. Depths sorted: ..., 0.5, 2, 3. Max 3 cm; p99 = rank ceil(0.99 * 120) = 119 of
  // 120 = 2 cm; more than 1 cm: 2 of 120.
  Track t(60);
  t.joint[kToe][0][1].y = 0.0f;
  t.joint[kToe][0][10].y = 0.005f;
  t.joint[kAnkle][0][10].y = 0.05f;
  t.joint[kAnkle][1][2].y = 0.085f;
  const ViewerFeetStats s = measure({t});
  EXPECT_EQ(s.penetration_samples, 120);
  EXPECT_NEAR(s.penetration_max_cm, 3.0, 1e-4);
  // A percentile comes from the quantile sketch: within its documented relative error.
  EXPECT_NEAR(s.penetration_p99_cm, 2.0, 2.0 * QuantileSketch::kRelativeError + 1e-6);
  EXPECT_NEAR(s.penetration_ratio, 2.0 / 120.0, 1e-12);
}

TEST(ViewerMetrics, LimbPopCountsAgentFramesAboveTwiceTheReference) {
  // The left knee jumps 10 cm up on frame 5 only. Second differences: +0.1 m on frames 4 and 6,
  // -0.2 m on frame 5, i.e. 360, 720, 360 m/s^2 (0.1 / (1/60)^2 = 360). The right ankle jumps on
  // the same frame: still one agent-frame each. 60 frames = 1 agent-second = 1/60 agent-minute.
  Track t(60);
  t.joint[kKnee][0][5].y += 0.1f;
  t.joint[kAnkle][1][5].y += 0.1f;
  FeetReference ref = reference();
  auto with_reference = [&](float knee_ref) {
    ref.accel_m_s2[kKnee][0] = knee_ref;
    ref.accel_m_s2[kAnkle][1] = knee_ref;
    return measure({t}, ref);
  };
  const ViewerFeetStats low = with_reference(100.0f);  // threshold 200: frames 4, 5, 6
  EXPECT_EQ(low.limb_pops, 3);
  EXPECT_NEAR(low.limb_pop_rate, 3 * 60.0, 1e-3);
  EXPECT_EQ(with_reference(200.0f).limb_pops, 1);  // threshold 400: frame 5 only
  EXPECT_EQ(with_reference(400.0f).limb_pops, 0);  // threshold 800: none
}

TEST(ViewerMetrics, GmdSkateAt20FpsOverAllFrames) {
  // 61 frames at 60 Hz = 1 s: 21 frames at 20 fps (every 3rd), 20 with a previous one. The left
  // toe on its floor moves 1 cm per 60 Hz frame up to frame 30: 3 cm per 20 fps frame = 0.6 m/s,
  // skating on 20 fps frames 1-10. On 60 Hz frame 15 (20 fps frame 5) it is 10 cm up: frames 5
  // and 6 are not in contact, 8 skate. From frame 30 on it moves 0.75 cm per 60 Hz frame, 0.45
  // m/s at 20 fps (no skate), with a 1 cm jitter on frames 3k+1 that 20 fps never sees. The
  // right toe, 30 cm up and fast, is never in contact. Ratio 8 / 20.
  Track t(61);
  for (int f = 0; f <= 60; ++f) {
    float x = f <= 30 ? 0.01f * f : 0.3f + 0.0075f * (f - 30) + (f % 3 == 1 ? 0.01f : 0.0f);
    t.joint[kToe][0][f].x = x;
    t.joint[kToe][1][f] = glm::vec3(0.3f + 0.05f * f, 0.33f, 0.0f);
  }
  t.joint[kToe][0][15].y += 0.1f;
  const ViewerFeetStats s = measure({t});
  EXPECT_EQ(s.gmd_frames, 20);
  EXPECT_NEAR(s.gmd_skate_ratio, 8.0 / 20.0, 1e-12);
}

// Heights of each toe and ankle over the frames clip analysis marks as contact, per side,
// computed here from the analysis intervals and the clips as the library holds them.
struct ContactHeights {
  std::vector<float> toe[2], ankle[2];
};

ContactHeights contact_heights(const LocomotionLibrary& lib) {
  const Skeleton& sk = *lib.skeleton;
  ContactHeights h;
  std::vector<glm::quat> rot(sk.num_joints());
  std::vector<glm::vec3> trans(sk.num_joints());
  std::vector<glm::mat4> model(sk.num_joints());
  for (const LocomotionClip& lc : lib.clips) {
    if (!lc.gait) continue;
    const int n = lc.clip.num_frames;
    for (int f = 0; f < n; ++f) {
      SampleClipJob{&lc.clip, f / lc.clip.fps, rot, trans}.run();
      LocalToModelJob{&sk, rot, trans, glm::mat4(1.0f), model}.run();
      for (int s = 0; s < 2; ++s) {
        bool contact = false;
        for (const TimeInterval& iv : lc.analysis.contacts[s]) {
          const int a = static_cast<int>(std::lround(iv.start_s * lc.clip.fps));
          const int b = static_cast<int>(std::lround(iv.end_s * lc.clip.fps));
          for (int g = a; g <= b; ++g) contact |= ((g % n) + n) % n == f;
        }
        if (!contact) continue;
        h.toe[s].push_back(model[sk.toe(static_cast<Side>(s))][3].y);
        h.ankle[s].push_back(model[sk.ankle(static_cast<Side>(s))][3].y);
      }
    }
  }
  return h;
}

// A median m of v: no more than half (plus one sample) lies strictly below or strictly above.
void expect_median(const std::vector<float>& v, float m, const char* what) {
  ASSERT_FALSE(v.empty()) << what;
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  EXPECT_GE(m, *lo - 1e-5f) << what;
  EXPECT_LE(m, *hi + 1e-5f) << what;
  const auto below = std::count_if(v.begin(), v.end(), [&](float y) { return y < m - 1e-5f; });
  const auto above = std::count_if(v.begin(), v.end(), [&](float y) { return y > m + 1e-5f; });
  EXPECT_LE(below, static_cast<long>(v.size() / 2 + 1)) << what;
  EXPECT_LE(above, static_cast<long>(v.size() / 2 + 1)) << what;
}

void expect_reference_of(const LocomotionLibrary& lib) {
  const FeetReference ref = make_feet_reference(lib, kDt);
  const ContactHeights h = contact_heights(lib);
  for (int s = 0; s < 2; ++s) {
    expect_median(h.toe[s], ref.toe_floor_m[s], s ? "right toe" : "left toe");
    expect_median(h.ankle[s], ref.ankle_floor_m[s], s ? "right ankle" : "left ankle");
    // The ankle sits above the ball of the foot when planted.
    EXPECT_GT(ref.ankle_floor_m[s], ref.toe_floor_m[s]);
    for (int j = 0; j < kNumLimbJoints; ++j) {
      EXPECT_TRUE(std::isfinite(ref.accel_m_s2[j][s])) << j << " " << s;
      EXPECT_GT(ref.accel_m_s2[j][s], 0.0f) << j << " " << s;
    }
  }
}

TEST(ViewerMetrics, ReferenceOfTheBuiltinLibrary) { expect_reference_of(test::builtin_library()); }

TEST(ViewerMetrics, ReferenceOfTheCmuWalk) {
  GK_REQUIRE_DATA("clips/bvh/cmu_07_01_walk.bvh");
  auto lib = test::load_data_library({"clips/bvh/cmu_07_01_walk.bvh"});
  ASSERT_TRUE(lib.ok()) << lib.message();
  expect_reference_of(*lib);
}

TEST(ViewerMetrics, LibraryFloorOfTheBuiltinClips) {
  const LocomotionLibrary& lib = test::builtin_library();
  const FeetReference ref = make_feet_reference(lib, kDt);
  const ViewerFeetStats s = library_feet_floor(lib, ref, kDt);
  int clips = 0;
  for (const LocomotionClip& c : lib.clips) clips += c.gait;
  ASSERT_GT(clips, 0);
  ASSERT_GT(s.agent_frames, 0);
  EXPECT_EQ(s.penetration_samples, 2 * s.agent_frames);
  // The floors are medians of the planted heights of these very clips: some planted toe lies
  // below its floor, so the clips themselves reach into it.
  EXPECT_GT(s.penetration_max_cm, 0.0);
  // Each joint's reference is the 99.9th percentile (nearest rank) of the N accelerations the
  // pop test sees on these same clips (every frame with a neighbour on both sides): at most
  // N - ceil(0.999 N) of them exceed it, and twice it even fewer; 6 joints.
  const int64_t n = s.agent_frames - 2 * clips;
  const int64_t beyond = n - static_cast<int64_t>(std::ceil(0.999 * static_cast<double>(n)));
  EXPECT_LE(s.limb_pops, 6 * beyond);
}

}  // namespace
}  // namespace gk
