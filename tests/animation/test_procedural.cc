// The built-in default: procedural skeleton and locomotion clips (mannequin: test_mannequin.cc).
// Clips are checked by playing them with their own root motion through the project's FK and
// measuring what
// ../shared/docs/GAIT.md and METRICS.md define (contacts, slide, cadence, joint angles), against
// the generation parameters and the published ranges, never against numbers the generator printed.

#include <algorithm>
#include <cmath>
#include <numeric>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "animation/gait_generator.h"
#include "animation/pose_jobs.h"
#include "animation/procedural.h"

namespace gk {
namespace {

glm::vec3 pos(const glm::mat4& m) { return glm::vec3(m[3]); }
float angle_deg(glm::vec3 a, glm::vec3 b) {
  return glm::degrees(
      std::acos(std::clamp(glm::dot(glm::normalize(a), glm::normalize(b)), -1.f, 1.f)));
}
float horizontal(glm::vec3 d) { return std::hypot(d.x, d.z); }

std::vector<glm::mat4> fk(const Skeleton& s, const glm::quat* r, const glm::vec3* t,
                          glm::mat4 root = glm::mat4(1.0f)) {
  std::vector<glm::mat4> out(s.num_joints());
  LocalToModelJob job;
  job.skeleton = &s;
  job.rotations = {r, size_t(s.num_joints())};
  job.translations = {t, size_t(s.num_joints())};
  job.root_transform = root;
  job.out_model = out;
  EXPECT_TRUE(job.validate());
  job.run();
  return out;
}

// A clip played for `loops` loops with its own root motion; one loop advances the root by the
// generation parameters' speed x direction x duration.
struct Playback {
  const GaitParams* params = nullptr;
  const Clip* clip = nullptr;
  std::vector<std::vector<glm::mat4>> frames;
  std::vector<uint8_t> contact[2];  // METRICS.md definition, minima over the whole playback
};

Playback play(const Skeleton& s, const Clip& clip, const GaitParams& params, int loops = 2) {
  Playback p;
  p.params = &params;
  p.clip = &clip;
  const glm::vec3 dir = params.speed_m_s > 0 ? glm::normalize(params.direction) : glm::vec3(0);
  const glm::vec3 per_loop = dir * params.speed_m_s * clip.duration_s();
  for (int k = 0; k < loops; ++k) {
    const glm::mat4 root = glm::translate(glm::mat4(1.0f), per_loop * float(k));
    for (int f = 0; f < clip.num_frames; ++f) {
      p.frames.push_back(fk(s, clip.frame_rotations(f), clip.frame_translations(f), root));
    }
  }
  for (Side side : {Side::kLeft, Side::kRight}) {
    const int toe = s.toe(side), ankle = s.ankle(side);
    float min_t = 1e9f, min_a = 1e9f;
    for (const auto& m : p.frames) {
      min_t = std::min(min_t, pos(m[toe]).y);
      min_a = std::min(min_a, pos(m[ankle]).y);
    }
    for (const auto& m : p.frames) {
      p.contact[int(side)].push_back(pos(m[toe]).y <= min_t + 0.025f &&
                                     pos(m[ankle]).y <= min_a + 0.05f);
    }
  }
  return p;
}

class BuiltinClips : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    set_ = new ClipSet(make_builtin_clip_set());
    params_ = new std::vector<GaitParams>(builtin_gait_params());
  }
  static void TearDownTestSuite() {
    delete set_;
    delete params_;
  }
  const Skeleton& skel() const { return *set_->skeleton; }
  const GaitParams& params_of(const Clip& c) const {
    for (const GaitParams& p : *params_) {
      if (p.name == c.name) return p;
    }
    ADD_FAILURE() << "no parameters for clip " << c.name;
    return params_->front();
  }
  const Clip& clip(const std::string& name) const {
    for (const Clip& c : set_->clips) {
      if (c.name == name) return c;
    }
    ADD_FAILURE() << "missing clip " << name;
    return set_->clips.front();
  }
  static bool is_walk(const Clip& c) {
    return c.name.rfind("walk", 0) == 0 && c.name != "walk_backward";
  }
  static bool is_run(const Clip& c) { return c.name == "jog" || c.name == "run"; }
  static ClipSet* set_;
  static std::vector<GaitParams>* params_;
};
ClipSet* BuiltinClips::set_ = nullptr;
std::vector<GaitParams>* BuiltinClips::params_ = nullptr;

