#include "app/overlays.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>

namespace gk::app {
namespace {

glm::vec3 heading_dir(float yaw) { return {std::sin(yaw), 0.0f, std::cos(yaw)}; }

void arrow(CrowdRenderer* r, glm::vec3 from, glm::vec3 dir, float length, glm::vec3 color) {
  if (length < 1e-3f) return;
  const glm::vec3 tip = from + dir * length;
  const glm::vec3 side = glm::normalize(glm::cross(dir, glm::vec3(0, 1, 0))) * 0.06f;
  r->add_line(from, tip, color);
  r->add_line(tip, tip - dir * 0.12f + side, color);
  r->add_line(tip, tip - dir * 0.12f - side, color);
}

void cross(CrowdRenderer* r, glm::vec3 p, float half, glm::vec3 color) {
  r->add_line(p - glm::vec3(half, 0, half), p + glm::vec3(half, 0, half), color);
  r->add_line(p - glm::vec3(half, 0, -half), p + glm::vec3(half, 0, -half), color);
}

// Shortest signed angle from heading a to heading b [rad].
float angle_to(float a, float b) { return std::remainder(b - a, 6.2831853f); }

// A ray drawn as a cross of a flat and an upright ribbon, so it reads as a thick line from any
// camera pitch (GL core lines are one pixel wide).
void ribbon(CrowdRenderer* r, glm::vec3 from, glm::vec3 dir, float length, float half_width,
            glm::vec3 color) {
  const glm::vec3 tip = from + dir * length;
  const glm::vec3 side = glm::normalize(glm::cross(dir, glm::vec3(0, 1, 0))) * half_width;
  const glm::vec3 up(0.0f, half_width, 0.0f);
  const glm::vec4 c(color, 1.0f);
  r->add_triangle(from - side, tip - side, tip + side, c);
  r->add_triangle(from - side, tip + side, from + side, c);
  r->add_triangle(from - up, tip - up, tip + up, c);
  r->add_triangle(from - up, tip + up, from + up, c);
}

// A filled sector between headings a and a + sweep [rad], radii r0..r1 about centre.
void sector(CrowdRenderer* r, glm::vec3 centre, float a, float sweep, float r0, float r1,
            glm::vec4 color) {
  const int steps = std::max(1, static_cast<int>(std::ceil(std::abs(sweep) / 0.05f)));
  for (int k = 0; k < steps; ++k) {
    const glm::vec3 d0 = heading_dir(a + sweep * k / steps);
    const glm::vec3 d1 = heading_dir(a + sweep * (k + 1) / steps);
    if (r0 <= 0.0f) {
      r->add_triangle(centre, centre + d0 * r1, centre + d1 * r1, color);
    } else {
      r->add_triangle(centre + d0 * r0, centre + d0 * r1, centre + d1 * r1, color);
      r->add_triangle(centre + d0 * r0, centre + d1 * r1, centre + d1 * r0, color);
    }
  }
}

// The torso fan of one agent: what the simulator asks (theta), what the chest and the pelvis do,
// the twist between them, and how far the twist may go.
void torso_fan(CrowdRenderer* r, glm::vec3 ground, float pelvis, float chest, float theta,
               float limit_rad) {
  constexpr float kHeight_m = 1.2f;  // about the lowest ribs: the fan stays clear of the arms
  constexpr float kRadius_m = 0.85f;
  constexpr glm::vec3 kPelvis(0.25f, 0.55f, 1.0f), kChest(1.0f, 0.5f, 0.1f),
      kTheta(1.0f, 0.85f, 0.1f);
  const glm::vec3 c = ground + glm::vec3(0.0f, kHeight_m, 0.0f);
  const float twist = angle_to(pelvis, chest);
  const float asked = angle_to(chest, theta);
  sector(r, c, pelvis, twist, 0.0f, kRadius_m, glm::vec4(kChest, 0.45f));
  // Theta the chest does not (yet, or may not) follow.
  sector(r, c, chest, asked, 0.0f, kRadius_m * 1.15f, glm::vec4(kTheta, 0.22f));
  sector(r, c, pelvis - limit_rad, 2.0f * limit_rad, kRadius_m * 1.22f, kRadius_m * 1.3f,
         glm::vec4(1.0f, 1.0f, 1.0f, 0.8f));
  for (const float end : {pelvis - limit_rad, pelvis + limit_rad}) {
    ribbon(r, c + heading_dir(end) * kRadius_m * 1.12f, heading_dir(end), kRadius_m * 0.28f,
           0.012f, {1.0f, 1.0f, 1.0f});
  }
  ribbon(r, c, heading_dir(pelvis), kRadius_m, 0.02f, kPelvis);
  ribbon(r, c, heading_dir(chest), kRadius_m, 0.02f, kChest);
  ribbon(r, c, heading_dir(theta), kRadius_m * 1.15f, 0.015f, kTheta);
}

// The legs against the path: where the lower body walks (blue), where the simulator moves the
// agent (green), the difference filled red, and the band feedback keeps the velocity in (white).
void legs_fan(CrowdRenderer* r, glm::vec3 ground, float pelvis, float velocity, float band_rad) {
  constexpr float kRadius_m = 0.9f;
  constexpr glm::vec3 kLegs(0.25f, 0.55f, 1.0f), kPath(0.2f, 0.9f, 0.3f);
  const glm::vec3 c = ground + glm::vec3(0.0f, 0.02f, 0.0f);
  sector(r, c, pelvis, angle_to(pelvis, velocity), 0.0f, kRadius_m, {1.0f, 0.2f, 0.15f, 0.5f});
  sector(r, c, pelvis - band_rad, 2.0f * band_rad, kRadius_m * 1.05f, kRadius_m * 1.12f,
         glm::vec4(1.0f, 1.0f, 1.0f, 0.8f));
  ribbon(r, c, heading_dir(pelvis), kRadius_m, 0.025f, kLegs);
  ribbon(r, c, heading_dir(velocity), kRadius_m * 1.15f, 0.02f, kPath);
}

glm::vec3 slide_color(float slide_m_s) {
  const float t = std::clamp(slide_m_s / kSkateSpeed_m_s, 0.0f, 1.0f);
  return glm::mix(glm::vec3(0.2f, 0.95f, 0.3f), glm::vec3(1.0f, 0.15f, 0.1f), t);
}

}  // namespace

bool enable_overlay(const std::string& n, OverlayToggles* t) {
  if (n == "all") {
    *t = {true, true, true, true, true, true, true, true};
    return true;
  }
  bool* flags[] = {&t->velocity, &t->theta, &t->facing, &t->planted,
                   &t->trails,   &t->paths, &t->torso,  &t->legs};
  const char* names[] = {"velocity", "theta", "facing", "planted",
                         "trails",   "paths", "torso",  "legs"};
  for (int k = 0; k < 8; ++k) {
    if (n == names[k]) return *flags[k] = true;
  }
  return false;
}

namespace {

// The frame index of an agent and its plan slot, if it is in the lane's frame with a slot.
std::optional<std::pair<size_t, int>> find_agent(const AgentFrame& frame,
                                                  const AnimationPlans& plans, int64_t agent_id) {
  for (size_t i = 0; i < frame.size(); ++i) {
    if (frame.ids[i] != agent_id) continue;
    const int slot = plans.slot_of_agent[i];
    if (slot < 0) return std::nullopt;
    return std::make_pair(i, slot);
  }
  return std::nullopt;
}

}  // namespace

std::optional<TorsoReadout> torso_readout(const CrowdSession& session, const AnimationLane& lane,
                                          int64_t agent_id) {
  const AgentFrame& frame = session.frame_of(lane);
  const AnimationPlans& plans = lane.plans();
  if (const auto found = find_agent(frame, plans, agent_id)) {
    const auto [i, slot] = *found;
    const glm::vec2 root = plans.root_xz[slot];
    const float pelvis = lane.poses().pelvis_heading(slot);
    TorsoReadout out;
    out.head = glm::vec3(root.x, 2.05f, root.y);
    out.twist_deg = glm::degrees(angle_to(pelvis, lane.poses().upper_heading(slot)));
    out.theta_deg = glm::degrees(angle_to(pelvis, frame.thetas[i]));
    out.limit_deg = lane.params().torsion_limit_deg;
    return out;
  }
  return std::nullopt;
}

std::optional<LegsReadout> legs_readout(const CrowdSession& session, const AnimationLane& lane,
                                        int64_t agent_id) {
  const AgentFrame& frame = session.frame_of(lane);
  const AnimationPlans& plans = lane.plans();
  if (const auto found = find_agent(frame, plans, agent_id)) {
    const auto [i, slot] = *found;
    const glm::vec2 v = frame.velocities[i];
    const float speed = glm::length(v);
    if (speed < lane.params().stop_speed_m_s) return std::nullopt;
    const glm::vec2 root = plans.root_xz[slot];
    LegsReadout out;
    out.head = glm::vec3(root.x, 2.05f, root.y);
    out.speed_m_s = speed;
    const MediatorParams& params = lane.params();
    out.band_deg = params.turn_feedback_deg;
    const LocomotionLibrary& lib = session.library();
    if (lib.forward_group >= 0 && !lib.groups[lib.forward_group].clips.empty()) {
      out.legs_max_m_s = lib.clips[lib.groups[lib.forward_group].clips.back()].speed_m_s *
                         params.max_playback_rate * (1.0f + params.max_stride_warp);
    }
    return out;
  }
  return std::nullopt;
}

OverlayHistory::OverlayHistory(const CrowdSession& session, size_t capacity)
    : capacity_(std::max<size_t>(capacity, 1)) {
  const Skeleton& sk = *session.library().skeleton;
  const LocomotionLibrary& lib = session.library();
  for (int s = 0; s < 2; ++s) {
    toe_joint_[s] = sk.toe(static_cast<Side>(s));
    if (toe_joint_[s] < 0) toe_joint_[s] = sk.ankle(static_cast<Side>(s));
    toe_floor_m_[s] = lib.planted_toe_m[s];
  }
  slot_id_.assign(capacity_, -1);
  count_.assign(capacity_, 0);
  toes_.assign(capacity_ * 2 * kTrailLength, ToeSample{glm::vec3(0.0f), -1.0f});
  path_.assign(capacity_ * kPathLength, glm::vec3(0.0f));
}

void OverlayHistory::record(const CrowdSession& session, const AnimationLane& lane, float dt_s) {
  const AgentFrame& frame = session.frame_of(lane);
  const AnimationPlans& plans = lane.plans();
  // METRICS.md v2: the support foot (the lower toe against its floor) within 5 cm of that floor.
  constexpr float kNearFloor_m = 0.05f;
  double slide_sum = 0.0;
  int samples = 0, skates = 0;
  for (size_t i = 0; i < frame.size(); ++i) {
    const size_t slot = static_cast<size_t>(plans.slot_of_agent[i]);
    if (slot >= capacity_) continue;
    if (slot_id_[slot] != frame.ids[i]) slot_id_[slot] = frame.ids[i], count_[slot] = 0;
    const int k = count_[slot];
    const PoseSynthesizer& poses = lane.poses();
    const int pose_slot = static_cast<int>(slot);
    float rel[2] = {1e9f, 1e9f};
    for (int s = 0; s < 2; ++s) {
      if (toe_joint_[s] >= 0) {
        rel[s] = poses.joint_position(pose_slot, toe_joint_[s]).y - toe_floor_m_[s];
      }
    }
    const int support = rel[1] < rel[0] ? 1 : 0;
    for (int s = 0; s < 2; ++s) {
      if (toe_joint_[s] < 0) continue;
      const glm::vec3 p = poses.joint_position(pose_slot, toe_joint_[s]);
      ToeSample* ring = &toes_[(slot * 2 + s) * kTrailLength];
      ToeSample& cur = ring[k % kTrailLength];
      const ToeSample& prev = ring[(k + kTrailLength - 1) % kTrailLength];
      const bool contact = s == support && rel[s] <= kNearFloor_m;
      float slide = contact ? 0.0f : -1.0f;
      if (contact && k > 0 && prev.slide_m_s >= 0.0f) {
        slide = glm::length(glm::vec2(p.x - prev.position.x, p.z - prev.position.z)) / dt_s;
        slide_sum += slide;
        ++samples;
        if (slide > kSkateSpeed_m_s) ++skates;
      }
      cur = {p, slide};
    }
    if (k % kPathEvery == 0) {
      const glm::vec2 r = plans.root_xz[slot];
      path_[slot * kPathLength + (k / kPathEvery) % kPathLength] = glm::vec3(r.x, 0.02f, r.y);
    }
    ++count_[slot];
  }
  last_slide_m_s_ = samples ? static_cast<float>(slide_sum / samples) : 0.0f;
  last_skate_ratio_ = samples ? static_cast<float>(skates) / samples : 0.0f;
}

void OverlayHistory::draw(const CrowdSession& session, const AnimationLane& lane,
                          const OverlayToggles& t, int64_t selected_id, CrowdRenderer* r) const {
  const AgentFrame& frame = session.frame_of(lane);
  const AnimationPlans& plans = lane.plans();
  const PoseSynthesizer& poses = lane.poses();
  const FootLocks& locks = poses.foot_locks();
  for (size_t i = 0; i < frame.size(); ++i) {
    const size_t slot = static_cast<size_t>(plans.slot_of_agent[i]);
    if (slot >= capacity_) continue;
    const glm::vec2 root = plans.root_xz[slot];
    const glm::vec3 ground(root.x, 0.03f, root.y);
    if (t.velocity) {
      const glm::vec2 v = frame.velocities[i];
      const float speed = glm::length(v);
      if (speed > 1e-3f) {
        arrow(r, ground, glm::vec3(v.x, 0, v.y) / speed, 0.5f * speed, {0.2f, 0.9f, 0.3f});
      }
    }
    if (t.theta) {
      arrow(r, ground + glm::vec3(0, 1.95f, 0), heading_dir(frame.thetas[i]), 0.6f,
            {1.0f, 0.85f, 0.1f});
    }
    if (t.facing) {
      const int s = static_cast<int>(slot);
      arrow(r, ground + glm::vec3(0, 0.95f, 0), heading_dir(poses.pelvis_heading(s)), 0.55f,
            {0.25f, 0.55f, 1.0f});
      arrow(r, ground + glm::vec3(0, 1.45f, 0), heading_dir(poses.upper_heading(s)), 0.55f,
            {1.0f, 0.5f, 0.1f});
    }
    if (t.planted) {
      for (int s = 0; s < 2; ++s) {
        const size_t k = slot * 2 + s;
        if (locks.lock[k].state == FootLockState::kLocked) {
          cross(r, locks.lock[k].target * glm::vec3(1, 0, 1) + glm::vec3(0, 0.01f, 0), 0.12f,
                {1.0f, 1.0f, 1.0f});
        }
      }
    }
    const int n = count_[slot];
    if (t.trails) {
      for (int s = 0; s < 2; ++s) {
        const ToeSample* ring = &toes_[(slot * 2 + s) * kTrailLength];
        const int m = std::min(n, kTrailLength);
        for (int j = n - m + 1; j < n; ++j) {
          const ToeSample& a = ring[(j - 1) % kTrailLength];
          const ToeSample& b = ring[j % kTrailLength];
          if (b.slide_m_s < 0.0f || a.slide_m_s < 0.0f) continue;
          const glm::vec3 pa(a.position.x, 0.015f, a.position.z);
          const glm::vec3 pb(b.position.x, 0.015f, b.position.z);
          const glm::vec3 c = slide_color(b.slide_m_s);
          // A footprint tick at every contact sample, plus the slide itself.
          cross(r, pb, 0.04f, c);
          r->add_line(pa, pb, c);
        }
      }
    }
    if (t.paths) {
      const int m = std::min((n + kPathEvery - 1) / kPathEvery, kPathLength);
      const int last = (n - 1) / kPathEvery;
      for (int j = last - m + 2; j <= last; ++j) {
        r->add_line(path_[slot * kPathLength + (j - 1) % kPathLength],
                    path_[slot * kPathLength + j % kPathLength], {0.45f, 0.35f, 0.9f});
      }
    }
    if (selected_id >= 0 && frame.ids[i] == selected_id) {
      if (t.torso) {
        const int s = static_cast<int>(slot);
        torso_fan(r, ground, poses.pelvis_heading(s), poses.upper_heading(s), frame.thetas[i],
                  glm::radians(lane.params().torsion_limit_deg));
      }
      const glm::vec2 v = frame.velocities[i];
      if (t.legs && glm::length(v) >= lane.params().stop_speed_m_s) {
        legs_fan(r, ground, poses.pelvis_heading(static_cast<int>(slot)), std::atan2(v.x, v.y),
                 glm::radians(lane.params().turn_feedback_deg));
      }
      draw_selection_ring(ground, r);
    }
  }
}

void draw_selection_ring(const glm::vec3& ground, CrowdRenderer* r) {
  constexpr int kSegments = 24;
  for (int k = 0; k < kSegments; ++k) {
    const float a0 = 6.2831853f * k / kSegments, a1 = 6.2831853f * (k + 1) / kSegments;
    r->add_line(ground + 0.5f * glm::vec3(std::cos(a0), 0, std::sin(a0)),
                ground + 0.5f * glm::vec3(std::cos(a1), 0, std::sin(a1)), {1.0f, 0.2f, 0.9f});
  }
}

}  // namespace gk::app
