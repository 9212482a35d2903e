#pragma once
// Scenarios: JSON files in data/scenarios/ describing walls (line segments), agent groups with
// spawn areas, goals / waypoint chains, desired-speed distributions and attention targets. Schema
// documented in README.md; errors name the file and the field.

#include <cstdint>
#include <string>
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

// Fully resolved initial agents (the spawn areas of a scenario expanded for a given agent count
// and seed), as plain arrays.
struct ScenarioAgents {
  std::vector<glm::vec2> positions;
  std::vector<float> desired_speeds_m_s;
  std::vector<float> radii_m;
  // Waypoint chain per agent: waypoints[waypoint_begin[i] .. waypoint_begin[i+1]).
  std::vector<uint32_t> waypoint_begin;
  std::vector<glm::vec2> waypoints;
  std::vector<uint8_t> loop_waypoints;  // 1: go round the chain forever
  size_t size() const { return positions.size(); }
};

struct Scenario {
  std::string name;
  std::string source;  // file path
  std::string description;
  glm::vec2 bounds_min{-20.0f}, bounds_max{20.0f};  // region that the camera/navmesh cover [m]
  std::vector<WallSegment> walls;
  std::vector<AttentionTarget> attention_targets;
  int default_agents = 100;
  // The raw JSON groups are kept by the loader to expand for any agent count; see scenario.cc.
  std::string json_text;
};

}  // namespace gk