TEST(ProceduralSkeleton, RolesFilledByBuilderAgreeWithDetection) {
  const auto skel = make_humanoid_skeleton();
  EXPECT_TRUE(validate_skeleton(*skel, "builtin").ok());
  EXPECT_TRUE(skel->has_locomotion_roles());
  EXPECT_GE(skel->num_joints(), 22);
  EXPECT_LE(skel->num_joints(), 32);
  Skeleton detected = *skel;
  detected.roles.fill(-1);
  detected.spine_chain.clear();
  detect_joint_roles(&detected);
  for (int r = 0; r < kNumJointRoles; ++r) {
    EXPECT_EQ(detected.roles[r], skel->roles[r]) << joint_role_name(JointRole(r));
  }
  EXPECT_EQ(detected.spine_chain, skel->spine_chain);
  EXPECT_EQ(skel->parents[skel->role(JointRole::kHips)], -1) << "Hips must be the root";
}

TEST(ProceduralSkeleton, AnthropometricProportions) {
  // Drillis and Contini: hip joint 0.53 h, knee 0.285 h, ankle 0.039 h, foot length 0.152 h.
  for (float h : {1.5f, 1.75f, 1.9f}) {
    const auto skel = make_humanoid_skeleton({h});
    const auto m = fk(*skel, skel->rest_rotations.data(), skel->rest_translations.data());
    for (Side side : {Side::kLeft, Side::kRight}) {
      EXPECT_NEAR(pos(m[skel->hip(side)]).y, 0.53f * h, 0.02f * h);
      EXPECT_NEAR(pos(m[skel->knee(side)]).y, 0.285f * h, 0.01f * h);
      EXPECT_NEAR(pos(m[skel->ankle(side)]).y, 0.039f * h, 0.005f * h);
      const glm::vec3 toe = pos(m[skel->toe(side)]), ankle = pos(m[skel->ankle(side)]);
      EXPECT_GT(toe.z - ankle.z, 0.06f * h) << "ball of the foot ahead of the ankle (+z)";
      EXPECT_GT(toe.y, 0.0f);
      EXPECT_LT(toe.y, ankle.y);
    }
    EXPECT_GT(pos(m[skel->hip(Side::kLeft)]).x, 0.0f) << "left side at +x";
    EXPECT_NEAR(pos(m[skel->role(JointRole::kHead)]).y, 0.89f * h, 0.04f * h);
  }
}

TEST_F(BuiltinClips, NamesFormatAndMetadata) {
  std::vector<std::string> names;
  for (const Clip& c : set_->clips) names.push_back(c.name);
  EXPECT_EQ(names, (std::vector<std::string>{"idle", "walk_slow", "walk", "walk_fast", "jog", "run",
                                             "strafe_left", "strafe_right", "walk_backward"}));
  EXPECT_EQ(set_->scale_m_per_unit, 1.0f);
  EXPECT_EQ(set_->scale_reason, "builtin (metres)");
  ASSERT_TRUE(set_->mesh);
  for (const Clip& c : set_->clips) {
    EXPECT_TRUE(validate_clip(c, skel()).ok()) << c.name;
    EXPECT_EQ(c.fps, 60.0f);
    EXPECT_TRUE(c.loops);
    EXPECT_EQ(c.source, "builtin");
    // An integer number of strides: the clip spans whole strides at the parameters' cadence.
    const GaitParams& p = params_of(c);
    if (p.kind == GaitKind::kIdle) continue;
    const float stride_frames = 60.0f * 120.0f / p.cadence_steps_min;
    EXPECT_NEAR(float(c.num_frames) / p.num_strides, stride_frames, 0.5f) << c.name;
  }
}

