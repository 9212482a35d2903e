// Social forces: the guarantees (walls, speed caps, determinism, feedback) and the behaviour
// (goals reached in bounded time, personal space, looking at exhibits), each checked against
// bounds derived here from the scenario, not from the simulator's own output.
#include "crowd/social_forces.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <set>
#include <vector>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "crowd/spatial_grid.h"
#include "tests/test_data.h"

namespace gk {
namespace {

constexpr float kDt = 1.0f / 60.0f;
constexpr double kPi = std::numbers::pi;

struct World {
  Scenario scenario;
  ScenarioAgents agents;
  std::unique_ptr<SocialForces> sim;
};

void make(const std::string& name, int n, uint64_t seed, const SocialForceParams& params,
          World* out) {
  auto loaded = load_scenario_by_name(name, test::source_path("data/scenarios"));
  ASSERT_TRUE(loaded.ok()) << loaded.message();
  out->scenario = scale_scenario(*loaded, n);
  auto agents = expand_agents(out->scenario, n, seed);
  ASSERT_TRUE(agents.ok()) << agents.message();
  out->agents = std::move(agents).value();
  auto sim = SocialForces::create(out->scenario, out->agents, params);
  ASSERT_TRUE(sim.ok()) << sim.message();
  out->sim = std::move(sim).value();
}

// Test-local geometry (double precision), independent of crowd/spatial_grid.
double cross(glm::dvec2 a, glm::dvec2 b, glm::dvec2 c) {
  return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}
bool strictly_crosses(glm::vec2 p0, glm::vec2 p1, const WallSegment& w) {
  const glm::dvec2 a(p0), b(p1), c(w.a), d(w.b);
  const double d1 = cross(a, b, c), d2 = cross(a, b, d), d3 = cross(c, d, a), d4 = cross(c, d, b);
  return ((d1 > 0) != (d2 > 0)) && ((d3 > 0) != (d4 > 0)) && d1 != 0 && d2 != 0 && d3 != 0 &&
         d4 != 0;
}
double wall_distance(glm::vec2 p, const WallSegment& w) {
  const glm::dvec2 a(w.a), ab = glm::dvec2(w.b) - a, q(p);
  const double t = std::clamp(glm::dot(q - a, ab) / glm::dot(ab, ab), 0.0, 1.0);
  return glm::length(q - (a + t * ab));
}
double angle_between(float a, float b) {  // [rad], in [0, pi]
  return std::abs(std::remainder(double(a) - double(b), 2.0 * kPi));
}
double direction_angle(glm::vec2 d) { return std::atan2(d.x, d.y); }  // theta convention

// Runs `steps` steps; every step checks that no agent's step crossed a wall and that every agent
// stays at least half its radius from every wall.
void run_checking_walls(World& s, int steps) {
  std::map<uint32_t, glm::vec2> previous;
  for (int t = 0; t < steps; ++t) {
    ASSERT_TRUE(s.sim->step(kDt).ok());
    const AgentFrame f = s.sim->frame();
    for (size_t i = 0; i < f.size(); ++i) {
      const auto it = previous.find(f.ids[i]);
      for (const WallSegment& w : s.scenario.walls) {
        if (it != previous.end()) {
          ASSERT_FALSE(strictly_crosses(it->second, f.positions[i], w))
              << "agent " << f.ids[i] << " crossed a wall at step " << t;
        }
        ASSERT_GE(wall_distance(f.positions[i], w), 0.5 * s.agents.radii_m[f.ids[i]])
            << "agent " << f.ids[i] << " step " << t;
      }
    }
    previous.clear();
    for (size_t i = 0; i < f.size(); ++i) previous[f.ids[i]] = f.positions[i];
  }
}

TEST(SocialForces, NoAgentCrossesAWallInCorridor) {
  World s;
  ASSERT_NO_FATAL_FAILURE(make("corridor", 60, 1, {}, &s));
  run_checking_walls(s, 40 * 60);
}

TEST(SocialForces, NoAgentCrossesAWallInBottleneck) {
  // Dense: 200 agents push toward the door and against the walls beside it.
  World s;
  ASSERT_NO_FATAL_FAILURE(make("bottleneck", 200, 2, {}, &s));
  run_checking_walls(s, 40 * 60);
  // The room empties through the door: agents are removed at the exit.
  EXPECT_GT(s.sim->stats().removed, 50u);
  EXPECT_EQ(s.sim->stats().removed + s.sim->stats().live, 200u);
}

// Without wall forces only the hard constraint stands between the crowd and the walls.
TEST(SocialForces, NoAgentCrossesAWallWithoutWallForces) {
  SocialForceParams params;
  params.wall_strength_m_s2 = 0.0f;
  params.contact_forces = false;
  World s;
  ASSERT_NO_FATAL_FAILURE(make("bottleneck", 200, 3, params, &s));
  run_checking_walls(s, 20 * 60);
}

TEST(SocialForces, SpeedsNeverExceedTheAgentsMax) {
  World s;
  ASSERT_NO_FATAL_FAILURE(make("plaza", 150, 3, {}, &s));
  for (int t = 0; t < 20 * 60; ++t) {
    ASSERT_TRUE(s.sim->step(kDt).ok());
    const AgentFrame f = s.sim->frame();
    for (size_t i = 0; i < f.size(); ++i) {
      const double max = 1.3 * s.agents.desired_speeds_m_s[f.ids[i]];  // max = 1.3 x desired
      ASSERT_LE(glm::length(f.velocities[i]), max * (1.0 + 1e-5)) << "agent " << f.ids[i];
    }
  }
}

// Each agent must come within its goal radius of `goal_of(agent)` no later than 2.5 x the time
// its straight path takes at its desired speed, plus 5 s to accelerate and to get through.
void expect_goals_reached(World& s, const std::function<glm::vec2(size_t)>& goal_of,
                          float goal_radius) {
  const size_t n = s.agents.size();
  std::vector<double> bound(n);
  double longest = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const double path = glm::length(goal_of(i) - s.agents.positions[i]);
    bound[i] = 2.5 * path / s.agents.desired_speeds_m_s[i] + 5.0;
    longest = std::max(longest, bound[i]);
  }
  std::vector<double> reached(n, -1.0);
  for (int t = 1; t * kDt <= longest + kDt; ++t) {
    ASSERT_TRUE(s.sim->step(kDt).ok());
    const AgentFrame f = s.sim->frame();
    for (size_t k = 0; k < f.size(); ++k) {
      const uint32_t i = f.ids[k];
      if (reached[i] < 0.0 && glm::length(f.positions[k] - goal_of(i)) <= goal_radius + 1e-3f) {
        reached[i] = t * kDt;
      }
    }
  }
  for (size_t i = 0; i < n; ++i) {
    EXPECT_GE(reached[i], 0.0) << "agent " << i << " never reached its goal";
    EXPECT_LE(reached[i], bound[i]) << "agent " << i;
  }
}

TEST(SocialForces, CorridorAgentsReachTheFarEndInBoundedTime) {
  World s;
  ASSERT_NO_FATAL_FAILURE(make("corridor", 60, 4, {}, &s));
  const ScenarioAgents& a = s.agents;
  expect_goals_reached(
      s, [&](size_t i) { return a.waypoints[a.waypoint_begin[i]]; }, 0.5f);
}

TEST(SocialForces, CircleAgentsReachTheirAntipodesInBoundedTime) {
  World s;
  ASSERT_NO_FATAL_FAILURE(make("circle", 24, 5, {}, &s));
  const ScenarioAgents& a = s.agents;
  expect_goals_reached(
      s, [&](size_t i) { return -a.positions[i]; }, 0.3f);  // centre (0, 0)
  EXPECT_EQ(s.sim->stats().reached_goal, 24u);
}

// Personal space in moderate density: centres never closer than 0.3 m (bodies are 0.5 m wide).
TEST(SocialForces, ClosestApproachStaysAboveAFloor) {
  for (const auto& [name, n] : std::vector<std::pair<std::string, int>>{
           {"corridor", 60}, {"crossing", 80}, {"plaza", 150}, {"gallery", 40}}) {
    SCOPED_TRACE(name);
    World s;
    ASSERT_NO_FATAL_FAILURE(make(name, n, 6, {}, &s));
    double closest = std::numeric_limits<double>::max();
    for (int t = 0; t < 30 * 60; ++t) {
      ASSERT_TRUE(s.sim->step(kDt).ok());
      if (t % 3) continue;
      const AgentFrame f = s.sim->frame();
      for (size_t i = 0; i < f.size(); ++i) {
        for (size_t j = i + 1; j < f.size(); ++j) {
          closest = std::min<double>(closest, glm::length(f.positions[i] - f.positions[j]));
        }
      }
    }
    EXPECT_GE(closest, 0.3);
  }
}

std::vector<char> snapshot(const SocialForces& sim) {
  const AgentFrame f = sim.frame();
  std::vector<char> bytes;
  auto add = [&](const void* p, size_t size) {
    bytes.insert(bytes.end(), static_cast<const char*>(p), static_cast<const char*>(p) + size);
  };
  add(f.ids.data(), f.ids.size_bytes());
  add(f.positions.data(), f.positions.size_bytes());
  add(f.velocities.data(), f.velocities.size_bytes());
  add(f.thetas.data(), f.thetas.size_bytes());
  return bytes;
}

TEST(SocialForces, BitIdenticalForASeedAndAnyThreadCount) {
  auto run = [](uint64_t seed, int threads, const char* scenario) {
    SocialForceParams params;
    params.threads = threads;
    World s;
    make(scenario, 1500, seed, params, &s);
    std::vector<char> all;
    for (int t = 0; t < 90; ++t) {
      EXPECT_TRUE(s.sim->step(kDt).ok());
      if (t % 30 == 29) {
        const auto snap = snapshot(*s.sim);
        all.insert(all.end(), snap.begin(), snap.end());
      }
    }
    return all;
  };
  for (const char* scenario : {"plaza", "bottleneck"}) {
    SCOPED_TRACE(scenario);
    const auto single = run(7, 1, scenario);
    ASSERT_FALSE(single.empty());
    EXPECT_TRUE(single == run(7, 1, scenario)) << "same seed, different run";
    EXPECT_TRUE(single == run(7, 2, scenario)) << "threads = 2 differs from threads = 1";
    EXPECT_FALSE(single == run(8, 1, scenario)) << "the seed has no effect";
  }
}

// Gallery: walking past an exhibit, theta turns toward it while v keeps going along the hall.
TEST(SocialForces, GalleryVisitorsLookAtExhibitsTheyPass) {
  World s;
  ASSERT_NO_FATAL_FAILURE(make("gallery", 40, 8, {}, &s));
  const auto& targets = s.scenario.attention_targets;
  ASSERT_FALSE(targets.empty());
  int looking = 0, free_walking = 0, free_walking_aligned = 0;
  for (int t = 0; t < 40 * 60; ++t) {
    ASSERT_TRUE(s.sim->step(kDt).ok());
    if (t < 120) continue;  // let everyone get going
    const AgentFrame f = s.sim->frame();
    for (size_t i = 0; i < f.size(); ++i) {
      const float speed = glm::length(f.velocities[i]);
      if (speed < 0.5f) continue;
      const double walk = direction_angle(f.velocities[i]);
      bool near_any = false;
      for (const AttentionTarget& target : targets) {
        const glm::vec2 d = target.position - f.positions[i];
        if (glm::length(d) > target.radius_m + 1.0f) continue;
        near_any = true;
        // Looks at this exhibit: theta within 10 deg of it, at least 30 deg away from v.
        if (angle_between(f.thetas[i], direction_angle(d)) < 10.0 * kPi / 180.0 &&
            angle_between(f.thetas[i], walk) > 30.0 * kPi / 180.0) {
          ++looking;
        }
      }
      if (!near_any && s.agents.attentive[f.ids[i]]) {
        ++free_walking;
        if (angle_between(f.thetas[i], walk) < 25.0 * kPi / 180.0) ++free_walking_aligned;
      }
      // Never twisted beyond the max look twist (100 deg) plus smoothing lag, away from the
      // hall's ends (|x| > 11 m), where visitors turn round and theta lags behind a reversed v.
      if (std::abs(f.positions[i].x) < 10.0f) {
        EXPECT_LT(angle_between(f.thetas[i], walk), 120.0 * kPi / 180.0)
            << f.positions[i].x << " id " << f.ids[i] << " t " << t;
      }
    }
  }
  EXPECT_GT(looking, 40 * 60) << "visitors should look at exhibits for a good while";
  ASSERT_GT(free_walking, 1000);
  EXPECT_GT(free_walking_aligned, 0.9 * free_walking) << "away from exhibits theta follows v";
}

TEST(SocialForces, WithoutTargetsThetaFollowsTheWalkingDirection) {
  World s;
  ASSERT_NO_FATAL_FAILURE(make("corridor", 40, 9, {}, &s));
  int aligned = 0, samples = 0;
  for (int t = 0; t < 20 * 60; ++t) {
    ASSERT_TRUE(s.sim->step(kDt).ok());
    const AgentFrame f = s.sim->frame();
    for (size_t i = 0; i < f.size() && t > 120; ++i) {
      if (glm::length(f.velocities[i]) < 0.8f) continue;
      ++samples;
      aligned += angle_between(f.thetas[i], direction_angle(f.velocities[i])) < 20.0 * kPi / 180.0;
    }
  }
  ASSERT_GT(samples, 10000);
  EXPECT_GT(aligned, 0.95 * samples);
}

TEST(SocialForces, StandingAgentsDoNotSpin) {
  World s;
  ASSERT_NO_FATAL_FAILURE(make("circle", 12, 10, {}, &s));
  for (int t = 0; t < 30 * 60; ++t) ASSERT_TRUE(s.sim->step(kDt).ok());  // all arrive and stand
  std::vector<float> before(s.sim->frame().thetas.begin(), s.sim->frame().thetas.end());
  for (int t = 0; t < 60; ++t) ASSERT_TRUE(s.sim->step(kDt).ok());
  const AgentFrame f = s.sim->frame();
  for (size_t i = 0; i < f.size(); ++i) {
    ASSERT_LT(glm::length(f.velocities[i]), 0.1f) << "agent " << i << " should be standing";
    EXPECT_LT(angle_between(f.thetas[i], before[i]), 5.0 * kPi / 180.0) << "agent " << i;
  }
}

TEST(SocialForces, FeedbackIsHonoured) {
  World s;
  ASSERT_NO_FATAL_FAILURE(make("plaza", 20, 11, {}, &s));
  ASSERT_EQ(s.sim->feedback_policy(), FeedbackPolicy::kHonoured);
  ASSERT_TRUE(s.sim->step(kDt).ok());
  const AgentFrame f0 = s.sim->frame();
  const size_t n = f0.size();
  std::vector<glm::vec2> p(f0.positions.begin(), f0.positions.end());
  std::vector<glm::vec2> v(f0.velocities.begin(), f0.velocities.end());
  std::vector<float> th(f0.thetas.begin(), f0.thetas.end());
  std::vector<uint8_t> flag(n, 0);
  const std::vector<glm::vec2> p_before = p, v_before = v;
  flag[3] = 1;
  p[3] += glm::vec2(0.05f, -0.04f);
  v[3] = glm::vec2(0.2f, 0.3f);
  th[3] = 1.25f;
  ASSERT_TRUE(s.sim->apply_feedback({flag, p, v, th}).ok());
  const AgentFrame f1 = s.sim->frame();
  EXPECT_EQ(f1.positions[3], p[3]);
  EXPECT_EQ(f1.velocities[3], v[3]);
  EXPECT_FLOAT_EQ(f1.thetas[3], 1.25f);
  for (size_t i = 0; i < n; ++i) {
    if (i == 3) continue;
    EXPECT_EQ(f1.positions[i], p_before[i]);
    EXPECT_EQ(f1.velocities[i], v_before[i]);
  }
  // The next step starts from the fed-back state: one step moves at most max speed x dt.
  ASSERT_TRUE(s.sim->step(kDt).ok());
  const float max_step = 1.3f * s.agents.desired_speeds_m_s[f1.ids[3]] * kDt;
  EXPECT_LE(glm::length(s.sim->frame().positions[3] - p[3]), max_step * 1.001f);
}

TEST(SocialForces, InvalidFeedbackIsRejectedAndChangesNothing) {
  World s;
  ASSERT_NO_FATAL_FAILURE(make("corridor", 10, 12, {}, &s));
  ASSERT_TRUE(s.sim->step(kDt).ok());
  const auto before = snapshot(*s.sim);
  const AgentFrame f = s.sim->frame();
  const size_t n = f.size();
  std::vector<glm::vec2> p(f.positions.begin(), f.positions.end());
  std::vector<glm::vec2> v(f.velocities.begin(), f.velocities.end());
  std::vector<float> th(f.thetas.begin(), f.thetas.end());
  std::vector<uint8_t> flag(n, 1);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  auto try_with = [&](auto mutate) {
    auto p2 = p, v2 = v;
    auto th2 = th;
    mutate(p2, v2, th2);
    return s.sim->apply_feedback({flag, p2, v2, th2});
  };
  const Status nan_v = try_with([&](auto&, auto& v2, auto&) { v2[5].x = nan; });
  ASSERT_FALSE(nan_v.ok());
  EXPECT_NE(nan_v.message().find("non-finite"), std::string::npos) << nan_v.message();
  EXPECT_FALSE(try_with([&](auto&, auto&, auto& t2) { t2[0] = INFINITY; }).ok());
  EXPECT_FALSE(try_with([&](auto& p2, auto&, auto&) { p2[9].y = nan; }).ok());
  const Status fast = try_with([&](auto&, auto& v2, auto&) { v2[2] = glm::vec2(300.0f, 0.0f); });
  ASSERT_FALSE(fast.ok());
  EXPECT_NE(fast.message().find("max_feedback_speed_m_s"), std::string::npos) << fast.message();
  EXPECT_FALSE(try_with([&](auto& p2, auto&, auto&) { p2[1] += glm::vec2(50.0f, 0.0f); }).ok());
  std::vector<uint8_t> short_flags(n - 1, 1);
  EXPECT_FALSE(s.sim->apply_feedback({short_flags, p, v, th}).ok());
  EXPECT_TRUE(before == snapshot(*s.sim)) << "a rejected feedback must not change the state";
}

TEST(SocialForces, FeedbackCannotMoveAnAgentThroughAWall) {
  Scenario scenario;
  scenario.walls = {{{-5.0f, 0.0f}, {5.0f, 0.0f}}};
  ScenarioAgents a;
  a.positions = {{0.0f, -0.6f}};
  a.desired_speeds_m_s = {1.3f};
  a.radii_m = {0.25f};
  a.waypoint_begin = {0, 1};
  a.waypoints = {{0.0f, -5.0f}};
  a.loop_waypoints = {0};
  auto sim = SocialForces::create(scenario, a);
  ASSERT_TRUE(sim.ok()) << sim.message();
  const std::vector<uint8_t> flag{1};
  const std::vector<glm::vec2> p{{0.0f, 0.6f}}, v{{0.0f, 0.0f}};
  const std::vector<float> th{0.0f};
  ASSERT_TRUE((*sim)->apply_feedback({flag, p, v, th}).ok());
  EXPECT_LE((*sim)->frame().positions[0].y, -0.25f * 0.999f) << "stays on its side, a body away";
}

TEST(SocialForces, ZeroAgentsAndCapacityLimits) {
  auto loaded = load_scenario_by_name("plaza", test::source_path("data/scenarios"));
  ASSERT_TRUE(loaded.ok());
  auto none = expand_agents(*loaded, 0, 1);
  ASSERT_TRUE(none.ok());
  auto empty = SocialForces::create(*loaded, *none);
  ASSERT_TRUE(empty.ok()) << empty.message();
  ASSERT_TRUE((*empty)->step(kDt).ok());
  EXPECT_EQ((*empty)->frame().size(), 0u);
  EXPECT_TRUE((*empty)->apply_feedback({}).ok());

  const Scenario scaled = scale_scenario(*loaded, 600);
  auto many = expand_agents(scaled, 600, 1);
  ASSERT_TRUE(many.ok());
  SocialForceParams small;
  small.max_agents = 500;
  auto refused = SocialForces::create(scaled, *many, small);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.message().find("600 agents exceed max_agents 500"), std::string::npos)
      << refused.message();
  SocialForceParams absurd;
  absurd.max_agents = 10'000'000;
  EXPECT_FALSE(validate(absurd).ok());
}

