// The demo's JSON report (`--report`, for tests and scripts): the window and panel rectangles,
// the crowd shown (live or the scrubbed record) with the agents' and exhibits' pixels, camera,
// simulated time, pause, help, selection, the lesson with both lanes' parameters, the timeline.
#include <fstream>

#include <nlohmann/json.hpp>

#include "app/demo_app.h"

namespace gk::app {

void DemoApp::write_report(const std::string& path) const {
  nlohmann::json agents = nlohmann::json::array();
  const glm::ivec2 size = view_size();
  const float offset = session_->has_compare() ? static_cast<float>(size.x) : 0.0f;
  const auto draws = shown_lane(false).draw_span();
  for (size_t i = 0; i < draws.size(); ++i) {
    const ProjectedPoint p = camera_.project(draws[i].position + glm::vec3(0, 0.9f, 0), size);
    agents.push_back({{"id", shown_id(false, i)},
                      {"x", draws[i].position.x},
                      {"z", draws[i].position.z},
                      {"px", p.pixel.x + offset},
                      {"py", p.pixel.y},
                      {"in_front", p.in_front}});
  }
  nlohmann::json exhibits = nlohmann::json::array();
  const Exhibits shown =
      make_exhibits(session_->setup(), 0.5f * (session_->bounds_min() + session_->bounds_max()),
                    view_->renderer().settings().wall_thickness_m);
  for (const glm::vec3& c : shown.canvas_centers) {
    const ProjectedPoint p = camera_.project(c, size);
    exhibits.push_back({{"px", p.pixel.x + offset}, {"py", p.pixel.y}, {"in_front", p.in_front}});
  }
  nlohmann::json clips = nlohmann::json::array();
  for (const LocomotionClip& c : session_->library().clips) {
    clips.push_back({{"name", c.clip.name}, {"speed_m_s", c.speed_m_s}});
  }
  nlohmann::json lesson_items = nlohmann::json::array();
  for (const glm::vec4& r : lesson_item_rects_) lesson_items.push_back({r.x, r.y, r.z, r.w});
  const glm::ivec2 fb = context_->framebuffer_size();
  const glm::ivec2 scene = scene_size();
  const nlohmann::json j = {
      {"scene_width", scene.x},
      {"width", fb.x},
      {"height", fb.y},
      {"compare", session_->has_compare()},
      {"lesson", lesson_ ? lesson_->name : ""},
      {"timeline",
       {{"scrubbing", scrubbing()},
        {"shown_time_s", scrubbing() ? recorder_->time_s(scrub_) : session_->crowd().time_s()},
        {"records", recorder_->size()},
        {"bytes", recorder_->bytes()},
        {"posed_capacity", recorder_->posed_capacity()}}},
      {"time_scale", time_scale_},
      {"overlays",
       {{"velocity", overlays_.velocity},
        {"theta", overlays_.theta},
        {"planted", overlays_.planted},
        {"trails", overlays_.trails},
        {"torso", overlays_.torso},
        {"legs", overlays_.legs}}},
      {"params", nlohmann::json::parse(mediator_params_to_json(session_->params()))},
      {"compare_params", session_->has_compare() ? nlohmann::json::parse(mediator_params_to_json(
                                                       session_->compare_lane().params()))
                                                 : nlohmann::json()},
      {"compare_own_crowd", session_->compare_has_own_crowd()},
      {"lessons_menu",
       {lessons_menu_rect_.x, lessons_menu_rect_.y, lessons_menu_rect_.z, lessons_menu_rect_.w}},
      {"lesson_items", lesson_items},
      {"lesson_text",
       {lesson_text_rect_.x, lesson_text_rect_.y, lesson_text_rect_.z, lesson_text_rect_.w}},
      {"scenario", session_->setup().scenario_name},
      {"agent_count", session_->setup().agents},
      {"frames", frames_drawn_},
      {"time_s", session_->crowd().time_s()},
      {"paused", paused_},
      {"help", help_},
      {"help_rect", {help_rect_.x, help_rect_.y, help_rect_.z, help_rect_.w}},
      {"hint", hint()},
      {"selected", selected_id_},
      {"following", director_.following()},
      {"camera",
       {{"target", {camera_.target.x, camera_.target.y, camera_.target.z}},
        {"distance_m", camera_.distance_m},
        {"pitch_rad", camera_.pitch_rad},
        {"yaw_rad", camera_.yaw_rad}}},
      {"panel", {panel_rect_.x, panel_rect_.y, panel_rect_.z, panel_rect_.w}},
      {"status", status_},
      {"clips", clips},
      {"clips_left_out", describe_left_out(session_->library())},
      {"roles", session_->options().roles},
      {"agents", agents},
      {"exhibits", exhibits}};
  std::ofstream out(path);
  out << j.dump(1) << "\n";
  if (!out) fail("demo", 1, path + ": cannot write the report");
}

}  // namespace gk::app
