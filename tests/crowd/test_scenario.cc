// Scenario loading (every shipped scenario, malformed fixtures) and expansion into agents.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "crowd/scenario.h"
#include "tests/test_data.h"

namespace gk {
namespace {

std::string scenarios() { return test::source_path("data/scenarios"); }

// Test-local geometry, written independently of the crowd module's helpers.
double point_segment_distance(glm::vec2 p, glm::vec2 a, glm::vec2 b) {
  const double abx = b.x - a.x, abz = b.y - a.y;
  const double t =
      std::clamp(((p.x - a.x) * abx + (p.y - a.y) * abz) / (abx * abx + abz * abz), 0.0, 1.0);
  return std::hypot(p.x - (a.x + t * abx), p.y - (a.y + t * abz));
}

TEST(Scenario, ShipsTheSixScenarios) {
  std::set<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(scenarios())) {
    if (e.path().extension() == ".json") names.insert(e.path().stem().string());
  }
  for (const char* n : {"corridor", "crossing", "circle", "bottleneck", "plaza", "gallery"}) {
    EXPECT_TRUE(names.count(n)) << n;
  }
}

// Every shipped scenario (and those of the README's figures, in docs/) loads and expands to 1, 10
// and 500 agents that start inside the bounds, apart from each other and clear of every wall, with
// a goal to walk to.
TEST(Scenario, EveryScenarioExpandsTo1_10_500Agents) {
  std::vector<std::filesystem::path> files;
  for (const std::string& dir : {scenarios(), test::source_path("docs")}) {
    for (const auto& e : std::filesystem::directory_iterator(dir)) {
      if (e.path().extension() == ".json") files.push_back(e.path());
    }
  }
  ASSERT_GE(files.size(), 9u);
  for (const std::filesystem::path& path : files) {
    const auto e = std::filesystem::directory_entry(path);
    SCOPED_TRACE(e.path().string());
    auto loaded = load_scenario(e.path().string());
    ASSERT_TRUE(loaded.ok()) << loaded.message();
    EXPECT_FALSE(loaded->walls.empty() && loaded->name != "circle");
    for (int n : {1, 10, 500}) {
      SCOPED_TRACE(n);
      const Scenario s = scale_scenario(*loaded, n);
      auto agents = expand_agents(s, n, 7);
      ASSERT_TRUE(agents.ok()) << agents.message();
      const ScenarioAgents& a = *agents;
      ASSERT_EQ(a.size(), size_t(n));
      ASSERT_EQ(a.waypoint_begin.size(), size_t(n) + 1);
      ASSERT_EQ(a.waypoint_begin.back(), a.waypoints.size());
      for (size_t i = 0; i < a.size(); ++i) {
        const glm::vec2 p = a.positions[i];
        EXPECT_TRUE(p.x >= s.bounds_min.x && p.x <= s.bounds_max.x && p.y >= s.bounds_min.y &&
                    p.y <= s.bounds_max.y);
        EXPECT_LT(a.waypoint_begin[i], a.waypoint_begin[i + 1]) << "agent without a goal";
        EXPECT_GT(a.desired_speeds_m_s[i], 0.0f);
        for (const WallSegment& w : s.walls) {
          ASSERT_GE(point_segment_distance(p, w.a, w.b), a.radii_m[i]) << "agent " << i;
        }
        for (size_t j = i + 1; j < a.size(); ++j) {
          const glm::vec2 d = p - a.positions[j];
          ASSERT_GE(std::hypot(d.x, d.y), a.radii_m[i] + a.radii_m[j]) << i << " and " << j;
        }
      }
    }
  }
}

TEST(Scenario, ScalingKeepsSpawnDensityAndGrowsGeometry) {
  auto s = load_scenario_by_name("corridor", scenarios());
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_FLOAT_EQ(scale_factor_for(*s, 10), 1.0f);
  const Scenario big = scale_scenario(*s, 2000);
  ASSERT_GT(big.scale, 1.0f);
  // Walls and bounds scale by the same factor about the origin.
  EXPECT_NEAR(big.walls[0].a.x, s->walls[0].a.x * big.scale, 1e-3);
  EXPECT_NEAR(big.bounds_max.y, s->bounds_max.y * big.scale, 1e-3);
  // Each spawn rect of the corridor holds half the agents at <= max_spawn_density.
  const Area& spawn = big.groups[0].spawn;
  const float area = (spawn.max.x - spawn.min.x) * (spawn.max.y - spawn.min.y);
  EXPECT_LE(1000.0f / area, big.max_spawn_density * 1.001f);
  auto agents = expand_agents(big, 2000, 1);
  ASSERT_TRUE(agents.ok()) << agents.message();
  // Too many agents for the unscaled geometry: a clear error naming the group's spawn area.
  auto unscaled = expand_agents(*s, 2000, 1);
  ASSERT_FALSE(unscaled.ok());
  EXPECT_NE(unscaled.message().find("groups[0].spawn"), std::string::npos) << unscaled.message();
}

TEST(Scenario, ExpansionIsDeterministicPerSeed) {
  auto s = load_scenario_by_name("plaza", scenarios());
  ASSERT_TRUE(s.ok()) << s.message();
  auto a = expand_agents(*s, 100, 42), b = expand_agents(*s, 100, 42),
       c = expand_agents(*s, 100, 43);
  ASSERT_TRUE(a.ok() && b.ok() && c.ok());
  EXPECT_EQ(a->positions, b->positions);
  EXPECT_EQ(a->waypoints, b->waypoints);
  EXPECT_EQ(a->desired_speeds_m_s, b->desired_speeds_m_s);
  EXPECT_NE(a->positions, c->positions);
}

TEST(Scenario, GroupSharesAndGoals) {
  auto s = load_scenario_by_name("plaza", scenarios());
  ASSERT_TRUE(s.ok());
  auto a = expand_agents(*s, 10, 3);  // fractions 0.7 / 0.3
  ASSERT_TRUE(a.ok());
  EXPECT_EQ(std::count(a->group.begin(), a->group.end(), 0), 7);
  EXPECT_EQ(std::count(a->group.begin(), a->group.end(), 1), 3);
  for (size_t i = 0; i < a->size(); ++i) {
    EXPECT_EQ(a->waypoint_begin[i + 1] - a->waypoint_begin[i], 10u);  // "count": 10
    EXPECT_EQ(a->loop_waypoints[i], 1);
  }
  auto circle = load_scenario_by_name("circle", scenarios());
  ASSERT_TRUE(circle.ok());
  auto c = expand_agents(*circle, 12, 3);
  ASSERT_TRUE(c.ok());
  for (size_t i = 0; i < c->size(); ++i) {  // antipode of the start through the centre (0, 0)
    EXPECT_NEAR(c->waypoints[c->waypoint_begin[i]].x, -c->positions[i].x, 1e-5);
    EXPECT_NEAR(c->waypoints[c->waypoint_begin[i]].y, -c->positions[i].y, 1e-5);
    EXPECT_NEAR(std::hypot(c->positions[i].x, c->positions[i].y), 8.0, 0.5);  // on the ring
    EXPECT_EQ(c->loop_waypoints[i], 0);
  }
}

// Desired speeds follow the file's normal distribution (mean 1.34, sd 0.26 for plaza walkers),
// within sampling error, and stay inside [min, max].
TEST(Scenario, DesiredSpeedsFollowTheDistribution) {
  auto s = parse_scenario(R"({"groups": [{"spawn": {"rect": {"min": [-40, -40], "max": [40, 40]}},
      "waypoints": [{"point": [0, 0]}], "speed": {"mean": 1.34, "sd": 0.26, "min": 0.3, "max": 2.4}}]})",
                          "inline.json");
  ASSERT_TRUE(s.ok()) << s.message();
  const int n = 4000;
  auto a = expand_agents(*s, n, 11);
  ASSERT_TRUE(a.ok()) << a.message();
  double sum = 0.0, sum2 = 0.0;
  for (float v : a->desired_speeds_m_s) {
    ASSERT_GE(v, 0.3f);
    ASSERT_LE(v, 2.4f);
    sum += v;
    sum2 += double(v) * v;
  }
  const double mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean);
  EXPECT_NEAR(mean, 1.34, 4.0 * 0.26 / std::sqrt(n));
  EXPECT_NEAR(sd, 0.26, 0.02);
}

