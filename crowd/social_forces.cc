#include "crowd/social_forces.h"

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cmath>
#include <numbers>
#include <string>

#include <emmintrin.h>
#include <xmmintrin.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "crowd/simd_atan2.h"
#include "crowd/simd_exp.h"
#include "crowd/spatial_grid.h"

namespace gk {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;
constexpr float kWallReach = 1.5f;   // walls listed per cell: covers a step plus a body [m]
constexpr float kGridMargin = 5.0f;  // agent grid extends this far past everything known [m]
constexpr size_t kGrain = 512;       // agents per parallel task: amortises scheduling
constexpr uint32_t kCandidates = 64;  // neighbours buffered before their forces are summed

float wrap_angle(float a) {
  // remainder() returns a itself within [-pi, pi] (2 kPi / 2 == kPi exactly): skip the call, most
  // angles are there already.
  if (std::abs(a) <= kPi) return a;
  return std::remainder(a, 2.0f * kPi);
}
// theta convention of crowd_source.h: 0 faces +z, pi/2 faces +x. atan2_1, not std::atan2: the
// same bits on every machine, and no unpredictable branches in the commit pass.
float angle_of(glm::vec2 d) { return atan2_1(d.x, d.y); }
bool finite(glm::vec2 v) { return std::isfinite(v.x) && std::isfinite(v.y); }

Status check_range(bool ok, const char* name, const char* expected) {
  return ok ? Status::Ok()
            : Status::Error(std::string("SocialForceParams::") + name + ": expected " + expected);
}

}  // namespace

Status validate(const SocialForceParams& p) {
  GK_RETURN_IF_ERROR(check_range(p.relaxation_time_s > 0.01f && p.relaxation_time_s <= 100.0f,
                                 "relaxation_time_s", "a value in (0.01, 100]"));
  GK_RETURN_IF_ERROR(check_range(p.max_speed_factor >= 1.0f && p.max_speed_factor <= 10.0f,
                                 "max_speed_factor", "a value in [1, 10]"));
  GK_RETURN_IF_ERROR(check_range(p.agent_strength_m_s2 >= 0.0f && p.agent_strength_m_s2 <= 1e3f,
                                 "agent_strength_m_s2", "a value in [0, 1000]"));
  GK_RETURN_IF_ERROR(check_range(p.agent_range_m >= 0.05f && p.agent_range_m <= 10.0f,
                                 "agent_range_m", "a value in [0.05, 10]"));
  GK_RETURN_IF_ERROR(check_range(p.field_of_view_weight >= 0.0f && p.field_of_view_weight <= 1.0f,
                                 "field_of_view_weight", "a value in [0, 1]"));
  GK_RETURN_IF_ERROR(check_range(p.anticipation_time_s >= 0.0f && p.anticipation_time_s <= 5.0f,
                                 "anticipation_time_s", "a value in [0, 5]"));
  GK_RETURN_IF_ERROR(
      check_range(p.side_step >= 0.0f && p.side_step <= 1.0f, "side_step", "a value in [0, 1]"));
  GK_RETURN_IF_ERROR(check_range(p.neighbour_radius_m > 0.1f && p.neighbour_radius_m <= 20.0f,
                                 "neighbour_radius_m", "a value in (0.1, 20]"));
  GK_RETURN_IF_ERROR(check_range(p.wall_strength_m_s2 >= 0.0f && p.wall_strength_m_s2 <= 1e3f,
                                 "wall_strength_m_s2", "a value in [0, 1000]"));
  GK_RETURN_IF_ERROR(check_range(p.wall_range_m >= 0.02f && p.wall_range_m <= 10.0f, "wall_range_m",
                                 "a value in [0.02, 10]"));
  GK_RETURN_IF_ERROR(check_range(p.wall_radius_m > 0.0f && p.wall_radius_m <= 20.0f,
                                 "wall_radius_m", "a value in (0, 20]"));
  GK_RETURN_IF_ERROR(check_range(p.body_stiffness_s2 >= 0.0f && p.body_stiffness_s2 <= 1e5f,
                                 "body_stiffness_s2", "a value in [0, 1e5]"));
  GK_RETURN_IF_ERROR(
      check_range(p.heading_time_s > 0.0f && p.heading_speed_m_s > 0.0f && p.look_time_s > 0.0f,
                  "heading_time_s/heading_speed_m_s/look_time_s", "values > 0"));
  GK_RETURN_IF_ERROR(check_range(p.max_look_twist_deg >= 0.0f && p.max_look_twist_deg <= 180.0f,
                                 "max_look_twist_deg", "a value in [0, 180]"));
  GK_RETURN_IF_ERROR(check_range(p.threads >= 0 && p.threads <= 256, "threads", "0 to 256"));
  GK_RETURN_IF_ERROR(
      check_range(p.max_agents >= 1 && p.max_agents <= 1'000'000, "max_agents", "1 to 1000000"));
  return check_range(p.max_feedback_speed_m_s > 0.0f && p.max_feedback_jump_m > 0.0f,
                     "max_feedback_speed_m_s/max_feedback_jump_m", "values > 0");
}

