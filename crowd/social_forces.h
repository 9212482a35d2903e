#pragma once
// The default crowd simulator: Helbing & Molnar social forces with the usual extensions.
//   dv/dt = (v0 e - v) / tau                               drive toward the current waypoint
//         + sum_j A exp((r_ij - b_ij) / B) n_ij w(phi)     anisotropic agent repulsion, b_ij the
//                                                          distance corrected for relative motion
//         + sum_j k max(0, r_ij - d_ij) n_ij               body contact (optional)
//         + sum_W A_w exp((r_i - d_iW) / B_w) n_iW + contact   walls (closest point on segment)
// with w(phi) = lambda + (1 - lambda) (1 + cos phi) / 2, so what is ahead matters more.
// Speeds are capped at max_speed_factor x the desired speed. After integrating, no step may cross
// a wall (the step is slid along the wall or cancelled) and agents are kept their radius away.
//
// One step is two whole-crowd passes over flat arrays: compute every new velocity from the frozen
// state, then commit positions, waypoints and orientations. The velocity pass walks the agents in
// uniform-grid cell order over a packed copy of what it reads, so neighbours are contiguous in
// memory, and computes the neighbour forces four at a time (SSE2; exp and atan2 are the SSE2
// ones of crowd/simd_exp.h and crowd/simd_atan2.h, so the bits do not depend on the CPU's libm
// variant). Each agent sums its neighbours in a fixed order (cell order, four lane sums added up
// in a fixed order), so results do not depend on the thread count: runs with threads = 2 equal
// threads = 1 bit for bit. Capacity and scratch are fixed at creation.

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "crowd/crowd_source.h"
#include "crowd/scenario.h"

namespace gk {

struct SocialForceParams {
  float relaxation_time_s = 0.5f;     // tau [s] [Limit: > 0]
  float max_speed_factor = 1.3f;      // max speed = factor x desired speed [-] [Limit: >= 1]
  float agent_strength_m_s2 = 3.0f;   // A: repulsion at contact [m/s^2] [Limit: >= 0]
  float agent_range_m = 0.35f;        // B: decay length of the repulsion [m] [Limit: > 0]
  float field_of_view_weight = 0.3f;  // lambda: weight of what is behind [-] [Limit: 0..1]
  // Relative velocities are extrapolated this far (elliptical specification II, Johansson et al.
  // 2007) [s] [Limit: 0..5]; 0 is the circular specification (distance only).
  float anticipation_time_s = 0.5f;
  // Share of an agent's frontal repulsion turned to its right, so that two agents meeting head
  // on side-step instead of stalling [-] [Limit: 0..1]. 0 is textbook Helbing-Molnar.
  float side_step = 0.2f;
  float neighbour_radius_m = 2.0f;    // cutoff of agent interaction; grid cell size [m] [> 0]
  float wall_strength_m_s2 = 6.0f;    // A_w [m/s^2] [Limit: >= 0]
  float wall_range_m = 0.15f;         // B_w [m] [Limit: > 0]
  float wall_radius_m = 1.0f;         // cutoff of wall interaction [m] [Limit: > 0]
  bool contact_forces = true;         // body compression (Helbing 2000), agents and walls
  float body_stiffness_s2 = 1000.0f;  // k / mass [1/s^2] [Limit: >= 0; k dt^2 < 1 for stability]
  float heading_time_s = 0.3f;        // smoothing of the walking direction [s] [Limit: > 0]
  float heading_speed_m_s = 0.3f;     // below this speed the heading turns proportionally
                                      // slower, so standing agents do not spin [m/s] [> 0]
  float look_time_s = 0.25f;          // smoothing of theta toward its target [s] [Limit: > 0]
  float max_look_twist_deg = 100.0f;  // theta may look this far from v at a target [deg] [0..180]
  int threads = 1;                    // 1: single-threaded; 0: all cores [Limit: 0..256]
  size_t max_agents = 250'000;        // refuse larger crowds [Limit: 1..1,000,000]
  float max_feedback_speed_m_s = 10.0f;  // feedback velocities above this are rejected [m/s]
  float max_feedback_jump_m = 2.0f;      // feedback positions farther than this are rejected [m]
};

// Empty Status when every parameter is within its limits, else which one is not.
Status validate(const SocialForceParams& params);

struct SocialForceStats {
  size_t live = 0;          // agents simulated now
  size_t removed = 0;       // agents that reached a final goal that removes them
  size_t reached_goal = 0;  // agents that reached their final waypoint at least once (removed
                            // ones included; looping agents count after one round)
};

class SocialForces final : public CrowdSource {
 public:
  static Result<std::unique_ptr<SocialForces>> create(const Scenario& scenario,
                                                      const ScenarioAgents& agents,
                                                      const SocialForceParams& params = {});
  ~SocialForces() override;