TEST(Scenario, AgentCountLimits) {
  auto s = load_scenario_by_name("plaza", scenarios());
  ASSERT_TRUE(s.ok());
  auto zero = expand_agents(*s, 0, 1);
  ASSERT_TRUE(zero.ok());
  EXPECT_EQ(zero->size(), 0u);
  EXPECT_TRUE(zero->waypoint_begin.empty());
  EXPECT_FALSE(expand_agents(*s, -1, 1).ok());
  auto million = expand_agents(*s, 1'000'000, 1);
  ASSERT_FALSE(million.ok());
  EXPECT_NE(million.message().find("1000000 agents"), std::string::npos) << million.message();
}

struct BadCase {
  const char* file;
  const char* expected;  // must appear in the message, after the file name
};

TEST(Scenario, MalformedFilesNameTheFileAndField) {
  const BadCase cases[] = {
      {"bad_speed_mean.json", "groups[1].speed.mean: expected a number in (0, 10]"},
      {"syntax_error.json", "invalid JSON: parse error at line 3"},
      {"unknown_field.json", "walls[0].segmnet: unknown field"},
      {"missing_groups.json", "groups: expected an array of 1 to 256 agent groups"},
      {"short_point.json", "groups[0].spawn.rect.min: expected [x, z]"},
      {"inverted_rect.json", "groups[0].spawn.rect.max: expected max > min"},
      {"zero_length_wall.json", "walls[1]: segment 1 has zero length"},
      {"bad_at_goal.json", "groups[0].at_goal: expected \"stop\" or \"remove\""},
      {"no_goal.json", "groups[0].waypoints: expected at least one waypoint or random_goals"},
      {"ring_waypoint.json", "groups[0].waypoints[1].ring: a ring is only allowed as a spawn"},
      {"attention_out_of_range.json", "groups[0].attention: expected a number in [0, 1]"},
      {"radius_as_string.json", "groups[0].radius: expected a number in (0, 1]"},
      {"random_goals_count.json", "groups[0].random_goals.count: expected an integer in [1, 1000]"},
      {"bad_target.json", "attention_targets[0].radius: expected a number > 0"},
  };
  for (const BadCase& c : cases) {
    const std::string path = test::source_path(std::string("tests/data/bad/scenarios/") + c.file);
    ASSERT_TRUE(std::filesystem::exists(path)) << path;
    auto s = load_scenario(path);
    ASSERT_FALSE(s.ok()) << c.file;
    EXPECT_EQ(s.message().rfind(path + ": ", 0), 0u) << s.message();
    EXPECT_NE(s.message().find(c.expected), std::string::npos)
        << c.file << ": got \"" << s.message() << "\"";
  }
}

