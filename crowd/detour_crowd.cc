#include "crowd/detour_crowd.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include <DetourCrowd.h>
#include <DetourNavMesh.h>
#include <DetourNavMeshQuery.h>

#include "crowd/navmesh_builder.h"

namespace gk {
namespace {

constexpr float kPi = 3.14159265358979f;
constexpr float kDefaultRadius_m = 0.3f;
constexpr float kMaxRadius_m = 2.0f;
constexpr float kMaxSpeed_m_s = 12.0f;
constexpr float kAgentHeight_m = 1.8f;
// An agent start within this distance of the walkable area is snapped onto it (spawn areas often
// touch the agent-radius margin along walls); farther away is an error.
constexpr float kStartSnap_m = 1.0f;
// Waypoints may lie in the margin or just outside the bounds (exits); farther is an error.
constexpr float kWaypointSnap_m = 2.0f;
// An intermediate waypoint counts as passed within this distance: a crowd cannot all squeeze
// through one point, and Detour slows agents down near the final corner of a path.
constexpr float kWaypointReached_m = 1.0f;
constexpr float kHeadingMinSpeed_m_s = 0.1f;
// Detour's sampled avoidance velocities jitter from frame to frame: smooth the heading over
// about a quarter second so theta does not twitch.
constexpr float kThetaTau_s = 0.25f;
// Long frames are split so Detour's explicit integration and collision passes stay stable.
constexpr float kMaxSubstep_s = 1.0f / 30.0f;
constexpr int kMaxSubsteps = 16;
constexpr int kQueryMaxNodes = 2048;
constexpr unsigned char kAvoidanceSet = 0;  // the one avoidance parameter set we configure

// Adaptive velocity sampling per quality level (divisions, rings, depth), low to high: the number
// of candidate velocities, hence the cost, grows with each.
struct AvoidancePreset {
  unsigned char divs, rings, depth;
};
constexpr AvoidancePreset kAvoidancePresets[4] = {{5, 2, 1}, {5, 2, 2}, {7, 2, 3}, {7, 3, 3}};

// Into [-pi, pi]; angles already there are returned unchanged (no fmod rounding).
float wrap_angle(float a) {
  if (a >= -kPi && a <= kPi) return a;
  a = std::fmod(a + kPi, 2.0f * kPi);
  if (a < 0.0f) a += 2.0f * kPi;
  return a - kPi;
}
float heading_of(glm::vec2 v) { return std::atan2(v.x, v.y); }  // 0 faces +z, pi/2 faces +x
bool finite2(glm::vec2 v) { return std::isfinite(v.x) && std::isfinite(v.y); }

struct QueryDeleter {
  void operator()(dtNavMeshQuery* q) const { dtFreeNavMeshQuery(q); }
};
struct CrowdDeleter {
  void operator()(dtCrowd* c) const { dtFreeCrowd(c); }
};

// Nearest walkable point within `snap_m` (horizontally) of ground point p, or ref 0.
dtPolyRef snap_to_navmesh(const dtNavMeshQuery& query, const dtQueryFilter& filter, glm::vec2 p,
                          float snap_m, float out_pos[3]) {
  const float center[3] = {p.x, 0.0f, p.y};
  const float half_extents[3] = {snap_m, 1.0f, snap_m};
  dtPolyRef ref = 0;
  if (dtStatusFailed(query.findNearestPoly(center, half_extents, &filter, &ref, out_pos))) return 0;
  if (ref == 0) return 0;
  const float dx = out_pos[0] - p.x, dz = out_pos[2] - p.y;
  return dx * dx + dz * dz <= snap_m * snap_m ? ref : 0;
}

class DetourCrowdSource final : public CrowdSource {
 public:
  std::string name() const override { return name_; }
  Status step(float dt_s) override;
  AgentFrame frame() const override {
    return AgentFrame{live_ids_, live_positions_, live_velocities_, live_thetas_};
  }
  FeedbackPolicy feedback_policy() const override { return FeedbackPolicy::kHonoured; }
  Status apply_feedback(const AgentFeedback& feedback) override;
  double time_s() const override { return time_s_; }
  size_t capacity() const override { return ids_.size(); }

  Status init(const Scenario& scenario, const ScenarioAgents& agents, const DetourParams& params);

 private:
  void advance_waypoints();
  void request_target(size_t i);
  void gather_live();

