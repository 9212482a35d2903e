// DetourCrowd behind CrowdSource on a hand-built corridor with two baffles: goals reached, walls
// never crossed, speeds within the maximum, runs reproducible, feedback honoured, bad input
// reported.

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <vector>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "crowd/detour_crowd.h"
#include "tests/test_data.h"

namespace gk {
namespace {

constexpr float kDt = 1.0f / 60.0f;
// Detour's velocity sampling accepts candidates up to max speed + 1 mm/s; allow that and float
// rounding, nothing more.
constexpr float kSpeedSlack_m_s = 0.0011f;

// A 20 m x 4 m corridor along x (walls at z = +-2), closed at x = -3 from below up to z = 0.3 and
// at x = +3 from above down to z = -0.3, so walkers have to weave. The bounds hug the side walls so
// nothing walkable is left outside them.
Scenario corridor() {
  Scenario s;
  s.name = "test_corridor";
  s.bounds_min = {-10.0f, -2.3f};
  s.bounds_max = {10.0f, 2.3f};
  s.walls = {{{-10.0f, 2.0f}, {10.0f, 2.0f}},
             {{-10.0f, -2.0f}, {10.0f, -2.0f}},
             {{-3.0f, -2.0f}, {-3.0f, 0.3f}},
             {{3.0f, 2.0f}, {3.0f, -0.3f}}};
  return s;
}

void add_agent(ScenarioAgents* a, glm::vec2 p, float speed, float radius,
               std::vector<glm::vec2> waypoints, bool loop = false) {
  if (a->waypoint_begin.empty()) a->waypoint_begin.push_back(0);
  a->positions.push_back(p);
  a->desired_speeds_m_s.push_back(speed);
  a->radii_m.push_back(radius);
  a->waypoints.insert(a->waypoints.end(), waypoints.begin(), waypoints.end());
  a->waypoint_begin.push_back(static_cast<uint32_t>(a->waypoints.size()));
  a->loop_waypoints.push_back(loop ? 1 : 0);
}

// Four walkers each way, crossing both baffles.
ScenarioAgents two_flows() {
  ScenarioAgents a;
  const float zs[4] = {-1.2f, -0.4f, 0.4f, 1.2f};
  for (int k = 0; k < 4; ++k) {
    add_agent(&a, {-8.5f, zs[k]}, 1.2f + 0.05f * k, 0.25f + 0.01f * k, {{8.0f, zs[k]}});
    add_agent(&a, {8.5f, zs[k]}, 1.3f - 0.05f * k, 0.3f - 0.01f * k, {{-8.0f, zs[k]}});
  }
  return a;
}

std::unique_ptr<CrowdSource> make(const Scenario& s, const ScenarioAgents& a) {
  Result<std::unique_ptr<CrowdSource>> r = make_detour_crowd(s, a);
  EXPECT_TRUE(r.ok()) << r.message();
  return r.ok() ? std::move(*r) : nullptr;
}

double cross(glm::dvec2 a, glm::dvec2 b) { return a.x * b.y - a.y * b.x; }

// Proper or touching intersection of segments pq and ab.
bool segments_intersect(glm::vec2 p, glm::vec2 q, glm::vec2 a, glm::vec2 b) {
  const glm::dvec2 r = glm::dvec2(q - p), s = glm::dvec2(b - a), ap = glm::dvec2(a - p);
  const double d = cross(r, s);
  if (std::abs(d) < 1e-12) return false;  // parallel: a walker moving along a wall never crosses
  const double t = cross(ap, s) / d, u = cross(ap, r) / d;
  return t >= 0.0 && t <= 1.0 && u >= 0.0 && u <= 1.0;
}

double distance_to_segment(glm::vec2 p, const WallSegment& w) {
  const glm::dvec2 ab = glm::dvec2(w.b - w.a), ap = glm::dvec2(p - w.a);
  const double t = std::clamp(glm::dot(ap, ab) / glm::dot(ab, ab), 0.0, 1.0);
  return glm::length(ap - t * ab);
}

TEST(DetourCrowd, CorridorWalkersReachGoalsWithinWallsAndSpeeds) {
  const Scenario scenario = corridor();
  const ScenarioAgents agents = two_flows();
  auto crowd = make(scenario, agents);
  ASSERT_TRUE(crowd);
  EXPECT_EQ(crowd->capacity(), agents.size());
  EXPECT_EQ(crowd->feedback_policy(), FeedbackPolicy::kHonoured);
  std::vector<glm::vec2> prev(crowd->frame().positions.begin(), crowd->frame().positions.end());
  double min_wall_distance = 1e9, max_speed_excess = -1e9;
  bool all_arrived = false;
  int steps = 0;
  for (; steps < 60 * 60 && !all_arrived; ++steps) {
    ASSERT_TRUE(crowd->step(kDt).ok());
    const AgentFrame f = crowd->frame();
    ASSERT_EQ(f.size(), agents.size());
    all_arrived = true;
    for (size_t i = 0; i < f.size(); ++i) {
      ASSERT_EQ(f.ids[i], i);
      for (const WallSegment& w : scenario.walls) {
        ASSERT_FALSE(segments_intersect(prev[i], f.positions[i], w.a, w.b))
            << "agent " << i << " crossed a wall at step " << steps;
        min_wall_distance = std::min(min_wall_distance, distance_to_segment(f.positions[i], w));
      }
      const float max_speed = agents.desired_speeds_m_s[i];
      max_speed_excess =
          std::max(max_speed_excess, double(glm::length(f.velocities[i]) - max_speed));
      const glm::vec2 goal = agents.waypoints[agents.waypoint_begin[i]];
      all_arrived = all_arrived && glm::length(f.positions[i] - goal) < 0.5f;
      prev[i] = f.positions[i];
    }
  }
  EXPECT_TRUE(all_arrived) << "after " << steps * kDt << " s";
  // Centres stay out of the 0.2 m wall boxes by about the agent radius; 0.2 m leaves room for
  // Recast's voxel rounding and contour simplification (a cell or two of 0.1 m).
  EXPECT_GE(min_wall_distance, 0.2);
  EXPECT_LE(max_speed_excess, kSpeedSlack_m_s);
  std::cout << "corridor: all arrived after " << steps * kDt << " s, closest to a wall "
            << min_wall_distance << " m, max |v| - max speed " << max_speed_excess << " m/s\n";
}

TEST(DetourCrowd, SameInputsGiveIdenticalRuns) {
  const Scenario scenario = corridor();
  const ScenarioAgents agents = two_flows();
  auto first = make(scenario, agents);
  auto second = make(scenario, agents);
  ASSERT_TRUE(first && second);
  for (int step = 0; step < 600; ++step) {
    ASSERT_TRUE(first->step(kDt).ok());
    ASSERT_TRUE(second->step(kDt).ok());
    const AgentFrame a = first->frame(), b = second->frame();
    ASSERT_EQ(a.size(), b.size());
    for (size_t i = 0; i < a.size(); ++i) {
      ASSERT_EQ(a.positions[i], b.positions[i]) << "step " << step << " agent " << i;
      ASSERT_EQ(a.velocities[i], b.velocities[i]);
      ASSERT_EQ(a.thetas[i], b.thetas[i]);
    }
  }
}

TEST(DetourCrowd, FeedbackIsHonouredButNeverThroughWalls) {
  const Scenario scenario = corridor();
  ScenarioAgents agents;
  add_agent(&agents, {-8.0f, 0.0f}, 1.2f, 0.3f, {{-5.0f, 0.0f}});
  add_agent(&agents, {6.0f, 1.0f}, 1.2f, 0.3f, {{8.0f, 1.0f}});
  auto crowd = make(scenario, agents);
  ASSERT_TRUE(crowd);
  for (int step = 0; step < 60; ++step) ASSERT_TRUE(crowd->step(kDt).ok());
  const glm::vec2 p0 = crowd->frame().positions[0];
  const glm::vec2 p1 = crowd->frame().positions[1];
  // Agent 0 is nudged sideways with a slower velocity and a turned torso; agent 1 is asked to go
  // through the wall at z = 2 and must stop on this side of it.
  const uint8_t has[2] = {1, 1};
  const glm::vec2 pos[2] = {p0 + glm::vec2(0.0f, 0.25f), glm::vec2(p1.x, 2.6f)};
  const glm::vec2 vel[2] = {{0.5f, 0.1f}, {0.0f, 0.0f}};
  const float theta[2] = {1.0f, -2.0f};
  ASSERT_TRUE(crowd->apply_feedback({has, pos, vel, theta}).ok());
  AgentFrame f = crowd->frame();
  EXPECT_NEAR(f.positions[0].x, pos[0].x, 1e-3f);
  EXPECT_NEAR(f.positions[0].y, pos[0].y, 1e-3f);
  EXPECT_EQ(f.velocities[0], vel[0]);
  EXPECT_EQ(f.thetas[0], theta[0]);
  EXPECT_LT(f.positions[1].y, 2.0f - 0.1f);
  EXPECT_GT(f.positions[1].y, p1.y);  // it did slide toward the wall
  // The next step starts from the fed-back state: Detour turns the velocity toward its own plan
  // at most max_accel * dt, so the agent moves about vel * dt from where it was put.
  ASSERT_TRUE(crowd->step(kDt).ok());
  f = crowd->frame();
  const float max_move = (glm::length(vel[0]) + 8.0f * kDt) * kDt;
  EXPECT_LE(glm::length(f.positions[0] - pos[0]), max_move * 1.01f);
  // Badly sized or non-finite feedback is refused.
  EXPECT_FALSE(crowd->apply_feedback({std::span(has, 1), pos, vel, theta}).ok());
  const glm::vec2 bad[2] = {glm::vec2(NAN), glm::vec2(0.0f)};
  EXPECT_FALSE(crowd->apply_feedback({has, bad, vel, theta}).ok());
}

TEST(DetourCrowd, ZeroAgents) {
  auto crowd = make(corridor(), ScenarioAgents{});
  ASSERT_TRUE(crowd);
  EXPECT_EQ(crowd->capacity(), 0u);
  ASSERT_TRUE(crowd->step(kDt).ok());
  EXPECT_EQ(crowd->frame().size(), 0u);
  EXPECT_TRUE(crowd->apply_feedback({}).ok());
  EXPECT_FALSE(crowd->step(0.0f).ok());
  ScenarioAgents none;
  none.waypoint_begin = {0};  // the "n + 1 offsets" form of an empty chain list is fine too
  EXPECT_TRUE(make_detour_crowd(corridor(), none).ok());
}

TEST(DetourCrowd, StartsOffTheWalkableAreaAreSnappedOrRefused) {
  const Scenario scenario = corridor();
  ScenarioAgents near_wall;
  // Inside the baffle wall at x = -3: within a metre of the walkable area, so snapped beside it.
  add_agent(&near_wall, {-3.0f, -1.0f}, 1.2f, 0.3f, {{-8.0f, -1.0f}});
  auto crowd = make(scenario, near_wall);
  ASSERT_TRUE(crowd);
  const glm::vec2 p = crowd->frame().positions[0];
  EXPECT_GE(distance_to_segment(p, scenario.walls[2]), 0.2);
  EXPECT_LE(glm::length(p - glm::vec2(-3.0f, -1.0f)), 1.0f);

  ScenarioAgents far_away = near_wall;
  far_away.positions[0] = {0.0f, 50.0f};
  Result<std::unique_ptr<CrowdSource>> r = make_detour_crowd(scenario, far_away);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.message().find("agents.positions[0]"), std::string::npos) << r.message();
  EXPECT_NE(r.message().find("not on the walkable area"), std::string::npos) << r.message();

