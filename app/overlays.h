#pragma once
// Teaching overlays drawn with CrowdRenderer::add_line: what the simulator asks (velocity v,
// torso orientation theta), what the body does (lower/upper body facing), planted feet (the pose
// synthesizer's foot locks), foot trails coloured by slide speed, and the agents' recent paths.
// Histories are ring buffers per mediator slot sized at creation: recording allocates nothing.

#include <cstdint>
#include <optional>
#include <vector>

#include <string>

#include <glm/vec3.hpp>

#include "app/crowd_session.h"
#include "render/crowd_renderer.h"

namespace gk::app {

struct OverlayToggles {
  bool velocity = false;  // v from the simulator (green, on the ground, 0.5 s of travel)
  bool theta = false;     // desired torso orientation (yellow, above the head)
  bool facing = false;    // lower body = pelvis (blue, hip height), upper body = chest (orange)
  bool planted = false;   // locked feet: crosses at the lock targets (white)
  bool trails = false;  // support-foot toe within 5 cm of its floor (METRICS.md v2), green (still)
                        // .. red (>= 30 cm/s)
  bool paths = false;   // root path of the last 4 s (violet)
  // The selected agent's torso fan: pelvis (blue), chest (orange) and theta (yellow) directions,
  // the twist filled between pelvis and chest, and the torsion limit as a white arc.
  bool torso = false;
  // The selected agent's legs against its path: the lower body's heading (blue) and the
  // simulator's velocity (green) on the ground, the angle between them filled (red), and the band
  // within which feedback keeps the velocity (turn_feedback_deg, white).
  bool legs = false;
  bool any() const {
    return velocity || theta || facing || planted || trails || paths || torso || legs;
  }
};

// Overlay names of the CLI (`--overlay`): velocity, theta, facing, planted, trails, paths, torso
// and all. Sets the toggle and returns true, or false for an unknown name.
bool enable_overlay(const std::string& name, OverlayToggles* toggles);
inline constexpr const char* kOverlayNames =
    "velocity, theta, facing, planted, trails, paths, torso, legs or all";

// What the torso fan shows, for its label above the head.
struct TorsoReadout {
  glm::vec3 head{0.0f};     // a point just above the head [m]
  float twist_deg = 0.0f;   // chest heading - pelvis heading, signed
  float theta_deg = 0.0f;   // simulator's theta - pelvis heading, signed (what was asked)
  float limit_deg = 0.0f;   // the torsion limit
};
std::optional<TorsoReadout> torso_readout(const CrowdSession& session, const AnimationLane& lane,
                                          int64_t agent_id);

// What the legs overlay shows, for its label above the head.
struct LegsReadout {
  glm::vec3 head{0.0f};    // a point just above the head [m]
  float speed_m_s = 0.0f;  // simulator speed
  float band_deg = 0.0f;   // turn_feedback_deg: where feedback (when on) keeps the velocity
  // The fastest the legs can go: the fastest forward clip at the largest playback rate and
  // stride warp (beyond it, feedback when on slows the simulator down) [m/s].
  float legs_max_m_s = 0.0f;
};
// nullopt when the agent is not in the lane's frame or stands (no direction to compare).
std::optional<LegsReadout> legs_readout(const CrowdSession& session, const AnimationLane& lane,
                                        int64_t agent_id);

// The selected agent's ring (magenta, 0.5 m) around `ground` (its root, just above the floor).
void draw_selection_ring(const glm::vec3& ground, CrowdRenderer* renderer);

// Slide speed [m/s] from which a trail sample is fully red: METRICS.md's skate threshold.
inline constexpr float kSkateSpeed_m_s = 0.30f;

class OverlayHistory {
 public:
  OverlayHistory(const CrowdSession& session, size_t capacity);
  // Appends this frame's toe and root positions of every live agent of the lane.
  void record(const CrowdSession& session, const AnimationLane& lane, float dt_s);
  // Mean support-foot slide on the last recorded frame [m/s] (the same foot the support within
  // 5 cm of its floor on this frame and the previous one: METRICS.md v2), and the share of those
  // samples above kSkateSpeed_m_s.
  float last_slide_m_s() const { return last_slide_m_s_; }
  float last_skate_ratio() const { return last_skate_ratio_; }
  // Queues the enabled overlays as debug lines (and the torso fan's triangles). `selected_id` (or
  // -1) gets a ring at its feet and, with `torso`, the fan.
  void draw(const CrowdSession& session, const AnimationLane& lane, const OverlayToggles& toggles,
            int64_t selected_id, CrowdRenderer* renderer) const;

 private:
  static constexpr int kTrailLength = 90;  // samples of each toe (1.5 s at 60 Hz)
  static constexpr int kPathLength = 60;   // root samples, one every kPathEvery frames
  static constexpr int kPathEvery = 4;
  struct ToeSample {
    glm::vec3 position;
    float slide_m_s;  // < 0: not in contact
  };
  size_t capacity_;
  float last_slide_m_s_ = 0.0f;
  float last_skate_ratio_ = 0.0f;
  int toe_joint_[2] = {-1, -1};
  float toe_floor_m_[2] = {0.0f, 0.0f};
  std::vector<int64_t> slot_id_;  // id recorded in the slot, -1 when empty
  std::vector<int> count_;        // samples recorded since the slot's agent appeared
  std::vector<ToeSample> toes_;   // [(slot * 2 + side) * kTrailLength + k]
  std::vector<glm::vec3> path_;   // [slot * kPathLength + k]
};

}  // namespace gk::app