struct SocialForces::Impl {
  UniformGrid grid;
  WallGrid walls;
  std::unique_ptr<tbb::task_arena> arena;  // null when single-threaded
  std::atomic<bool> non_finite{false};
};

SocialForces::SocialForces(const SocialForceParams& params, size_t capacity)
    : params_(params), capacity_(capacity) {}
SocialForces::~SocialForces() = default;

Result<std::unique_ptr<SocialForces>> SocialForces::create(const Scenario& scenario,
                                                           const ScenarioAgents& agents,
                                                           const SocialForceParams& params) {
  GK_RETURN_IF_ERROR(validate(params));
  const size_t n = agents.size();
  const std::string where = "social forces (" + scenario.name + "): ";
  if (n > params.max_agents) {
    return Status::Error(where + std::to_string(n) + " agents exceed max_agents " +
                         std::to_string(params.max_agents) + " (SocialForceParams::max_agents)");
  }
  auto optional_ok = [n](size_t size) { return size == 0 || size == n; };
  if (agents.desired_speeds_m_s.size() != n || agents.radii_m.size() != n ||
      agents.loop_waypoints.size() != n ||
      (agents.waypoint_begin.size() != n + 1 && !(n == 0 && agents.waypoint_begin.empty())) ||
      (n > 0 && agents.waypoint_begin.back() > agents.waypoints.size()) ||
      !optional_ok(agents.remove_at_goal.size()) || !optional_ok(agents.goal_radii_m.size()) ||
      !optional_ok(agents.attentive.size())) {
    return Status::Error(where + "inconsistent ScenarioAgents array sizes");
  }
  for (size_t i = 0; i < n; ++i) {
    const bool ok = finite(agents.positions[i]) && agents.desired_speeds_m_s[i] > 0.0f &&
                    agents.desired_speeds_m_s[i] <= 10.0f && agents.radii_m[i] > 0.0f &&
                    agents.radii_m[i] <= 1.0f &&
                    agents.waypoint_begin[i] <= agents.waypoint_begin[i + 1] &&
                    (agents.goal_radii_m.empty() || agents.goal_radii_m[i] > 0.0f);
    if (!ok) return Status::Error(where + "agent " + std::to_string(i) + ": invalid initial state");
  }
  for (const glm::vec2& w : agents.waypoints) {
    if (!finite(w)) return Status::Error(where + "non-finite waypoint");
  }

  std::unique_ptr<SocialForces> sim(new SocialForces(params, n));
  SocialForces& s = *sim;
  glm::vec2 lo = scenario.bounds_min, hi = scenario.bounds_max;
  for (const glm::vec2& p : agents.positions) lo = glm::min(lo, p), hi = glm::max(hi, p);
  for (const glm::vec2& p : agents.waypoints) lo = glm::min(lo, p), hi = glm::max(hi, p);
  auto grid = UniformGrid::create(lo - kGridMargin, hi + kGridMargin, params.neighbour_radius_m, n);
  if (!grid.ok()) return Status::Error(where + grid.message());
  s.impl_ = std::make_unique<Impl>();
  s.impl_->grid = std::move(grid).value();
  s.impl_->walls = WallGrid(scenario.walls, 2.0f, std::max(params.wall_radius_m, kWallReach));
  if (params.threads != 1) {
    s.impl_->arena = std::make_unique<tbb::task_arena>(
        params.threads == 0 ? static_cast<int>(tbb::task_arena::automatic) : params.threads);
  }
  s.targets_ = scenario.attention_targets;
  s.waypoints_ = agents.waypoints;
  s.num_ = n;
  s.id_.resize(n);
  s.position_ = agents.positions;
  s.velocity_.assign(n, glm::vec2(0.0f));
  s.theta_.resize(n);
  s.heading_.resize(n);
  s.desired_speed_ = agents.desired_speeds_m_s;
  s.max_speed_.resize(n);
  s.radius_ = agents.radii_m;
  s.goal_radius_.assign(n, 0.5f);
  s.waypoint_.resize(n);
  s.waypoint_begin_.resize(n);
  s.waypoint_end_.resize(n);
  s.goal_.resize(n);
  s.loop_ = agents.loop_waypoints;
  s.remove_at_goal_.assign(n, 0);
  s.attentive_.assign(n, 1);
  s.arrived_.assign(n, 0);
  s.reached_.assign(n, 0);
  for (size_t i = 0; i < n; ++i) {
    s.id_[i] = static_cast<uint32_t>(i);
    s.max_speed_[i] = params.max_speed_factor * s.desired_speed_[i];
    if (!agents.goal_radii_m.empty()) s.goal_radius_[i] = agents.goal_radii_m[i];
    if (!agents.remove_at_goal.empty()) s.remove_at_goal_[i] = agents.remove_at_goal[i];
    if (!agents.attentive.empty()) s.attentive_[i] = agents.attentive[i];
    s.waypoint_begin_[i] = s.waypoint_[i] = agents.waypoint_begin[i];
    s.waypoint_end_[i] = agents.waypoint_begin[i + 1];
    s.arrived_[i] = s.waypoint_begin_[i] == s.waypoint_end_[i] ? 1 : 0;  // nowhere to go: stand
    s.goal_[i] = s.arrived_[i] ? s.position_[i] : s.waypoints_[s.waypoint_[i]];
    const glm::vec2 to_goal =
        s.arrived_[i] ? glm::vec2(0.0f, 1.0f) : s.waypoints_[s.waypoint_[i]] - s.position_[i];
    s.heading_[i] = s.theta_[i] = glm::dot(to_goal, to_goal) > 0.0f ? angle_of(to_goal) : 0.0f;
  }
  s.new_velocity_.resize(n);
  s.sorted_.resize(n);
  s.sorted_x_.assign(n + 3, 0.0f);  // a row's last group of four may read three past its end
  s.sorted_z_.assign(n + 3, 0.0f);
  return sim;
}

