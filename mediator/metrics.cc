#include "mediator/metrics.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numbers>

#include "animation/pose_jobs.h"
#include "mediator/springs.h"

namespace gk {
namespace {

constexpr float kDeg = 180.0f / std::numbers::pi_v<float>;
constexpr float kMinHeadingSpeed = 0.2f;  // [m/s] METRICS.md: heading error only above this

int non_finite(const glm::vec3& p) {
  return !std::isfinite(p.x) + !std::isfinite(p.y) + !std::isfinite(p.z);
}

}  // namespace

MetricsRecorder::MetricsRecorder(const LocomotionLibrary& library, float frame_time_s,
                                 size_t capacity)
    : library_(library),
      dt_(frame_time_s),
      capacity_(capacity),
      feet_reference_(make_feet_reference(library, frame_time_s)),
      feet_floor_(library_feet_floor(library, feet_reference_, frame_time_s)),
      tracks_(capacity),
      feet_tracks_(capacity),
      slide_(2 * capacity, frame_time_s),
      feet_(feet_reference_) {}

size_t MetricsRecorder::num_live_tracks() const {
  return static_cast<size_t>(std::count_if(tracks_.begin(), tracks_.end(),
                                           [](const Track& t) { return t.last_frame >= 0; }));
}

void MetricsRecorder::end_track(size_t slot) {
  Track& t = tracks_[slot];
  if (t.last_frame < 0) return;
  for (size_t s = 0; s < 2; ++s) slide_.end(2 * slot + s);
  feet_.end_track(feet_tracks_[slot], dt_);
  t = Track();
}

void MetricsRecorder::record(const AgentFrame& frame, const Mediator& m,
                             const PoseSynthesizer& poses, std::span<const uint8_t> include) {
  const Skeleton& sk = *library_.skeleton;
  const AnimationPlans& pl = m.plans();
  const MediatorParams& P = m.params();
  const int hips = sk.role(JointRole::kHips);
  const FeedbackBuffers& fb = m.feedback();
  const float pop_threshold = 2.0f * library_.max_rotation_step_rad;
  constexpr int kToe = static_cast<int>(LimbJoint::kToe);
  constexpr int kAnkle = static_cast<int>(LimbJoint::kAnkle);
  constexpr int kKnee = static_cast<int>(LimbJoint::kKnee);
  for (size_t i = 0; i < frame.size(); ++i) {
    const int slot_i = pl.slot_of_agent[i];
    assert(slot_i >= 0 && static_cast<size_t>(slot_i) < capacity_);
    if (slot_i < 0 || static_cast<size_t>(slot_i) >= capacity_) continue;
    const size_t slot = static_cast<size_t>(slot_i);
    if (!include.empty() && !include[slot]) continue;  // its track ends below
    Track& t = tracks_[slot];
    // A track holds consecutive frames of one agent; one that vanished and came back starts anew
    // (and a slot the mediator gave to a newcomer ends its former agent's track).
    const bool continues = t.last_frame >= 0 && t.last_frame == frame_ - 1 && t.id == frame.ids[i];
    if (!continues) {
      end_track(slot);
      t.id = frame.ids[i];
      for (size_t s = 0; s < 2; ++s) slide_.start(2 * slot + s);
      feet_tracks_[slot] = ViewerTrack();
    }
    LimbFrame limbs;
    for (int s = 0; s < 2; ++s) {
      limbs.joint[kToe][s] = poses.joint_position(slot_i, sk.toe(static_cast<Side>(s)));
      limbs.joint[kAnkle][s] = poses.joint_position(slot_i, sk.ankle(static_cast<Side>(s)));
      limbs.joint[kKnee][s] = poses.joint_position(slot_i, sk.knee(static_cast<Side>(s)));
      for (int j = 0; j < kNumLimbJoints; ++j) non_finite_ += non_finite(limbs.joint[j][s]);
      slide_.add(2 * slot + s, limbs.joint[kToe][s], limbs.joint[kAnkle][s].y);
    }
    const glm::vec3 pelvis = poses.joint_position(slot_i, hips);
    non_finite_ += non_finite(pelvis);
    const glm::vec2 root(pelvis.x, pelvis.z);
    limbs.root = root;
    feet_.add_frame(feet_tracks_[slot], limbs, dt_);
    if (t.frames >= 3) {
      const glm::vec2* p = t.roots;
      const glm::vec2 j = (root - 3.0f * p[2] + 3.0f * p[1] - p[0]) / (dt_ * dt_ * dt_);
      max_jerk_ = std::max(max_jerk_, static_cast<double>(glm::length(j)));
    }
    const glm::vec2 prev_root = continues ? t.roots[2] : root;
    t.roots[0] = t.roots[1];
    t.roots[1] = t.roots[2];
    t.roots[2] = root;
    ++t.frames;
    t.last_frame = frame_;
    ++agent_frames_;

    torsion_.add(std::abs(poses.torsion(slot_i)) * kDeg);
    if (std::isfinite(frame.thetas[i])) {
      const float err = std::abs(wrap_pi(poses.upper_heading(slot_i) - frame.thetas[i])) * kDeg;
      facing_.add(err);
      const float asked = std::abs(wrap_pi(frame.thetas[i] - poses.pelvis_heading(slot_i))) * kDeg;
      if (asked <= P.torsion_limit_deg) facing_within_.add(err);
    }
    // A simulator's garbage position (sanitised by the mediator) has no distance to measure.
    const glm::vec2 p = frame.positions[i];
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::abs(p.x) < 1e6f && std::abs(p.y) < 1e6f) {
      root_error_.add(100.0f * glm::length(root - p));
    }
    if (continues) {
      const glm::vec2 vel = (root - prev_root) / dt_;
      if (glm::length(vel) > kMinHeadingSpeed) {
        const float actual = std::atan2(vel.x, vel.y);
        heading_.add(std::abs(wrap_pi(pl.travel_yaw[slot_i] - actual)) * kDeg);
      }
      if (poses.max_rotation_change(slot_i) > pop_threshold) ++pops_;
    }
    const float rate = pl.playback_rate[slot_i];
    rate_.add(rate);
    if (rate < P.min_playback_rate - 1e-4f || rate > P.max_playback_rate + 1e-4f) ++rate_outside_;
    if (fb.has_feedback[i]) {
      const glm::vec2 v_sim = m.sim_velocities()[i];
      const float sim_len = glm::length(v_sim);
      if (sim_len > 1e-4f && glm::length(fb.velocities[i] - v_sim) > 1e-6f) {
        feedback_change_sum_ += glm::length(fb.velocities[i] - v_sim) / sim_len;
        ++feedback_changes_;
      }
    }
  }
  // Agents of the previous frame missing from this one have left: their tracks end here, so
  // that memory follows the live agents, not every agent ever seen.
  for (size_t slot = 0; slot < capacity_; ++slot) {
    if (tracks_[slot].last_frame >= 0 && tracks_[slot].last_frame != frame_) end_track(slot);
  }
  ++frame_;
}

