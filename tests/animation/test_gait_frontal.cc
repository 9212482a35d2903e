// The built-in gait seen from the front (../shared/docs/GAIT.md; issue #13 "Looks"): step width,
// feet on their own side of the line of progression, knees over the feet, relaxed arms that hang
// close to the body with the elbows slightly flexed. Every number is measured by playing the
// generated clips through the project's FK; the bounds come from GAIT.md and the skeleton's own
// rest geometry, never from what the generator was told.

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "animation/gait_generator.h"
#include "animation/pose_jobs.h"
#include "animation/procedural.h"

namespace gk {
namespace {

glm::vec3 pos(const glm::mat4& m) { return glm::vec3(m[3]); }

std::vector<glm::mat4> fk(const Skeleton& s, const glm::quat* r, const glm::vec3* t) {
  std::vector<glm::mat4> out(s.num_joints());
  LocalToModelJob job;
  job.skeleton = &s;
  job.rotations = {r, size_t(s.num_joints())};
  job.translations = {t, size_t(s.num_joints())};
  job.out_model = out;
  EXPECT_TRUE(job.validate());
  job.run();
  return out;
}

int child_of(const Skeleton& s, int joint) {
  for (int j = 0; j < s.num_joints(); ++j) {
    if (s.parents[j] == joint) return j;
  }
  return -1;
}

// One loop of a clip in model space, with per-foot contact flags (METRICS.md: toe within 2.5 cm
// and ankle within 5 cm of their lowest heights over the clip).
struct Frames {
  std::vector<std::vector<glm::mat4>> model;
  std::vector<uint8_t> contact[2];
};

Frames play(const Skeleton& s, const Clip& clip) {
  Frames out;
  for (int f = 0; f < clip.num_frames; ++f) {
    out.model.push_back(fk(s, clip.frame_rotations(f), clip.frame_translations(f)));
  }
  for (Side side : {Side::kLeft, Side::kRight}) {
    float min_t = 1e9f, min_a = 1e9f;
    for (const auto& m : out.model) {
      min_t = std::min(min_t, pos(m[s.toe(side)]).y);
      min_a = std::min(min_a, pos(m[s.ankle(side)]).y);
    }
    for (const auto& m : out.model) {
      out.contact[int(side)].push_back(pos(m[s.toe(side)]).y <= min_t + 0.025f &&
                                       pos(m[s.ankle(side)]).y <= min_a + 0.05f);
    }
  }
  return out;
}

class FrontalGait : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { set_ = new ClipSet(make_builtin_clip_set()); }
  static void TearDownTestSuite() { delete set_; }
  const Skeleton& skel() const { return *set_->skeleton; }
  // Forward and backward walks and runs: the clips whose feet step along +-z.
  static bool steps_forward(const Clip& c) {
    return c.name.rfind("walk", 0) == 0 || c.name == "jog" || c.name == "run";
  }
  static bool is_run(const Clip& c) { return c.name == "jog" || c.name == "run"; }
  // The line of progression: the pelvis' mean lateral position over the loop (the clips travel
  // along z, left is +x), so the sway toward each stance leg averages out.
  float progression_x(const Frames& fr) const {
    double sum = 0.0;
    for (const auto& m : fr.model) sum += pos(m[skel().role(JointRole::kHips)]).x;
    return float(sum / fr.model.size());
  }
  // Contact point of a foot: midway between the ankle and the ball (toe joint), on the ground.
  glm::vec3 contact_point(const std::vector<glm::mat4>& m, Side side) const {
    return 0.5f * (pos(m[skel().ankle(side)]) + pos(m[skel().toe(side)]));
  }
  static ClipSet* set_;
};
ClipSet* FrontalGait::set_ = nullptr;

constexpr Side kSides[] = {Side::kLeft, Side::kRight};
float outward(Side side) { return side == Side::kLeft ? 1.0f : -1.0f; }  // left is +x

// GAIT.md / issue #13: the two feet's contact points 5-15 cm apart across the line of progression.
TEST_F(FrontalGait, StepWidthIsFiveToFifteenCentimetres) {
  for (const Clip& c : set_->clips) {
    if (!steps_forward(c)) continue;
    const Frames fr = play(skel(), c);
    double lateral[2] = {0.0, 0.0};
    int count[2] = {0, 0};
    for (size_t f = 0; f < fr.model.size(); ++f) {
      for (Side side : kSides) {
        if (!fr.contact[int(side)][f]) continue;
        lateral[int(side)] += contact_point(fr.model[f], side).x;
        ++count[int(side)];
      }
    }
    ASSERT_GT(count[0], 0) << c.name;
    ASSERT_GT(count[1], 0) << c.name;
    const double width = lateral[0] / count[0] - lateral[1] / count[1];
    EXPECT_GE(width, 0.05) << c.name << ": step width " << width * 100 << " cm";
    EXPECT_LE(width, 0.15) << c.name << ": step width " << width * 100 << " cm";
  }
}

// No scissor gait: neither foot nor knee ever crosses the line of progression, in stance or in
// swing.
TEST_F(FrontalGait, FeetAndKneesStayOnTheirOwnSide) {
  for (const Clip& c : set_->clips) {
    if (!steps_forward(c)) continue;
    const Frames fr = play(skel(), c);
    const float line = progression_x(fr);
    for (size_t f = 0; f < fr.model.size(); ++f) {
      for (Side side : kSides) {
        const auto& m = fr.model[f];
        const float sign = outward(side);
        for (int joint : {skel().ankle(side), skel().toe(side), skel().knee(side)}) {
          EXPECT_GT(sign * (pos(m[joint]).x - line), 0.01f)
              << c.name << " frame " << f << " " << skel().names[joint] << " at or across the line";
        }
      }
    }
  }
}

// Knees over the feet: in stance the knee stands above the foot (within half the foot's width of
// the ankle, estimated from the skeleton) and never inside the hip-ankle line (no valgus).
TEST_F(FrontalGait, KneesStayOverTheFeetInStance) {
  const float half_foot = 0.5f * estimate_foot_shape(skel(), Side::kLeft).width_m;
  for (const Clip& c : set_->clips) {
    if (!steps_forward(c)) continue;
    const Frames fr = play(skel(), c);
    for (size_t f = 0; f < fr.model.size(); ++f) {
      for (Side side : kSides) {
        if (!fr.contact[int(side)][f]) continue;
        const auto& m = fr.model[f];
        const float sign = outward(side);
        const glm::vec3 hip = pos(m[skel().hip(side)]), knee = pos(m[skel().knee(side)]),
                        ankle = pos(m[skel().ankle(side)]);
        EXPECT_LE(std::abs(knee.x - ankle.x), half_foot) << c.name << " frame " << f;
        // Lateral position of the straight hip-ankle line at the knee's height.
        const float u = (hip.y - knee.y) / std::max(hip.y - ankle.y, 1e-3f);
        const float line_x = hip.x + (ankle.x - hip.x) * u;
        EXPECT_GE(sign * (knee.x - line_x), -0.01f)
            << c.name << " frame " << f << ": knee inside the hip-ankle line (valgus)";
      }
    }
  }
}

// Relaxed arms close to the body: seen from the front, the hand hangs no farther out than the
// shoulder joint it hangs from (no splayed arms; in the chest's frame, so that the trunk's own
// sway and roll do not count) and outside the hip joint (beside the body, not in it; in the
// pelvis' frame).
TEST_F(FrontalGait, HandsHangBesideTheBody) {
  const auto rest = fk(skel(), skel().rest_rotations.data(), skel().rest_translations.data());
  const int hips = skel().role(JointRole::kHips), chest = skel().role(JointRole::kChest);
  auto outward_in = [&](const std::vector<glm::mat4>& m, int frame_joint, int joint, float sign) {
    const glm::vec3 local = glm::vec3(glm::inverse(m[frame_joint]) * glm::vec4(pos(m[joint]), 1));
    return sign * local.x;
  };
  for (const Clip& c : set_->clips) {
    const Frames fr = play(skel(), c);
    for (Side side : kSides) {
      const float sign = outward(side);
      const int shoulder =
          skel().role(side == Side::kLeft ? JointRole::kLeftShoulder : JointRole::kRightShoulder);
      const int hand = child_of(skel(), child_of(skel(), shoulder));
      ASSERT_GE(hand, 0);
      // Rest offsets: rest rotations are identity, so a joint's frame is its rest position.
      const float shoulder_out = sign * (pos(rest[shoulder]).x - pos(rest[chest]).x);
      const float hip_out = sign * (pos(rest[skel().hip(side)]).x - pos(rest[hips]).x);
      for (size_t f = 0; f < fr.model.size(); ++f) {
        const auto& m = fr.model[f];
        EXPECT_LE(outward_in(m, chest, hand, sign), shoulder_out + 0.01f)
            << c.name << " frame " << f << ": arm splayed";
        EXPECT_GE(outward_in(m, hips, hand, sign), hip_out)
            << c.name << " frame " << f << ": hand inside the body";
      }
    }
  }
}

// GAIT.md: elbow slightly flexed (20-40 deg) in walking, more at higher speed; about 90 deg in
// running.
TEST_F(FrontalGait, ElbowsFlexLikeGaitFacts) {
  double walk_slow = 0.0, walk_fast = 0.0;
  for (const Clip& c : set_->clips) {
    if (!steps_forward(c)) continue;
    const Frames fr = play(skel(), c);
    double sum = 0.0;
    int n = 0;
    for (Side side : kSides) {
      const int shoulder =
          skel().role(side == Side::kLeft ? JointRole::kLeftShoulder : JointRole::kRightShoulder);
      const int elbow = child_of(skel(), shoulder), wrist = child_of(skel(), elbow);
      for (const auto& m : fr.model) {
        const glm::vec3 upper = pos(m[elbow]) - pos(m[shoulder]);
        const glm::vec3 fore = pos(m[wrist]) - pos(m[elbow]);
        sum += glm::degrees(std::acos(
            std::clamp(glm::dot(glm::normalize(upper), glm::normalize(fore)), -1.0f, 1.0f)));
        ++n;
      }
    }
    const double mean = sum / n;
    if (is_run(c)) {
      EXPECT_GE(mean, 70.0) << c.name;
      EXPECT_LE(mean, 110.0) << c.name;
    } else {
      EXPECT_GE(mean, 20.0) << c.name;
      EXPECT_LE(mean, 40.0) << c.name;
    }
    if (c.name == "walk_slow") walk_slow = mean;
    if (c.name == "walk_fast") walk_fast = mean;
  }
  EXPECT_GT(walk_fast, walk_slow) << "more elbow flexion at higher speed";
}

}  // namespace
}  // namespace gk