TEST(SocialForces, InvalidParametersAndStepsAreErrors) {
  SocialForceParams p;
  EXPECT_TRUE(validate(p).ok());
  p.relaxation_time_s = 0.0f;
  EXPECT_NE(validate(p).message().find("relaxation_time_s"), std::string::npos);
  p = {};
  p.field_of_view_weight = 1.5f;
  EXPECT_FALSE(validate(p).ok());
  p = {};
  p.agent_range_m = NAN;
  EXPECT_FALSE(validate(p).ok());
  World s;
  ASSERT_NO_FATAL_FAILURE(make("circle", 4, 1, {}, &s));
  EXPECT_FALSE(s.sim->step(0.0f).ok());
  EXPECT_FALSE(s.sim->step(NAN).ok());
  EXPECT_FALSE(s.sim->step(-1.0f).ok());
  EXPECT_DOUBLE_EQ(s.sim->time_s(), 0.0);
}

// The wall constraint on its own, with random moves (some longer than the grid's reach) around a
// zig-zag of walls: the move it allows never crosses a wall.
TEST(WallGrid, ConstrainedMovesNeverCrossWalls) {
  std::vector<WallSegment> walls;
  for (int k = 0; k < 8; ++k) {
    walls.push_back({{float(k), (k % 2) ? 1.0f : -1.0f}, {float(k + 1), (k % 2) ? -1.0f : 1.0f}});
  }
  walls.push_back({{-1.0f, 2.0f}, {9.0f, 2.0f}});
  const WallGrid grid(walls, 2.0f, 1.5f);
  uint64_t state = 12345;
  auto uniform = [&](float lo, float hi) {  // LCG: enough to scatter test moves
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return lo + (hi - lo) * float(state >> 40) / float(1 << 24);
  };
  int slid_or_stopped = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const glm::vec2 from(uniform(-1.0f, 9.0f), uniform(-3.0f, 1.9f));
    const float reach = trial % 10 == 0 ? 4.0f : 0.3f;
    const glm::vec2 to = from + glm::vec2(uniform(-reach, reach), uniform(-reach, reach));
    const glm::vec2 got = grid.constrain_move(from, to, 0.2f);
    bool from_on_wall = false;
    for (const WallSegment& w : walls) from_on_wall |= wall_distance(from, w) < 1e-4;
    if (from_on_wall) continue;
    for (const WallSegment& w : walls) {
      ASSERT_FALSE(strictly_crosses(from, got, w)) << "trial " << trial;
    }
    slid_or_stopped += got != to;
  }
  EXPECT_GT(slid_or_stopped, 1000) << "the walls should have been in the way often";
}

