#pragma once
// Replay of recorded pedestrian trajectories in the ETH/UCY text format (frame, id, x, y per line,
// tab or space separated). Positions are resampled smoothly (C1: no velocity jumps) to the
// simulation rate; velocity and theta are derived; agents appear and vanish with the data. Feedback
// is ignored: the data is the truth.

#include <memory>
#include <string>

#include "crowd/crowd_source.h"

namespace gk {

struct ReplayOptions {
  // Seconds between two consecutive samples of one pedestrian, a sample step being the file's
  // usual difference between consecutive frame numbers (10 in the ETH/UCY files). [s] [> 0]
  float frame_time_s = 0.4f;
};

Result<std::unique_ptr<CrowdSource>> load_trajectory_replay(const std::string& path,
                                                            const ReplayOptions& options = {});

}  // namespace gk