TEST(Scenario, MissingFileAndUnknownName) {
  auto missing = load_scenario("/nonexistent/dir/x.json");
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.message().find("/nonexistent/dir/x.json: cannot open"), std::string::npos);
  auto unknown = load_scenario_by_name("no_such_scenario", scenarios());
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.message().find("unknown scenario 'no_such_scenario'"), std::string::npos);
  EXPECT_NE(unknown.message().find("corridor"), std::string::npos) << "lists what is available";
  // A path is loaded as a path, whatever the folder.
  auto by_path = load_scenario_by_name(scenarios() + "/circle.json", "/nonexistent");
  EXPECT_TRUE(by_path.ok()) << by_path.message();
}

// Issue #12: nlohmann reports a number beyond a double as out_of_range, not parse_error; it must
// be an error naming the file and line, not std::terminate.
TEST(Scenario, NumberTooLargeForADoubleNamesFileAndLine) {
  const std::string path = test::scratch_dir("scenario_bad") + "/huge.json";
  std::ofstream(path) << "{\n  \"name\": \"huge\",\n  \"default_agents\": 1e400\n}\n";
  auto s = load_scenario(path);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.message().rfind(path + ": invalid JSON: number too large at line 3", 0), 0u)
      << s.message();
  EXPECT_NE(s.message().find("'1e400'"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("range of a double"), std::string::npos) << s.message();
}

