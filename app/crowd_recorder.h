#pragma once
// The last minute of the crowd for the demo's timeline (pause, scrub, step, inspect any agent at
// any moment), in memory sized once at creation.
//
// Recorded every 0.05 s of simulated time (20 Hz): for every live agent of each lane its id,
// drawn root, simulator velocity and playback rate (32 bytes), and for up to
// posed_capacity() agents per lane the skinning palette as 3x4 floats (48 bytes a joint), enough
// to redraw them exactly as drawn. Poses are what costs: 60 s at 20 Hz of a 25-joint agent is
// 1.44 MB, so the palettes are capped at kPoseBudgetBytes (256 MiB): 186 agent-lanes of 25
// joints, i.e. every agent of the default scenarios alone (at most 150, the plaza) and of all but
// the plaza in the split (80 + 80 at the bottleneck). Beyond the cap the first agents of the
// frame are posed, the selected agent always among them; the others keep their state (shown in
// the panel) but are not drawn while scrubbing.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec4.hpp>

#include "app/crowd_session.h"

namespace gk::app {

class CrowdRecorder {
 public:
  static constexpr double kInterval_s = 0.05;  // simulated time between records (20 Hz)
  static constexpr int kRecordsPer5s = 100;
  static constexpr int kFrames = 60 * 20;      // records held: the last 60 s
  static constexpr size_t kPoseBudgetBytes = size_t{256} << 20;

  // `capacity`: the crowd's agent capacity; `lanes`: 1, or 2 with the split's compare lane.
  CrowdRecorder(size_t capacity, int joints, int lanes);

  // After each simulation step: records when kInterval_s of simulated time has passed since the
  // last record.
  void record(const CrowdSession& session, int64_t selected_id);

  int lanes() const { return lanes_; }
  int size() const { return count_ < kFrames ? count_ : kFrames; }  // records held
  double time_s(int k) const { return time_s_[index(k)]; }          // k = 0: the oldest
  size_t posed_capacity() const { return posed_cap_; }
  size_t bytes() const;  // everything allocated

  struct AgentState {
    int64_t id = -1;
    glm::vec2 root_xz{0.0f};      // drawn root [m]
    glm::vec2 velocity_xz{0.0f};  // simulator velocity [m/s]
    float playback_rate = 0.0f;
    bool posed = false;           // drawn when scrubbing
  };
  std::optional<AgentState> agent(int k, int lane, int64_t id) const;
  // Lane `lane` of record k into `out` (draws and palettes of the posed agents, sized like the
  // session's lanes) and their ids into `out_ids`; returns how many. Allocates nothing.
  size_t restore(int k, int lane, AnimationLane* out, std::vector<int64_t>* out_ids) const;

 private:
  int index(int k) const { return (count_ - size() + k) % kFrames; }
  size_t capacity_;
  int joints_;
  int lanes_;
  size_t posed_cap_;
  int count_ = 0;
  double last_time_s_ = 0.0;
  std::vector<double> time_s_;                 // [frame]
  std::vector<uint32_t> num_agents_;           // [frame * lanes + lane]
  std::vector<uint32_t> num_posed_;            // [frame * lanes + lane]
  std::vector<AgentState> states_;             // [(frame * lanes + lane) * capacity + i]
  std::vector<int64_t> posed_ids_;             // [(frame * lanes + lane) * posed_cap + j]
  // [((f * lanes + l) * posed_cap + j) * J * 3 + r]; not zero-filled, so its pages become
  // resident as the minute fills rather than all at creation.
  std::unique_ptr<glm::vec4[]> rows_;
  size_t num_rows_ = 0;
};

}  // namespace gk::app