  ScenarioAgents bad = near_wall;
  bad.waypoints[0] = {40.0f, 0.0f};
  r = make_detour_crowd(scenario, bad);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.message().find("agents.waypoints[0]"), std::string::npos) << r.message();
  bad = near_wall;
  bad.radii_m[0] = 0.0f;
  EXPECT_FALSE(make_detour_crowd(scenario, bad).ok());
  bad = near_wall;
  bad.positions[0] = glm::vec2(NAN);
  EXPECT_FALSE(make_detour_crowd(scenario, bad).ok());
  bad = near_wall;
  bad.loop_waypoints.clear();
  EXPECT_FALSE(make_detour_crowd(scenario, bad).ok());
  DetourParams params;
  params.avoidance_quality = 4;
  EXPECT_FALSE(make_detour_crowd(scenario, near_wall, params).ok());
  params = DetourParams{};
  params.cell_size_m = 0.0f;
  EXPECT_FALSE(make_detour_crowd(scenario, near_wall, params).ok());
  Scenario walled_in = scenario;
  walled_in.bounds_max = walled_in.bounds_min + glm::vec2(0.4f);  // thinner than two radii
  r = make_detour_crowd(walled_in, ScenarioAgents{});
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.message().find("walkable"), std::string::npos) << r.message();
}

