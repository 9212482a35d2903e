#include "crowd/spatial_grid.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

namespace gk {

glm::vec2 closest_point_on_segment(glm::vec2 p, glm::vec2 a, glm::vec2 b) {
  const glm::vec2 ab = b - a;
  const float len2 = glm::dot(ab, ab);
  const float t = len2 > 0.0f ? std::clamp(glm::dot(p - a, ab) / len2, 0.0f, 1.0f) : 0.0f;
  return a + t * ab;
}

float distance_to_segment(glm::vec2 p, glm::vec2 a, glm::vec2 b) {
  return glm::length(p - closest_point_on_segment(p, a, b));
}

namespace {
double orient(double ax, double az, double bx, double bz, double cx, double cz) {
  return (bx - ax) * (cz - az) - (bz - az) * (cx - ax);
}
bool on_segment(double ax, double az, double bx, double bz, double px, double pz) {
  return std::min(ax, bx) <= px && px <= std::max(ax, bx) && std::min(az, bz) <= pz &&
         pz <= std::max(az, bz);
}
}  // namespace

bool segments_intersect(glm::vec2 p0, glm::vec2 p1, glm::vec2 a, glm::vec2 b) {
  const double o1 = orient(p0.x, p0.y, p1.x, p1.y, a.x, a.y);
  const double o2 = orient(p0.x, p0.y, p1.x, p1.y, b.x, b.y);
  const double o3 = orient(a.x, a.y, b.x, b.y, p0.x, p0.y);
  const double o4 = orient(a.x, a.y, b.x, b.y, p1.x, p1.y);
  if (((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) && ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0))) {
    return true;
  }
  // Touching or collinear overlap counts as an intersection.
  return (o1 == 0 && on_segment(p0.x, p0.y, p1.x, p1.y, a.x, a.y)) ||
         (o2 == 0 && on_segment(p0.x, p0.y, p1.x, p1.y, b.x, b.y)) ||
         (o3 == 0 && on_segment(a.x, a.y, b.x, b.y, p0.x, p0.y)) ||
         (o4 == 0 && on_segment(a.x, a.y, b.x, b.y, p1.x, p1.y));
}

Result<UniformGrid> UniformGrid::create(glm::vec2 min, glm::vec2 max, float cell_size_m,
                                        size_t capacity) {
  if (!std::isfinite(min.x) || !std::isfinite(min.y) || !std::isfinite(max.x) ||
      !std::isfinite(max.y) || !(cell_size_m > 0.0f) || !std::isfinite(cell_size_m)) {
    return Status::Error("spatial grid: expected finite bounds and a cell size > 0");
  }
  if (capacity >= std::numeric_limits<uint32_t>::max()) {
    return Status::Error("spatial grid: capacity exceeds 32-bit indices");
  }
  UniformGrid g;
  const glm::vec2 extent = glm::max(max - min, glm::vec2(cell_size_m));
  // Grow the cells until their count is bounded: a huge scenario then costs time, not memory.
  double cell = cell_size_m;
  while ((extent.x / cell + 1.0) * (extent.y / cell + 1.0) > static_cast<double>(kMaxCells)) {
    cell *= 1.5;
  }
  g.min_ = min;
  g.cell_size_ = static_cast<float>(cell);
  g.inv_cell_ = 1.0f / g.cell_size_;
  g.num_x_ = static_cast<int>(std::ceil(extent.x / cell)) + 1;
  g.num_z_ = static_cast<int>(std::ceil(extent.y / cell)) + 1;
  const size_t cells = static_cast<size_t>(g.num_x_) * static_cast<size_t>(g.num_z_);
  g.cell_start_.assign(cells + 1, 0);
  g.cursor_.assign(cells, 0);
  g.point_cell_.assign(capacity, 0);
  g.order_.assign(capacity, 0);
  g.rank_.assign(capacity, 0);
  return g;
}

void UniformGrid::build(std::span<const glm::vec2> points) {
  assign_cells(points, 0, points.size());
  sort_cells(points.size());
}

void UniformGrid::assign_cells(std::span<const glm::vec2> points, size_t begin, size_t end) {
  assert(end <= points.size() && points.size() <= point_cell_.size());
  for (size_t i = begin; i < end; ++i) {
    const auto [cx, cz] = cell_of(points[i]);
    point_cell_[i] = static_cast<uint32_t>(cz * num_x_ + cx);
  }
}

void UniformGrid::sort_cells(size_t num_points) {
  assert(num_points <= order_.size());
  num_points_ = num_points;
  std::fill(cell_start_.begin(), cell_start_.end(), 0u);
  for (size_t i = 0; i < num_points; ++i) ++cell_start_[point_cell_[i] + 1];
  for (size_t c = 1; c < cell_start_.size(); ++c) cell_start_[c] += cell_start_[c - 1];
  std::copy(cell_start_.begin(), cell_start_.end() - 1, cursor_.begin());
  for (size_t i = 0; i < num_points; ++i) {
    const uint32_t k = cursor_[point_cell_[i]]++;
    order_[k] = static_cast<uint32_t>(i);
    rank_[i] = k;
  }
}

