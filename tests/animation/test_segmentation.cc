// Long takes against what PROVENANCE.md of the subject-16 set states independently (speeds, the
// start, the stop, the 90-degree turn), and the cut-out cycles against a stride period derived
// here from the take's own toe heights (autocorrelation), not from contact analysis.

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "animation/analysis.h"
#include "animation/clip_library.h"
#include "animation/mirror.h"
#include "animation/pose_jobs.h"
#include "animation/segmentation.h"
#include "tests/animation/joint_positions.h"
#include "tests/test_data.h"

namespace gk {
namespace {

constexpr float kDeg = 180.0f / std::numbers::pi_v<float>;

struct Take {
  ClipSet set;
  ClipAnalysis analysis;
  TakeSegmentation seg;
  const Clip& clip() const { return set.clips.at(0); }
};

Take load_take(const std::string& rel) {
  Result<ClipSet> set = load_clip_file(test::data_path(rel));
  EXPECT_TRUE(set.ok()) << set.message();
  if (!set.ok()) return {};
  Take t{std::move(*set), {}, {}};
  t.analysis = analyze_clip(t.clip(), *t.set.skeleton);
  t.seg = segment_take(t.clip(), *t.set.skeleton, t.analysis);
  return t;
}

std::vector<glm::vec3> joint_track(const Clip& c, const Skeleton& sk, int joint) {
  std::vector<glm::mat4> model(sk.num_joints());
  std::vector<glm::vec3> out;
  for (int f = 0; f < c.num_frames; ++f) {
    clip_frame_model(c, sk, f, model);
    out.push_back(translation_of(model[joint]));
  }
  return out;
}

// Stride period [s] of a take: the lag (0.5-2 s) at which the left toe's height best repeats
// itself (normalised autocorrelation, first peak above 0.5 of the best).
float toe_height_period(const Clip& c, const Skeleton& sk) {
  const std::vector<glm::vec3> toe = joint_track(c, sk, sk.toe(Side::kLeft));
  const int n = static_cast<int>(toe.size());
  double mean = 0.0;
  for (const glm::vec3& p : toe) mean += p.y;
  mean /= n;
  const int lo = static_cast<int>(0.5f * c.fps), hi = std::min(n - 4, static_cast<int>(2.0f * c.fps));
  std::vector<double> r(hi + 2, 0.0);
  for (int lag = lo; lag <= hi + 1 && lag < n; ++lag) {
    double num = 0.0, d0 = 0.0, d1 = 0.0;
    for (int f = 0; f + lag < n; ++f) {
      const double x = toe[f].y - mean, y = toe[f + lag].y - mean;
      num += x * y;
      d0 += x * x;
      d1 += y * y;
    }
    r[lag] = num / std::sqrt(std::max(d0 * d1, 1e-12));
  }
  const double best = *std::max_element(r.begin() + lo, r.begin() + hi + 1);
  for (int lag = lo + 1; lag <= hi; ++lag) {
    if (r[lag] >= 0.5 * best && r[lag] >= r[lag - 1] && r[lag] >= r[lag + 1]) return lag / c.fps;
  }
  return 0.0f;
}

const TakeSegment* first_of(const TakeSegmentation& s, SegmentKind kind) {
  for (const TakeSegment& seg : s.segments) {
    if (seg.kind == kind) return &seg;
  }
  return nullptr;
}

#define REQUIRE_TAKE(rel) GK_REQUIRE_DATA(rel)

// Steady takes: one steady segment over (nearly) the whole take, at PROVENANCE.md's average root
// speed within 5%, and a cycle one stride long.
TEST(Segmentation, SteadyTakesAreOneSteadySegmentAtTheirSpeed) {
  struct Case {
    const char* file;
    float speed_m_s;  // PROVENANCE.md "Average root speed"
  };
  for (const Case& c : {Case{"clips/bvh/more/cmu_16_11_walk_veer_left.bvh", 0.96f},
                        Case{"clips/bvh/more/cmu_16_15_walk_mrl30.bvh", 1.17f},
                        Case{"clips/bvh/more/cmu_16_22_fast_walk_mrl30.bvh", 1.73f},
                        Case{"clips/bvh/more/cmu_16_36_run_jog_mrl30.bvh", 2.86f}}) {
    REQUIRE_TAKE(c.file);
    const Take t = load_take(c.file);
    ASSERT_FALSE(t.seg.segments.empty()) << c.file;
    const TakeSegment* steady = first_of(t.seg, SegmentKind::kSteady);
    ASSERT_NE(steady, nullptr) << c.file;
    EXPECT_GT(steady->span.end_s - steady->span.start_s, 0.8f * t.analysis.duration_s) << c.file;
    EXPECT_NEAR(steady->speed_m_s, c.speed_m_s, 0.05f * c.speed_m_s) << c.file;
    EXPECT_TRUE(t.seg.problems.empty()) << c.file << ": " << t.seg.problems.front();
    ASSERT_FALSE(t.seg.cycles.empty()) << c.file;
  }
}

// Every cut-out cycle is one stride: as long as the period of the take's toe height, and with
// exactly one contact of each foot when analysed as the loop the library plays.
TEST(Segmentation, CyclesAreOneStrideLong) {
  for (const char* file : {"clips/bvh/more/cmu_16_11_walk_veer_left.bvh",
                           "clips/bvh/more/cmu_16_15_walk_mrl30.bvh",
                           "clips/bvh/more/cmu_16_17_walk_90_left_turn_mrl30.bvh",
                           "clips/bvh/more/cmu_16_22_fast_walk_mrl30.bvh",
                           "clips/bvh/more/cmu_16_31_start_walk_mrl30.bvh",
                           "clips/bvh/more/cmu_16_36_run_jog_mrl30.bvh",
                           "clips/bvh/cmu_07_01_walk.bvh", "clips/bvh/cmu_09_11_run.bvh"}) {
    REQUIRE_TAKE(file);
    const Take t = load_take(file);
    const Skeleton& sk = *t.set.skeleton;
    const float period = toe_height_period(t.clip(), sk);
    ASSERT_GT(period, 0.0f) << file;
    ASSERT_FALSE(t.seg.cycles.empty()) << file;
    for (const TakeSegment& seg : t.seg.segments) {
      // A steady segment two periods long or more walks at the take's dominant stride.
      if (seg.cycle < 0 || seg.span.end_s - seg.span.start_s < 2.0f * period) continue;
      const Stride& st = t.seg.strides[seg.cycle];
      EXPECT_NEAR(st.span.end_s - st.span.start_s, period, std::max(0.1f * period, 2.0f / t.clip().fps))
          << file;
    }
    for (int ci : t.seg.cycles) {
      const Clip loop = extract_cycle(t.clip(), sk, t.analysis, t.seg.strides[ci]);
      EXPECT_TRUE(loop.loops);
      EXPECT_NEAR(loop.duration_s(), t.seg.strides[ci].span.end_s - t.seg.strides[ci].span.start_s,
                  1.0f / loop.fps) << file;
      const ClipAnalysis la = analyze_clip(loop, sk);
      EXPECT_EQ(la.contacts[0].size(), 1u) << file;
      EXPECT_EQ(la.contacts[1].size(), 1u) << file;
      // The loop travels the way the take's stride did, forward.
      EXPECT_NEAR(la.native_speed_m_s, t.seg.strides[ci].speed_m_s,
                  0.05f * t.seg.strides[ci].speed_m_s)
          << file;
      EXPECT_LT(std::abs(la.direction_rad) * kDeg, 10.0f) << file;
    }
  }
}

// A take that walks and then walks faster, with no stop between (subject 16's walk followed by
// its fast walk, the second's root carried on from where the first ends: one steady segment),
// gives a loop at each pace, at PROVENANCE.md's speeds within 5%; each one stride long.
TEST(Segmentation, ATakeAtTwoPacesGivesALoopAtEach) {
  const char* walk_file = "clips/bvh/more/cmu_16_15_walk_mrl30.bvh";
  const char* fast_file = "clips/bvh/more/cmu_16_22_fast_walk_mrl30.bvh";
  REQUIRE_TAKE(walk_file);
  REQUIRE_TAKE(fast_file);
  Result<ClipSet> walk = load_clip_file(test::data_path(walk_file));
  Result<ClipSet> fast = load_clip_file(test::data_path(fast_file));
  ASSERT_TRUE(walk.ok() && fast.ok());
  Clip take = walk->clips.at(0);
  const Clip& more = fast->clips.at(0);
  ASSERT_EQ(take.num_joints, more.num_joints);
  ASSERT_EQ(take.fps, more.fps);
  const size_t J = static_cast<size_t>(take.num_joints);
  const glm::vec3 end = take.translations[(take.num_frames - 1) * J];
  const glm::vec3 start = more.translations[0];
  for (int f = 0; f < more.num_frames; ++f) {
    take.rotations.insert(take.rotations.end(), more.frame_rotations(f), more.frame_rotations(f) + J);
    std::vector<glm::vec3> tr(more.frame_translations(f), more.frame_translations(f) + J);
    tr[0].x += end.x - start.x;
    tr[0].z += end.z - start.z;
    take.translations.insert(take.translations.end(), tr.begin(), tr.end());
  }
  take.num_frames += more.num_frames;
  const Skeleton& sk = *walk->skeleton;
  const ClipAnalysis a = analyze_clip(take, sk);
  const TakeSegmentation seg = segment_take(take, sk, a);
  int steady = 0;
  for (const TakeSegment& s : seg.segments) steady += s.kind == SegmentKind::kSteady ? 1 : 0;
  EXPECT_EQ(steady, 1);
  ASSERT_EQ(seg.cycles.size(), 2u);
  std::vector<float> speeds;
  for (int ci : seg.cycles) {
    const Stride& st = seg.strides[ci];
    speeds.push_back(st.speed_m_s);
    const Clip loop = extract_cycle(take, sk, a, st);
    const ClipAnalysis la = analyze_clip(loop, sk);
    EXPECT_EQ(la.contacts[0].size(), 1u);
    EXPECT_EQ(la.contacts[1].size(), 1u);
    EXPECT_NEAR(la.native_speed_m_s, st.speed_m_s, 0.05f * st.speed_m_s);
  }
  std::sort(speeds.begin(), speeds.end());
  EXPECT_NEAR(speeds[0], 1.17f, 0.05f * 1.17f);  // PROVENANCE.md: the walk's average root speed
  EXPECT_NEAR(speeds[1], 1.73f, 0.05f * 1.73f);  // and the fast walk's
}

// The loop's seam adds no step the take did not have: for every joint, the change of its local
// rotation from the loop's last frame to its first is at most the larger of the take's own step
// there (the stride's last frame to the next) and the loop's largest step elsewhere, plus its share
// of the closing.
TEST(Segmentation, LoopSeamIsNoBiggerThanTheTakesSteps) {
  for (const char* file : {"clips/bvh/more/cmu_16_11_walk_veer_left.bvh",
                           "clips/bvh/more/cmu_16_15_walk_mrl30.bvh",
                           "clips/bvh/more/cmu_16_22_fast_walk_mrl30.bvh",
                           "clips/bvh/cmu_07_01_walk.bvh"}) {
    REQUIRE_TAKE(file);
    const Take t = load_take(file);
    ASSERT_FALSE(t.seg.cycles.empty()) << file;
    const Stride& st = t.seg.strides[t.seg.cycles[0]];
    const Clip loop = extract_cycle(t.clip(), *t.set.skeleton, t.analysis, st);
    const int a = static_cast<int>(std::lround(st.span.start_s * t.clip().fps));
    const int n = loop.num_frames;
    auto step = [](const Clip& c, int f0, int f1, int j) {
      const float d = std::abs(glm::dot(c.frame_rotations(f0)[j], c.frame_rotations(f1)[j]));
      return 2.0f * std::acos(std::min(1.0f, d));
    };
    for (int j = 1; j < loop.num_joints; ++j) {
      float inside = 0.0f;
      for (int f = 0; f + 1 < n; ++f) inside = std::max(inside, step(loop, f, f + 1, j));
      const float take_step = step(t.clip(), a + n - 1, a + n, j);
      // Closing the loop spreads the joint's mismatch between the stride's ends over its frames:
      // each step may grow by at most that share (smoothstep-shaped for the legs: 1.5 times it).
      const float share = 1.5f * step(t.clip(), a, a + n, j) / n;
      EXPECT_LE(step(loop, n - 1, 0, j), std::max(inside, take_step) + share + 1e-4f)
          << file << " joint " << t.set.skeleton->names[j];
    }
  }
}

// Closing a loop never bends a leg that bears weight where it need not: through every stance that
// lies inside the stride (a run's other foot, down between two swings), that leg's knee in the
// cut-out cycle bends exactly as much as in the take (the closing is taken up while the foot
// swings). Held straight in the take, a running knee was bent backwards by 11 degrees in a cycle
// whose longer swing came before that stance. Returns the frames checked.
float knee_angle_deg(const std::vector<glm::mat4>& m, const Skeleton& sk, Side s) {
  const glm::vec3 h = translation_of(m[sk.hip(s)]), k = translation_of(m[sk.knee(s)]),
                  a = translation_of(m[sk.ankle(s)]);
  const float c = glm::dot(glm::normalize(k - h), glm::normalize(a - k));
  return std::acos(std::clamp(c, -1.0f, 1.0f)) * kDeg;
}

int expect_stance_knees_kept(const Clip& take, const Skeleton& sk, const ClipAnalysis& an,
                             const Clip& loop, int a, const std::string& what) {
  std::vector<glm::mat4> mt(sk.num_joints()), ml(sk.num_joints());
  int checked = 0;
  const int len = loop.num_frames;
  for (int k = 1; k + 1 < len; ++k) {
    clip_frame_model(take, sk, a + k, mt);
    clip_frame_model(loop, sk, k, ml);
    for (int s = 0; s < 2; ++s) {
      bool inside = false;
      for (const TimeInterval& iv : an.contacts[s]) {
        const int f0 = static_cast<int>(std::lround(iv.start_s * take.fps)) - a;
        const int f1 = static_cast<int>(std::lround(iv.end_s * take.fps)) - a;
        inside |= f0 > 0 && f1 < len && k >= f0 && k <= f1;
      }
      if (!inside) continue;
      ++checked;
      const Side sd = static_cast<Side>(s);
      EXPECT_NEAR(knee_angle_deg(ml, sk, sd), knee_angle_deg(mt, sk, sd), 0.5f)
          << what << ": frame " << k << " of the cycle, " << (s ? "right" : "left") << " knee";
    }
  }
  return checked;
}

TEST(Segmentation, ClosingALoopKeepsTheStanceKnees) {
  int checked = 0;
  for (const char* file :
       {"clips/bvh/more/cmu_16_11_walk_veer_left.bvh", "clips/bvh/more/cmu_16_15_walk_mrl30.bvh",
        "clips/bvh/more/cmu_16_17_walk_90_left_turn_mrl30.bvh",
        "clips/bvh/more/cmu_16_22_fast_walk_mrl30.bvh",
        "clips/bvh/more/cmu_16_31_start_walk_mrl30.bvh",
        "clips/bvh/more/cmu_16_36_run_jog_mrl30.bvh", "clips/bvh/cmu_07_01_walk.bvh",
        "clips/bvh/cmu_09_11_run.bvh"}) {
    REQUIRE_TAKE(file);
    const Take t = load_take(file);
    const Skeleton& sk = *t.set.skeleton;
    ASSERT_FALSE(t.seg.cycles.empty()) << file;
    // Every stride of the take cut as a cycle, not only the ones chosen: each has its own seam.
    for (const Stride& st : t.seg.strides) {
      const int a = static_cast<int>(std::lround(st.span.start_s * t.clip().fps));
      const Clip loop = extract_cycle(t.clip(), sk, t.analysis, st);
      checked += expect_stance_knees_kept(
          t.clip(), sk, t.analysis, loop, a,
          std::string(file) + " stride at " + std::to_string(st.span.start_s));
    }
  }
  EXPECT_GT(checked, 100);  // the runs' strides have such stances
}

// The start take (PROVENANCE.md: stands, then speeds up to a 1.3-1.4 m/s walk in about 1.5 s):
// standing, then a start, then steady walking at the speed of its late windows (1.32, 1.41, 1.36,
// 1.31 m/s).
TEST(Segmentation, StartTakeStandsStartsThenWalks) {
  const char* file = "clips/bvh/more/cmu_16_31_start_walk_mrl30.bvh";
  REQUIRE_TAKE(file);
  const Take t = load_take(file);
  const TakeSegment* idle = first_of(t.seg, SegmentKind::kIdle);
  const TakeSegment* start = first_of(t.seg, SegmentKind::kStart);
  const TakeSegment* steady = first_of(t.seg, SegmentKind::kSteady);
  ASSERT_NE(idle, nullptr);
  ASSERT_NE(start, nullptr);
  ASSERT_NE(steady, nullptr);
  EXPECT_LT(idle->span.start_s, start->span.start_s);
  EXPECT_LT(start->span.start_s, steady->span.start_s);
  EXPECT_NEAR(start->span.end_s - idle->span.end_s, 1.5f, 0.5f);  // "in about 1.5 s"
  const float late = (1.32f + 1.41f + 1.36f + 1.31f) / 4.0f;
  EXPECT_NEAR(steady->speed_m_s, late, 0.05f * late);
}

// The stop takes end standing after a stop; the turn take turns left by about 90 degrees
// (PROVENANCE.md: heading -3 -> +85 deg), most of it in its turn segment.
TEST(Segmentation, StopsEndStandingAndTheTurnTurnsLeft) {
  for (const char* file : {"clips/bvh/more/cmu_16_33_slow_walk_stop_mrl30.bvh",
                           "clips/bvh/more/cmu_16_57_run_jog_sudden_stop_mrl30.bvh"}) {
    REQUIRE_TAKE(file);
    const Take t = load_take(file);
    ASSERT_GE(t.seg.segments.size(), 2u) << file;
    EXPECT_EQ(t.seg.segments.back().kind, SegmentKind::kIdle) << file;
    EXPECT_EQ(t.seg.segments[t.seg.segments.size() - 2].kind, SegmentKind::kStop) << file;
    const TakeSegment& stop = t.seg.segments[t.seg.segments.size() - 2];
    EXPECT_GT(stop.speed_in_m_s, 3.0f * stop.speed_out_m_s) << file;
  }
  const char* file = "clips/bvh/more/cmu_16_17_walk_90_left_turn_mrl30.bvh";
  REQUIRE_TAKE(file);
  const Take t = load_take(file);
  float total = 0.0f;
  for (const TakeSegment& s : t.seg.segments) total += s.turn_rad;
  EXPECT_NEAR(total * kDeg, 88.0f, 12.0f);
  const TakeSegment* turn = first_of(t.seg, SegmentKind::kTurn);
  ASSERT_NE(turn, nullptr);
  EXPECT_GT(turn->turn_rad * kDeg, 45.0f);
}

// The stop takes have no steady stride (each slows down by a third or more), but a step that walks:
// that step and its mirror image make the cycle. The loop is two of its steps long, its feet
// alternate (each foot down as long as the other, landing half a loop after it) and it travels
// at the step's speed; turned round in the world first, the take makes the same loop.
TEST(Segmentation, AStopTakeLoopsItsSteadiestStepAndItsMirrorImage) {
  for (const char* file : {"clips/bvh/more/cmu_16_33_slow_walk_stop_mrl30.bvh",
                           "clips/bvh/more/cmu_16_57_run_jog_sudden_stop_mrl30.bvh"}) {
    REQUIRE_TAKE(file);
    const Take t = load_take(file);
    const Skeleton& sk = *t.set.skeleton;
    ASSERT_TRUE(t.seg.fallback_cycle) << file;
    ASSERT_GE(t.seg.mirror_step, 0) << file;
    const Stride& step = t.seg.steps[t.seg.mirror_step];
    const float fps = t.clip().fps;
    const int step_frames = static_cast<int>(std::lround((step.span.end_s - step.span.start_s) * fps));
    const std::vector<int16_t> map = mirror_joint_map(sk);
    const MirroredCycle mc = extract_mirrored_cycle(t.clip(), sk, t.analysis, step, map);
    EXPECT_TRUE(mc.loop.loops) << file;
    EXPECT_EQ(mc.loop.num_frames, 2 * step_frames) << file;
    const float duration = mc.loop.duration_s();
    ASSERT_EQ(mc.contacts[0].size(), 1u) << file;
    ASSERT_EQ(mc.contacts[1].size(), 1u) << file;
    const TimeInterval l = mc.contacts[0][0], r = mc.contacts[1][0];
    EXPECT_NEAR(l.end_s - l.start_s, r.end_s - r.start_s, 1.01f / fps) << file;
    float apart = std::abs(l.start_s - r.start_s);
    EXPECT_NEAR(apart, 0.5f * duration, 1.01f / fps) << file;
    const ClipAnalysis la = analyze_clip(mc.loop, sk);
    EXPECT_NEAR(la.native_speed_m_s, step.speed_m_s, 0.1f * step.speed_m_s) << file;

    // The same take turned 70 degrees about the vertical and moved: the same loop.
    Clip turned = t.clip();
    const glm::quat yaw = glm::angleAxis(glm::radians(70.0f), glm::vec3(0, 1, 0));
    for (int f = 0; f < turned.num_frames; ++f) {
      for (int j = 0; j < turned.num_joints; ++j) {
        if (sk.parents[j] >= 0) continue;
        const size_t i = static_cast<size_t>(f) * turned.num_joints + j;
        turned.rotations[i] = glm::normalize(yaw * turned.rotations[i]);
        turned.translations[i] = yaw * turned.translations[i] + glm::vec3(3.0f, 0.0f, -2.0f);
      }
    }
    const ClipAnalysis ta = analyze_clip(turned, sk);
    const TakeSegmentation ts = segment_take(turned, sk, ta);
    ASSERT_GE(ts.mirror_step, 0) << file;
    const MirroredCycle tc = extract_mirrored_cycle(turned, sk, ta, ts.steps[ts.mirror_step], map);
    EXPECT_EQ(tc.loop.num_frames, mc.loop.num_frames) << file;
    EXPECT_NEAR(analyze_clip(tc.loop, sk).native_speed_m_s, la.native_speed_m_s,
                0.02f * la.native_speed_m_s)
        << file;
    // Frame by frame, the turned take's loop is the loop turned and moved: the feet keep their
    // distance from the hips (and each other) to the millimetre.
    for (int f = 0; f < mc.loop.num_frames; ++f) {
      const std::vector<glm::vec3> a = test::joint_positions(mc.loop, sk, f);
      const std::vector<glm::vec3> b = test::joint_positions(tc.loop, sk, f);
      const int hips = sk.role(JointRole::kHips);
      for (int j = 0; j < sk.num_joints(); ++j) {
        EXPECT_NEAR(glm::length(a[j] - a[hips]), glm::length(b[j] - b[hips]), 2e-3f)
            << file << " frame " << f << " " << sk.names[j];
      }
    }
  }
}

// Contacts against hand labels (tests/data/contact_labels: touchdown and lift-off frames judged
// frame by frame from heel and toe height and speed traces, by someone who had not seen this
// program's output): the same contacts, each touchdown and lift-off within 2 frames (a contact
// cut by the take's first or last frame is checked at its other end only).
TEST(Segmentation, ContactsMatchHandLabelsWithinTwoFrames) {
  const std::string dir = test::source_path("tests/data/contact_labels");
  int checked = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    std::ifstream in(entry.path());
    const nlohmann::json labels = nlohmann::json::parse(in);
    const std::string rel = "clips/bvh/more/" + labels["clip"].get<std::string>();
    REQUIRE_TAKE(rel);
    const Take t = load_take(rel);
    const int last = t.clip().num_frames - 1;
    for (int s = 0; s < 2; ++s) {
      const nlohmann::json& want = labels[s == 0 ? "left" : "right"];
      const std::vector<TimeInterval>& got = t.analysis.contacts[s];
      ASSERT_EQ(got.size(), want.size()) << rel << (s == 0 ? " left" : " right");
      for (size_t i = 0; i < got.size(); ++i) {
        const int g0 = static_cast<int>(std::lround(got[i].start_s * t.clip().fps));
        const int g1 = static_cast<int>(std::lround(got[i].end_s * t.clip().fps));
        const int w0 = want[i][0].get<int>(), w1 = want[i][1].get<int>();
        if (w0 > 0) {
          EXPECT_NEAR(g0, w0, 2) << rel << " side " << s << " contact " << i << " touchdown";
        }
        if (w1 < last) {
          EXPECT_NEAR(g1, w1, 2) << rel << " side " << s << " contact " << i << " lift-off";
        }
        ++checked;
      }
    }
  }
  EXPECT_GE(checked, 30);
}

}  // namespace
}  // namespace gk