TEST_F(BuiltinClips, LoopSeamIsAsSmoothAsTheInterior) {
  for (const Clip& c : set_->clips) {
    const int n = c.num_frames, nj = c.num_joints;
    float max_step = 0.0f, seam = 0.0f, last_vs_first = 0.0f;
    for (int f = 0; f < n; ++f) {
      const int g = (f + 1) % n;
      for (int j = 0; j < nj; ++j) {
        const float d = glm::degrees(
            glm::angle(glm::inverse(c.frame_rotations(f)[j]) * c.frame_rotations(g)[j]));
        const float d_wrapped = std::min(d, 360.0f - d);
        if (g == 0)
          seam = std::max(seam, d_wrapped);
        else
          max_step = std::max(max_step, d_wrapped);
      }
    }
    last_vs_first = seam;
    EXPECT_LE(seam, 1.5f * max_step + 0.1f) << c.name;
    EXPECT_GT(last_vs_first, 1e-3f) << c.name << ": last frame duplicates the first";
    // Root across the seam: frame 0 of the next loop is one loop's displacement ahead.
    const GaitParams& p = params_of(c);
    const glm::vec3 dir = p.speed_m_s > 0 ? glm::normalize(p.direction) : glm::vec3(0);
    const glm::vec3 next0 = c.frame_translations(0)[0] + dir * p.speed_m_s * c.duration_s();
    const glm::vec3 step = next0 - c.frame_translations(n - 1)[0];
    EXPECT_NEAR(horizontal(step), p.speed_m_s / c.fps, 0.002f) << c.name;
  }
}

TEST_F(BuiltinClips, RootSpeedAndDirectionMatchParameters) {
  for (const Clip& c : set_->clips) {
    const GaitParams& p = params_of(c);
    const glm::vec3 d = c.frame_translations(c.num_frames - 1)[0] - c.frame_translations(0)[0];
    const float span_s = (c.num_frames - 1) / c.fps;
    if (p.speed_m_s == 0.0f) {
      EXPECT_LT(horizontal(d), 0.01f) << c.name;
      continue;
    }
    const float speed = horizontal(d) / span_s;
    EXPECT_NEAR(speed, p.speed_m_s, 0.01f * p.speed_m_s) << c.name;
    EXPECT_LT(angle_deg(glm::vec3(d.x, 0, d.z), p.direction), 2.0f) << c.name;
  }
  EXPECT_GT(params_of(clip("strafe_left")).direction.x, 0.5f) << "left is +x";
  EXPECT_LT(params_of(clip("walk_backward")).direction.z, -0.5f);
}

TEST_F(BuiltinClips, FeetDoNotSlideAndTouchTheGround) {
  const auto rest = fk(skel(), skel().rest_rotations.data(), skel().rest_translations.data());
  for (const Clip& c : set_->clips) {
    const Playback pb = play(skel(), c, params_of(c));
    double sum = 0.0;
    int samples = 0;
    for (Side side : {Side::kLeft, Side::kRight}) {
      const int toe = skel().toe(side), ankle = skel().ankle(side);
      for (size_t f = 1; f < pb.frames.size(); ++f) {
        if (!pb.contact[int(side)][f] || !pb.contact[int(side)][f - 1]) continue;
        sum += horizontal(pos(pb.frames[f][toe]) - pos(pb.frames[f - 1][toe])) * c.fps;
        ++samples;
      }
      float min_toe = 1e9f, min_ankle = 1e9f;
      for (const auto& m : pb.frames) {
        min_toe = std::min(min_toe, pos(m[toe]).y);
        min_ankle = std::min(min_ankle, pos(m[ankle]).y);
      }
      // Planted feet stand on y = 0: the ball and ankle reach exactly their rest heights above
      // the sole (the rest pose stands on the ground), no floating, no sinking.
      EXPECT_NEAR(min_toe, pos(rest[toe]).y, 0.003f) << c.name;
      EXPECT_NEAR(min_ankle, pos(rest[ankle]).y, 0.003f) << c.name;
    }
    ASSERT_GT(samples, 10) << c.name;
    EXPECT_LT(sum / samples * 100.0, 1.0) << c.name << ": mean slide speed [cm/s]";
  }
}