template <typename Fn>
void SocialForces::for_agents(Fn&& fn) {
  if (!impl_->arena) {
    fn(size_t{0}, num_);
    return;
  }
  impl_->arena->execute([&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, num_, kGrain),
                      [&](const tbb::blocked_range<size_t>& r) { fn(r.begin(), r.end()); });
  });
}

Status SocialForces::step(float dt_s) {
  if (!(dt_s > 0.0f && dt_s <= 0.5f)) {
    return Status::Error("social forces: step dt_s " + std::to_string(dt_s) +
                         ": expected a value in (0, 0.5]");
  }
  // Agents into grid cells (the cells in parallel, the counting sort serially), then their records
  // straight into cell order, so that neighbours are contiguous in memory.
  for_agents([&](size_t b, size_t e) {
    impl_->grid.assign_cells({position_.data(), num_}, b, e);
  });
  impl_->grid.sort_cells(num_);
  for_agents([&](size_t b, size_t e) { prepare(b, e); });
  impl_->non_finite.store(false, std::memory_order_relaxed);
  for_agents([&](size_t b, size_t e) { compute_velocities(b, e, dt_s); });
  for_agents([&](size_t b, size_t e) { commit(b, e, dt_s); });
  remove_finished();
  time_s_ += dt_s;
  if (impl_->non_finite.load(std::memory_order_relaxed)) {
    return Status::Error("social forces: non-finite velocity computed (agents held in place)");
  }
  return Status::Ok();
}

// Pass 0: the records of agents [begin, end), from their arrays read sequentially, written to
// their places in cell order (scattered writes, which do not stall like scattered reads).
void SocialForces::prepare(size_t begin, size_t end) {
  const auto rank = impl_->grid.rank();
  for (size_t i = begin; i < end; ++i) {
    const glm::vec2 pos = position_[i];
    glm::vec2 dir(0.0f);  // desired direction e
    if (!arrived_[i]) {
      const glm::vec2 to_goal = goal_[i] - pos;
      const float len = glm::length(to_goal);
      if (len > 1e-6f) dir = to_goal / len;
    }
    const uint32_t k = rank[i];
    sorted_[k] = Body{pos, velocity_[i], dir, radius_[i], desired_speed_[i]};
    sorted_x_[k] = pos.x;
    sorted_z_[k] = pos.y;
  }
}

