#pragma once
// Private to crowd/: reading of ETH/UCY pedestrian trajectory text files ("frame id x y" per line,
// or the 8 columns of ETH's obsmat.txt, "frame id pos_x pos_z pos_y v_x v_z v_y", every row alike;
// tab or space separated) into per-pedestrian tracks, validated row by row.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <glm/vec2.hpp>

#include "common/status.h"

namespace gk {

// Tracks as flat arrays, sorted by pedestrian id; the samples of track k are
// [track_begin[k], track_begin[k + 1]), in increasing frame order.
struct TrajectoryTable {
  std::vector<uint32_t> ped_ids;      // per track: the file's pedestrian id
  std::vector<uint32_t> track_begin;  // num_tracks + 1 entries
  std::vector<int64_t> frames;        // per sample: the file's frame number
  std::vector<glm::vec2> positions;   // per sample: file (x, y) [m]
  // The file's usual (most common) frame difference between consecutive samples of one
  // pedestrian; 1 when no pedestrian has two samples. [frames] [> 0]
  int64_t frame_step = 1;
  int64_t first_frame = 0;  // smallest frame number in the file
  // A file with a time column: the seconds one of `frames` stands for (its times, to the
  // millisecond); 0: frame numbers, timed by ReplayOptions::frame_time_s.
  double seconds_per_frame = 0.0;
  size_t num_tracks() const { return ped_ids.size(); }
};

// Parses `text`; `file_name` only labels error messages ("name:line: what").
Result<TrajectoryTable> parse_trajectory_text(std::string_view text, const std::string& file_name);

// Reads and parses the file at `path`.
Result<TrajectoryTable> read_trajectory_file(const std::string& path);

}  // namespace gk