  std::string name_;
  // Destroyed in reverse order: the crowd and the query refer to the navmesh.
  NavMeshPtr navmesh_;
  std::unique_ptr<dtNavMeshQuery, QueryDeleter> query_;
  std::unique_ptr<dtCrowd, CrowdDeleter> crowd_;
  // Per agent; agent i is dtCrowd pool index i and has id i.
  std::vector<uint32_t> ids_;
  std::vector<glm::vec2> positions_, velocities_;
  std::vector<glm::vec2> before_;  // positions before a Detour update
  float max_step_speed_factor_ = 2.0f;
  std::vector<float> thetas_;
  std::vector<uint32_t> waypoint_begin_, waypoint_end_, waypoint_current_;
  std::vector<uint8_t> loop_;
  std::vector<uint8_t> remove_at_goal_;  // vanish at the end of a non-looping chain
  std::vector<float> goal_radius_;       // final waypoint reached within this distance [m]
  std::vector<uint8_t> alive_;
  // The frame: live agents only, compacted (frame index k is dtCrowd agent live_agent_[k]).
  std::vector<uint32_t> live_ids_;
  std::vector<glm::vec2> live_positions_, live_velocities_;
  std::vector<float> live_thetas_;
  std::vector<uint32_t> live_agent_;
  // Waypoints snapped onto the navmesh: (x, y, z) and their polygons.
  std::vector<float> waypoint_pos_;
  std::vector<dtPolyRef> waypoint_ref_;
  double time_s_ = 0.0;
};

Status DetourCrowdSource::init(const Scenario& scenario, const ScenarioAgents& agents,
                               const DetourParams& params) {
  const std::string& file = scenario.source.empty() ? scenario.name : scenario.source;
  name_ = "detour " + scenario.name;
  const size_t n = agents.size();
  const auto field = [](const char* array, size_t i) {
    return std::string("agents.") + array + "[" + std::to_string(i) + "]";
  };
  if (agents.desired_speeds_m_s.size() != n || agents.radii_m.size() != n ||
      agents.loop_waypoints.size() != n ||
      (agents.waypoint_begin.size() != n + 1 && !(n == 0 && agents.waypoint_begin.empty())) ||
      (n > 0 && agents.waypoint_begin[n] > agents.waypoints.size())) {
    return Status::AtField(file, "agents",
                           "array sizes disagree with " + std::to_string(n) + " agents");
  }
  if (!std::isfinite(params.max_accel_m_s2) || params.max_accel_m_s2 <= 0.0f) {
    return Status::AtField(file, "max_accel_m_s2", "expected a finite acceleration > 0");
  }
  if (!std::isfinite(params.max_step_speed_factor)) {
    return Status::AtField(file, "max_step_speed_factor", "expected a finite number (<= 0: off)");
  }
  max_step_speed_factor_ = params.max_step_speed_factor;
  if (params.avoidance_quality < 0 || params.avoidance_quality > 3) {
    return Status::AtField(file, "avoidance_quality", "expected 0, 1, 2 or 3");
  }
  float max_radius = n == 0 ? kDefaultRadius_m : 0.0f;
  for (size_t i = 0; i < n; ++i) {
    const float r = agents.radii_m[i], v = agents.desired_speeds_m_s[i];
    if (!(r > 0.0f && r <= kMaxRadius_m)) {
      return Status::AtField(file, field("radii_m", i), "expected a radius in (0, 2] m");
    }
    if (!(v >= 0.0f && v <= kMaxSpeed_m_s)) {
      return Status::AtField(file, field("desired_speeds_m_s", i), "expected a speed in [0, 12]");
    }
    if (!finite2(agents.positions[i])) {
      return Status::AtField(file, field("positions", i), "expected a finite position");
    }
    if (agents.waypoint_begin[i] > agents.waypoint_begin[i + 1]) {
      return Status::AtField(file, field("waypoint_begin", i), "expected a non-decreasing index");
    }
    max_radius = std::max(max_radius, r);
  }

  NavMeshBuildParams build;
  // A scenario scaled up for thousands of agents spans hundreds of metres: coarsen the voxels so
  // the navmesh grid stays around 2,000 cells a side (walls stay exact; only the walkable margin
  // is quantised more coarsely).
  const glm::vec2 extent = scenario.bounds_max - scenario.bounds_min;
  build.cell_size_m = params.cell_size_m;  // an invalid size is reported by the builder
  if (params.cell_size_m > 0.0f && std::isfinite(extent.x) && std::isfinite(extent.y)) {
    build.cell_size_m = std::max(params.cell_size_m, std::max(extent.x, extent.y) / 2000.0f);
  }
  build.agent_radius_m = max_radius;
  Result<NavMeshPtr> navmesh = build_navmesh(scenario, build);
  if (!navmesh.ok()) return navmesh.status();
  navmesh_ = std::move(*navmesh);
  query_.reset(dtAllocNavMeshQuery());
  crowd_.reset(dtAllocCrowd());
  if (!query_ || dtStatusFailed(query_->init(navmesh_.get(), kQueryMaxNodes)) || !crowd_ ||
      !crowd_->init(static_cast<int>(std::max<size_t>(n, 1)), max_radius, navmesh_.get())) {
    return Status::AtField(file, "navmesh", "Detour crowd initialisation failed");
  }
  const AvoidancePreset& preset = kAvoidancePresets[params.avoidance_quality];
  dtObstacleAvoidanceParams avoid = *crowd_->getObstacleAvoidanceParams(kAvoidanceSet);
  avoid.velBias = 0.5f;
  avoid.adaptiveDivs = preset.divs;
  avoid.adaptiveRings = preset.rings;
  avoid.adaptiveDepth = preset.depth;
  crowd_->setObstacleAvoidanceParams(kAvoidanceSet, &avoid);
  const dtQueryFilter& filter = *crowd_->getFilter(0);

  const size_t num_waypoints = n ? agents.waypoint_begin[n] : 0;
  waypoint_pos_.resize(3 * num_waypoints);
  waypoint_ref_.resize(num_waypoints);
  for (size_t w = 0; w < num_waypoints; ++w) {
    if (!finite2(agents.waypoints[w])) {
      return Status::AtField(file, field("waypoints", w), "expected a finite point");
    }
    waypoint_ref_[w] = snap_to_navmesh(*query_, filter, agents.waypoints[w], kWaypointSnap_m,
                                       &waypoint_pos_[3 * w]);
    if (waypoint_ref_[w] == 0) {
      return Status::AtField(file, field("waypoints", w),
                             "(" + std::to_string(agents.waypoints[w].x) + ", " +
                                 std::to_string(agents.waypoints[w].y) +
                                 ") is more than 2 m from the walkable area");
    }
  }

  ids_.resize(n);
  positions_.resize(n);
  velocities_.assign(n, glm::vec2(0.0f));
  before_.assign(n, glm::vec2(0.0f));
  thetas_.assign(n, 0.0f);
  waypoint_begin_.resize(n);
  waypoint_end_.resize(n);
  waypoint_current_.resize(n);
  loop_.resize(n);
  alive_.assign(n, 1);
  remove_at_goal_.assign(n, 0);
  goal_radius_.assign(n, kWaypointReached_m);
  live_ids_.reserve(n);
  live_positions_.reserve(n);
  live_velocities_.reserve(n);
  live_thetas_.reserve(n);
  live_agent_.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    if (!agents.remove_at_goal.empty()) remove_at_goal_[i] = agents.remove_at_goal[i];
    if (!agents.goal_radii_m.empty() && agents.goal_radii_m[i] > 0.0f) {
      goal_radius_[i] = agents.goal_radii_m[i];
    }
    float start[3];
    if (snap_to_navmesh(*query_, filter, agents.positions[i], kStartSnap_m, start) == 0) {
      return Status::AtField(file, field("positions", i),
                             "(" + std::to_string(agents.positions[i].x) + ", " +
                                 std::to_string(agents.positions[i].y) +
                                 ") is not on the walkable area (walls, bounds and an agent-radius "
                                 "margin excluded) nor within 1 m of it");
    }
    dtCrowdAgentParams ap{};
    ap.radius = agents.radii_m[i];
    ap.height = kAgentHeight_m;
    ap.maxAcceleration = params.max_accel_m_s2;
    // Detour walks at maxSpeed whenever the way is free, so the desired speed is the maximum.
    ap.maxSpeed = agents.desired_speeds_m_s[i];
    ap.collisionQueryRange = ap.radius * 12.0f;
    ap.pathOptimizationRange = ap.radius * 30.0f;
    ap.separationWeight = 2.0f;
    ap.updateFlags = DT_CROWD_ANTICIPATE_TURNS | DT_CROWD_OBSTACLE_AVOIDANCE | DT_CROWD_SEPARATION |
                     DT_CROWD_OPTIMIZE_VIS | DT_CROWD_OPTIMIZE_TOPO;
    ap.obstacleAvoidanceType = kAvoidanceSet;
    ap.queryFilterType = 0;
    if (crowd_->addAgent(start, &ap) != static_cast<int>(i)) {
      return Status::AtField(file, field("positions", i), "Detour could not add the agent");
    }
    ids_[i] = static_cast<uint32_t>(i);
    positions_[i] = glm::vec2(start[0], start[2]);
    waypoint_begin_[i] = agents.waypoint_begin[i];
    waypoint_end_[i] = agents.waypoint_begin[i + 1];
    waypoint_current_[i] = waypoint_begin_[i];
    loop_[i] = agents.loop_waypoints[i] != 0;
    if (waypoint_begin_[i] < waypoint_end_[i]) {
      const float* target = &waypoint_pos_[3 * waypoint_begin_[i]];
      const glm::vec2 to_target = glm::vec2(target[0], target[2]) - positions_[i];
      if (glm::length(to_target) > 1e-3f) thetas_[i] = heading_of(to_target);
      request_target(i);
    }
  }
  // Detour has no randomness: the seed is not needed for reproducible runs.
  (void)params.seed;
  gather_live();
  return Status::Ok();
}

void DetourCrowdSource::request_target(size_t i) {
  const uint32_t w = waypoint_current_[i];
  crowd_->requestMoveTarget(static_cast<int>(i), waypoint_ref_[w], &waypoint_pos_[3 * w]);
}

// Moves each agent on to its next waypoint when it is close to the current one, or when its path
// is partial (target unreachable) and it has come to the end of it.
void DetourCrowdSource::advance_waypoints() {
  for (size_t i = 0; i < ids_.size(); ++i) {
    const uint32_t begin = waypoint_begin_[i], end = waypoint_end_[i];
    if (begin == end || !alive_[i]) continue;
    const uint32_t w = waypoint_current_[i];
    const bool is_last = w + 1 == end;
    const dtCrowdAgent* ag = crowd_->getAgent(static_cast<int>(i));
    if (is_last && !loop_[i]) {
      // The end of the chain: agents that leave the scene (an exit) vanish there.
      const float* goal = &waypoint_pos_[3 * w];
      const float gx = ag->npos[0] - goal[0], gz = ag->npos[2] - goal[2];
      // At least kWaypointReached_m: a crowd cannot all reach one point, the last ones would pile
      // up.
      const float r = std::max(goal_radius_[i], kWaypointReached_m);
      if (remove_at_goal_[i] && gx * gx + gz * gz <= r * r) {
        crowd_->removeAgent(static_cast<int>(i));
        alive_[i] = 0;
      }
      continue;
    }
    const float* target = ag->partial ? ag->corridor.getTarget() : &waypoint_pos_[3 * w];
    const float dx = ag->npos[0] - target[0], dz = ag->npos[2] - target[2];
    if (dx * dx + dz * dz > kWaypointReached_m * kWaypointReached_m) continue;
    waypoint_current_[i] = is_last ? begin : w + 1;
    request_target(i);
  }
}

Status DetourCrowdSource::step(float dt_s) {
  if (!std::isfinite(dt_s) || dt_s <= 0.0f) {
    return Status::Error(name_ + ": step: expected a finite dt > 0 s, found " +
                         std::to_string(dt_s));
  }
  const int substeps =
      std::clamp(static_cast<int>(std::ceil(dt_s / kMaxSubstep_s)), 1, kMaxSubsteps);
  const float h = dt_s / static_cast<float>(substeps);
  // Detour's collision resolution can push an agent in a packed jam, or against a wall corner, by
  // 20 cm in one step (12 m/s): a body cannot be moved that fast, and a drawn body that follows it
  // jumps. Each update's displacement is held to max_step_speed_factor times the agent's own
  // maximum speed (the push is still felt, over several steps), sliding along the navmesh.
  const float jump_cap = max_step_speed_factor_;
  for (int s = 0; s < substeps; ++s) {
    if (jump_cap > 0.0f) {
      for (size_t i = 0; i < ids_.size(); ++i) {
        const dtCrowdAgent* ag = crowd_->getAgent(static_cast<int>(i));
        before_[i] = glm::vec2(ag->npos[0], ag->npos[2]);
      }
    }
    crowd_->update(h, nullptr);
    if (jump_cap > 0.0f) {
      const dtQueryFilter* filter = crowd_->getFilter(0);
      for (size_t i = 0; i < ids_.size(); ++i) {
        if (!alive_[i]) continue;
        dtCrowdAgent* ag = crowd_->getEditableAgent(static_cast<int>(i));
        if (!ag->active || ag->state != DT_CROWDAGENT_STATE_WALKING) continue;
        const glm::vec2 d = glm::vec2(ag->npos[0], ag->npos[2]) - before_[i];
        const float cap = jump_cap * ag->params.maxSpeed * h;
        const float len = glm::length(d);
        if (len <= cap) continue;
        const glm::vec2 to = before_[i] + d * (cap / len);
        const float target[3] = {to.x, ag->npos[1], to.y};
        if (ag->corridor.movePosition(target, query_.get(), filter)) {
          const float* pos = ag->corridor.getPos();
          ag->npos[0] = pos[0];
          ag->npos[1] = pos[1];
          ag->npos[2] = pos[2];
        }
      }
    }
    advance_waypoints();
  }
  time_s_ += dt_s;

  const float blend = 1.0f - std::exp(-dt_s / kThetaTau_s);
  for (size_t i = 0; i < ids_.size(); ++i) {
    if (!alive_[i]) continue;
    const dtCrowdAgent* ag = crowd_->getAgent(static_cast<int>(i));
    const glm::vec2 p(ag->npos[0], ag->npos[2]), v(ag->vel[0], ag->vel[2]);
    if (!finite2(p) || !finite2(v)) {
      return Status::Error(name_ + ": agent " + std::to_string(i) +
                           ": Detour produced a non-finite position or velocity");
    }
    positions_[i] = p;
    velocities_[i] = v;
    if (glm::length(v) >= kHeadingMinSpeed_m_s) {
      thetas_[i] = wrap_angle(thetas_[i] + wrap_angle(heading_of(v) - thetas_[i]) * blend);
    }
  }
  gather_live();
  return Status::Ok();
}

void DetourCrowdSource::gather_live() {
  live_ids_.clear();
  live_positions_.clear();
  live_velocities_.clear();
  live_thetas_.clear();
  live_agent_.clear();
  for (size_t i = 0; i < ids_.size(); ++i) {
    if (!alive_[i]) continue;
    live_ids_.push_back(ids_[i]);
    live_positions_.push_back(positions_[i]);
    live_velocities_.push_back(velocities_[i]);
    live_thetas_.push_back(thetas_[i]);
    live_agent_.push_back(static_cast<uint32_t>(i));
  }
}

Status DetourCrowdSource::apply_feedback(const AgentFeedback& fb) {
  const size_t n = live_ids_.size();
  if (fb.has_feedback.size() != n || fb.positions.size() != n || fb.velocities.size() != n ||
      fb.thetas.size() != n) {
    return Status::Error(name_ + ": apply_feedback: expected " + std::to_string(n) +
                         " entries per array");
  }
  // Check everything first so a bad entry leaves the crowd untouched.
  for (size_t i = 0; i < n; ++i) {
    if (fb.has_feedback[i] &&
        (!finite2(fb.positions[i]) || !finite2(fb.velocities[i]) || !std::isfinite(fb.thetas[i]))) {
      return Status::Error(name_ + ": apply_feedback: agent " + std::to_string(i) +
                           ": expected finite position, velocity and theta");
    }
  }
  const dtQueryFilter* filter = crowd_->getFilter(0);
  for (size_t k = 0; k < n; ++k) {
    if (!fb.has_feedback[k]) continue;
    const size_t i = live_agent_[k];
    dtCrowdAgent* ag = crowd_->getEditableAgent(static_cast<int>(i));
    if (!ag->active || ag->state != DT_CROWDAGENT_STATE_WALKING) continue;
    // Slide along the navmesh toward the requested position (as Detour's own integration does),
    // so feedback can never put an agent inside a wall or off the mesh.
    const float target[3] = {fb.positions[k].x, ag->npos[1], fb.positions[k].y};
    if (ag->corridor.movePosition(target, query_.get(), filter)) {
      const float* pos = ag->corridor.getPos();
      ag->npos[0] = pos[0];
      ag->npos[1] = pos[1];
      ag->npos[2] = pos[2];
    }
    ag->vel[0] = fb.velocities[k].x;
    ag->vel[1] = 0.0f;
    ag->vel[2] = fb.velocities[k].y;
    positions_[i] = glm::vec2(ag->npos[0], ag->npos[2]);
    velocities_[i] = fb.velocities[k];
    thetas_[i] = wrap_angle(fb.thetas[k]);
  }
  gather_live();
  return Status::Ok();
}

}  // namespace

Result<std::unique_ptr<CrowdSource>> make_detour_crowd(const Scenario& scenario,
                                                       const ScenarioAgents& agents,
                                                       const DetourParams& params) {
  auto source = std::make_unique<DetourCrowdSource>();
  GK_RETURN_IF_ERROR(source->init(scenario, agents, params));
  return std::unique_ptr<CrowdSource>(std::move(source));
}

}  // namespace gk