namespace {
// _mm_max_ps(lo, x) below is std::max(x, lo), NaN and signed zeros included: (x < lo) ? lo : x.
__m128 select(__m128 mask, __m128 if_true, __m128 if_false) {
  return _mm_or_ps(_mm_and_ps(mask, if_true), _mm_andnot_ps(mask, if_false));
}
}  // namespace

// For each 4-bit mask of candidates kept, the lanes kept packed to the front, and their count.
struct alignas(16) Pack {
  int32_t lanes[4];
  uint32_t count;
};
constexpr Pack make_pack(uint32_t bits) {
  Pack pack{{0, 0, 0, 0}, 0};
  for (int32_t l = 0; l < 4; ++l) {
    if (bits & (1u << l)) pack.lanes[pack.count++] = l;
  }
  return pack;
}
constexpr Pack kPack[16] = {make_pack(0),  make_pack(1),  make_pack(2),  make_pack(3),
                            make_pack(4),  make_pack(5),  make_pack(6),  make_pack(7),
                            make_pack(8),  make_pack(9),  make_pack(10), make_pack(11),
                            make_pack(12), make_pack(13), make_pack(14), make_pack(15)};

// Lane l sums the forces of candidates l, l + 4, l + 8, ... of an agent, in that order; the lanes
// are added up once at the end in a fixed order, so the result depends only on the candidate
// list (cell order), never on the thread count. The parameters are broadcast once per pass.
struct SocialForces::ForceLanes {
  explicit ForceLanes(const SocialForceParams& p)
      : lambda(_mm_set1_ps(p.field_of_view_weight)),
        lambda_rest_half(_mm_set1_ps((1.0f - p.field_of_view_weight) * 0.5f)),
        anticipation(_mm_set1_ps(p.anticipation_time_s)),
        inv_b(_mm_set1_ps(1.0f / p.agent_range_m)),
        strength(_mm_set1_ps(p.agent_strength_m_s2)),
        side_step(_mm_set1_ps(p.side_step)),
        stiffness(_mm_set1_ps(p.contact_forces ? p.body_stiffness_s2 : 0.0f)) {}
  void set_agent(glm::vec2 position, glm::vec2 velocity, glm::vec2 facing, float radius,
                 uint32_t agent_index) {
    px = _mm_set1_ps(position.x), pz = _mm_set1_ps(position.y);
    vx = _mm_set1_ps(velocity.x), vz = _mm_set1_ps(velocity.y);
    fx = _mm_set1_ps(facing.x), fz = _mm_set1_ps(facing.y);
    ri = _mm_set1_ps(radius);
    index = agent_index;
    sum_x = sum_z = _mm_setzero_ps();
  }
  glm::vec2 total() const {
    alignas(16) float sx[4], sz[4];
    _mm_store_ps(sx, sum_x);
    _mm_store_ps(sz, sum_z);
    return {(sx[0] + sx[1]) + (sx[2] + sx[3]), (sz[0] + sz[1]) + (sz[2] + sz[3])};
  }
  __m128 lambda, lambda_rest_half, anticipation, inv_b, strength, side_step, stiffness;
  __m128 px, pz, vx, vz, fx, fz, ri;  // the agent; its right is (-fz, fx)
  uint32_t index = 0;  // in the state arrays; its id_ is read only for a neighbour on its spot
  __m128 sum_x, sum_z;
};

