#pragma once
// Uniform grids for the crowd: UniformGrid buckets moving points (agents) per step with a counting
// sort, so a neighbour search is linear in the number of agents; WallGrid lists, once, the static
// wall segments near each cell. Plus the segment geometry both need.

#include <algorithm>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include "common/status.h"
#include "crowd/scenario.h"

namespace gk {

glm::vec2 closest_point_on_segment(glm::vec2 p, glm::vec2 a, glm::vec2 b);
float distance_to_segment(glm::vec2 p, glm::vec2 a, glm::vec2 b);
// True when segment p0-p1 crosses or touches segment a-b. Evaluated in double precision because
// it is the last line of defence of the no-wall-crossing guarantee.
bool segments_intersect(glm::vec2 p0, glm::vec2 p1, glm::vec2 a, glm::vec2 b);

class UniformGrid {
 public:
  // Cells cover [min, max] (grown when the cell count would exceed kMaxCells); points outside
  // fall into the border cells, which stays correct and only costs time.
  static constexpr size_t kMaxCells = size_t{1} << 22;
  static Result<UniformGrid> create(glm::vec2 min, glm::vec2 max, float cell_size_m,
                                    size_t capacity);

  // Stable counting sort of the points into cells, O(points + cells). No allocation when
  // points.size() <= capacity (asserted).
  void build(std::span<const glm::vec2> points);
  // build() in two steps, so that the first can run in parallel: assign_cells() for points
  // [begin, end) of `points` (disjoint ranges may run concurrently), then sort_cells() for the
  // first num_points, serial. The same result as build().
  void assign_cells(std::span<const glm::vec2> points, size_t begin, size_t end);
  void sort_cells(size_t num_points);

  int num_x() const { return num_x_; }
  int num_z() const { return num_z_; }
  float cell_size() const { return cell_size_; }
  // Cell of p, clamped to the grid; non-finite coordinates go to cell 0.
  std::pair<int, int> cell_of(glm::vec2 p) const;
  // Indices of the built points, ordered by cell (row-major, x fastest), within a cell by index.
  std::span<const uint32_t> order() const { return {order_.data(), num_points_}; }
  // The inverse of order(): where point i is in it.
  std::span<const uint32_t> rank() const { return {rank_.data(), num_points_}; }
  // Half-open range in order() covering cells x0..x1 (inclusive, clamped) of row z: one
  // contiguous range, because rows are stored consecutively.
  std::pair<uint32_t, uint32_t> row_range(int z, int x0, int x1) const;

 private:
  glm::vec2 min_{0.0f};
  float cell_size_ = 1.0f;
  float inv_cell_ = 1.0f;
  int num_x_ = 1, num_z_ = 1;
  size_t num_points_ = 0;
  std::vector<uint32_t> cell_start_;  // num cells + 1
  std::vector<uint32_t> cursor_;      // scratch of the scatter
  std::vector<uint32_t> point_cell_;  // capacity
  std::vector<uint32_t> order_;       // capacity
  std::vector<uint32_t> rank_;        // capacity
};

class WallGrid {
 public:
  WallGrid() = default;
  // Lists for each cell every wall that comes within reach_m of it.
  WallGrid(std::span<const WallSegment> walls, float cell_size_m, float reach_m);

  // A superset of the walls within reach_m() of p; empty far from every wall.
  std::span<const uint32_t> near(glm::vec2 p) const;
  float reach() const { return reach_m_; }
  std::span<const WallSegment> walls() const { return walls_; }
  // Where a body of `radius` moving from `from` toward `to` may end up: a move that would cross a
  // wall slides along it (or is cancelled), and the end point is pushed out to `radius` from
  // nearby walls unless that push would itself cross a wall. The segment from `from` to the
  // result never crosses a wall.
  glm::vec2 constrain_move(glm::vec2 from, glm::vec2 to, float radius) const;
  // Every wall index, for movements longer than reach().
  std::span<const uint32_t> all() const { return all_; }

 private:
  glm::vec2 constrain_move_near_walls(glm::vec2 from, glm::vec2 to, float radius,
                                      std::span<const uint32_t> near_from) const;
  std::vector<WallSegment> walls_;
  std::vector<uint32_t> all_;
  glm::vec2 min_{0.0f};
  float inv_cell_ = 1.0f;
  float reach_m_ = 0.0f;
  int num_x_ = 0, num_z_ = 0;
  std::vector<uint32_t> cell_start_;
  std::vector<uint32_t> items_;
};

// Defined here so that the per-agent look-ups of the simulator inline.

inline std::pair<int, int> UniformGrid::cell_of(glm::vec2 p) const {
  // Written with comparisons so that NaN lands in cell 0 instead of an undefined float-to-int cast.
  const float fx = (p.x - min_.x) * inv_cell_;
  const float fz = (p.y - min_.y) * inv_cell_;
  const int cx =
      fx >= 0.0f ? (fx < static_cast<float>(num_x_) ? static_cast<int>(fx) : num_x_ - 1) : 0;
  const int cz =
      fz >= 0.0f ? (fz < static_cast<float>(num_z_) ? static_cast<int>(fz) : num_z_ - 1) : 0;
  return {cx, cz};
}

inline std::pair<uint32_t, uint32_t> UniformGrid::row_range(int z, int x0, int x1) const {
  if (z < 0 || z >= num_z_) return {0, 0};
  x0 = std::max(x0, 0);
  x1 = std::min(x1, num_x_ - 1);
  if (x0 > x1) return {0, 0};
  const size_t row = static_cast<size_t>(z) * static_cast<size_t>(num_x_);
  return {cell_start_[row + x0], cell_start_[row + x1 + 1]};
}

inline std::span<const uint32_t> WallGrid::near(glm::vec2 p) const {
  if (walls_.empty()) return {};
  const float fx = (p.x - min_.x) * inv_cell_;
  const float fz = (p.y - min_.y) * inv_cell_;
  // Outside the grid (or NaN) means farther than reach from every wall: the grid is the walls'
  // bounding box grown by reach.
  if (!(fx >= 0.0f && fz >= 0.0f && fx < static_cast<float>(num_x_) &&
        fz < static_cast<float>(num_z_))) {
    return {};
  }
  const size_t c = static_cast<size_t>(fz) * num_x_ + static_cast<size_t>(fx);
  return {items_.data() + cell_start_[c], items_.data() + cell_start_[c + 1]};
}

inline glm::vec2 WallGrid::constrain_move(glm::vec2 from, glm::vec2 to, float radius) const {
  if (walls_.empty()) return to;
  const std::span<const uint32_t> near_from = near(from);
  // No wall near `from` and a short move: nothing can change `to` (the common case).
  if (near_from.empty() && glm::length(to - from) + radius <= reach_m_) return to;
  return constrain_move_near_walls(from, to, radius, near_from);
}

}  // namespace gk