TEST(Scenario, DirectoryIsNotAScenarioFile) {
  const std::string dir = test::scratch_dir("scenario_bad") + "/folder.json";
  std::filesystem::create_directories(dir);
  auto s = load_scenario(dir);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.message(), dir + ": is a directory, expected a scenario file");
}

TEST(Scenario, EnvironmentOverridesScenarioDir) {
  const std::string dir = test::scratch_dir("scenario_env");
  ASSERT_EQ(setenv("GAITKEEPER_SCENARIOS", dir.c_str(), 1), 0);
  EXPECT_EQ(scenario_dir(), dir);
  ASSERT_EQ(unsetenv("GAITKEEPER_SCENARIOS"), 0);
  EXPECT_TRUE(std::filesystem::exists(scenario_dir() + "/corridor.json")) << scenario_dir();
}

TEST(Scenario, WallShapesBecomeSegments) {
  auto s = parse_scenario(R"({"walls": [{"rect": {"min": [0, 0], "max": [2, 1]}},
                                        {"polyline": [[0, 5], [1, 5], [1, 6]], "closed": true},
                                        {"polyline": [[0, 9], [1, 9], [1, 10]]}],
                              "groups": [{"spawn": {"circle": {"center": [5, 5], "radius": 1}},
                                          "waypoints": [{"point": [5, 0]}]}]})",
                          "walls.json");
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(s->walls.size(), 4u + 3u + 2u);
  // Default bounds cover everything mentioned.
  EXPECT_LE(s->bounds_min.x, 0.0f);
  EXPECT_GE(s->bounds_max.y, 10.0f);
}


// A group without "radius" takes the drawn body's radius; one that sets it keeps it; the expanded
// agents carry the result.
TEST(Scenario, BodyRadiusFillsOnlyGroupsWithoutARadius) {
  auto s = parse_scenario(R"({"groups": [
      {"spawn": {"rect": {"min": [-5, -5], "max": [5, 5]}}, "waypoints": [{"point": [0, 9]}]},
      {"spawn": {"rect": {"min": [-5, 6], "max": [5, 9]}}, "waypoints": [{"point": [0, -9]}],
       "radius": 0.2}]})",
                          "radius.json");
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_FALSE(s->groups[0].radius_given);
  EXPECT_TRUE(s->groups[1].radius_given);
  Scenario body = *s;
  apply_body_radius(&body, 0.31f);
  EXPECT_FLOAT_EQ(body.groups[0].radius_m, 0.31f);
  EXPECT_FLOAT_EQ(body.groups[1].radius_m, 0.2f);
  auto a = expand_agents(body, 10, 3);
  ASSERT_TRUE(a.ok()) << a.message();
  for (size_t i = 0; i < a->size(); ++i) {
    EXPECT_FLOAT_EQ(a->radii_m[i], a->group[i] == 0 ? 0.31f : 0.2f);
  }
  // Out of (0, 1]: nothing changes.
  Scenario same = *s;
  apply_body_radius(&same, 0.0f);
  apply_body_radius(&same, 1.5f);
  EXPECT_FLOAT_EQ(same.groups[0].radius_m, s->groups[0].radius_m);
}

}  // namespace
}  // namespace gk