// The forces of the neighbours (sorted indices) candidates[0, count) on the agent of *f, four at
// a time with SSE2, added to its lane sums.
void SocialForces::add_neighbour_forces(const uint32_t* candidates, uint32_t count,
                                        ForceLanes* f) const {
  const __m128 zero = _mm_setzero_ps(), half = _mm_set1_ps(0.5f), one = _mm_set1_ps(1.0f);
  const __m128i lane = _mm_setr_epi32(0, 1, 2, 3);
  __m128 sum_x = f->sum_x, sum_z = f->sum_z;
  for (uint32_t g = 0; g < count; g += 4) {
    const uint32_t lanes = std::min(count - g, 4u);
    const __m128 used = _mm_castsi128_ps(_mm_cmplt_epi32(lane, _mm_set1_epi32(int(lanes))));
    // Unused lanes repeat the group's first neighbour (and add nothing). Each record starts with
    // position and velocity: four loads and a transpose give them lane by lane.
    const Body& o0 = sorted_[candidates[g]];
    const Body& o1 = sorted_[candidates[g + (lanes > 1 ? 1 : 0)]];
    const Body& o2 = sorted_[candidates[g + (lanes > 2 ? 2 : 0)]];
    const Body& o3 = sorted_[candidates[g + (lanes > 3 ? 3 : 0)]];
    static_assert(offsetof(Body, velocity) == 2 * sizeof(float));
    __m128 ox = _mm_loadu_ps(&o0.position.x), oz = _mm_loadu_ps(&o1.position.x);
    __m128 ovx = _mm_loadu_ps(&o2.position.x), ovz = _mm_loadu_ps(&o3.position.x);
    _MM_TRANSPOSE4_PS(ox, oz, ovx, ovz);
    const __m128 orad = _mm_setr_ps(o0.radius, o1.radius, o2.radius, o3.radius);
    const __m128 dx = _mm_sub_ps(f->px, ox), dz = _mm_sub_ps(f->pz, oz);
    const __m128 d2 = _mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dz, dz));
    __m128 dist = _mm_sqrt_ps(d2);
    const __m128 inv_dist = _mm_div_ps(one, dist);
    __m128 nx = _mm_mul_ps(dx, inv_dist), nz = _mm_mul_ps(dz, inv_dist);
    const __m128 same_spot = _mm_and_ps(used, _mm_cmple_ps(d2, _mm_set1_ps(1e-12f)));
    if (_mm_movemask_ps(same_spot)) {  // rare: separate the pair by id, so it pushes apart
      alignas(16) float sign[4] = {1.0f, 1.0f, 1.0f, 1.0f};
      const auto order = impl_->grid.order();
      for (uint32_t l = 0; l < lanes; ++l) {
        if (id_[f->index] < id_[order[candidates[g + l]]]) sign[l] = -1.0f;
      }
      nx = select(same_spot, _mm_load_ps(sign), nx);
      nz = select(same_spot, zero, nz);
      dist = select(same_spot, zero, dist);
    }
    const __m128 radii = _mm_add_ps(f->ri, orad);
    const __m128 overlap = _mm_sub_ps(radii, dist);
    const __m128 cos_phi =  // 1: the other is straight ahead
        _mm_xor_ps(_mm_set1_ps(-0.0f), _mm_add_ps(_mm_mul_ps(nx, f->fx), _mm_mul_ps(nz, f->fz)));
    const __m128 w =
        _mm_add_ps(f->lambda, _mm_mul_ps(f->lambda_rest_half, _mm_add_ps(one, cos_phi)));
    // Elliptical specification II (Johansson, Helbing & Shukla 2007): the distance is replaced by
    // the semi-minor axis b of an ellipse through p_i with foci at p_j and at p_j moved by the
    // relative velocity over the anticipation time, so agents on a collision course repel early
    // and sideways, while agents walking alongside barely interact.
    const __m128 yx = _mm_mul_ps(_mm_sub_ps(ovx, f->vx), f->anticipation);
    const __m128 yz = _mm_mul_ps(_mm_sub_ps(ovz, f->vz), f->anticipation);
    const __m128 dyx = _mm_sub_ps(dx, yx), dyz = _mm_sub_ps(dz, yz);
    const __m128 dy_len = _mm_sqrt_ps(_mm_add_ps(_mm_mul_ps(dyx, dyx), _mm_mul_ps(dyz, dyz)));
    const __m128 sum = _mm_add_ps(dist, dy_len);
    const __m128 yy = _mm_add_ps(_mm_mul_ps(yx, yx), _mm_mul_ps(yz, yz));
    const __m128 b =
        _mm_mul_ps(half, _mm_sqrt_ps(_mm_max_ps(zero, _mm_sub_ps(_mm_mul_ps(sum, sum), yy))));
    // The potential's gradient grows as sum / 2b; capping b keeps it finite when the other is
    // predicted to pass right through p_i.
    const __m128 floor_b = _mm_add_ps(_mm_mul_ps(_mm_set1_ps(0.1f), sum), _mm_set1_ps(1e-6f));
    const __m128 stretch = _mm_div_ps(sum, _mm_mul_ps(_mm_set1_ps(2.0f), _mm_max_ps(floor_b, b)));
    const __m128 has_dy = _mm_cmpgt_ps(dy_len, _mm_set1_ps(1e-6f));
    const __m128 inv_dy = _mm_div_ps(one, dy_len);
    const __m128 dirx =
        _mm_mul_ps(half, _mm_add_ps(nx, select(has_dy, _mm_mul_ps(dyx, inv_dy), nx)));
    const __m128 dirz =
        _mm_mul_ps(half, _mm_add_ps(nz, select(has_dy, _mm_mul_ps(dyz, inv_dy), nz)));
    const __m128 repulsion = _mm_mul_ps(
        _mm_mul_ps(_mm_mul_ps(f->strength, exp4(_mm_mul_ps(_mm_sub_ps(radii, b), f->inv_b))), w),
        stretch);
    // Side-step to the right, (-fz, fx), for what is ahead; body contact along n where bodies
    // overlap.
    const __m128 side = _mm_and_ps(_mm_cmpgt_ps(cos_phi, zero),
                                   _mm_mul_ps(_mm_mul_ps(f->side_step, repulsion), cos_phi));
    const __m128 contact =
        _mm_and_ps(_mm_cmpgt_ps(overlap, zero), _mm_mul_ps(f->stiffness, overlap));
    const __m128 force_x = _mm_add_ps(
        _mm_sub_ps(_mm_mul_ps(repulsion, dirx), _mm_mul_ps(side, f->fz)), _mm_mul_ps(contact, nx));
    const __m128 force_z = _mm_add_ps(
        _mm_add_ps(_mm_mul_ps(repulsion, dirz), _mm_mul_ps(side, f->fx)), _mm_mul_ps(contact, nz));
    sum_x = _mm_add_ps(sum_x, _mm_and_ps(used, force_x));
    sum_z = _mm_add_ps(sum_z, _mm_and_ps(used, force_z));
  }
  f->sum_x = sum_x;
  f->sum_z = sum_z;
}