// A looping chain between two points far apart is walked round and round.
TEST(DetourCrowd, LoopingWaypointChain) {
  ScenarioAgents agents;
  add_agent(&agents, {-7.0f, 1.0f}, 1.4f, 0.3f, {{-7.0f, 1.0f}, {-4.5f, -1.0f}}, true);
  auto crowd = make(corridor(), agents);
  ASSERT_TRUE(crowd);
  int visits = 0;
  bool near_second = false;
  for (int step = 0; step < 60 * 30; ++step) {
    ASSERT_TRUE(crowd->step(kDt).ok());
    const glm::vec2 p = crowd->frame().positions[0];
    const bool at_second = glm::length(p - glm::vec2(-4.5f, -1.0f)) < 1.0f;
    const bool at_first = glm::length(p - glm::vec2(-7.0f, 1.0f)) < 1.0f;
    if (at_second && !near_second) ++visits;
    if (at_second) near_second = true;
    if (at_first) near_second = false;
  }
  // 3.2 m each way at 1.4 m/s: several rounds in 30 s even with slow turns.
  EXPECT_GE(visits, 3);
}

TEST(DetourCrowd, AgentsLeavingAtTheirGoalVanishFromTheFrame) {
  // Two walkers: one leaves the scene at its goal, one stays there; ids stay stable.
  ScenarioAgents agents;
  add_agent(&agents, {-8.0f, -1.0f}, 1.4f, 0.3f, {{-5.0f, -1.0f}});
  add_agent(&agents, {-8.0f, 1.0f}, 1.4f, 0.3f, {{-5.0f, 1.0f}});
  agents.remove_at_goal = {1, 0};
  agents.goal_radii_m = {0.5f, 0.5f};
  auto crowd = make(corridor(), agents);
  ASSERT_TRUE(crowd);
  ASSERT_EQ(crowd->frame().size(), 2u);
  for (int step = 0; step < 60 * 10; ++step) ASSERT_TRUE(crowd->step(kDt).ok());
  // 3 m at 1.4 m/s takes about 2 s: after 10 s the first has gone, the second stands at its goal.
  const AgentFrame f = crowd->frame();
  ASSERT_EQ(f.size(), 1u);
  EXPECT_EQ(f.ids[0], 1u);
  EXPECT_LT(glm::length(f.positions[0] - glm::vec2(-5.0f, 1.0f)), 1.0f);
  // Feedback is index-aligned with the (shorter) frame.
  const uint8_t has[1] = {1};
  const glm::vec2 pos[1] = {f.positions[0]}, vel[1] = {{0.0f, 0.0f}};
  const float th[1] = {0.5f};
  EXPECT_TRUE(crowd->apply_feedback({has, pos, vel, th}).ok());
  EXPECT_FLOAT_EQ(crowd->frame().thetas[0], 0.5f);
}

