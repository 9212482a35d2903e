#pragma once
// Replay of recorded pedestrian trajectories in the ETH/UCY text format (frame, id, x, y per line,
// tab or space separated; or the ETH authors' obsmat.txt, frame id pos_x pos_z pos_y v_x v_z v_y,
// whose ground plane is (pos_x, pos_y)), or as CSV (comma or semicolon separated), with or without
// a header row that names the frame (or time, in seconds), id, x and y columns (in any order,
// among others); lines beginning with '#' are comments. Positions are resampled smoothly (C1: no
// velocity jumps) to the simulation rate; velocity and theta are derived; agents appear and
// vanish with the data. Feedback is ignored: the data is the truth.
//
// Units: metres, unless the pedestrians would then move implausibly (their typical speed outside
// 0.15-6 m/s) and centimetres or millimetres bring them to a walking pace; the replay's name then
// says so ("replay x.csv (in millimetres, by its walking speeds)").
// Coordinates: the file's ground (x, y) [m] becomes our ground (x, z) = (x, y) unchanged, so
// distances, speeds and ids match the data; seen from above (+y) the scene is the mirror image of a
// plot of the file with y up (a reflection, harmless for walking).
// Time: t = (frame - first frame of the file) / step * frame_time_s, where step is the file's usual
// frame difference between consecutive samples of a pedestrian; time_s() starts at 0 there.
// A pedestrian is live from its first sample to its last (missing frames within a track are
// interpolated across); ids are the file's pedestrian ids; capacity() is the largest number of
// pedestrians live at once. Positions follow a monotone cubic Hermite spline through the samples
// (exact at the recorded times, no overshoot per axis), velocity is its derivative and theta is the
// smoothed heading of the velocity, held while the speed is below 0.1 m/s.
//
// Errors (file and line): a header without frame (or time), id, x or y, wrong column count,
// non-numbers, NaN/inf, frame not a whole number in [0, 2^31), time beyond +-1e7 s, id not a whole
// number in [0, 2^32), duplicate (frame, id), no rows at all.
//
// With ReplayOptions::loop the file plays round and round for as long as it is stepped.

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "crowd/crowd_source.h"

namespace gk {

struct ReplayOptions {
  // Seconds between two consecutive samples of one pedestrian, a sample step being the file's
  // usual difference between consecutive frame numbers (10 in the ETH/UCY files). [s] [> 0]
  // Note: biwi_eth.txt is resampled from 6-frame annotations; its 10-id step spans ~0.667 s.
  // Not used for a file whose header names a time column: its rows are replayed at their times.
  float frame_time_s = 0.4f;
  // Play the file again and again: one sample step after its last sample, it starts over from its
  // first frame (time_s() keeps counting). Every pedestrian leaves before the file starts over,
  // so each comes back as a new agent with its id (absent for at least that step).
  bool loop = false;
};

// True for the file names a trajectory file may have: .txt, .csv, .tsv or .dat (any case).
bool is_trajectory_file_name(std::string_view path);

// `out_pedestrian_ids` (optional) receives every pedestrian id of the file, sorted, so that an
// option naming an agent can be checked before the replay runs.
Result<std::unique_ptr<CrowdSource>> load_trajectory_replay(
    const std::string& path, const ReplayOptions& options = {},
    std::vector<uint32_t>* out_pedestrian_ids = nullptr);

}  // namespace gk