// Pass 1: new velocity of the agents at sorted positions [begin, end), from the frozen state.
void SocialForces::compute_velocities(size_t begin, size_t end, float dt_s) {
  const UniformGrid& grid = impl_->grid;
  const auto order = grid.order();
  const SocialForceParams& p = params_;
  const float inv_tau = 1.0f / p.relaxation_time_s;
  const float inv_bw = 1.0f / p.wall_range_m;
  const __m128 cutoff2 = _mm_set1_ps(p.neighbour_radius_m * p.neighbour_radius_m);
  ForceLanes forces(p);
  int cell_x = -1, cell_z = -1;
  std::pair<uint32_t, uint32_t> rows[3];
  const float wall_cutoff2 = p.wall_radius_m * p.wall_radius_m;
  const float stiffness = p.contact_forces ? p.body_stiffness_s2 : 0.0f;
  for (size_t k = begin; k < end; ++k) {
    const uint32_t i = order[k];
    const Body& self = sorted_[k];
    const glm::vec2 pos = self.position;
    const glm::vec2 vel = self.velocity;
    const float r_i = self.radius;
    const glm::vec2 dir = self.direction;
    // max_speed_ is max_speed_factor x desired_speed_ (create()), computed again here bit for bit
    // rather than gathered.
    const float max_speed = p.max_speed_factor * self.desired_speed;
    glm::vec2 acc = (self.desired_speed * dir - vel) * inv_tau;
    // Facing for the field of view: the velocity, or the desired direction when (nearly) still.
    const float speed = glm::length(vel);
    const glm::vec2 facing = speed > 0.1f ? vel / speed : dir;
    forces.set_agent(pos, vel, facing, r_i, i);
    // The agents of the 3 x 3 cells around, three contiguous row ranges, shared by the agents of
    // one cell (they are consecutive in k).
    const auto [cx, cz] = grid.cell_of(pos);
    if (cx != cell_x || cz != cell_z) {
      cell_x = cx, cell_z = cz;
      for (int r = 0; r < 3; ++r) rows[r] = grid.row_range(cz - 1 + r, cx - 1, cx + 1);
    }
    // Four candidates at a time: those within the cutoff (not the agent itself) are appended to a
    // small buffer in cell order, and their forces are computed four at a time when it fills.
    uint32_t candidates[kCandidates];
    uint32_t count = 0;
    const __m128 px = _mm_set1_ps(pos.x), pz = _mm_set1_ps(pos.y);
    for (const auto& [m0, m1] : rows) {
      for (uint32_t m = m0; m < m1; m += 4) {
        const __m128 dx = _mm_sub_ps(px, _mm_loadu_ps(&sorted_x_[m]));
        const __m128 dz = _mm_sub_ps(pz, _mm_loadu_ps(&sorted_z_[m]));
        const __m128 d2 = _mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dz, dz));
        uint32_t bits = static_cast<uint32_t>(_mm_movemask_ps(_mm_cmplt_ps(d2, cutoff2)));
        if (m1 - m < 4) bits &= (1u << (m1 - m)) - 1;  // past the row (the arrays are padded)
        if (k - m < 4) bits &= ~(1u << (k - m));       // the agent itself
        _mm_storeu_si128(
            reinterpret_cast<__m128i*>(candidates + count),
            _mm_add_epi32(_mm_set1_epi32(static_cast<int>(m)),
                          _mm_load_si128(reinterpret_cast<const __m128i*>(kPack[bits].lanes))));
        count += kPack[bits].count;
        if (count > kCandidates - 4) {
          add_neighbour_forces(candidates, count, &forces);
          count = 0;
        }
      }
    }
    add_neighbour_forces(candidates, count, &forces);
    acc += forces.total();
    for (const uint32_t wi : impl_->walls.near(pos)) {
      const WallSegment& wall = impl_->walls.walls()[wi];
      const glm::vec2 d = pos - closest_point_on_segment(pos, wall.a, wall.b);
      const float d2 = glm::dot(d, d);
      if (d2 >= wall_cutoff2 || d2 < 1e-12f) continue;  // on the wall: the commit pass pushes out
      const float dist = std::sqrt(d2);
      const glm::vec2 n = d / dist;
      const float overlap = r_i - dist;
      acc += (p.wall_strength_m_s2 * exp1(overlap * inv_bw)) * n;
      if (overlap > 0.0f) acc += (stiffness * overlap) * n;
    }
    glm::vec2 v_new = vel + acc * dt_s;
    const float s2 = glm::dot(v_new, v_new);
    if (s2 > max_speed * max_speed) v_new *= max_speed / std::sqrt(s2);
    if (!finite(v_new)) {
      impl_->non_finite.store(true, std::memory_order_relaxed);
      v_new = glm::vec2(0.0f);
    }
    new_velocity_[i] = v_new;
  }
}

