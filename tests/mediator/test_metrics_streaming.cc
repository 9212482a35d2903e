// The streamed metrics (MetricsRecorder, fixed memory) against an exact computation over every
// stored sample and whole tracks, on long runs with real clips: a crowd of 30 walking the plaza
// with the CMU walk and run for 5,000 frames, and a bottleneck of 40 emptied round after round
// (agents leave at the door, a new round comes in) for 6,000 frames. Every figure must agree
// within the documented error (docs/metrics.md): exact counts, means and maxima; percentiles
// within QuantileSketch::kRelativeError; METRICS.md v1's foot slide equal to its definition with
// the contact band decided FootSlideStream::kLag_s late, and between METRICS.md's own band and
// that band widened by the reported excess.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "animation/foot_metrics.h"
#include "animation/pose_jobs.h"
#include "crowd/restarting_crowd.h"
#include "crowd/scenario.h"
#include "crowd/social_forces.h"
#include "mediator/metrics.h"
#include "mediator/springs.h"
#include "tests/mediator/exact_viewer_metrics.h"
#include "tests/mediator/mediator_fixture.h"
#include "tests/test_data.h"

namespace gk {
namespace {

constexpr float kDt = 1.0f / 60.0f;
constexpr float kDeg = 180.0f / std::numbers::pi_v<float>;
constexpr int kToe = static_cast<int>(LimbJoint::kToe);
constexpr int kAnkle = static_cast<int>(LimbJoint::kAnkle);
constexpr int kKnee = static_cast<int>(LimbJoint::kKnee);

// One agent's consecutive frames, as stored by the exact reference.
struct StoredTrack {
  std::vector<glm::vec3> joint[kNumLimbJoints][2];
  std::vector<glm::vec2> root;
  LimbTrack view() const {
    LimbTrack t;
    for (int j = 0; j < kNumLimbJoints; ++j) {
      for (int s = 0; s < 2; ++s) t.joint[j][s] = joint[j][s];
    }
    t.root = root;
    return t;
  }
};

// Every sample of a run, stored: what MetricsRecorder streams, computed here from the same
// mediator and poses with METRICS.md's definitions.
struct ExactRun {
  std::vector<StoredTrack> tracks;                  // finished and open
  std::map<uint32_t, std::pair<size_t, int>> open;  // id -> (track, last frame)
  std::vector<double> torsion, facing, facing_within, heading, root_error, rate;
  double feedback_sum = 0.0;
  int64_t feedback_n = 0, rate_outside = 0, pops = 0, agent_frames = 0;
  double max_jerk = 0.0;