MetricsReport MetricsRecorder::finish() const {
  MetricsReport r;
  r.agent_frames = agent_frames_;
  const FootSlideResult slide = slide_.finish();
  r.slide = slide.stats;
  r.slide_samples = slide.samples;
  r.slide_toe_band_excess_m = slide.toe_band_excess_m;
  r.slide_ankle_band_excess_m = slide.ankle_band_excess_m;
  ViewerFeetAccumulator feet = feet_;
  for (size_t slot = 0; slot < capacity_; ++slot) {
    if (tracks_[slot].last_frame >= 0) feet.end_track(feet_tracks_[slot], dt_);
  }
  r.feet = feet.finish();
  r.feet_floor = feet_floor_;
  r.feet_reference = feet_reference_;
  r.max_root_jerk = max_jerk_;
  r.torsion_deg = torsion_.summary();
  r.facing_error_deg = facing_.summary();
  r.facing_error_within_limit_deg = facing_within_.summary();
  r.heading_error_deg = heading_.summary();
  r.root_error_cm = root_error_.summary();
  r.playback_rate = rate_.summary();
  r.playback_outside_limits =
      r.playback_rate.count ? static_cast<double>(rate_outside_) / r.playback_rate.count : 0.0;
  if (feedback_changes_ > 0) {
    r.feedback_speed_change = feedback_change_sum_ / static_cast<double>(feedback_changes_);
  }
  r.pop_count = pops_;
  r.non_finite = non_finite_;
  for (const StreamSummary* s :
       {&torsion_, &facing_, &facing_within_, &heading_, &root_error_, &rate_}) {
    r.non_finite += static_cast<int64_t>(s->sketch().num_nan());
  }
  return r;
}

}  // namespace gk