// Pass 2: move agents [begin, end), keep them out of walls, advance waypoints, turn theta.
void SocialForces::commit(size_t begin, size_t end, float dt_s) {
  const float heading_rate = 1.0f - std::exp(-dt_s / params_.heading_time_s);
  const float look_rate = 1.0f - std::exp(-dt_s / params_.look_time_s);
  const float max_twist = params_.max_look_twist_deg * (kPi / 180.0f);
  for (size_t i = begin; i < end; ++i) {
    const glm::vec2 from = position_[i];
    const glm::vec2 to =
        impl_->walls.constrain_move(from, from + new_velocity_[i] * dt_s, radius_[i]);
    glm::vec2 vel = (to - from) / dt_s;  // what the agent really did after the walls
    const float s2 = glm::dot(vel, vel);
    if (s2 > max_speed_[i] * max_speed_[i]) vel *= max_speed_[i] / std::sqrt(s2);
    position_[i] = to;
    velocity_[i] = vel;
    if (!arrived_[i] && glm::length(goal_[i] - to) < goal_radius_[i]) {
      if (waypoint_[i] + 1 < waypoint_end_[i]) {
        ++waypoint_[i];
      } else {
        reached_[i] = 1;
        if (loop_[i]) {
          waypoint_[i] = waypoint_begin_[i];
        } else {
          arrived_[i] = 1;
        }
      }
      goal_[i] = waypoints_[waypoint_[i]];
    }
    // Heading: exponential smoothing of the walking direction, slowed down in proportion to the
    // speed below heading_speed_m_s so that jitter of a standing agent does not spin it.
    const float speed = std::sqrt(glm::dot(vel, vel));
    if (speed > 1e-4f) {
      const float rate = heading_rate * std::min(1.0f, speed / params_.heading_speed_m_s);
      heading_[i] = wrap_angle(heading_[i] + rate * wrap_angle(angle_of(vel) - heading_[i]));
    }
    float look = heading_[i];
    if (attentive_[i]) {
      float best = 0.0f;
      for (const AttentionTarget& t : targets_) {
        const glm::vec2 d = t.position - to;
        const float d2 = glm::dot(d, d);
        if (d2 >= t.radius_m * t.radius_m || (best > 0.0f && d2 >= best) || d2 < 1e-8f) continue;
        const float toward = angle_of(d);
        if (std::abs(wrap_angle(toward - heading_[i])) <= max_twist) {
          look = toward;
          best = d2;
        }
      }
    }
    theta_[i] = wrap_angle(theta_[i] + look_rate * wrap_angle(look - theta_[i]));
  }
}

