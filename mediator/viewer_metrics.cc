#include "mediator/viewer_metrics.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "animation/pose_jobs.h"
#include "common/stats.h"

namespace gk {
namespace {

int joint_index(const Skeleton& sk, LimbJoint j, Side s) {
  switch (j) {
    case LimbJoint::kToe:
      return sk.toe(s);
    case LimbJoint::kAnkle:
      return sk.ankle(s);
    case LimbJoint::kKnee:
      return sk.knee(s);
  }
  return -1;
}

// One locomotion clip played once with its own root motion (the in-place clip plus its travel)
// at a step of dt_s: world positions of the limb joints and the root.
struct PlayedClip {
  std::vector<glm::vec3> joint[kNumLimbJoints][2];
  std::vector<glm::vec2> root;
  LimbTrack track() const {
    LimbTrack t;
    for (int j = 0; j < kNumLimbJoints; ++j) {
      for (int s = 0; s < 2; ++s) t.joint[j][s] = joint[j][s];
    }
    t.root = root;
    return t;
  }
};

PlayedClip play_with_root_motion(const LocomotionClip& lc, const Skeleton& sk, float dt_s) {
  PlayedClip out;
  const size_t J = sk.num_joints();
  std::vector<glm::quat> rot(J);
  std::vector<glm::vec3> trans(J);
  std::vector<glm::mat4> model(J);
  // The take as captured where there is one; a clip authored in place travels at its speed.
  const bool take = lc.source.num_frames > 1;
  const Clip& clip = take ? lc.source : lc.clip;
  const float duration = clip.duration_s();
  const glm::vec3 travel =
      take ? glm::vec3(0.0f)
           : lc.speed_m_s * glm::vec3(std::sin(lc.direction_rad), 0.0f, std::cos(lc.direction_rad));
  const int hips = sk.role(JointRole::kHips);
  // A loop is played for one period (its end is its start); a take from its first to last frame.
  const int steps = static_cast<int>(std::floor(duration / dt_s + (clip.loops ? -1e-4f : 1e-4f)));
  for (int k = 0; k <= steps; ++k) {
    const float t = k * dt_s;
    SampleClipJob{&clip, t, rot, trans}.run();
    glm::mat4 root(1.0f);
    root[3] = glm::vec4(travel * t, 1.0f);
    LocalToModelJob{&sk, rot, trans, root, model}.run();
    for (int j = 0; j < kNumLimbJoints; ++j) {
      for (int s = 0; s < 2; ++s) {
        out.joint[j][s].push_back(translation_of(
            model[joint_index(sk, static_cast<LimbJoint>(j), static_cast<Side>(s))]));
      }
    }
    const glm::vec3 p = translation_of(model[hips]);
    out.root.emplace_back(p.x, p.z);
  }
  return out;
}

bool locomotion(const LocomotionClip& c) { return c.gait; }

}  // namespace

std::string limb_joint_name(const Skeleton& sk, LimbJoint j, Side s) {
  const int i = joint_index(sk, j, s);
  return i >= 0 ? sk.names[i] : std::string();
}

FeetReference make_feet_reference(const LocomotionLibrary& library, float dt_s) {
  FeetReference ref;
  const Skeleton& sk = *library.skeleton;
  std::vector<float> accel[kNumLimbJoints][2];
  for (const LocomotionClip& lc : library.clips) {
    if (!locomotion(lc)) continue;
    const PlayedClip played = play_with_root_motion(lc, sk, dt_s);
    for (int j = 0; j < kNumLimbJoints; ++j) {
      for (int s = 0; s < 2; ++s) {
        const auto& p = played.joint[j][s];
        for (size_t k = 1; k + 1 < p.size(); ++k) {
          accel[j][s].push_back(glm::length(p[k + 1] - 2.0f * p[k] + p[k - 1]) / (dt_s * dt_s));
        }
      }
    }
  }
  for (int s = 0; s < 2; ++s) {
    ref.toe_floor_m[s] = library.planted_toe_m[s];
    ref.ankle_floor_m[s] = library.planted_ankle_m[s];
    for (int j = 0; j < kNumLimbJoints; ++j) ref.accel_m_s2[j][s] = percentile(accel[j][s], 0.999);
  }
  return ref;
}

// The METRICS.md v2 definitions, one frame at a time. Double precision throughout, so that a
// check recomputed from the joint dump (whose numbers reproduce these floats exactly) breaks ties
// between the feet the same way.
void ViewerFeetAccumulator::add_frame(ViewerTrack& t, const LimbFrame& cur, float dt) {
  const double floor_toe[2] = {ref_.toe_floor_m[0], ref_.toe_floor_m[1]};
  const double floor_ankle[2] = {ref_.ankle_floor_m[0], ref_.ankle_floor_m[1]};
  constexpr int kToe = static_cast<int>(LimbJoint::kToe);
  constexpr int kAnkle = static_cast<int>(LimbJoint::kAnkle);
  auto rel = [&](const LimbFrame& p, int s) {
    return static_cast<double>(p.joint[kToe][s].y) - floor_toe[s];
  };
  auto support = [&](const LimbFrame& p) { return rel(p, 1) < rel(p, 0) ? 1 : 0; };
  auto near = [&](const LimbFrame& p, int s) { return rel(p, s) <= kNearFloorM; };
  auto horizontal = [](const glm::vec3& a, const glm::vec3& b) {
    return std::hypot(static_cast<double>(a.x) - b.x, static_cast<double>(a.z) - b.z);
  };
  const int64_t f = t.frames;
  ++agent_frames_;
  seconds_ += static_cast<double>(dt);
  for (int s = 0; s < 2; ++s) {
    const double depth = std::max(
        {0.0, floor_toe[s] - cur.joint[kToe][s].y, floor_ankle[s] - cur.joint[kAnkle][s].y});
    depth_cm_.add(static_cast<float>(100.0 * depth));
    if (depth > kPenetrationCountM) ++deep_;
  }
  if (f >= 1) {
    const LimbFrame& prev = t.last[1];
    const int sup = support(cur);
    if (sup == support(prev) && near(cur, sup) && near(prev, sup)) {
      const double v = 100.0 * horizontal(cur.joint[kToe][sup], prev.joint[kToe][sup]) / dt;
      support_cm_s_.add(static_cast<float>(v));
      if (v > kSkateCmS) ++support_skates_;
    }
    const double root_speed = std::hypot(static_cast<double>(cur.root.x) - prev.root.x,
                                         static_cast<double>(cur.root.y) - prev.root.y) /
                              dt;
    if (root_speed >= kFloatMinSpeed && root_speed <= kFloatMaxSpeed) {
      ++float_samples_;
      if (!near(cur, 0) && !near(cur, 1)) ++float_frames_;
    }
  }
  if (f >= 2) {
    // The acceleration of the previous frame, now that its successor is known.
    bool pop = false;
    for (int j = 0; j < kNumLimbJoints && !pop; ++j) {
      for (int s = 0; s < 2 && !pop; ++s) {
        const glm::dvec3 d2 = glm::dvec3(cur.joint[j][s]) -
                              2.0 * glm::dvec3(t.last[1].joint[j][s]) +
                              glm::dvec3(t.last[0].joint[j][s]);
        const double a = glm::length(d2) / (static_cast<double>(dt) * dt);
        pop = a > 2.0f * ref_.accel_m_s2[j][s];
      }
    }
    if (pop) ++pops_;
  }
  // The literature's ratio at 20 fps: toes linearly resampled from the run's frames. Sample k lies
  // at frame x = k / 20 / dt; those between the previous frame and this one are due now.
  if (f == 0) {
    for (int s = 0; s < 2; ++s) t.gmd_prev[s] = glm::dvec3(cur.joint[kToe][s]);
  } else {
    const LimbFrame& prev = t.last[1];
    for (;; ++t.next_gmd) {
      const double x = t.next_gmd / static_cast<double>(kGmdRateHz) / dt;
      if (static_cast<int64_t>(x + 1e-9) > f - 1) break;
      const double u = std::clamp(x - static_cast<double>(f - 1), 0.0, 1.0);
      glm::dvec3 toe[2];
      for (int s = 0; s < 2; ++s) {
        const glm::dvec3 a(prev.joint[kToe][s]);
        toe[s] = a + (glm::dvec3(cur.joint[kToe][s]) - a) * u;
      }
      add_gmd_sample(t, toe);
    }
  }
  t.last[0] = t.last[1];
  t.last[1] = cur;
  ++t.frames;
}

void ViewerFeetAccumulator::add_gmd_sample(ViewerTrack& t, const glm::dvec3 toe[2]) {
  const double floor_toe[2] = {ref_.toe_floor_m[0], ref_.toe_floor_m[1]};
  bool skates = false;
  for (int s = 0; s < 2; ++s) {
    const glm::dvec3& cur = toe[s];
    const glm::dvec3& prev = t.gmd_prev[s];
    const bool contact =
        cur.y - floor_toe[s] <= kNearFloorM && prev.y - floor_toe[s] <= kNearFloorM;
    if (contact && std::hypot(cur.x - prev.x, cur.z - prev.z) * kGmdRateHz > kGmdSkateM_S) {
      skates = true;
    }
    t.gmd_prev[s] = cur;
  }
  ++gmd_frames_;
  if (skates) ++gmd_skates_;
}

void ViewerFeetAccumulator::end_track(const ViewerTrack& track, float dt) {
  const int64_t n = track.frames;
  if (n == 0) return;
  // The 20 fps samples over the track's span at or after its last frame hold that frame.
  ViewerTrack t = track;
  const double span_s = static_cast<double>(n - 1) * static_cast<double>(dt);
  const int64_t m = static_cast<int64_t>(std::floor(span_s * kGmdRateHz + 1e-6)) + 1;
  constexpr int kToe = static_cast<int>(LimbJoint::kToe);
  const glm::dvec3 toe[2] = {glm::dvec3(t.last[1].joint[kToe][0]),
                             glm::dvec3(t.last[1].joint[kToe][1])};
  for (; t.next_gmd < m; ++t.next_gmd) add_gmd_sample(t, toe);
}

void ViewerFeetAccumulator::add_track(const LimbTrack& t, float dt) {
  ViewerTrack track;
  for (size_t f = 0; f < t.root.size(); ++f) {
    LimbFrame frame;
    for (int j = 0; j < kNumLimbJoints; ++j) {
      for (int s = 0; s < 2; ++s) frame.joint[j][s] = t.joint[j][s][f];
    }
    frame.root = t.root[f];
    add_frame(track, frame, dt);
  }
  end_track(track, dt);
}

ViewerFeetStats ViewerFeetAccumulator::finish() const {
  ViewerFeetStats r;
  r.agent_frames = agent_frames_;
  const Summary support = support_cm_s_.summary();
  r.support_samples = static_cast<int64_t>(support.count);
  if (support.count > 0) {
    r.support_slide_cm_s = support.mean;
    r.support_slide_p95_cm_s = support_cm_s_.sketch().floor_rank(0.95);
    r.support_skate_ratio = static_cast<double>(support_skates_) / support.count;
  }
  r.float_samples = float_samples_;
  if (float_samples_) r.float_ratio = static_cast<double>(float_frames_) / float_samples_;
  r.penetration_samples = static_cast<int64_t>(depth_cm_.count());
  if (r.penetration_samples > 0) {
    r.penetration_p99_cm = depth_cm_.floor_rank(0.99);
    r.penetration_max_cm = depth_cm_.max();
    r.penetration_ratio = static_cast<double>(deep_) / r.penetration_samples;
  }
  r.limb_pops = pops_;
  if (seconds_ > 0.0) r.limb_pop_rate = pops_ / (seconds_ / 60.0);
  r.gmd_frames = gmd_frames_;
  if (gmd_frames_) r.gmd_skate_ratio = static_cast<double>(gmd_skates_) / gmd_frames_;
  return r;
}

ViewerFeetStats library_feet_floor(const LocomotionLibrary& library, const FeetReference& ref,
                                   float dt_s) {
  ViewerFeetAccumulator acc(ref);
  for (const LocomotionClip& lc : library.clips) {
    if (!locomotion(lc)) continue;
    const PlayedClip played = play_with_root_motion(lc, *library.skeleton, dt_s);
    acc.add_track(played.track(), dt_s);
  }
  return acc.finish();
}

}  // namespace gk
