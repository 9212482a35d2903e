#pragma once
// Scenarios: JSON files in data/scenarios/ describing walls (line segments), agent groups with
// spawn areas, goals / waypoint chains, desired-speed distributions and attention targets. The
// schema is documented in docs/scenarios.md; every error names the file and the JSON field path
// ("corridor.json: groups[1].speed.mean: expected a number > 0").
//
// A scenario scales to any agent count: scale_scenario() grows the whole geometry about (0, 0) so
// that the spawn areas hold the agents at no more than max_spawn_density, and expand_agents()
// draws the agents (positions, speeds, per-agent goal points) for a seed. Coordinates are (x, z)
// on the ground plane [m].

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <glm/vec2.hpp>

#include "common/status.h"

namespace gk {

struct WallSegment {
  glm::vec2 a{0.0f};
  glm::vec2 b{0.0f};
};

// A point (x, z) agents look at while they walk past within `radius_m`.
struct AttentionTarget {
  glm::vec2 position{0.0f};
  float radius_m = 4.0f;
};

// A region of the ground: where agents spawn, or where a per-agent goal point is drawn.
struct Area {
  enum class Shape : uint8_t {
    kPoint,   // `center`
    kRect,    // [min, max]
    kCircle,  // disc of `radius_m` about `center`
    kRing,    // the circle line of `radius_m` about `center` (spawn only)
  };
  Shape shape = Shape::kPoint;
  glm::vec2 min{0.0f}, max{0.0f};
  glm::vec2 center{0.0f};
  float radius_m = 0.0f;
};

struct WaypointSpec {
  enum class Kind : uint8_t {
    kArea,      // a point drawn per agent in `area` (a kPoint area gives everyone the same point)
    kAntipode,  // the agent's spawn position mirrored through `area.center`
  };
  Kind kind = Kind::kArea;
  Area area;
};

// Desired walking speed: normal(mean, sd) clamped to [min, max] [m/s].
struct SpeedDistribution {
  float mean_m_s = 1.34f;
  float sd_m_s = 0.26f;
  float min_m_s = 0.5f;
  float max_m_s = 2.2f;
};

struct AgentGroup {
  std::string name;
  float fraction = 1.0f;  // share of the agents, normalised over all groups [> 0]
  Area spawn;             // kRect, kCircle or kRing
  std::vector<WaypointSpec> waypoints;
  // random_goal_count > 0: the chain is that many points drawn in random_goal_area (after the
  // explicit waypoints), so the agent keeps picking new random goals when `loop` is set.
  int random_goal_count = 0;
  Area random_goal_area;
  bool loop = false;            // go round the chain forever
  bool remove_at_goal = false;  // at the end of a non-looping chain: vanish (else stop and stay)
  SpeedDistribution speed;
  float radius_m = 0.25f;      // body radius [m] [Limit: (0, 1]]
  // The file set "radius". Groups without it take the drawn body's radius when the app knows the
  // clip library (apply_body_radius).
  bool radius_given = false;
  float goal_radius_m = 0.5f;  // a waypoint counts as reached within this distance [m] [> 0]
  float attention = 1.0f;      // probability that an agent looks at attention targets [0, 1]
};

// Fully resolved initial agents (the spawn areas of a scenario expanded for a given agent count
// and seed), as plain arrays.
struct ScenarioAgents {
  std::vector<glm::vec2> positions;
  std::vector<float> desired_speeds_m_s;
  std::vector<float> radii_m;
  // Waypoint chain per agent: waypoints[waypoint_begin[i] .. waypoint_begin[i+1]); n + 1
  // entries (expand_agents leaves it empty when there are no agents).
  std::vector<uint32_t> waypoint_begin;
  std::vector<glm::vec2> waypoints;
  std::vector<uint8_t> loop_waypoints;  // 1: go round the chain forever
  std::vector<uint8_t> remove_at_goal;  // 1: vanish at the end of a non-looping chain
  std::vector<float> goal_radii_m;      // waypoint reached within this distance [m]
  std::vector<uint8_t> attentive;       // 1: looks at attention targets it walks past
  std::vector<uint16_t> group;          // index into Scenario::groups
  size_t size() const { return positions.size(); }
};

struct Scenario {
  std::string name;
  std::string source;  // file path
  std::string description;
  glm::vec2 bounds_min{-20.0f}, bounds_max{20.0f};  // region that the camera/navmesh cover [m]
  std::vector<WallSegment> walls;
  std::vector<AttentionTarget> attention_targets;
  std::vector<AgentGroup> groups;
  int default_agents = 100;
  // Spawn areas are filled at most this densely [agents/m^2] [Limit: (0, 4]]; on a ring the
  // spacing is 1/sqrt(density).
  float max_spawn_density = 1.0f;
  float scale = 1.0f;  // geometry factor applied by scale_scenario() (1 = as in the file)
};

// Hard limit on agents drawn from a scenario (the memory of the expansion, not the simulator).
inline constexpr int kMaxScenarioAgents = 500'000;

// Parses scenario JSON; `source_name` is used in error messages and as Scenario::source.
Result<Scenario> parse_scenario(std::string_view json_text, const std::string& source_name);
Result<Scenario> load_scenario(const std::string& path);
// `name_or_path`: a file path (contains '/' or ends in ".json"), else
// `<scenarios_dir>/<name>.json`.
Result<Scenario> load_scenario_by_name(const std::string& name_or_path,
                                       const std::string& scenarios_dir);
// $GAITKEEPER_SCENARIOS if set, else the repository's data/scenarios.
std::string scenario_dir();

// The geometry factor (>= 1) under which every group's spawn area holds its share of
// `num_agents` at max_spawn_density.
float scale_factor_for(const Scenario& scenario, int num_agents);
// The scenario with all geometry (walls, bounds, areas, waypoints, attention target positions)
// multiplied by scale_factor_for(scenario, num_agents) about (0, 0). Body and goal radii, look
// radii and speeds keep their values.
Scenario scale_scenario(const Scenario& scenario, int num_agents);

// Gives every group whose file did not set "radius" the body radius `radius_m` [m] (the
// half-width of the body that is drawn, so that where the simulator keeps two agents apart their
// bodies do not overlap). radius_m outside (0, 1] leaves the scenario as it is.
void apply_body_radius(Scenario* scenario, float radius_m);

// Draws `num_agents` agents for `seed` (same seed, same agents). Fails, naming the group, when
// the spawn areas cannot hold them at max_spawn_density (call scale_scenario first) or when
// num_agents is outside [0, kMaxScenarioAgents].
Result<ScenarioAgents> expand_agents(const Scenario& scenario, int num_agents, uint64_t seed);

}  // namespace gk