  void record(int frame_index, const AgentFrame& frame, const Mediator& m,
              const PoseSynthesizer& poses, const LocomotionLibrary& lib) {
    const Skeleton& sk = *lib.skeleton;
    const AnimationPlans& pl = m.plans();
    const MediatorParams& P = m.params();
    for (size_t i = 0; i < frame.size(); ++i) {
      const int slot = pl.slot_of_agent[i];
      const auto w = poses.world(slot);
      auto it = open.find(frame.ids[i]);
      const bool continues = it != open.end() && it->second.second == frame_index - 1;
      if (!continues) {
        tracks.emplace_back();
        it = open.insert_or_assign(frame.ids[i], std::pair{tracks.size() - 1, 0}).first;
      }
      it->second.second = frame_index;
      StoredTrack& t = tracks[it->second.first];
      for (int s = 0; s < 2; ++s) {
        const Side side = static_cast<Side>(s);
        t.joint[kToe][s].push_back(translation_of(w[sk.toe(side)]));
        t.joint[kAnkle][s].push_back(translation_of(w[sk.ankle(side)]));
        t.joint[kKnee][s].push_back(translation_of(w[sk.knee(side)]));
      }
      const glm::vec3 pelvis = translation_of(w[sk.role(JointRole::kHips)]);
      const glm::vec2 root(pelvis.x, pelvis.z);
      const glm::vec2 prev = continues ? t.root.back() : root;
      t.root.push_back(root);
      const size_t k = t.root.size() - 1;
      if (k >= 3) {
        const auto& p = t.root;
        const glm::vec2 j =
            (p[k] - 3.0f * p[k - 1] + 3.0f * p[k - 2] - p[k - 3]) / (kDt * kDt * kDt);
        max_jerk = std::max(max_jerk, static_cast<double>(glm::length(j)));
      }
      ++agent_frames;
      torsion.push_back(std::abs(poses.torsion(slot)) * kDeg);
      if (std::isfinite(frame.thetas[i])) {
        const float err = std::abs(wrap_pi(poses.upper_heading(slot) - frame.thetas[i])) * kDeg;
        facing.push_back(err);
        const float asked = std::abs(wrap_pi(frame.thetas[i] - poses.pelvis_heading(slot))) * kDeg;
        if (asked <= P.torsion_limit_deg) facing_within.push_back(err);
      }
      const glm::vec2 p = frame.positions[i];
      if (std::isfinite(p.x) && std::isfinite(p.y) && std::abs(p.x) < 1e6f &&
          std::abs(p.y) < 1e6f) {
        root_error.push_back(100.0f * glm::length(root - p));
      }
      if (continues) {
        const glm::vec2 vel = (root - prev) / kDt;
        if (glm::length(vel) > 0.2f) {
          heading.push_back(std::abs(wrap_pi(pl.travel_yaw[slot] - std::atan2(vel.x, vel.y))) *
                            kDeg);
        }
        if (poses.max_rotation_change(slot) > 2.0f * lib.max_rotation_step_rad) ++pops;
      }
      const float playback = pl.playback_rate[slot];
      rate.push_back(playback);
      rate_outside +=
          playback < P.min_playback_rate - 1e-4f || playback > P.max_playback_rate + 1e-4f;
      const FeedbackBuffers& fb = m.feedback();
      if (fb.has_feedback[i]) {
        const glm::vec2 v_sim = m.sim_velocities()[i];
        const float sim_len = glm::length(v_sim);
        if (sim_len > 1e-4f && glm::length(fb.velocities[i] - v_sim) > 1e-6f) {
          feedback_sum += glm::length(fb.velocities[i] - v_sim) / sim_len;
          ++feedback_n;
        }
      }
    }
  }
};

// The k-th smallest (0-based) of v.
double order_statistic(std::vector<double> v, size_t k) {
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}
double nearest_rank(const std::vector<double>& v, double q) {
  const auto k = static_cast<size_t>(std::ceil(q * static_cast<double>(v.size())));
  return order_statistic(v, std::clamp<size_t>(k, 1, v.size()) - 1);
}

// Within the sketch's documented error of the exact order statistic (kMinValue absolute below).
void expect_sketched(double streamed, double exact, const char* what) {
  EXPECT_NEAR(streamed, exact,
              std::max(exact * (QuantileSketch::kRelativeError + 1e-9), QuantileSketch::kMinValue))
      << what;
}

void expect_summary(const Summary& s, const std::vector<double>& v, const char* what) {
  ASSERT_EQ(s.count, v.size()) << what;
  ASSERT_FALSE(v.empty()) << what;
  double sum = 0.0;
  for (double x : v) sum += x;
  EXPECT_NEAR(s.mean, sum / v.size(), 1e-9 * std::abs(sum / v.size())) << what;
  EXPECT_EQ(s.min, *std::min_element(v.begin(), v.end())) << what;
  EXPECT_EQ(s.max, *std::max_element(v.begin(), v.end())) << what;
  expect_sketched(s.p95, nearest_rank(v, 0.95), what);
}

// METRICS.md v1 over stored tracks, deciding contact against minima over [0, min(t + lag, n-1)]
// (lag < 0: the whole track, METRICS.md's definition), with the bands widened by extra_*.
struct V1 {
  SlideStats stats;
  double speed_sum = 0.0;
  int64_t skating = 0;
};
V1 exact_v1(const std::vector<StoredTrack>& tracks, int lag, float extra_toe = 0.0f,
            float extra_ankle = 0.0f) {
  SlideAccumulator acc;
  std::vector<uint8_t> contact;
  V1 out;
  for (const StoredTrack& t : tracks) {
    for (int s = 0; s < 2; ++s) {
      const auto& toe = t.joint[kToe][s];
      const auto& ankle = t.joint[kAnkle][s];
      const size_t n = toe.size();
      std::vector<float> min_toe(n), min_ankle(n);  // prefix minima
      for (size_t i = 0; i < n; ++i) {
        min_toe[i] = i ? std::min(min_toe[i - 1], toe[i].y) : toe[i].y;
        min_ankle[i] = i ? std::min(min_ankle[i - 1], ankle[i].y) : ankle[i].y;
      }
      contact.assign(n, 0);
      for (size_t i = 0; i < n; ++i) {
        const size_t k = lag < 0 ? n - 1 : std::min(n - 1, i + static_cast<size_t>(lag));
        contact[i] = toe[i].y <= min_toe[k] + (0.025f + extra_toe) &&
                     ankle[i].y <= min_ankle[k] + (0.05f + extra_ankle);
      }
      for (size_t i = 1; i < n; ++i) {
        if (!contact[i] || !contact[i - 1]) continue;
        const float v = 100.0f * std::hypot(toe[i].x - toe[i - 1].x, toe[i].z - toe[i - 1].z) / kDt;
        out.speed_sum += v;
        out.skating += v > 30.0f;
      }
      acc.add_track_with_contacts(toe, contact, kDt);
    }
  }
  out.stats = acc.finish();
  return out;
}

void compare(CrowdSource& crowd, const LocomotionLibrary& lib, int frames, const char* what) {
  SCOPED_TRACE(what);
  CrowdPipeline pipeline(lib, MediatorParams{}, test::test_pipeline_options(crowd.capacity(), kDt));
  const MetricsRecorder& streamed = *pipeline.metrics();
  ExactRun exact;
  // The exact figures from the very frames the pipeline recorded (as planned, before feedback).
  pipeline.add_frame_hook([&](const CrowdPipeline& p) {
    exact.record(static_cast<int>(p.frames_run() - 1), p.frame(), p.mediator(), p.poses(), lib);
    return Status::Ok();
  });
  size_t most_live = 0;
  for (int f = 0; f < frames; ++f) {
    ASSERT_TRUE(pipeline.step(crowd, kDt).ok());
    // Bounded by the live agents: a track ends the frame its agent is gone.
    ASSERT_EQ(streamed.num_live_tracks(), pipeline.frame().size()) << "frame " << f;
    most_live = std::max(most_live, pipeline.frame().size());
  }
  const MetricsReport r = streamed.finish();
  EXPECT_GT(exact.tracks.size(), most_live / 2);

  // Every stored sample against its stream.
  EXPECT_EQ(r.agent_frames, exact.agent_frames);
  EXPECT_EQ(r.non_finite, 0);
  expect_summary(r.torsion_deg, exact.torsion, "torsion_deg");
  expect_summary(r.facing_error_deg, exact.facing, "facing_error_deg");
  expect_summary(r.facing_error_within_limit_deg, exact.facing_within, "facing within limit");
  expect_summary(r.heading_error_deg, exact.heading, "heading_error_deg");
  expect_summary(r.root_error_cm, exact.root_error, "root_error_cm");
  expect_summary(r.playback_rate, exact.rate, "playback_rate");
  EXPECT_EQ(r.playback_outside_limits,
            static_cast<double>(exact.rate_outside) / static_cast<double>(exact.rate.size()));
  ASSERT_EQ(r.feedback_speed_change.has_value(), exact.feedback_n > 0);
  if (exact.feedback_n > 0) {
    EXPECT_NEAR(*r.feedback_speed_change, exact.feedback_sum / exact.feedback_n, 1e-9);
  }
  EXPECT_EQ(r.pop_count, exact.pops);
  EXPECT_EQ(r.max_root_jerk, exact.max_jerk);

  // METRICS.md v2 against the stored-track reference.
  std::vector<LimbTrack> views;
  for (const StoredTrack& t : exact.tracks) views.push_back(t.view());
  const test::ExactFeet v2 = test::exact_viewer_feet(views, r.feet_reference, kDt);
  ASSERT_GT(v2.support_cm_s.size(), 1000u);
  EXPECT_EQ(r.feet.support_samples, static_cast<int64_t>(v2.support_cm_s.size()));
  EXPECT_NEAR(r.feet.support_slide_cm_s, v2.support_mean(), 1e-9 * v2.support_mean() + 1e-12);
  EXPECT_EQ(r.feet.support_skate_ratio, v2.support_skate_ratio());
  expect_sketched(r.feet.support_slide_p95_cm_s, v2.support_p95(), "support_slide_p95_cm_s");
  EXPECT_EQ(r.feet.float_samples, v2.float_samples);
  EXPECT_EQ(r.feet.float_ratio, v2.float_ratio());
  EXPECT_EQ(r.feet.penetration_samples, static_cast<int64_t>(v2.depth_cm.size()));
  EXPECT_EQ(r.feet.penetration_max_cm, v2.depth_max());
  EXPECT_EQ(r.feet.penetration_ratio, v2.penetration_ratio());
  expect_sketched(r.feet.penetration_p99_cm, v2.depth_p99(), "penetration_cm.p99");
  EXPECT_EQ(r.feet.limb_pops, v2.pops);
  EXPECT_NEAR(r.feet.limb_pop_rate, v2.pop_rate(), 1e-9 * v2.pop_rate() + 1e-12);
  EXPECT_EQ(r.feet.gmd_frames, v2.gmd_frames);
  EXPECT_EQ(r.feet.gmd_skate_ratio, v2.gmd_skate_ratio());

  // METRICS.md v1: equal to its definition with the band decided kLag_s late ...
  const int lag = static_cast<int>(std::lround(FootSlideStream::kLag_s / kDt));
  const V1 late = exact_v1(exact.tracks, lag);
  ASSERT_GT(late.stats.num_samples, 1000);
  EXPECT_EQ(r.slide_samples, late.stats.num_samples);
  EXPECT_NEAR(r.slide.mean_cm_s, late.stats.mean_cm_s, 1e-6 * late.stats.mean_cm_s);
  EXPECT_NEAR(r.slide.skate_ratio, late.stats.skate_ratio, 1e-7);
  EXPECT_NEAR(r.slide.drift_cm_per_step, late.stats.drift_cm_per_step,
              1e-6 * late.stats.drift_cm_per_step);
  expect_sketched(r.slide.p95_cm_s, late.stats.p95_cm_s, "foot_slide_p95_cm_s");
  // ... and between METRICS.md's (the whole track's minima) and that band widened by the excess
  // the report gives (a micrometre more for the rounding of float sums).
  const V1 metrics_md = exact_v1(exact.tracks, -1);
  const V1 widened = exact_v1(exact.tracks, -1, r.slide_toe_band_excess_m + 1e-6f,
                              r.slide_ankle_band_excess_m + 1e-6f);
  EXPECT_GE(r.slide_toe_band_excess_m, 0.0f);
  EXPECT_GE(r.slide_ankle_band_excess_m, 0.0f);
  EXPECT_LE(metrics_md.stats.num_samples, r.slide_samples);
  EXPECT_LE(r.slide_samples, widened.stats.num_samples);
  EXPECT_LE(metrics_md.speed_sum, late.speed_sum * (1 + 1e-12));
  EXPECT_LE(late.speed_sum, widened.speed_sum * (1 + 1e-12));
  EXPECT_LE(metrics_md.skating, late.skating);
  EXPECT_LE(late.skating, widened.skating);
  if (r.slide_toe_band_excess_m == 0.0f && r.slide_ankle_band_excess_m == 0.0f) {
    EXPECT_EQ(r.slide_samples, metrics_md.stats.num_samples);
  }
  std::printf(
      "[ %s ] %zu tracks, %lld agent-frames; foot slide streamed %.5f cm/s (p95 %.5f, skate "
      "%.5f, drift %.5f cm, %lld samples), METRICS.md exact %.5f cm/s (p95 %.5f, skate %.5f, "
      "drift %.5f cm, %d samples); band excess toe %.3f mm, ankle %.3f mm; support slide p95 "
      "%.6f vs %.6f, torsion p95 %.4f vs %.4f\n",
      what, exact.tracks.size(), static_cast<long long>(r.agent_frames), r.slide.mean_cm_s,
      r.slide.p95_cm_s, r.slide.skate_ratio, r.slide.drift_cm_per_step,
      static_cast<long long>(r.slide_samples), metrics_md.stats.mean_cm_s,
      metrics_md.stats.p95_cm_s, metrics_md.stats.skate_ratio, metrics_md.stats.drift_cm_per_step,
      metrics_md.stats.num_samples, 1000.0 * r.slide_toe_band_excess_m,
      1000.0 * r.slide_ankle_band_excess_m, r.feet.support_slide_p95_cm_s, v2.support_p95(),
      r.torsion_deg.p95, nearest_rank(exact.torsion, 0.95));
}

std::unique_ptr<CrowdSource> social(const std::string& name, int agents, uint64_t seed) {
  auto loaded = load_scenario_by_name(name, scenario_dir());
  EXPECT_TRUE(loaded.ok()) << loaded.message();
  const Scenario s = scale_scenario(*loaded, agents);
  auto expanded = expand_agents(s, agents, seed);
  EXPECT_TRUE(expanded.ok()) << expanded.message();
  auto sim = SocialForces::create(s, *expanded, SocialForceParams{});
  EXPECT_TRUE(sim.ok()) << sim.message();
  return std::move(*sim);
}

TEST(MetricsStreaming, PlazaWithCmuClipsEqualsTheExactFigures) {
  GK_REQUIRE_DATA("clips/bvh/cmu_07_01_walk.bvh");
  auto lib =
      test::load_data_library({"clips/bvh/cmu_07_01_walk.bvh", "clips/bvh/cmu_09_11_run.bvh"});
  ASSERT_TRUE(lib.ok()) << lib.message();
  auto crowd = social("plaza", 30, 1);
  compare(*crowd, *lib, 5000, "plaza, 30 agents, CMU walk and run");
}

TEST(MetricsStreaming, BottleneckRoundsEqualTheExactFigures) {
  GK_REQUIRE_DATA("clips/bvh/cmu_07_01_walk.bvh");
  auto lib = test::load_data_library({"clips/bvh/cmu_07_01_walk.bvh"});
  ASSERT_TRUE(lib.ok()) << lib.message();
  // Agents leave at the door; when the room is empty a new round of 40 comes in, ids reused.
  auto rounds = RestartingCrowd::create([](int round) -> Result<std::unique_ptr<CrowdSource>> {
    return social("bottleneck", 40, 1 + static_cast<uint64_t>(round));
  });
  ASSERT_TRUE(rounds.ok()) << rounds.message();
  compare(**rounds, *lib, 6000, "bottleneck rounds, 40 agents, CMU walk");
  EXPECT_GE((*rounds)->rounds(), 2);
}

}  // namespace
}  // namespace gk
