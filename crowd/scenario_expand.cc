// Scaling a scenario to an agent count and drawing the agents for a seed. Spawn areas are filled
// from a jittered grid whose cell is 1/sqrt(max_spawn_density) (never less than a body diameter
// plus a gap), so agents never start overlapping each other or a wall.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <unordered_set>

#include <glm/geometric.hpp>

#include "crowd/scenario.h"
#include "crowd/spatial_grid.h"

namespace gk {
namespace {

constexpr float kSpawnGap = 0.1f;  // free space between two spawned bodies [m]
constexpr float kWallGap = 0.05f;  // free space between a spawned body and a wall [m]

// splitmix64: tiny, fast and the same on every platform (std::normal_distribution is not).
class Rng {
 public:
  explicit Rng(uint64_t seed) : state_(seed) {}
  uint64_t next() {
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  float uniform() { return static_cast<float>(next() >> 40) * (1.0f / 16777216.0f); }  // [0, 1)
  float uniform(float lo, float hi) { return lo + (hi - lo) * uniform(); }
  float normal() {  // Box-Muller
    const double u1 = (static_cast<double>(next() >> 11) + 1.0) * (1.0 / 9007199254740992.0);
    const double u2 = static_cast<double>(next() >> 11) * (1.0 / 9007199254740992.0);
    return static_cast<float>(std::sqrt(-2.0 * std::log(u1)) *
                              std::cos(2.0 * std::numbers::pi * u2));
  }

 private:
  uint64_t state_;
};

// Rect and circle spawns of all groups share one lattice, so groups whose areas overlap can never
// take the same slot; its cell fits the largest body of the scenario.
float lattice_cell(const Scenario& s) {
  float cell = 1.0f / std::sqrt(s.max_spawn_density);
  for (const AgentGroup& g : s.groups) cell = std::max(cell, 2.0f * g.radius_m + kSpawnGap);
  return cell;
}
float max_radius(const Scenario& s) {
  float r = 0.0f;
  for (const AgentGroup& g : s.groups) r = std::max(r, g.radius_m);
  return r;
}

bool clear_of_walls(const Scenario& s, glm::vec2 p, float clearance) {
  for (const WallSegment& w : s.walls) {
    if (distance_to_segment(p, w.a, w.b) < clearance) return false;
  }
  return true;
}

// Spawn slots of a group: lattice points (rect, circle) or ring slots, each of which may be moved
// by up to `jitter` in x and z without touching a wall or a neighbouring slot's body.
struct SpawnSlots {
  std::vector<glm::vec2> centers;
  std::vector<int64_t> keys;  // lattice point of each centre (empty for rings)
  float jitter = 0.0f;
};

SpawnSlots spawn_slots(const Scenario& s, const AgentGroup& g) {
  SpawnSlots out;
  const Area& a = g.spawn;
  if (a.shape == Area::Shape::kRing) {
    const float cell =
        std::max(1.0f / std::sqrt(s.max_spawn_density), 2.0f * g.radius_m + kSpawnGap);
    out.jitter = std::max(0.0f, 0.5f * (cell - 2.0f * g.radius_m - kSpawnGap));
    const float reach = g.radius_m + out.jitter * std::numbers::sqrt2_v<float> + kWallGap;
    // Slots a chord of `cell` apart (the arc would put small rings' bodies too close).
    const double half_angle = cell < 2.0f * a.radius_m ? std::asin(cell / (2.0 * a.radius_m)) : 0.0;
    const auto num =
        half_angle > 0.0 ? static_cast<size_t>(std::min(std::numbers::pi / half_angle, 4.0e6)) : 1;
    for (size_t k = 0; k < num; ++k) {
      const double angle =
          2.0 * std::numbers::pi * static_cast<double>(k) / static_cast<double>(num);
      const glm::vec2 p = a.center + a.radius_m * glm::vec2(std::cos(angle), std::sin(angle));
      if (clear_of_walls(s, p, reach)) out.centers.push_back(p);
    }
    return out;
  }
  const float cell = lattice_cell(s);
  out.jitter = std::max(0.0f, 0.5f * (cell - 2.0f * max_radius(s) - kSpawnGap));
  const float reach = g.radius_m + out.jitter * std::numbers::sqrt2_v<float> + kWallGap;
  const glm::vec2 lo = a.shape == Area::Shape::kRect ? a.min : a.center - glm::vec2(a.radius_m);
  const glm::vec2 hi = a.shape == Area::Shape::kRect ? a.max : a.center + glm::vec2(a.radius_m);
  // Lattice points are (i + 1/2, k + 1/2) * cell; those inside the area are the slots.
  const double x0 = std::ceil(lo.x / cell - 0.5), x1 = std::floor(hi.x / cell - 0.5);
  const double z0 = std::ceil(lo.y / cell - 0.5), z1 = std::floor(hi.y / cell - 0.5);
  if (x1 < x0 || z1 < z0 || (x1 - x0 + 1) * (z1 - z0 + 1) > 16.0e6) return out;
  for (auto k = static_cast<int64_t>(z0); k <= static_cast<int64_t>(z1); ++k) {
    for (auto i = static_cast<int64_t>(x0); i <= static_cast<int64_t>(x1); ++i) {
      const glm::vec2 p =
          cell * glm::vec2(static_cast<float>(i) + 0.5f, static_cast<float>(k) + 0.5f);
      if (a.shape == Area::Shape::kCircle &&
          glm::length(p - a.center) + out.jitter * std::numbers::sqrt2_v < float >> a.radius_m) {
        continue;
      }
      if (!clear_of_walls(s, p, reach)) continue;
      out.centers.push_back(p);
      out.keys.push_back(static_cast<int64_t>(static_cast<uint64_t>(i) << 32) ^
                         static_cast<int64_t>(static_cast<uint32_t>(k)));
    }
  }
  return out;
}

// Bounding box of a spawn area, to tell which groups may compete for lattice slots.
std::pair<glm::vec2, glm::vec2> box_of(const Area& a) {
  if (a.shape == Area::Shape::kRect) return {a.min, a.max};
  return {a.center - glm::vec2(a.radius_m), a.center + glm::vec2(a.radius_m)};
}
bool boxes_overlap(const Area& a, const Area& b) {
  const auto [alo, ahi] = box_of(a);
  const auto [blo, bhi] = box_of(b);
  return alo.x <= bhi.x && blo.x <= ahi.x && alo.y <= bhi.y && blo.y <= ahi.y;
}
// Slots group g is sure to find free, whatever earlier groups with overlapping areas picked.
size_t guaranteed_slots(const Scenario& s, const std::vector<int>& counts, size_t g,
                        size_t num_slots) {
  if (s.groups[g].spawn.shape == Area::Shape::kRing) return num_slots;
  size_t taken = 0;
  for (size_t h = 0; h < g; ++h) {
    if (s.groups[h].spawn.shape != Area::Shape::kRing &&
        boxes_overlap(s.groups[h].spawn, s.groups[g].spawn)) {
      taken += static_cast<size_t>(counts[h]);
    }
  }
  return num_slots > taken ? num_slots - taken : 0;
}

// Agents per group: shares of num_agents by fraction, rounded by largest remainder so they sum up.
std::vector<int> group_counts(const Scenario& s, int num_agents) {
  double total = 0.0;
  for (const AgentGroup& g : s.groups) total += g.fraction;
  std::vector<int> counts(s.groups.size(), 0);
  std::vector<std::pair<double, size_t>> remainders;
  int assigned = 0;
  for (size_t i = 0; i < s.groups.size(); ++i) {
    const double exact = num_agents * s.groups[i].fraction / total;
    counts[i] = static_cast<int>(std::floor(exact));
    assigned += counts[i];
    remainders.emplace_back(exact - counts[i], i);
  }
  std::stable_sort(remainders.begin(), remainders.end(),
                   [](const auto& l, const auto& r) { return l.first > r.first; });
  for (size_t k = 0; assigned < num_agents; ++k, ++assigned) ++counts[remainders[k].second];
  return counts;
}

Area scaled(Area a, float f) {
  a.min *= f;
  a.max *= f;
  a.center *= f;
  a.radius_m *= f;
  return a;
}

Scenario scaled(const Scenario& in, float f) {
  Scenario s = in;
  s.scale *= f;
  s.bounds_min *= f;
  s.bounds_max *= f;
  for (WallSegment& w : s.walls) w = {w.a * f, w.b * f};
  for (AttentionTarget& t : s.attention_targets) t.position *= f;
  for (AgentGroup& g : s.groups) {
    g.spawn = scaled(g.spawn, f);
    g.random_goal_area = scaled(g.random_goal_area, f);
    for (WaypointSpec& w : g.waypoints) w.area = scaled(w.area, f);
  }
  return s;
}

bool fits(const Scenario& s, const std::vector<int>& counts) {
  for (size_t i = 0; i < s.groups.size(); ++i) {
    if (counts[i] > 0 &&
        guaranteed_slots(s, counts, i, spawn_slots(s, s.groups[i]).centers.size()) <
            size_t(counts[i])) {
      return false;
    }
  }
  return true;
}

// A point in `a`, away from walls by `clearance` if a few tries find such a point.
glm::vec2 sample_area(const Scenario& s, const Area& a, float clearance, Rng& rng) {
  glm::vec2 p = a.center;
  for (int attempt = 0; attempt < 16; ++attempt) {
    switch (a.shape) {
      case Area::Shape::kPoint:
        return a.center;
      case Area::Shape::kRect:
        p = glm::vec2(rng.uniform(a.min.x, a.max.x), rng.uniform(a.min.y, a.max.y));
        break;
      case Area::Shape::kCircle:
      case Area::Shape::kRing: {
        const float r =
            a.shape == Area::Shape::kRing ? a.radius_m : a.radius_m * std::sqrt(rng.uniform());
        const float angle = 2.0f * std::numbers::pi_v<float> * rng.uniform();
        p = a.center + r * glm::vec2(std::cos(angle), std::sin(angle));
        break;
      }
    }
    if (clear_of_walls(s, p, clearance)) return p;
  }
  return p;
}

}  // namespace

float scale_factor_for(const Scenario& scenario, int num_agents) {
  if (num_agents <= 0 || scenario.groups.empty()) return 1.0f;
  num_agents = std::min(num_agents, kMaxScenarioAgents);
  const std::vector<int> counts = group_counts(scenario, num_agents);
  // First guess from the area alone (slots grow with f^2, ring slots with f), then grow until
  // the real slot count, with walls taken out, suffices.
  float f = 1.0f;
  for (size_t i = 0; i < scenario.groups.size(); ++i) {
    const AgentGroup& g = scenario.groups[i];
    const double slots = static_cast<double>(spawn_slots(scenario, g).centers.size());
    const double need = counts[i];
    if (need <= slots) continue;
    const double ratio = need / std::max(slots, 0.5);
    f = std::max(
        f, static_cast<float>(g.spawn.shape == Area::Shape::kRing ? ratio : std::sqrt(ratio)));
  }
  for (int iteration = 0; iteration < 200 && !fits(scaled(scenario, f), counts); ++iteration) {
    f *= 1.05f;
  }
  return f;
}

Scenario scale_scenario(const Scenario& scenario, int num_agents) {
  const float f = scale_factor_for(scenario, num_agents);
  return f == 1.0f ? scenario : scaled(scenario, f);
}

void apply_body_radius(Scenario* scenario, float radius_m) {
  if (!(radius_m > 0.0f && radius_m <= 1.0f)) return;
  for (AgentGroup& g : scenario->groups) {
    if (!g.radius_given) g.radius_m = radius_m;
  }
}

Result<ScenarioAgents> expand_agents(const Scenario& s, int num_agents, uint64_t seed) {
  if (num_agents < 0 || num_agents > kMaxScenarioAgents) {
    return Status::Error(s.source + ": " + std::to_string(num_agents) +
                         " agents requested; expected 0 to " + std::to_string(kMaxScenarioAgents));
  }
  if (s.groups.empty() && num_agents > 0) {
    return Status::AtField(s.source, "groups", "no agent groups to spawn agents from");
  }
  ScenarioAgents out;
  const auto n = static_cast<size_t>(num_agents);
  out.positions.reserve(n);
  out.waypoint_begin.reserve(n + 1);
  const std::vector<int> counts = group_counts(s, num_agents);
  std::unordered_set<int64_t> taken;  // lattice slots in use
  for (size_t gi = 0; gi < s.groups.size(); ++gi) {
    const AgentGroup& g = s.groups[gi];
    const std::string field = "groups[" + std::to_string(gi) + "].spawn";
    SpawnSlots slots = spawn_slots(s, g);
    if (!slots.keys.empty()) {  // drop lattice slots that earlier groups took
      size_t kept = 0;
      for (size_t k = 0; k < slots.centers.size(); ++k) {
        if (taken.count(slots.keys[k])) continue;
        slots.centers[kept] = slots.centers[k];
        slots.keys[kept++] = slots.keys[k];
      }
      slots.centers.resize(kept);
      slots.keys.resize(kept);
    }
    const auto count = static_cast<size_t>(counts[gi]);
    if (count > slots.centers.size()) {
      return Status::AtField(s.source, field,
                             std::to_string(count) + " agents do not fit at max_spawn_density " +
                                 std::to_string(s.max_spawn_density) + " (room for " +
                                 std::to_string(slots.centers.size()) +
                                 "); scale the scenario first (gk::scale_scenario)");
    }
    // Each group has its own stream, so adding agents to one group leaves the others unchanged.
    Rng rng(seed ^ (0x51A7E5C0FFEEull * (gi + 1)));
    if (g.spawn.shape == Area::Shape::kRing) {
      // Spread the agents evenly round the ring instead of taking random slots.
      std::vector<glm::vec2> even(count);
      for (size_t k = 0; k < count; ++k) even[k] = slots.centers[k * slots.centers.size() / count];
      slots.centers = std::move(even);
    } else {
      for (size_t k = 0; k < count; ++k) {  // partial Fisher-Yates: random distinct slots
        const size_t pick = k + static_cast<size_t>(rng.next() % (slots.centers.size() - k));
        std::swap(slots.centers[k], slots.centers[pick]);
        std::swap(slots.keys[k], slots.keys[pick]);
        taken.insert(slots.keys[k]);
      }
    }
    const float clearance = g.radius_m + 0.2f;
    for (size_t k = 0; k < count; ++k) {
      const glm::vec2 p = slots.centers[k] + glm::vec2(rng.uniform(-slots.jitter, slots.jitter),
                                                       rng.uniform(-slots.jitter, slots.jitter));
      const float speed = std::clamp(g.speed.mean_m_s + g.speed.sd_m_s * rng.normal(),
                                     g.speed.min_m_s, g.speed.max_m_s);
      out.positions.push_back(p);
      out.desired_speeds_m_s.push_back(speed);
      out.radii_m.push_back(g.radius_m);
      out.waypoint_begin.push_back(static_cast<uint32_t>(out.waypoints.size()));
      for (const WaypointSpec& w : g.waypoints) {
        out.waypoints.push_back(w.kind == WaypointSpec::Kind::kAntipode
                                    ? 2.0f * w.area.center - p
                                    : sample_area(s, w.area, clearance, rng));
      }
      for (int r = 0; r < g.random_goal_count; ++r) {
        out.waypoints.push_back(sample_area(s, g.random_goal_area, clearance, rng));
      }
      out.loop_waypoints.push_back(g.loop ? 1 : 0);
      out.remove_at_goal.push_back(g.remove_at_goal ? 1 : 0);
      out.goal_radii_m.push_back(g.goal_radius_m);
      out.attentive.push_back(rng.uniform() < g.attention ? 1 : 0);
      out.group.push_back(static_cast<uint16_t>(gi));
    }
  }
  // The closing entry; none at all for an empty crowd (both forms are accepted by the sims).
  if (n > 0) out.waypoint_begin.push_back(static_cast<uint32_t>(out.waypoints.size()));
  return out;
}

}  // namespace gk