// One step of a packed cluster against the model of social_forces.h written out here in double
// precision. Every agent has about 100 neighbours within the cutoff (more than the simulator
// buffers at once) and two agents share one spot (separated by id), so every path of the
// neighbour sum is exercised.
TEST(SocialForces, OneStepOfAPackedClusterFollowsTheModel) {
  constexpr int kAgents = 101;
  constexpr float kStep = 0.01f;
  uint64_t state = 12345;
  auto uniform = [&state](double lo, double hi) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return lo + (hi - lo) * double(state >> 40) / double(1 << 24);
  };
  Scenario scenario;
  scenario.bounds_min = glm::vec2(-10.0f);
  scenario.bounds_max = glm::vec2(10.0f);
  ScenarioAgents a;
  std::vector<glm::vec2> velocities;
  for (int i = 0; i < kAgents; ++i) {
    const double r = 0.9 * std::sqrt(uniform(0.0, 1.0)), phi = uniform(0.0, 2.0 * kPi);
    a.positions.emplace_back(i == 1 ? a.positions[0]  // agent 1 on agent 0's spot
                                    : glm::vec2(r * std::cos(phi), r * std::sin(phi)));
    a.desired_speeds_m_s.push_back(float(uniform(1.0, 1.4)));
    a.radii_m.push_back(float(uniform(0.05, 0.2)));
    a.waypoint_begin.push_back(uint32_t(i));
    const double goal = uniform(0.0, 2.0 * kPi);
    a.waypoints.emplace_back(8.0 * std::cos(goal), 8.0 * std::sin(goal));
    a.loop_waypoints.push_back(0);
    const double speed = uniform(0.0, 0.6), heading = uniform(0.0, 2.0 * kPi);
    velocities.emplace_back(speed * std::cos(heading), speed * std::sin(heading));
  }
  a.waypoint_begin.push_back(uint32_t(kAgents));
  const SocialForceParams params;
  auto sim = SocialForces::create(scenario, a, params);
  ASSERT_TRUE(sim.ok()) << sim.message();
  const std::vector<uint8_t> all(kAgents, 1);
  const std::vector<float> thetas(kAgents, 0.0f);
  ASSERT_TRUE((*sim)->apply_feedback({all, a.positions, velocities, thetas}).ok());
  ASSERT_TRUE((*sim)->step(kStep).ok());
  const AgentFrame f = (*sim)->frame();
  ASSERT_EQ(f.size(), size_t(kAgents));

  const SocialForceParams& p = params;
  int checked = 0;
  for (int i = 0; i < kAgents; ++i) {
    ASSERT_EQ(f.ids[i], uint32_t(i));
    const glm::dvec2 pi(a.positions[i]), vi(velocities[i]);
    const glm::dvec2 to_goal = glm::dvec2(a.waypoints[i]) - pi;
    const glm::dvec2 e = to_goal / glm::length(to_goal);
    glm::dvec2 acc = (double(a.desired_speeds_m_s[i]) * e - vi) / double(p.relaxation_time_s);
    double magnitude = glm::length(acc);  // sum of the terms' sizes, for the tolerance
    const glm::dvec2 facing = glm::length(vi) > 0.1 ? vi / glm::length(vi) : e;
    const glm::dvec2 right(-facing.y, facing.x);
    int neighbours = 0;
    for (int j = 0; j < kAgents; ++j) {
      const glm::dvec2 d = pi - glm::dvec2(a.positions[j]);
      if (j == i || glm::dot(d, d) >= double(p.neighbour_radius_m) * p.neighbour_radius_m) continue;
      ++neighbours;
      const double dist = glm::length(d);
      const glm::dvec2 n = dist > 0.0 ? d / dist : glm::dvec2(i < j ? -1.0 : 1.0, 0.0);
      const double radii = double(a.radii_m[i]) + a.radii_m[j];
      const double cos_phi = -glm::dot(n, facing);
      const double lambda = p.field_of_view_weight;
      const double w = lambda + (1.0 - lambda) * 0.5 * (1.0 + cos_phi);
      const glm::dvec2 y = (glm::dvec2(velocities[j]) - vi) * double(p.anticipation_time_s);
      const glm::dvec2 dy = d - y;
      const double sum = dist + glm::length(dy);
      const double b = 0.5 * std::sqrt(std::max(sum * sum - glm::dot(y, y), 0.0));
      const double stretch = sum / (2.0 * std::max(b, 0.1 * sum + 1e-6));
      const glm::dvec2 dir = 0.5 * (n + dy / glm::length(dy));
      const double repulsion = p.agent_strength_m_s2 * std::exp((radii - b) / p.agent_range_m) *
                               w * stretch;
      acc += repulsion * dir;
      magnitude += repulsion;
      if (cos_phi > 0.0) acc += p.side_step * repulsion * cos_phi * right;
      if (radii - dist > 0.0) {
        acc += double(p.body_stiffness_s2) * (radii - dist) * n;
        magnitude += double(p.body_stiffness_s2) * (radii - dist);
      }
    }
    EXPECT_GE(neighbours, 80) << "agent " << i;
    glm::dvec2 expected = vi + acc * double(kStep);
    const double max_speed = double(p.max_speed_factor) * a.desired_speeds_m_s[i];
    if (glm::length(expected) > max_speed) expected *= max_speed / glm::length(expected);
    // Float sums, and a velocity read back from a float position step of 1 cm or less.
    const double tolerance = 1e-5 * magnitude * kStep + 5e-5;
    EXPECT_NEAR(f.velocities[i].x, expected.x, tolerance) << "agent " << i;
    EXPECT_NEAR(f.velocities[i].y, expected.y, tolerance) << "agent " << i;
    ++checked;
  }
  EXPECT_EQ(checked, kAgents);
}

