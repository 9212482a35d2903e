// Text over the demo's 3D view (Dear ImGui's foreground list): which half of the split is which,
// frames per second and the simulation's speed against real time, the selected agent's twist
// above its head, hints over an empty scene, and the help window (H).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include <imgui.h>

#include "app/demo_app.h"

namespace gk::app {
namespace {

constexpr ImU32 kWhite = IM_COL32(255, 255, 255, 255);
constexpr ImU32 kShade = IM_COL32(0, 0, 0, 160);

// Text with a dark box behind it, at `size_px` (the default font scaled), centred on at.x when
// `centred`; lines longer than `wrap_px` wrap.
void boxed_text(ImDrawList* dl, ImVec2 at, const char* text, float size_px, ImU32 color,
                bool centred = false, float wrap_px = 0.0f) {
  ImFont* font = ImGui::GetFont();
  const ImVec2 extent = font->CalcTextSizeA(size_px, 1e9f, wrap_px, text);
  if (centred) at.x = std::max(8.0f, at.x - 0.5f * extent.x);
  dl->AddRectFilled(ImVec2(at.x - 5, at.y - 3), ImVec2(at.x + extent.x + 5, at.y + extent.y + 3),
                    kShade, 4.0f);
  dl->AddText(font, size_px, at, color, text, nullptr, wrap_px);
}

// A label above the head projected at `head_px` in the half at `offset_x` of `width` x `height`:
// kept inside that half (the head may be near or past its edge, e.g. a twin running ahead).
void above_head(ImDrawList* dl, glm::vec2 head_px, float offset_x, float width, float height,
                const char* text, float size_px, ImU32 color) {
  const ImVec2 extent = ImGui::GetFont()->CalcTextSizeA(size_px, 1e9f, 0.0f, text);
  const float x = std::clamp(head_px.x - 0.5f * extent.x, 8.0f,
                             std::max(8.0f, width - extent.x - 8.0f));
  const float y = std::clamp(head_px.y - 1.7f * size_px, 6.0f + 1.6f * size_px,
                             std::max(6.0f + 1.6f * size_px, height - 2.0f * size_px));
  boxed_text(dl, ImVec2(offset_x + x, y), text, size_px, color);
}

}  // namespace

void DemoApp::draw_overlay_text() {
  ImDrawList* fg = ImGui::GetForegroundDrawList();
  const glm::ivec2 view = view_size();
  const bool split = session_->has_compare();
  const float half = static_cast<float>(view.x);
  const float base = ImGui::GetFontSize();
  char text[160];
  if (split) {
    const std::string_view right =
        lesson_ ? lesson_->on_label : mediator_mode_name(session_->params().mode);
    std::snprintf(text, sizeof(text), "%.*s", static_cast<int>(right.size()), right.data());
    boxed_text(fg, ImVec2(12, 10), lesson_ ? lesson_->off_label : "naive", base * 1.4f, kWhite);
    boxed_text(fg, ImVec2(half + 12, 10), text, base * 1.4f, kWhite);
    fg->AddLine(ImVec2(half, 0), ImVec2(half, static_cast<float>(view.y)),
                IM_COL32(20, 20, 20, 255), 2.0f);
  }
  // Frames per second and whether the simulation keeps real time, bottom left of the view.
  const float bottom = static_cast<float>(view.y) - base - 10.0f;
  if (fps_ > 0.0f) {
    std::snprintf(text, sizeof(text), "%.0f FPS   sim step %.1f ms   H: help", fps_,
                  SimClock::step_s(time_scale_) * 1000.0);
  } else {
    std::snprintf(text, sizeof(text), "sim step %.1f ms   H: help",
                  SimClock::step_s(time_scale_) * 1000.0);
  }
  boxed_text(fg, ImVec2(12, bottom), text, base, IM_COL32(220, 220, 220, 255));
  draw_lesson_text(bottom - base * 2.6f);
  if (clock_.behind() && !paused_) {
    std::snprintf(text, sizeof(text), "simulation at %.2fx real time (asked %.2fx): this machine "
                  "cannot keep up", clock_.achieved_rate(), time_scale_);
    boxed_text(fg, ImVec2(12, bottom - base * 1.8f), text, base * 1.2f,
               IM_COL32(255, 170, 60, 255));
  } else if (scrubbing()) {
    std::snprintf(text, sizeof(text), "recorded %.2f s (live %.2f s)",
                  recorder_->time_s(scrub_), session_->crowd().time_s());
    boxed_text(fg, ImVec2(12, bottom - base * 1.8f), text, base * 1.2f,
               IM_COL32(120, 200, 255, 255));
  } else if (paused_) {
    boxed_text(fg, ImVec2(12, bottom - base * 1.8f), "paused (Space)", base * 1.2f,
               IM_COL32(255, 220, 90, 255));
  }
  // The torso fan's reading above the selected head, in each half.
  if (overlays_.torso && selected_id_ >= 0) {
    auto label = [&](const AnimationLane& lane, float offset_x) {
      const std::optional<TorsoReadout> t = torso_readout(*session_, lane, selected_id_);
      if (!t) return;
      const ProjectedPoint p = camera_.project(t->head, view);
      if (!p.in_front) return;
      std::snprintf(text, sizeof(text), "twist %.0f\xc2\xb0 (limit %.0f\xc2\xb0)",
                    std::abs(t->twist_deg), t->limit_deg);
      above_head(fg, p.pixel, offset_x, half, static_cast<float>(view.y), text, base * 1.3f,
                 IM_COL32(255, 200, 120, 255));
    };
    label(session_->lane(), split ? half : 0.0f);
    if (split) label(session_->compare_lane(), 0.0f);
  }
  // The legs' angle to the simulator's path above the selected head, in each half.
  if (overlays_.legs && selected_id_ >= 0) {
    auto label = [&](const AnimationLane& lane, float offset_x) {
      const std::optional<LegsReadout> l = legs_readout(*session_, lane, selected_id_);
      if (!l) return;
      const ProjectedPoint p = camera_.project(l->head, view);
      if (!p.in_front) return;
      std::snprintf(text, sizeof(text), "sim %.1f m/s, legs max %.1f", l->speed_m_s,
                    l->legs_max_m_s);
      above_head(fg, p.pixel, offset_x, half, static_cast<float>(view.y), text, base * 1.3f,
                 IM_COL32(255, 140, 120, 255));
    };
    label(session_->lane(), split ? half : 0.0f);
    if (split) label(session_->compare_lane(), 0.0f);
  }
  const char* h = hint();
  if (*h) {
    const glm::ivec2 scene = scene_size();
    boxed_text(fg, ImVec2(0.5f * static_cast<float>(scene.x), 0.42f * static_cast<float>(scene.y)),
               h, base * 1.5f, IM_COL32(255, 230, 140, 255), true,
               static_cast<float>(scene.x) - 40.0f);
  }
  if (help_) {
    draw_help();
  } else {
    help_rect_ = glm::vec4(0.0f);
    help_focused_ = false;
  }
}

void DemoApp::draw_help() {
  const glm::ivec2 scene = scene_size();
  // Over the scene, not the panel: as wide as the text or the scene allows, on top of the panel.
  const float width = std::min(600.0f, static_cast<float>(scene.x) - 20.0f);
  ImGui::SetNextWindowPos(ImVec2(0.5f * static_cast<float>(scene.x), 0.5f * scene.y),
                          ImGuiCond_Always, ImVec2(0.5f, 0.5f));
  ImGui::SetNextWindowSize(ImVec2(width, 0.0f), ImGuiCond_Always);
  ImGui::SetNextWindowSizeConstraints(ImVec2(width, 0.0f),
                                      ImVec2(width, static_cast<float>(scene.y) - 20.0f));
  ImGui::SetNextWindowBgAlpha(0.92f);
  // Brought to the front when it opens (not on every frame: focusing takes the mouse from a
  // slider being dragged in the panel).
  if (!help_focused_) ImGui::SetNextWindowFocus(), help_focused_ = true;
  ImGui::Begin("Help (H closes)", &help_, ImGuiWindowFlags_NoCollapse |
                                              ImGuiWindowFlags_NoSavedSettings |
                                              ImGuiWindowFlags_NoResize);
  const ImVec2 pos = ImGui::GetWindowPos(), size = ImGui::GetWindowSize();
  help_rect_ = glm::vec4(pos.x, pos.y, size.x, size.y);
  ImGui::PushTextWrapPos(0.0f);
  ImGui::TextUnformatted(
      "Keys\n"
      "  Space   pause / run\n"
      "  H       this help\n"
      "  R       restart the crowd (same seed, current parameters)\n"
      "  Esc     quit\n"
      "  Left / Right          timeline: back / forward 0.05 s (pauses)\n"
      "  Page Up / Page Down   timeline: back / forward 5 s\n"
      "  Lessons menu (panel): one idea off | on, with what to look at\n"
      "\n"
      "Mouse\n"
      "  left click    select an agent: the camera follows it\n"
      "  right drag    orbit       middle drag   pan (stops following)\n"
      "  wheel         zoom toward the cursor (toward the agent while following)\n"
      "\n"
      "What to look at\n"
      "  foot trails: green = a planted foot that stays put, red = a foot sliding\n"
      "  over the ground (skating). Naive animation (left in the split) slides;\n"
      "  the mediator (right) pins feet, matches playback to speed, and turns the\n"
      "  upper body toward where the agent looks (torso fan: blue pelvis, orange\n"
      "  chest, yellow look direction, white arc the twist limit).");
  ImGui::PopTextWrapPos();
  ImGui::End();
}

}  // namespace gk::app