// Every shipped scenario (loaded, scaled and expanded by the scenario module) runs on Detour:
// walls are never crossed, speeds stay within each agent's maximum and the crowd gets going.
TEST(DetourCrowd, RunsEveryScenarioFile) {
  const std::filesystem::path dir = test::source_path("data/scenarios");
  ASSERT_TRUE(std::filesystem::is_directory(dir)) << dir;
  int num_files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() != ".json") continue;
    ++num_files;
    const std::string name = entry.path().filename().string();
    Result<Scenario> loaded = load_scenario(entry.path().string());
    ASSERT_TRUE(loaded.ok()) << loaded.message();
    const int n = loaded->default_agents;
    const Scenario scenario = scale_scenario(*loaded, n);
    Result<ScenarioAgents> agents = expand_agents(scenario, n, 7);
    ASSERT_TRUE(agents.ok()) << agents.message();
    auto crowd = make(scenario, *agents);
    ASSERT_TRUE(crowd) << name;
    const std::vector<glm::vec2> start(crowd->frame().positions.begin(),
                                       crowd->frame().positions.end());
    std::vector<glm::vec2> prev = start;
    constexpr float kStep = 1.0f / 30.0f;
    for (int step = 0; step < 5 * 30; ++step) {
      ASSERT_TRUE(crowd->step(kStep).ok()) << name;
      const AgentFrame f = crowd->frame();
      for (size_t i = 0; i < f.size(); ++i) {
        for (const WallSegment& w : scenario.walls) {
          ASSERT_FALSE(segments_intersect(prev[i], f.positions[i], w.a, w.b))
              << name << ": agent " << i << " crossed a wall at step " << step;
        }
        ASSERT_LE(glm::length(f.velocities[i]), agents->desired_speeds_m_s[i] + kSpeedSlack_m_s)
            << name;
        prev[i] = f.positions[i];
      }
    }
    size_t moved = 0;
    for (size_t i = 0; i < start.size(); ++i) moved += glm::length(prev[i] - start[i]) > 1.0f;
    std::cout << name << ": " << n << " agents, " << moved << " moved over 1 m in 5 s\n";
    EXPECT_GE(moved * 2, start.size()) << name;
  }
  EXPECT_GT(num_files, 0);
}