void SocialForces::remove_finished() {
  size_t out = 0;
  for (size_t i = 0; i < num_; ++i) {
    if (arrived_[i] && remove_at_goal_[i]) {
      ++removed_;
      ++reached_removed_;
      continue;
    }
    if (out != i) {
      id_[out] = id_[i];
      position_[out] = position_[i];
      velocity_[out] = velocity_[i];
      theta_[out] = theta_[i];
      heading_[out] = heading_[i];
      desired_speed_[out] = desired_speed_[i];
      max_speed_[out] = max_speed_[i];
      radius_[out] = radius_[i];
      goal_radius_[out] = goal_radius_[i];
      waypoint_[out] = waypoint_[i];
      waypoint_begin_[out] = waypoint_begin_[i];
      waypoint_end_[out] = waypoint_end_[i];
      goal_[out] = goal_[i];
      loop_[out] = loop_[i];
      remove_at_goal_[out] = remove_at_goal_[i];
      attentive_[out] = attentive_[i];
      arrived_[out] = arrived_[i];
      reached_[out] = reached_[i];
    }
    ++out;
  }
  num_ = out;
}

AgentFrame SocialForces::frame() const {
  return AgentFrame{{id_.data(), num_},
                    {position_.data(), num_},
                    {velocity_.data(), num_},
                    {theta_.data(), num_}};
}

SocialForceStats SocialForces::stats() const {
  SocialForceStats s;
  s.live = num_;
  s.removed = removed_;
  s.reached_goal = reached_removed_;
  for (size_t i = 0; i < num_; ++i) s.reached_goal += reached_[i];
  return s;
}

Status SocialForces::apply_feedback(const AgentFeedback& fb) {
  if (fb.has_feedback.size() != num_ || fb.positions.size() != num_ ||
      fb.velocities.size() != num_ || fb.thetas.size() != num_) {
    return Status::Error("social forces: feedback for " + std::to_string(fb.has_feedback.size()) +
                         " agents, expected " + std::to_string(num_) +
                         " (all arrays index-aligned with frame())");
  }
  const float max_v = params_.max_feedback_speed_m_s, max_jump = params_.max_feedback_jump_m;
  for (size_t i = 0; i < num_; ++i) {  // validate everything before changing anything
    if (!fb.has_feedback[i]) continue;
    // The message is built only when there is an error: nothing is allocated per frame.
    auto who = [&] {
      return "social forces: feedback for agent id " + std::to_string(id_[i]) + ": ";
    };
    if (!finite(fb.positions[i]) || !finite(fb.velocities[i]) || !std::isfinite(fb.thetas[i])) {
      return Status::Error(who() + "non-finite position, velocity or theta");
    }
    if (glm::length(fb.velocities[i]) > max_v) {
      return Status::Error(who() + "speed " + std::to_string(glm::length(fb.velocities[i])) +
                           " m/s exceeds max_feedback_speed_m_s " + std::to_string(max_v));
    }
    if (glm::length(fb.positions[i] - position_[i]) > max_jump) {
      return Status::Error(who() + "position moves " +
                           std::to_string(glm::length(fb.positions[i] - position_[i])) +
                           " m, more than max_feedback_jump_m " + std::to_string(max_jump));
    }
  }
  // Each agent's own entries only (the walls are read): in parallel, as the step's passes (it is
  // the serial end of the mediator's stage otherwise).
  for_agents([&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
      if (!fb.has_feedback[i]) continue;
      position_[i] = impl_->walls.constrain_move(position_[i], fb.positions[i], radius_[i]);
      glm::vec2 v = fb.velocities[i];
      const float s = glm::length(v);
      if (s > max_speed_[i]) v *= max_speed_[i] / s;
      velocity_[i] = v;
      theta_[i] = wrap_angle(fb.thetas[i]);
    }
  });
  return Status::Ok();
}

}  // namespace gk