WallGrid::WallGrid(std::span<const WallSegment> walls, float cell_size_m, float reach_m)
    : walls_(walls.begin(), walls.end()), reach_m_(reach_m) {
  all_.resize(walls_.size());
  for (size_t i = 0; i < all_.size(); ++i) all_[i] = static_cast<uint32_t>(i);
  if (walls_.empty()) return;
  glm::vec2 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
  for (const WallSegment& w : walls_) {
    lo = glm::min(lo, glm::min(w.a, w.b));
    hi = glm::max(hi, glm::max(w.a, w.b));
  }
  lo -= glm::vec2(reach_m);
  hi += glm::vec2(reach_m);
  float cell = std::max(cell_size_m, 1e-3f);
  const glm::vec2 extent = hi - lo;
  while ((extent.x / cell + 1.0f) * (extent.y / cell + 1.0f) > 1.0e6f) cell *= 1.5f;
  min_ = lo;
  inv_cell_ = 1.0f / cell;
  num_x_ = static_cast<int>(std::ceil(extent.x / cell)) + 1;
  num_z_ = static_cast<int>(std::ceil(extent.y / cell)) + 1;
  // Conservative test: a wall is listed when it comes within reach + half a cell diagonal of
  // the cell centre, which covers every point of the cell.
  const float listed = reach_m + 0.5f * cell * std::sqrt(2.0f);
  std::vector<std::vector<uint32_t>> lists(static_cast<size_t>(num_x_) * num_z_);
  for (size_t w = 0; w < walls_.size(); ++w) {
    const glm::vec2 a = walls_[w].a, b = walls_[w].b;
    const int x0 = std::max(0, static_cast<int>((std::min(a.x, b.x) - listed - lo.x) * inv_cell_));
    const int x1 =
        std::min(num_x_ - 1, static_cast<int>((std::max(a.x, b.x) + listed - lo.x) * inv_cell_));
    const int z0 = std::max(0, static_cast<int>((std::min(a.y, b.y) - listed - lo.y) * inv_cell_));
    const int z1 =
        std::min(num_z_ - 1, static_cast<int>((std::max(a.y, b.y) + listed - lo.y) * inv_cell_));
    for (int z = z0; z <= z1; ++z) {
      for (int x = x0; x <= x1; ++x) {
        const glm::vec2 centre = lo + cell * glm::vec2(x + 0.5f, z + 0.5f);
        if (distance_to_segment(centre, a, b) <= listed) {
          lists[static_cast<size_t>(z) * num_x_ + x].push_back(static_cast<uint32_t>(w));
        }
      }
    }
  }
  cell_start_.assign(lists.size() + 1, 0);
  for (size_t c = 0; c < lists.size(); ++c) {
    cell_start_[c + 1] = cell_start_[c] + static_cast<uint32_t>(lists[c].size());
    items_.insert(items_.end(), lists[c].begin(), lists[c].end());
  }
}

// constrain_move() past its common case: a step that would cross a wall slides along it (or is
// cancelled), and the end point is pushed out to `radius` from nearby walls.
glm::vec2 WallGrid::constrain_move_near_walls(glm::vec2 from, glm::vec2 to, float radius,
                                              std::span<const uint32_t> near_from) const {
  const WallGrid& grid = *this;
  auto walls_for = [&](glm::vec2 target, float extra) {
    return glm::length(target - from) + extra <= grid.reach() ? near_from : grid.all();
  };
  auto crosses = [&](glm::vec2 target) {
    for (const uint32_t wi : walls_for(target, 0.0f)) {
      if (segments_intersect(from, target, grid.walls()[wi].a, grid.walls()[wi].b)) return int(wi);
    }
    return -1;
  };
  for (int attempt = 0; attempt < 2; ++attempt) {
    const int hit = crosses(to);
    if (hit < 0) break;
    const WallSegment& w = grid.walls()[hit];
    const glm::vec2 t = glm::normalize(w.b - w.a);
    to = from + glm::dot(to - from, t) * t;  // slide along the wall
  }
  for (int iteration = 0; iteration < 2; ++iteration) {
    for (const uint32_t wi : walls_for(to, radius)) {
      const WallSegment& w = grid.walls()[wi];
      const glm::vec2 c = closest_point_on_segment(to, w.a, w.b);
      const glm::vec2 d = to - c;
      const float dist = glm::length(d);
      if (dist >= radius) continue;
      glm::vec2 n;
      if (dist > 1e-6f) {
        n = d / dist;
      } else {  // on the wall line: push to the side the agent came from
        const glm::vec2 e = glm::normalize(w.b - w.a);
        n = glm::vec2(-e.y, e.x);
        if (glm::dot(from - c, n) < 0.0f) n = -n;
      }
      to = c + radius * n;
    }
  }
  return crosses(to) < 0 ? to : from;
}

}  // namespace gk
