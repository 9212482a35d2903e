#include "app/crowd_recorder.h"

#include <algorithm>

namespace gk::app {

CrowdRecorder::CrowdRecorder(size_t capacity, int joints, int lanes)
    : capacity_(std::max<size_t>(capacity, 1)), joints_(std::max(joints, 1)), lanes_(lanes) {
  const size_t per_agent = size_t{kFrames} * static_cast<size_t>(lanes_) *
                           static_cast<size_t>(joints_) * 3 * sizeof(glm::vec4);
  posed_cap_ = std::clamp<size_t>(kPoseBudgetBytes / per_agent, 1, capacity_);
  const size_t slots = size_t{kFrames} * static_cast<size_t>(lanes_);
  time_s_.assign(kFrames, 0.0);
  num_agents_.assign(slots, 0);
  num_posed_.assign(slots, 0);
  states_.assign(slots * capacity_, AgentState{});
  posed_ids_.assign(slots * posed_cap_, -1);
  num_rows_ = slots * posed_cap_ * static_cast<size_t>(joints_) * 3;
  rows_.reset(new glm::vec4[num_rows_]);  // only records written are read back
}

size_t CrowdRecorder::bytes() const {
  return time_s_.size() * sizeof(double) + num_agents_.size() * sizeof(uint32_t) * 2 +
         states_.size() * sizeof(AgentState) + posed_ids_.size() * sizeof(int64_t) +
         num_rows_ * sizeof(glm::vec4);
}

void CrowdRecorder::record(const CrowdSession& session, int64_t selected_id) {
  // By simulated time, so that the minute held is a minute at any time scale; a quarter of a
  // 60 Hz step of slack keeps float time from skipping a record.
  const double now = session.crowd_time_s();
  if (count_ > 0 && now - last_time_s_ < kInterval_s - 0.004) return;
  last_time_s_ = now;
  const int f = count_ % kFrames;
  time_s_[f] = now;
  const size_t J = static_cast<size_t>(joints_);
  for (int l = 0; l < lanes_; ++l) {
    const bool compare = l == 1;
    const size_t slot = static_cast<size_t>(f) * lanes_ + l;
    if (compare && !session.has_compare()) {
      num_agents_[slot] = num_posed_[slot] = 0;
      continue;
    }
    const AnimationLane& lane = compare ? session.compare_lane() : session.lane();
    const AgentFrame& frame = session.frame_of(lane);
    const AnimationPlans& plans = lane.plans();
    const size_t n = std::min(frame.size(), capacity_);
    // The selected agent is always posed: it takes the last place when it is beyond the cap.
    size_t selected_index = n;
    for (size_t i = 0; i < n; ++i) {
      if (frame.ids[i] == selected_id) selected_index = i;
    }
    AgentState* states = &states_[slot * capacity_];
    const size_t limit =
        selected_index < n && selected_index >= posed_cap_ ? posed_cap_ - 1 : posed_cap_;
    size_t posed = 0;
    for (size_t i = 0; i < n; ++i) {
      const int s = plans.slot_of_agent[i];
      AgentState& a = states[i];
      a.id = frame.ids[i];
      a.root_xz = s >= 0 ? plans.root_xz[s] : frame.positions[i];
      a.velocity_xz = frame.velocities[i];
      a.playback_rate = s >= 0 ? plans.playback_rate[s] : 0.0f;
      a.posed = s >= 0 && (i < limit || i == selected_index) && posed < posed_cap_;
      if (!a.posed) continue;
      // The skinning palette from the pose (world * inverse bind): the lane's own are made for the
      // upload (CrowdPipeline::update_palettes), after this.
      const auto world = lane.poses().world(s);
      const auto& inverse_bind = lane.poses().inverse_bind();
      // Kept as drawn: a held pose (level of detail) moved on by its root offset.
      const glm::vec2 offset = lane.poses().root_offset(s);
      const glm::vec3 moved(offset.x, 0.0f, offset.y);
      glm::vec4* rows = &rows_[(slot * posed_cap_ + posed) * J * 3];
      for (size_t j = 0; j < J && j < world.size() && j < inverse_bind.size(); ++j) {
        const glm::mat4 m = world[j] * inverse_bind[j];
        // Affine: the bottom row is (0, 0, 0, 1); the top three rows are kept.
        for (int r = 0; r < 3; ++r) {
          rows[j * 3 + r] = glm::vec4(m[0][r], m[1][r], m[2][r], m[3][r] + moved[r]);
        }
      }
      posed_ids_[slot * posed_cap_ + posed] = a.id;
      ++posed;
    }
    num_agents_[slot] = static_cast<uint32_t>(n);
    num_posed_[slot] = static_cast<uint32_t>(posed);
  }
  ++count_;
}

std::optional<CrowdRecorder::AgentState> CrowdRecorder::agent(int k, int lane,
                                                              int64_t id) const {
  if (k < 0 || k >= size() || lane < 0 || lane >= lanes_) return std::nullopt;
  const size_t slot = static_cast<size_t>(index(k)) * lanes_ + lane;
  const AgentState* states = &states_[slot * capacity_];
  for (uint32_t i = 0; i < num_agents_[slot]; ++i) {
    if (states[i].id == id) return states[i];
  }
  return std::nullopt;
}

size_t CrowdRecorder::restore(int k, int lane, AnimationLane* out,
                              std::vector<int64_t>* out_ids) const {
  out->num_collected = out->num_palettes = 0;
  if (k < 0 || k >= size() || lane < 0 || lane >= lanes_) return 0;
  const size_t slot = static_cast<size_t>(index(k)) * lanes_ + lane;
  const AgentState* states = &states_[slot * capacity_];
  const size_t J = static_cast<size_t>(joints_);
  size_t posed = 0;
  for (uint32_t i = 0; i < num_agents_[slot]; ++i) {
    const AgentState& a = states[i];
    if (!a.posed || posed >= num_posed_[slot] || posed >= out->draws.size()) continue;
    const glm::vec4* rows = &rows_[(slot * posed_cap_ + posed) * J * 3];
    for (size_t j = 0; j < J; ++j) {
      glm::mat4 m(1.0f);
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 4; ++c) m[c][r] = rows[j * 3 + r][c];
      }
      out->recorded_palettes[posed * J + j] = m;
    }
    out->draws[posed] =
        AgentDraw{glm::vec3(a.root_xz.x, 0.0f, a.root_xz.y),
                  agent_tint(static_cast<uint32_t>(a.id)), 0, static_cast<int>(posed)};
    (*out_ids)[posed] = a.id;
    ++posed;
  }
  out->num_collected = out->num_palettes = posed;
  return posed;
}

}  // namespace gk::app