// The bottleneck jam at 60 Hz: Detour's collision pushes move some agents by far more than they
// can walk in a step (an agent pushed 20 cm in a frame makes its drawn body jump). With the cap,
// no agent moves more than max_step_speed_factor times its top speed in a step. Returns the
// largest displacement per step over the agent's top speed step, over 600 steps.
float largest_step_over_walk(float factor) {
  const std::filesystem::path file = test::source_path("data/scenarios/bottleneck.json");
  Result<Scenario> loaded = load_scenario(file.string());
  EXPECT_TRUE(loaded.ok()) << loaded.message();
  const int n = loaded->default_agents;
  const Scenario scenario = scale_scenario(*loaded, n);
  Result<ScenarioAgents> agents = expand_agents(scenario, n, 1);
  EXPECT_TRUE(agents.ok()) << agents.message();
  DetourParams params;
  params.max_step_speed_factor = factor;
  auto made = make_detour_crowd(scenario, *agents, params);
  EXPECT_TRUE(made.ok()) << made.message();
  CrowdSource& crowd = **made;
  constexpr float kStep = 1.0f / 60.0f;
  std::vector<glm::vec2> prev(crowd.frame().positions.begin(), crowd.frame().positions.end());
  std::vector<uint32_t> ids(crowd.frame().ids.begin(), crowd.frame().ids.end());
  float worst = 0.0f;
  for (int step = 0; step < 600; ++step) {
    EXPECT_TRUE(crowd.step(kStep).ok());
    const AgentFrame f = crowd.frame();
    std::vector<glm::vec2> now(f.positions.begin(), f.positions.end());
    std::vector<uint32_t> now_ids(f.ids.begin(), f.ids.end());
    for (size_t i = 0; i < now.size(); ++i) {
      const auto it = std::find(ids.begin(), ids.end(), now_ids[i]);
      if (it == ids.end()) continue;
      const size_t k = static_cast<size_t>(it - ids.begin());
      // Agent ids are expand_agents' indices.
      const float walk = agents->desired_speeds_m_s[now_ids[i]] * kStep;
      worst = std::max(worst, glm::length(now[i] - prev[k]) / walk);
    }
    prev = std::move(now);
    ids = std::move(now_ids);
  }
  return worst;
}

TEST(DetourCrowd, NoAgentIsPushedFasterThanItCanBeMoved) {
  const float uncapped = largest_step_over_walk(0.0f);
  EXPECT_GT(uncapped, 4.0f) << "the jam no longer pushes agents hard: this test shows nothing";
  const float capped = largest_step_over_walk(DetourParams{}.max_step_speed_factor);
  std::cout << "largest step over the walking step: " << uncapped << " uncapped, " << capped
            << " capped\n";
  EXPECT_LE(capped, DetourParams{}.max_step_speed_factor + 0.01f);
}

}  // namespace
}  // namespace gk