  std::string name() const override { return "social_forces"; }
  Status step(float dt_s) override;
  AgentFrame frame() const override;
  FeedbackPolicy feedback_policy() const override { return FeedbackPolicy::kHonoured; }
  // Validates every flagged entry first (finite, speed and jump within the limits) and changes
  // nothing when one is invalid; positions taken over are kept clear of walls like steps are.
  Status apply_feedback(const AgentFeedback& feedback) override;
  double time_s() const override { return time_s_; }
  size_t capacity() const override { return capacity_; }

  const SocialForceParams& params() const { return params_; }
  SocialForceStats stats() const;
  // Per live agent, index-aligned with frame().
  std::span<const float> max_speeds_m_s() const { return {max_speed_.data(), num_}; }
  std::span<const float> radii_m() const { return {radius_.data(), num_}; }
  std::span<const uint8_t> reached_goal() const { return {reached_.data(), num_}; }

 private:
  struct Impl;
  SocialForces(const SocialForceParams& params, size_t capacity);
  // The force parameters and one agent's terms broadcast to SSE lanes, with the agent's four
  // lane sums; defined in the .cc, so that this header carries no SSE types.
  struct ForceLanes;
  void add_neighbour_forces(const uint32_t* candidates, uint32_t count, ForceLanes* f) const;
  void prepare(size_t begin, size_t end);
  void compute_velocities(size_t begin, size_t end, float dt_s);
  void commit(size_t begin, size_t end, float dt_s);
  void remove_finished();
  template <typename Fn>
  void for_agents(Fn&& fn);

  SocialForceParams params_;
  size_t capacity_ = 0;
  size_t num_ = 0;
  size_t removed_ = 0;
  size_t reached_removed_ = 0;
  double time_s_ = 0.0;
  std::unique_ptr<Impl> impl_;  // grids and the thread arena

  // Agent state, structure of arrays, `capacity_` long; the first num_ entries are live.
  std::vector<uint32_t> id_;
  std::vector<glm::vec2> position_, velocity_;
  std::vector<float> theta_, heading_;
  std::vector<float> desired_speed_, max_speed_, radius_, goal_radius_;
  std::vector<uint32_t> waypoint_, waypoint_begin_, waypoint_end_;  // current, chain [begin, end)
  std::vector<glm::vec2> goal_;  // waypoints_[waypoint_[i]], kept beside it for sequential reads
  std::vector<uint8_t> loop_, remove_at_goal_, attentive_, arrived_, reached_;
  std::vector<glm::vec2> waypoints_;  // all chains, immutable
  std::vector<AttentionTarget> targets_;
  // Scratch of one step. What the velocity pass reads of an agent, packed into one 32-byte record
  // and stored in the grid's cell order, so that an agent's neighbours are contiguous.
  struct Body {
    glm::vec2 position, velocity;
    glm::vec2 direction;  // desired direction e toward the current waypoint; 0 when arrived
    float radius, desired_speed;
  };
  std::vector<Body> sorted_;
  std::vector<float> sorted_x_, sorted_z_;  // sorted_'s positions, for the neighbour scan
  std::vector<glm::vec2> new_velocity_;
};

}  // namespace gk
