#include "mediator/metrics.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "animation/foot_metrics.h"
#include "animation/pose_jobs.h"
#include "mediator/springs.h"

namespace gk {
namespace {

constexpr float kDeg = 180.0f / std::numbers::pi_v<float>;
constexpr float kMinHeadingSpeed = 0.2f;  // [m/s] METRICS.md: heading error only above this

}  // namespace

Summary summarize(std::vector<float>& v) {
  Summary s;
  s.count = v.size();
  if (v.empty()) return s;
  double sum = 0.0;
  for (float x : v) sum += x;
  s.mean = sum / v.size();
  const auto [mn, mx] = std::minmax_element(v.begin(), v.end());
  s.min = *mn;
  s.max = *mx;
  const size_t k = static_cast<size_t>(std::ceil(0.95 * v.size())) - 1;
  std::nth_element(v.begin(), v.begin() + k, v.end());
  s.p95 = v[k];
  return s;
}

MetricsRecorder::MetricsRecorder(const LocomotionLibrary& library, float frame_time_s,
                                 size_t capacity, size_t frames_hint)
    : library_(library),
      dt_(frame_time_s),
      frames_hint_(frames_hint),
      feet_reference_(make_feet_reference(library, frame_time_s)),
      feet_floor_(library_feet_floor(library, feet_reference_, frame_time_s)) {
  const size_t n = capacity * frames_hint;
  torsion_.reserve(n);
  facing_.reserve(n);
  facing_within_.reserve(n);
  heading_.reserve(n);
  root_error_.reserve(n);
  rate_.reserve(n);
}

void MetricsRecorder::record(const AgentFrame& frame, const Mediator& m,
                             const PoseSynthesizer& poses) {
  const Skeleton& sk = *library_.skeleton;
  const AnimationPlans& pl = m.plans();
  const MediatorParams& P = m.params();
  const int hips = sk.role(JointRole::kHips);
  const FeedbackBuffers& fb = m.feedback();
  const float pop_threshold = 2.0f * library_.max_rotation_step_rad;
  for (size_t i = 0; i < frame.size(); ++i) {
    const int slot = pl.slot_of_agent[i];
    const std::span<const glm::mat4> w = poses.world(slot);
    Track& t = tracks_[frame.ids[i]];
    if (t.last_frame >= 0 && t.last_frame != frame_ - 1) {
      finished_.push_back(std::move(t));  // the agent vanished and came back: a new track
      t = Track();
    }
    if (t.root.empty()) {
      for (int s = 0; s < 2; ++s) {
        t.toe[s].reserve(frames_hint_);
        t.ankle[s].reserve(frames_hint_);
        t.knee[s].reserve(frames_hint_);
      }
      t.root.reserve(frames_hint_);
    }
    // A track holds consecutive frames only; an agent that vanished and came back starts anew.
    const bool continues = t.last_frame == frame_ - 1;
    for (int s = 0; s < 2; ++s) {
      t.toe[s].push_back(translation_of(w[sk.toe(static_cast<Side>(s))]));
      t.ankle[s].push_back(translation_of(w[sk.ankle(static_cast<Side>(s))]));
      t.knee[s].push_back(translation_of(w[sk.knee(static_cast<Side>(s))]));
    }
    const glm::vec3 pelvis = translation_of(w[hips]);
    const glm::vec2 root(pelvis.x, pelvis.z);
    const glm::vec2 prev_root = continues && !t.root.empty() ? t.root.back() : root;
    t.root.push_back(root);
    t.last_frame = frame_;
    ++agent_frames_;

    torsion_.push_back(std::abs(poses.torsion(slot)) * kDeg);
    if (std::isfinite(frame.thetas[i])) {
      const float err = std::abs(wrap_pi(poses.upper_heading(slot) - frame.thetas[i])) * kDeg;
      facing_.push_back(err);
      const float asked = std::abs(wrap_pi(frame.thetas[i] - poses.pelvis_heading(slot))) * kDeg;
      if (asked <= P.torsion_limit_deg) facing_within_.push_back(err);
    }
    // A simulator's garbage position (sanitised by the mediator) has no distance to measure.
    const glm::vec2 p = frame.positions[i];
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::abs(p.x) < 1e6f && std::abs(p.y) < 1e6f) {
      root_error_.push_back(100.0f * glm::length(root - p));
    }
    if (continues) {
      const glm::vec2 vel = (root - prev_root) / dt_;
      if (glm::length(vel) > kMinHeadingSpeed) {
        const float actual = std::atan2(vel.x, vel.y);
        heading_.push_back(std::abs(wrap_pi(pl.travel_yaw[slot] - actual)) * kDeg);
      }
      if (poses.max_rotation_change(slot) > pop_threshold) ++pops_;
    }
    const float rate = pl.playback_rate[slot];
    rate_.push_back(rate);
    if (rate < P.min_playback_rate - 1e-4f || rate > P.max_playback_rate + 1e-4f) ++rate_outside_;
    if (fb.has_feedback[i]) {
      const glm::vec2 v_sim = m.sim_velocities()[i];
      const float sim_len = glm::length(v_sim);
      if (sim_len > 1e-4f && glm::length(fb.velocities[i] - v_sim) > 1e-6f) {
        feedback_change_.push_back(glm::length(fb.velocities[i] - v_sim) / sim_len);
      }
    }
  }
  ++frame_;
}

MetricsReport MetricsRecorder::finish() const {
  MetricsReport r;
  r.agent_frames = agent_frames_;
  SlideAccumulator slide;
  ViewerFeetAccumulator feet(feet_reference_);
  double max_jerk = 0.0;
  auto add = [&](const Track& t) {
    for (int s = 0; s < 2; ++s) slide.add_track(t.toe[s], t.ankle[s], dt_);
    LimbTrack limbs;
    for (int s = 0; s < 2; ++s) {
      limbs.joint[static_cast<int>(LimbJoint::kToe)][s] = t.toe[s];
      limbs.joint[static_cast<int>(LimbJoint::kAnkle)][s] = t.ankle[s];
      limbs.joint[static_cast<int>(LimbJoint::kKnee)][s] = t.knee[s];
    }
    limbs.root = t.root;
    feet.add_track(limbs, dt_);
    const auto& p = t.root;
    for (size_t k = 3; k < p.size(); ++k) {
      const glm::vec2 j = (p[k] - 3.0f * p[k - 1] + 3.0f * p[k - 2] - p[k - 3]) / (dt_ * dt_ * dt_);
      max_jerk = std::max(max_jerk, static_cast<double>(glm::length(j)));
    }
  };
  for (const auto& [id, t] : tracks_) add(t);
  for (const Track& t : finished_) add(t);
  r.slide = slide.finish();
  r.feet = feet.finish();
  r.feet_floor = feet_floor_;
  r.feet_reference = feet_reference_;
  r.max_root_jerk = max_jerk;
  auto copy_summary = [](std::vector<float> v) { return summarize(v); };
  r.torsion_deg = copy_summary(torsion_);
  r.facing_error_deg = copy_summary(facing_);
  r.facing_error_within_limit_deg = copy_summary(facing_within_);
  r.heading_error_deg = copy_summary(heading_);
  r.root_error_cm = copy_summary(root_error_);
  r.playback_rate = copy_summary(rate_);
  r.playback_outside_limits =
      rate_.empty() ? 0.0 : static_cast<double>(rate_outside_) / rate_.size();
  if (!feedback_change_.empty()) {
    double sum = 0.0;
    for (float x : feedback_change_) sum += x;
    r.feedback_speed_change = sum / feedback_change_.size();
  }
  r.pop_count = pops_;
  return r;
}

}  // namespace gk
