// The demo's lessons (app/lessons.h): the Lessons menu, starting a lesson (scenario, split, camera,
// speed, overlays), its text over the scene, and the selected agent's stride length and cadence
// against speed beside the clip's own values (what playback-rate matching changes).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include <imgui.h>

#include "app/demo_app.h"

namespace gk::app {

void DemoApp::enable_split() {
  if (lesson_) {
    session_->enable_compare(lesson_->off, lesson_->own_crowd);
  } else {
    session_->enable_compare(MediatorMode::kNaive);
  }
  compare_history_.emplace(*session_, session_->crowd().capacity());
  compare_metrics_.reset();
}

void DemoApp::start_lesson(const Lesson& lesson) {
  lesson_ = &lesson;
  showcase_ = false;
  pick_showcase_ = false;
  crowd_.scenario = lesson.scenario;
  crowd_.builtin_walks_only = lesson.walk_clips_only;
  if (lesson.walk_clips_only) {  // the lesson is about the built-in forward clips
    crowd_.clips.clear();
    builtin_clips_ = true;
  }
  crowd_.sim = "social";
  sim_kind_ = 0;
  crowd_.agents = lesson.agents > 0 ? std::to_string(lesson.agents) : "";
  agents_edited_ = lesson.agents > 0;
  crowd_.seed = std::to_string(lesson.seed);
  crowd_.mode = "apm";
  crowd_.sets.clear();
  crowd_.params_file.clear();
  compare_ = false;  // the lesson's split is set below, on the new session
  if (!rebuild()) {
    lesson_ = nullptr;
    return;
  }
  MediatorParams p;
  p.seed = session_->params().seed;
  lesson.on(&p);
  session_->set_params(p);
  compare_ = true;
  enable_split();
  overlays_ = lesson.overlays;
  time_scale_ = lesson.time_scale;
  paused_ = false;
  help_ = false;
  overview_yaw_ = glm::radians(lesson.yaw_deg);
  camera_.yaw_rad = *overview_yaw_;
  pick_lesson_agent_ = lesson.follow;
}

void DemoApp::lessons_menu() {
  if (!ImGui::BeginMenuBar()) return;
  const bool open = ImGui::BeginMenu("Lessons");
  const ImVec2 lo = ImGui::GetItemRectMin(), hi = ImGui::GetItemRectMax();
  lessons_menu_rect_ = glm::vec4(lo.x, lo.y, hi.x - lo.x, hi.y - lo.y);
  lesson_item_rects_.clear();
  if (open) {
    for (const Lesson& l : lessons()) {
      if (ImGui::MenuItem(l.title, nullptr, lesson_ == &l)) start_lesson(l);
      const ImVec2 a = ImGui::GetItemRectMin(), b = ImGui::GetItemRectMax();
      lesson_item_rects_.emplace_back(a.x, a.y, b.x - a.x, b.y - a.y);
    }
    ImGui::EndMenu();
  }
  if (lesson_) {
    ImGui::TextDisabled("lesson: %s", lesson_->title);
  }
  ImGui::EndMenuBar();
}

void DemoApp::draw_lesson_text(float bottom_px) {
  lesson_text_rect_ = glm::vec4(0.0f);
  if (!lesson_) return;
  ImDrawList* fg = ImGui::GetForegroundDrawList();
  const glm::ivec2 scene = scene_size();
  const float base = ImGui::GetFontSize();
  const float wrap = static_cast<float>(scene.x) - 40.0f;
  ImFont* font = ImGui::GetFont();
  const ImVec2 title = font->CalcTextSizeA(base * 1.2f, 1e9f, wrap, lesson_->title);
  const ImVec2 body = font->CalcTextSizeA(base, 1e9f, wrap, lesson_->text);
  // Along the bottom of the scene: the followed agent's head and its labels are above the middle.
  const ImVec2 at(20.0f, bottom_px - title.y - body.y - 8.0f);
  const ImVec2 lo(at.x - 6, at.y - 4);
  const ImVec2 hi(at.x + std::max(title.x, body.x) + 6, at.y + title.y + body.y + 8);
  lesson_text_rect_ = glm::vec4(lo.x, lo.y, hi.x - lo.x, hi.y - lo.y);
  fg->AddRectFilled(lo, hi, IM_COL32(0, 0, 0, 170), 4.0f);
  fg->AddText(font, base * 1.2f, at, IM_COL32(255, 220, 120, 255), lesson_->title);
  fg->AddText(font, base, ImVec2(at.x, at.y + title.y + 4), IM_COL32(240, 240, 240, 255),
              lesson_->text, nullptr, wrap);
}

void DemoApp::record_gait() {
  if (selected_id_ != gait_id_) {
    gait_id_ = selected_id_;
    gait_count_ = 0;
  }
  if (selected_id_ < 0) return;
  for (int l = 0; l < 2; ++l) {
    if (gait_[l].empty()) gait_[l].assign(kGaitSamples, GaitSample{0.0f, 0.0f, 0.0f});
  }
  const auto& clips = session_->library().clips;
  auto sample = [&](const AnimationLane& lane, GaitSample* out, bool primary) {
    const AgentFrame& frame = session_->frame_of(lane);
    const AnimationPlans& plans = lane.plans();
    for (size_t i = 0; i < frame.size(); ++i) {
      if (frame.ids[i] != selected_id_) continue;
      const int slot = plans.slot_of_agent[i];
      if (slot < 0) return false;
      // The leading layer's clip sets the gait cycle: one stride is one cycle of clip time.
      int clip = -1;
      float best = 0.0f;
      for (int k = 0; k < kMaxBlendLayers; ++k) {
        const float w = plans.layer_weight[slot * kMaxBlendLayers + k];
        if (w > best) best = w, clip = plans.layer_clip[slot * kMaxBlendLayers + k];
      }
      if (clip < 0 || clip >= static_cast<int>(clips.size())) return false;
      const LocomotionClip& c = clips[clip];
      const float rate = std::max(plans.playback_rate[slot], 1e-3f);
      const float cycle_s = std::max(c.cycle_s, 1e-3f);
      const float speed = glm::length(frame.velocities[i]);
      // Two steps per cycle; the cycle lasts cycle_s / rate of real time.
      *out = {speed, speed * cycle_s / rate, 120.0f * rate / cycle_s};
      if (primary) {
        native_speed_m_s_ = c.speed_m_s;
        native_stride_m_ = c.speed_m_s * cycle_s;
        native_cadence_spm_ = 120.0f / cycle_s;
      }
      return true;
    }
    return false;
  };
  const int k = gait_count_ % kGaitSamples;
  if (!sample(session_->lane(), &gait_[0][k], true)) return;
  if (!session_->has_compare() || !sample(session_->compare_lane(), &gait_[1][k], false)) {
    gait_[1][k] = gait_[0][k];
  }
  ++gait_count_;
}

void DemoApp::panel_gait() {
  const int n = std::min(gait_count_, kGaitSamples);
  if (n == 0) {
    ImGui::TextDisabled("stride and cadence: select a walking agent");
    return;
  }
  const GaitSample& last = gait_[0][(gait_count_ - 1) % kGaitSamples];
  ImGui::Text("stride %.2f m (clip %.2f)  speed %.2f m/s (clip %.2f)", last.stride_m,
              native_stride_m_, last.speed_m_s, native_speed_m_s_);
  ImGui::Text("cadence %.0f steps/min (clip %.0f)", last.cadence_spm, native_cadence_spm_);
  const bool two = session_->has_compare();
  // Two scatter plots against speed: dots of the last 4 s, the clip's own value as a cross.
  const ImVec2 size(ImGui::GetContentRegionAvail().x * 0.5f - 4.0f, 90.0f);
  auto scatter = [&](const char* title, float y_max, float native, auto value) {
    ImGui::BeginGroup();
    ImGui::TextUnformatted(title);
    const ImVec2 p0 = ImGui::GetCursorScreenPos();
    ImGui::InvisibleButton(title, size);
    ImDrawList* dl = ImGui::GetWindowDrawList();
    dl->AddRectFilled(p0, ImVec2(p0.x + size.x, p0.y + size.y), IM_COL32(30, 30, 36, 255));
    constexpr float kSpeedMax = 2.5f;  // [m/s] the x axis
    auto at = [&](float x, float y) {
      return ImVec2(p0.x + size.x * std::clamp(x / kSpeedMax, 0.0f, 1.0f),
                    p0.y + size.y * (1.0f - std::clamp(y / y_max, 0.0f, 1.0f)));
    };
    for (int lane = two ? 1 : 0; lane >= 0; --lane) {
      const ImU32 color = lane == 0 ? IM_COL32(90, 220, 120, 255) : IM_COL32(240, 90, 70, 200);
      for (int k = 0; k < n; ++k) {
        const GaitSample& s = gait_[lane][k];
        dl->AddCircleFilled(at(s.speed_m_s, value(s)), 1.8f, color);
      }
    }
    const ImVec2 c = at(native_speed_m_s_, native);
    dl->AddLine(ImVec2(c.x - 6, c.y), ImVec2(c.x + 6, c.y), IM_COL32(255, 255, 255, 255), 2.0f);
    dl->AddLine(ImVec2(c.x, c.y - 6), ImVec2(c.x, c.y + 6), IM_COL32(255, 255, 255, 255), 2.0f);
    ImGui::TextDisabled("speed 0..2.5 m/s");
    ImGui::EndGroup();
  };
  scatter("stride [m] (0..2.5)", 2.5f, native_stride_m_,
          [](const GaitSample& s) { return s.stride_m; });
  ImGui::SameLine();
  scatter("cadence [1/min] (0..180)", 180.0f, native_cadence_spm_,
          [](const GaitSample& s) { return s.cadence_spm; });
  ImGui::TextDisabled(two ? "green: right half, red: left half, cross: the clip's own"
                          : "green: this agent, cross: the clip's own");
}

}  // namespace gk::app
