// The demo's timeline: the last minute of the crowd kept in a CrowdRecorder (app/crowd_recorder.h),
// scrubbed, stepped and inspected from the panel (and Left / Right, Page Up / Page Down). While a
// record is shown the simulation is paused; running again returns to the live crowd.
#include <algorithm>
#include <cfloat>
#include <cstdio>

#include <imgui.h>

#include "app/demo_app.h"

namespace gk::app {

void DemoApp::reset_recorder() {
  const size_t capacity = std::max<size_t>(session_->crowd().capacity(), 1);
  const int lanes = session_->has_compare() ? 2 : 1;
  recorder_.emplace(capacity, session_->joints(), lanes);
  scrub_ = -1;
  for (int l = 0; l < 2; ++l) {
    replay_[l].recorded_palettes.assign(capacity * static_cast<size_t>(session_->joints()),
                                        glm::mat4(1.0f));
    replay_[l].draws.assign(capacity, AgentDraw{});
    replay_[l].num_collected = 0;
    replay_[l].num_palettes = 0;
    replay_ids_[l].assign(capacity, -1);
  }
}

void DemoApp::scrub_to(int k) {
  if (!recorder_ || recorder_->size() == 0) return;
  if (k >= recorder_->size()) {
    scrub_ = -1;  // past the newest record: the live crowd, still paused
    return;
  }
  scrub_ = std::max(k, 0);
  paused_ = true;
  for (int l = 0; l < recorder_->lanes(); ++l) {
    recorder_->restore(scrub_, l, &replay_[l], &replay_ids_[l]);
  }
  director_.snap();  // the camera jumps with the crowd instead of flying there
}

void DemoApp::scrub_by(int records) {
  if (!recorder_ || recorder_->size() == 0) return;
  const int from = scrubbing() ? scrub_ : recorder_->size() - 1;
  scrub_to(std::max(from + records, 0));
}

const AnimationLane& DemoApp::shown_lane(bool compare) const {
  if (scrubbing()) return replay_[compare && recorder_->lanes() > 1 ? 1 : 0];
  return compare ? session_->compare_lane() : session_->lane();
}

int64_t DemoApp::shown_id(bool compare, size_t i) const {
  if (scrubbing()) return replay_ids_[compare && recorder_->lanes() > 1 ? 1 : 0][i];
  return session_->frame_of(shown_lane(compare)).ids[i];
}

std::optional<FollowedAgent> DemoApp::shown_followed() const {
  const int64_t id = director_.followed_id();
  if (!scrubbing()) return followed_agent(*session_, id);
  const auto a = recorder_->agent(scrub_, 0, id);
  if (!a) return std::nullopt;
  return FollowedAgent{glm::vec3(a->root_xz.x, 0.0f, a->root_xz.y), a->velocity_xz};
}

void DemoApp::panel_timeline() {
  const int n = recorder_ ? recorder_->size() : 0;
  if (n == 0) {
    ImGui::TextDisabled("the last minute is recorded as the crowd runs");
    return;
  }
  const double oldest = recorder_->time_s(0), newest = recorder_->time_s(n - 1);
  int k = scrubbing() ? scrub_ : n - 1;
  char label[64];
  std::snprintf(label, sizeof(label), "t = %.2f s", recorder_->time_s(k));
  ImGui::SetNextItemWidth(-FLT_MIN);
  if (ImGui::SliderInt("##timeline", &k, 0, n - 1, label)) scrub_to(k);
  if (ImGui::Button("-5 s")) scrub_by(-CrowdRecorder::kRecordsPer5s);
  ImGui::SameLine();
  if (ImGui::Button("< step")) scrub_by(-1);
  ImGui::SameLine();
  if (ImGui::Button("step >")) scrub_by(1);
  ImGui::SameLine();
  if (ImGui::Button("+5 s")) scrub_by(CrowdRecorder::kRecordsPer5s);
  ImGui::SameLine();
  if (ImGui::Button(scrubbing() ? "live" : "run")) scrub_ = -1, paused_ = false, clock_.reset();
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Back to the live crowd and run (Space)");
  ImGui::TextDisabled("%.1f .. %.1f s held, %zu of %zu agents posed, %.0f MiB", oldest, newest,
                      recorder_->posed_capacity(),
                      static_cast<size_t>(session_->crowd().capacity()),
                      static_cast<double>(recorder_->bytes()) / (1 << 20));
  if (ImGui::IsItemHovered()) {
    ImGui::SetTooltip(
        "Recorded at 20 Hz: every agent's root, velocity and playback rate, and the skinning "
        "palettes of up to the first %zu agents per lane (the selected one always): poses are "
        "capped at 256 MiB. Left / Right step, Page Up / Page Down 5 s.",
        recorder_->posed_capacity());
  }
}

}  // namespace gk::app