// Contact onsets (frame, side) over the playback, in time order.
std::vector<std::pair<int, int>> onsets(const Playback& pb) {
  std::vector<std::pair<int, int>> out;
  for (int side = 0; side < 2; ++side) {
    for (size_t f = 1; f < pb.frames.size(); ++f) {
      if (pb.contact[side][f] && !pb.contact[side][f - 1]) out.push_back({int(f), side});
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

TEST_F(BuiltinClips, ContactsAlternateWithDoubleSupportOrFlight) {
  for (const Clip& c : set_->clips) {
    if (c.name == "idle") continue;
    const Playback pb = play(skel(), c, params_of(c), 3);
    const auto on = onsets(pb);
    ASSERT_GE(on.size(), 4u) << c.name;
    for (size_t i = 1; i < on.size(); ++i) EXPECT_NE(on[i].second, on[i - 1].second) << c.name;
    int both = 0, none = 0;
    for (size_t f = 0; f < pb.frames.size(); ++f) {
      both += pb.contact[0][f] && pb.contact[1][f];
      none += !pb.contact[0][f] && !pb.contact[1][f];
    }
    if (is_run(c)) {
      EXPECT_GT(none, 0) << c.name << ": running needs a flight phase";
      EXPECT_EQ(both, 0) << c.name << ": running has no double support";
    } else {
      EXPECT_GT(both, 0) << c.name << ": walking needs double support";
      EXPECT_EQ(none, 0) << c.name << ": walking never leaves the ground";
    }
  }
}

float measured_cadence(const Playback& pb) {
  const auto on = onsets(pb);
  const float span_frames = float(on.back().first - on.front().first);
  return (on.size() - 1) / span_frames * pb.clip->fps * 60.0f;
}

TEST_F(BuiltinClips, CadenceAndStepLengthFollowGaitFacts) {
  for (const Clip& c : set_->clips) {
    if (c.name == "idle") continue;
    const GaitParams& p = params_of(c);
    const float cadence = measured_cadence(play(skel(), c, p, 3));
    const float step = 60.0f * p.speed_m_s / cadence;
    // Walk ratio (GAIT.md): cadence = sqrt(60 v / 0.006) at and above 1 m/s.
    const float ratio_cadence = std::sqrt(60.0f * p.speed_m_s / 0.006f);
    if (is_walk(c) && p.speed_m_s >= 1.0f) {
      EXPECT_NEAR(cadence, ratio_cadence, 0.03f * ratio_cadence) << c.name;
    }
    if (is_walk(c) && p.speed_m_s < 1.0f) {
      EXPECT_GT(cadence, ratio_cadence) << c.name << ": steps shorter than the ratio predicts";
      EXPECT_LT(step / cadence, 0.006f) << c.name;
    }
    if (c.name == "walk") {
      EXPECT_GE(cadence, 100.0f);
      EXPECT_LE(cadence, 120.0f);
      EXPECT_GE(step, 0.6f);
      EXPECT_LE(step, 0.75f);
    }
    if (is_run(c)) {
      EXPECT_GE(cadence, 160.0f) << c.name;
      EXPECT_LE(cadence, 180.0f) << c.name;
    }
    if (c.name == "walk_backward") {
      EXPECT_GT(cadence, ratio_cadence) << "backward: higher cadence than forward at this speed";
    }
  }
}

float knee_flexion(const Skeleton& s, const std::vector<glm::mat4>& m, Side side) {
  const glm::vec3 hip = pos(m[s.hip(side)]), knee = pos(m[s.knee(side)]),
                  ankle = pos(m[s.ankle(side)]);
  return angle_deg(knee - hip, ankle - knee);
}

TEST_F(BuiltinClips, KneeFlexionInGaitRanges) {
  for (const Clip& c : set_->clips) {
    if (!is_walk(c) && !is_run(c)) continue;
    const Playback pb = play(skel(), c, params_of(c), 1);
    float swing_peak = 0.0f, stance_peak = 0.0f;
    for (size_t f = 0; f < pb.frames.size(); ++f) {
      for (Side side : {Side::kLeft, Side::kRight}) {
        const float k = knee_flexion(skel(), pb.frames[f], side);
        (pb.contact[int(side)][f] ? stance_peak : swing_peak) =
            std::max(pb.contact[int(side)][f] ? stance_peak : swing_peak, k);
      }
    }
    if (is_walk(c)) {  // GAIT.md: 60-70 deg in mid-swing (5 deg tolerance)
      EXPECT_GE(swing_peak, 55.0f) << c.name;
      EXPECT_LE(swing_peak, 75.0f) << c.name;
    } else {  // about 40 deg in stance, 90 or more in swing
      EXPECT_GE(swing_peak, 90.0f) << c.name;
      EXPECT_GE(stance_peak, 30.0f) << c.name;
      EXPECT_LE(stance_peak, 55.0f) << c.name;
    }
  }
}

TEST_F(BuiltinClips, PelvisAndTrunkMotion) {
  const Clip& walk = clip("walk");
  const Playback pb = play(skel(), walk, params_of(walk), 1);
  const int hips = skel().role(JointRole::kHips), chest = skel().role(JointRole::kChest);
  std::vector<float> y, yaw_pelvis, yaw_chest;
  float lat_lo = 1e9f, lat_hi = -1e9f;
  for (const auto& m : pb.frames) {
    y.push_back(pos(m[hips]).y);
    lat_lo = std::min(lat_lo, pos(m[hips]).x);
    lat_hi = std::max(lat_hi, pos(m[hips]).x);
    yaw_pelvis.push_back(glm::degrees(heading_of(horizontal_forward(m[hips]))));
    yaw_chest.push_back(glm::degrees(heading_of(horizontal_forward(m[chest]))));
  }
  const auto [lo, hi] = std::minmax_element(y.begin(), y.end());
  EXPECT_GE(*hi - *lo, 0.035f) << "vertical excursion 4-5 cm";
  EXPECT_LE(*hi - *lo, 0.055f);
  EXPECT_GE(lat_hi - lat_lo, 0.02f) << "lateral shift about 4 cm";
  EXPECT_LE(lat_hi - lat_lo, 0.06f);
  // Two highs per stride: count cyclic local maxima that stand 1 cm above the lowest point.
  int highs = 0;
  const int n = int(y.size());
  for (int i = 0; i < n; ++i) {
    if (y[i] > y[(i + n - 1) % n] && y[i] >= y[(i + 1) % n] && y[i] > *lo + 0.01f) ++highs;
  }
  EXPECT_EQ(highs, 2);
  const auto [ylo, yhi] = std::minmax_element(yaw_pelvis.begin(), yaw_pelvis.end());
  EXPECT_GE(*yhi - *ylo, 6.0f) << "pelvis rotation about +-4-5 deg";
  EXPECT_LE(*yhi - *ylo, 12.0f);
  // Thorax counter-rotates: pelvis and chest headings are anti-correlated.
  double cov = 0.0;
  for (int i = 0; i < n; ++i) cov += yaw_pelvis[i] * yaw_chest[i];
  EXPECT_LT(cov, 0.0);
  // Running leans the trunk forward more than walking.
  auto lean = [&](const Clip& c) {
    const Playback p = play(skel(), c, params_of(c), 1);
    double sum = 0.0;
    for (const auto& m : p.frames) {
      const glm::vec3 up = pos(m[skel().role(JointRole::kNeck)]) - pos(m[hips]);
      sum += glm::degrees(std::atan2(up.z, up.y));
    }
    return sum / p.frames.size();
  };
  EXPECT_GT(lean(clip("run")), lean(walk) + 3.0);
}

TEST_F(BuiltinClips, ArmsSwingOppositeToTheSameSideLeg) {
  for (const Clip& c : set_->clips) {
    if (!is_walk(c) && !is_run(c)) continue;
    const Playback pb = play(skel(), c, params_of(c), 1);
    for (Side side : {Side::kLeft, Side::kRight}) {
      const int shoulder =
          skel().role(side == Side::kLeft ? JointRole::kLeftShoulder : JointRole::kRightShoulder);
      int elbow = -1;
      for (int j = 0; j < skel().num_joints() && elbow < 0; ++j) {
        if (skel().parents[j] == shoulder) elbow = j;
      }
      ASSERT_GE(elbow, 0);
      // Shoulder flexion against hip flexion: upper arm and thigh forward of their joints.
      std::vector<double> arm, leg;
      for (const auto& m : pb.frames) {
        arm.push_back(pos(m[elbow]).z - pos(m[shoulder]).z);
        leg.push_back(pos(m[skel().knee(side)]).z - pos(m[skel().hip(side)]).z);
      }
      const double ma = std::accumulate(arm.begin(), arm.end(), 0.0) / arm.size();
      const double ml = std::accumulate(leg.begin(), leg.end(), 0.0) / leg.size();
      double sab = 0, saa = 0, sbb = 0;
      for (size_t i = 0; i < arm.size(); ++i) {
        sab += (arm[i] - ma) * (leg[i] - ml);
        saa += (arm[i] - ma) * (arm[i] - ma);
        sbb += (leg[i] - ml) * (leg[i] - ml);
      }
      EXPECT_LT(sab / std::sqrt(saa * sbb), -0.7) << c.name;
    }
  }
}

// Foot pitch at contact onset: toe height above the ankle compared with the rest pose.
TEST_F(BuiltinClips, HeelFirstForwardToeFirstBackwardFlatSideways) {
  const auto rest = fk(skel(), skel().rest_rotations.data(), skel().rest_translations.data());
  const int toe = skel().toe(Side::kLeft), ankle = skel().ankle(Side::kLeft);
  const float rest_drop = pos(rest[toe]).y - pos(rest[ankle]).y;
  auto pitch_at_onset = [&](const Clip& c) {
    const Playback pb = play(skel(), c, params_of(c), 2);
    for (const auto& [f, side] : onsets(pb)) {
      if (side != 0) continue;
      // A few frames before the contact band is entered: the foot is arriving.
      const auto& m = pb.frames[std::max(f - 2, 0)];
      return (pos(m[toe]).y - pos(m[ankle]).y) - rest_drop;
    }
    return 0.0f;
  };
  EXPECT_GT(pitch_at_onset(clip("walk")), 0.01f) << "heel strike: toes up";
  EXPECT_LT(pitch_at_onset(clip("walk_backward")), -0.01f) << "toe contact first";
  EXPECT_NEAR(pitch_at_onset(clip("strafe_left")), 0.0f, 0.005f) << "no heel-toe roll";
}

TEST_F(BuiltinClips, NoJointFlipsBetweenFrames) {
  // A knee or hip flexes at most ~1,000 deg/s in running; at 60 fps that is under 0.3 rad per frame.
  // 0.6 rad leaves room for the toe's push-off yet catches any IK frame flip (~pi).
  for (const Clip& c : set_->clips) {
    for (int f = 0; f < c.num_frames; ++f) {
      const int g = (f + 1) % c.num_frames;
      for (int j = 1; j < c.num_joints; ++j) {
        const float d = std::abs(glm::dot(c.frame_rotations(f)[j], c.frame_rotations(g)[j]));
        EXPECT_LT(2.0f * std::acos(std::min(1.0f, d)), 0.6f)
            << c.name << " joint " << skel().names[j] << " frame " << f;
      }
    }
  }
}

}  // namespace
}  // namespace gk