// The uniform grid's 3x3-cell search finds exactly the pairs closer than a cell, as brute force;
// rank() inverts order().
TEST(UniformGrid, NeighbourSearchMatchesBruteForce) {
  std::vector<glm::vec2> points;
  uint64_t state = 99;
  for (int i = 0; i < 2000; ++i) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    const float x = float(state >> 40) / float(1 << 24);
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    const float z = float(state >> 40) / float(1 << 24);
    points.emplace_back(60.0f * x - 5.0f, 40.0f * z - 5.0f);  // some outside the grid's bounds
  }
  auto grid = UniformGrid::create({0.0f, 0.0f}, {50.0f, 30.0f}, 2.0f, points.size());
  ASSERT_TRUE(grid.ok());
  grid->build(points);
  for (uint32_t i = 0; i < points.size(); ++i) ASSERT_EQ(grid->order()[grid->rank()[i]], i);
  std::set<std::pair<uint32_t, uint32_t>> found, expected;
  for (uint32_t i = 0; i < points.size(); ++i) {
    const auto [cx, cz] = grid->cell_of(points[i]);
    for (int z = cz - 1; z <= cz + 1; ++z) {
      const auto [b, e] = grid->row_range(z, cx - 1, cx + 1);
      for (uint32_t k = b; k < e; ++k) {
        const uint32_t j = grid->order()[k];
        if (j > i && glm::length(points[i] - points[j]) < 2.0f) found.emplace(i, j);
      }
    }
    for (uint32_t j = i + 1; j < points.size(); ++j) {
      if (glm::length(points[i] - points[j]) < 2.0f) expected.emplace(i, j);
    }
  }
  EXPECT_GT(expected.size(), 1000u);
  EXPECT_EQ(found, expected);
}

}  // namespace
}  // namespace gk
