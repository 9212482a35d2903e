// The demo's Dear ImGui panel: crowd (rebuilds the session; files picked with a folder browser),
// the loaded clips, mediator parameters (live, in plain words; saved and loaded as JSON), view and
// overlays, live metrics with plots, per-stage timings, and the selected agent's animation state.
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <imgui.h>
#include <imgui_stdlib.h>

#include "app/demo_app.h"
#include "app/param_labels.h"
#include "crowd/trajectory_replay.h"

namespace gk::app {
namespace {

constexpr float kPanelWidth = static_cast<float>(kPanelWidth_px);
constexpr float kLabelColumn = 172.0f;  // [px] plain-language labels left, widgets right
constexpr const char* kSims[] = {"social forces", "DetourCrowd", "replay a trajectory file"};
constexpr const char* kModes[] = {"naive", "rate", "apm"};
enum BrowseFor : int {
  kBrowseClips,
  kBrowseTrajectory,
  kBrowseLoadParams,
  kBrowseSaveParams,
  kBrowseRoles
};

void help_marker(const char* text) {
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", text);
}

// A label in the left column; the next widget fills the rest of the row.
void row(const char* label) {
  ImGui::AlignTextToFramePadding();
  ImGui::TextUnformatted(label);
  ImGui::SameLine(kLabelColumn);
  ImGui::SetNextItemWidth(-FLT_MIN);
}

}  // namespace

void DemoApp::draw_panel() {
  const ImGuiIO& io = ImGui::GetIO();
  ImGui::SetNextWindowPos(ImVec2(io.DisplaySize.x - kPanelWidth, 0.0f), ImGuiCond_Always);
  ImGui::SetNextWindowSize(ImVec2(kPanelWidth, io.DisplaySize.y), ImGuiCond_Always);
  ImGui::SetNextWindowBgAlpha(1.0f);
  ImGui::Begin("Gaitkeeper", nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse |
                   ImGuiWindowFlags_MenuBar);
  lessons_menu();
  const ImVec2 pos = ImGui::GetWindowPos(), size = ImGui::GetWindowSize();
  panel_rect_ = glm::vec4(pos.x, pos.y, size.x, size.y);
  if (!status_.empty()) {
    ImGui::PushTextWrapPos(0.0f);
    ImGui::TextColored(ImVec4(1.0f, 0.4f, 0.3f, 1.0f), "%s", status_.c_str());
    ImGui::PopTextWrapPos();
  }
  ImGui::TextDisabled("Space pause, H help, R restart, Esc quit");
  if (ImGui::CollapsingHeader("Crowd", ImGuiTreeNodeFlags_DefaultOpen)) panel_crowd();
  if (ImGui::CollapsingHeader("View", ImGuiTreeNodeFlags_DefaultOpen)) panel_view();
  if (ImGui::CollapsingHeader("Timeline (last 60 s)", ImGuiTreeNodeFlags_DefaultOpen)) {
    panel_timeline();
  }
  if (lesson_ && lesson_->rate_plot) ImGui::SetNextItemOpen(true, ImGuiCond_Always);
  if (ImGui::CollapsingHeader("Stride and cadence against speed")) panel_gait();
  if (ImGui::CollapsingHeader("Metrics", ImGuiTreeNodeFlags_DefaultOpen)) panel_metrics();
  if (ImGui::CollapsingHeader("Selected agent", ImGuiTreeNodeFlags_DefaultOpen)) panel_agent();
  if (ImGui::CollapsingHeader("Level of detail")) panel_lod();
  if (ImGui::CollapsingHeader("Clips")) panel_clips();
  if (ImGui::CollapsingHeader("Mediator parameters")) panel_params();
  ImGui::End();
  // The focus is the camera's eye on the ground, every frame (also with the section closed).
  if (session_) {
    const glm::vec3 eye = camera_.eye();
    lod_.focus = glm::vec2(eye.x, eye.z);
    if (Status s = session_->pipeline().set_lod(lod_); !s.ok()) lod_.enabled = false;
  }
}

void DemoApp::panel_lod() {
  row("Level of detail");
  ImGui::Checkbox("##lod", &lod_.enabled);
  help_marker(
      "Agents far from the camera are planned and posed less often and with less: level 0 every "
      "frame with everything, 1 every 2nd frame without new foot locks, 2 every 4th and 3 every "
      "8th also without spine twist. Between updates their phase advances and their body follows "
      "the simulator. The metrics then cover level 0 agents only. (primary lane; "
      "docs/pipeline.md)");
  row("Boundaries [m]");
  float d[3] = {lod_.distances_m[0], lod_.distances_m[1], lod_.distances_m[2]};
  if (ImGui::DragFloat3("##lod_d", d, 0.5f, 0.0f, 1000.0f, "%.1f")) {
    d[1] = std::max(d[1], d[0]);
    d[2] = std::max(d[2], d[1]);
    for (int k = 0; k < 3; ++k) lod_.distances_m[k] = d[k];
  }
  help_marker("distances_m: levels 1, 2 and 3 start this far from the camera [m]");
  row("Hysteresis [m]");
  ImGui::SliderFloat("##lod_h", &lod_.hysteresis_m, 0.0f, 10.0f, "%.1f");
  help_marker("hysteresis_m: a level changes only this far past its boundary [m], so agents on a "
              "boundary do not flicker");
  if (!lod_.enabled || !session_) {
    ImGui::TextDisabled("off: every agent at full detail");
    return;
  }
  const LodPolicy& lod = session_->pipeline().lod();
  ImGui::Text("agents per level: %lld / %lld / %lld / %lld",
              static_cast<long long>(lod.counts()[0]), static_cast<long long>(lod.counts()[1]),
              static_cast<long long>(lod.counts()[2]), static_cast<long long>(lod.counts()[3]));
  ImGui::TextDisabled("every 1 / 2 / 4 / 8 frames; metrics: level 0 only");
}

void DemoApp::panel_crowd() {
  bool changed = false;
  row("simulator");
  if (ImGui::Combo("##simulator", &sim_kind_, kSims, 3)) changed = sim_kind_ != 2;
  if (sim_kind_ == 2) {
    row("trajectory file");
    ImGui::InputText("##trajectory", &replay_path_);
    help_marker(
        "A trajectory file: ETH/UCY .txt (frame id x y, or ETH's 8-column obsmat.txt), or CSV "
        "(.csv, .tsv, .dat) with a header naming frame (or time in seconds), id, x and y; "
        "positions in cm or mm are recognised; e.g. "
        "../shared/data/trajectories/zara1/crowds_zara01.txt");
    if (ImGui::Button("browse...##trajectory")) {
      browser_.open("Trajectory file", browse_start(replay_path_, "trajectories"),
                    {".txt", ".csv", ".tsv", ".dat"},
                    FileBrowser::Mode::kOpen, false, kBrowseTrajectory);
    }
    ImGui::SameLine();
    if (ImGui::Button("load trajectory")) changed = true;
  } else {
    row("scenario");
    if (ImGui::BeginCombo("##scenario", crowd_.scenario.c_str())) {
      for (const std::string& name : scenario_names_) {
        if (ImGui::Selectable(name.c_str(), name == crowd_.scenario)) {
          crowd_.scenario = name;
          agents_edited_ = false;  // a new scenario comes with its own agent count
          changed = true;
        }
      }
      ImGui::EndCombo();
    }
    row("agents");
    ImGui::InputInt("##agents", &agents_, 10, 100);
    help_marker(
        "Agent count (a new scenario starts with its own default); the scenario's geometry grows "
        "to keep its spawn density. Applied when you leave the field.");
    if (ImGui::IsItemDeactivatedAfterEdit()) changed = true, agents_edited_ = true;
  }
  row("clips");
  if (ImGui::Checkbox("built-in##clips", &builtin_clips_) && builtin_clips_) changed = true;
  if (!builtin_clips_) {
    ImGui::SetNextItemWidth(-FLT_MIN);
    ImGui::InputText("##clip_path", &clip_path_);
    help_marker("A BVH/glTF/GLB file or a folder of them, e.g. ../shared/data/clips/bvh");
    if (ImGui::Button("browse...##clips")) {
      browser_.open("Clip file or folder", browse_start(clip_path_, "clips"),
                    {".bvh", ".gltf", ".glb"}, FileBrowser::Mode::kOpen, true, kBrowseClips);
    }
    ImGui::SameLine();
    if (ImGui::Button("load clips")) changed = true;
    // The role manifest in use (the session's, not a choice that failed to load).
    const std::string& in_use = session_->options().roles;
    row("roles");
    ImGui::TextUnformatted(in_use.empty()
                               ? "from joint names"
                               : std::filesystem::path(in_use).filename().string().c_str());
    help_marker(
        "Which joint is the hips, each knee, ankle, toe...: found from the joint names (and, for "
        "feet parented to the root, from the rest pose), or given by a role manifest (--roles), "
        "a JSON file {\"roles\": {\"left_knee\": \"Knee_L\", ...}}. A library whose legs "
        "cannot be found says which roles are missing.");
    if (ImGui::Button("roles...")) {
      browser_.open("Role manifest",
                    roles_path_.empty() ? browse_start(clip_path_, "clips") : roles_path_,
                    {".json"}, FileBrowser::Mode::kOpen, false, kBrowseRoles);
    }
    if (!roles_path_.empty()) {
      ImGui::SameLine();
      if (ImGui::Button("no manifest")) {
        roles_path_.clear();
        changed = true;
      }
    }
  }
  // What the clips cannot play, said where the clips are chosen (the Clips section says what).
  const size_t gaps = library_gaps().size();
  if (gaps > 0) {
    ImGui::TextColored(ImVec4(1.0f, 0.7f, 0.3f, 1.0f), "%zu library gap%s: see Clips", gaps,
                       gaps == 1 ? "" : "s");
  }
  row("animation");
  int mode = static_cast<int>(session_->params().mode);
  if (ImGui::Combo("##mode", &mode, kModes, 3)) {
    MediatorParams p = session_->params();
    p.mode = static_cast<MediatorMode>(mode);
    session_->set_params(p);
  }
  help_marker(
      "naive: nearest clip at its native rate (skating); rate: speed-matched playback "
      "only; apm: the whole mediator");
  if (changed) apply_crowd();
  ImGui::Text("%s, %zu live agents, t = %.1f s", session_->crowd().name().c_str(),
              session_->frame().size(), session_->crowd().time_s());
}

void DemoApp::apply_crowd() {
  lesson_ = nullptr;  // another crowd: the lesson's text and split no longer apply
  crowd_.builtin_walks_only = false;  // nor its clip library
  crowd_.sim = sim_kind_ == 1 ? "detour" : "social";
  if (sim_kind_ == 2) {
    crowd_.scenario = replay_path_;
    crowd_.agents.clear();
  } else {
    if (is_trajectory_file_name(crowd_.scenario)) crowd_.scenario = "crossing";
    crowd_.agents = agents_edited_ ? std::to_string(std::max(agents_, 0)) : "";
  }
  crowd_.clips.clear();
  if (!builtin_clips_) crowd_.clips.push_back(clip_path_);
  crowd_.roles = builtin_clips_ ? "" : roles_path_;
  // Keep the current parameters (and mode) across the rebuild.
  crowd_.sets.clear();
  crowd_.params_file.clear();
  crowd_.mode = std::string(mediator_mode_name(session_->params().mode));
  const MediatorParams keep = session_->params();
  if (rebuild()) session_->set_params(keep);
}

const std::vector<std::string>& DemoApp::library_gaps() {
  const MediatorParams& p = session_->params();
  if (!gaps_.valid || gaps_.min_rate != p.min_playback_rate ||
      gaps_.max_rate != p.max_playback_rate || gaps_.stride_warp != p.max_stride_warp) {
    gaps_ = {true, p.min_playback_rate, p.max_playback_rate, p.max_stride_warp,
             describe_gaps(session_->library(), p)};
  }
  return gaps_.lines;
}

void DemoApp::panel_clips() {
  const auto& clips = session_->library().clips;
  ImGui::Text("%zu clips (speed and direction from clip analysis)", clips.size());
  if (!ImGui::BeginTable("clips", 4, ImGuiTableFlags_RowBg | ImGuiTableFlags_ScrollY,
                         ImVec2(0.0f, 160.0f))) {
    return;
  }
  ImGui::TableSetupColumn("clip");
  ImGui::TableSetupColumn("m/s", ImGuiTableColumnFlags_WidthFixed, 44.0f);
  ImGui::TableSetupColumn("dir", ImGuiTableColumnFlags_WidthFixed, 40.0f);
  ImGui::TableSetupColumn("cycle s", ImGuiTableColumnFlags_WidthFixed, 52.0f);
  ImGui::TableHeadersRow();
  for (const LocomotionClip& c : clips) {
    ImGui::TableNextRow();
    ImGui::TableNextColumn();
    if (c.doubts.empty()) {
      ImGui::TextUnformatted(c.clip.name.c_str());
    } else {
      ImGui::TextColored(ImVec4(1.0f, 0.7f, 0.3f, 1.0f), "%s (doubtful)", c.clip.name.c_str());
    }
    ImGui::TableNextColumn();
    ImGui::Text("%.2f", c.speed_m_s);
    ImGui::TableNextColumn();
    ImGui::Text("%.0f", c.direction_rad * 57.29578f);
    ImGui::TableNextColumn();
    ImGui::Text("%.2f", c.cycle_s);
  }
  ImGui::EndTable();
  // What the given files hold that the library does not use, and why (never dropped silently).
  const std::vector<std::string> left_out = describe_left_out(session_->library());
  if (!left_out.empty()) {
    ImGui::Text("left out (%zu clips):", session_->library().left_out.size());
    ImGui::PushTextWrapPos(0.0f);
    for (const std::string& l : left_out) ImGui::TextDisabled("%s", l.c_str());
    ImGui::PopTextWrapPos();
  }
  // Clips whose contacts cannot be trusted are played without foot locks (README: analyze-clip).
  const std::vector<std::string> doubtful = describe_doubts(session_->library());
  if (!doubtful.empty()) {
    ImGui::Text("doubtful analysis (%zu clips):", doubtful.size());
    ImGui::PushTextWrapPos(0.0f);
    for (const std::string& d : doubtful) ImGui::TextDisabled("%s", d.c_str());
    ImGui::PopTextWrapPos();
  }
  // What the clips cannot play (no walk; a walk and a run too far apart in speed).
  const std::vector<std::string>& gaps = library_gaps();
  if (!gaps.empty()) {
    ImGui::Text("library gaps:");
    ImGui::PushTextWrapPos(0.0f);
    for (const std::string& g : gaps) ImGui::TextDisabled("%s", g.c_str());
    ImGui::PopTextWrapPos();
  }
}

void DemoApp::panel_view() {
  if (ImGui::Checkbox("pause", &paused_)) clock_.reset();
  ImGui::SameLine();
  if (ImGui::Button("step")) step_requested_ = true, paused_ = true;
  ImGui::SameLine();
  if (ImGui::Button("restart")) restart_requested_ = true;
  row("time scale");
  ImGui::SliderFloat("##time_scale", &time_scale_, 0.05f, 2.0f, "%.2fx");
  if (ImGui::Checkbox(lesson_ ? "compare the lesson's idea off | on" : "compare naive | apm",
                      &compare_)) {
    if (compare_ && lesson_ && lesson_->own_crowd) {
      start_lesson(*lesson_);  // each half's own crowd starts together
    } else if (compare_) {
      enable_split();
    } else {
      session_->disable_compare();
    }
  }
  help_marker(
      "Split screen on the same crowd: the naive crowd on the left, the chosen mode on "
      "the right (only the right one feeds back to the simulator).");
  ImGui::Checkbox("v", &overlays_.velocity);
  help_marker("Simulator velocity v (green arrow on the ground, 0.5 s of travel)");
  ImGui::SameLine();
  ImGui::Checkbox("theta", &overlays_.theta);
  help_marker("Desired torso orientation theta from the simulator (yellow, above the head)");
  ImGui::SameLine();
  ImGui::Checkbox("facing", &overlays_.facing);
  help_marker("Lower body (pelvis, blue) and upper body (chest, orange) facing");
  ImGui::SameLine();
  ImGui::Checkbox("torso fan", &overlays_.torso);
  help_marker(
      "Selected agent: pelvis (blue), chest (orange) and theta (yellow) directions, the twist "
      "filled between pelvis and chest, the torsion limit as a white arc, the twist above the "
      "head");
  ImGui::Checkbox("planted feet", &overlays_.planted);
  help_marker("White crosses: feet locked in world space by two-bone IK");
  ImGui::SameLine();
  ImGui::Checkbox("foot trails", &overlays_.trails);
  help_marker(
      "Support-foot toe within 5 cm of the clips' floor (METRICS.md v2): green = still, red = "
      "sliding >= 30 cm/s");
  ImGui::SameLine();
  ImGui::Checkbox("paths", &overlays_.paths);
  help_marker("Root path of the last 4 s");
  ImGui::SameLine();
  ImGui::Checkbox("legs vs path", &overlays_.legs);
  help_marker(
      "Selected agent: where its legs walk (blue), where the simulator moves it (green), the "
      "angle between them filled red, the band within which feedback keeps the simulator's "
      "velocity (white, turn_feedback_deg), and above the head the simulator's speed against "
      "the fastest the legs can go");
  ImGui::TextDisabled("right drag orbit, middle drag pan, wheel zoom, click an agent");
}

void DemoApp::panel_metrics() {
  const bool behind = clock_.behind() && !paused_;
  if (fps_ > 0.0f) {
    ImGui::Text("%.0f FPS", fps_);
  } else {
    ImGui::TextDisabled("FPS after 0.5 s");
  }
  ImGui::SameLine();
  if (behind) {
    ImGui::TextColored(ImVec4(1.0f, 0.65f, 0.25f, 1.0f), "simulation at %.2fx real time",
                       clock_.achieved_rate());
  } else {
    ImGui::TextDisabled("simulation %s", paused_ ? "paused" : "keeps real time");
  }
  panel_mesh_lod();
  const int n = metrics_.count();
  for (int s = 0; s < kNumLiveSeries; ++s) {
    const auto series = static_cast<LiveSeries>(s);
    char overlay[64];
    if (session_->has_compare() && compare_metrics_.count() > 0) {
      // The left half's figure, named as the split names it.
      std::snprintf(overlay, sizeof(overlay), "%.2f %s (%s %.2f)", metrics_.mean(series),
                    LiveMetrics::unit(series), lesson_ ? lesson_->off_label : "naive",
                    compare_metrics_.mean(series));
    } else {
      std::snprintf(overlay, sizeof(overlay), "%.2f %s (5 s mean)", metrics_.mean(series),
                    LiveMetrics::unit(series));
    }
    ImGui::PlotLines(LiveMetrics::label(series), metrics_.series(series), n, 0, overlay, FLT_MAX,
                     FLT_MAX, ImVec2(0, 36));
  }
  ImGui::Text("ms:");
  for (int s = 0; s < kNumLiveStages; ++s) {
    ImGui::SameLine();
    ImGui::Text("%s %.2f", LiveMetrics::stage_name(static_cast<LiveStage>(s)),
                metrics_.stage_ms(static_cast<LiveStage>(s)));
    if (s == 2) ImGui::NewLine();
  }
  ImGui::PlotLines("frame ms", metrics_.stage_series(), metrics_.stage_count(), 0, nullptr, 0.0f,
                   FLT_MAX, ImVec2(0, 36));
}

void DemoApp::panel_mesh_lod() {
  // What the last draw (the right half of a split) cost the rasteriser, and where its agents went.
  const CrowdRenderer& r = view_->renderer();
  const RenderStats& st = r.stats();
  ImGui::Checkbox("mesh LOD", &mesh_lod_);
  if (ImGui::IsItemHovered()) {
    ImGui::SetTooltip(
        "Lighter meshes for agents small on screen: each agent gets the lightest "
        "level whose error stays under %.1f px (--mesh-lod)",
        r.settings().mesh_lod_selection.max_error_px);
  }
  ImGui::SameLine();
  ImGui::Text("%.3fM agent triangles drawn", static_cast<double>(st.agent_triangles) * 1e-6);
  char agents[96] = "", triangles[96] = "";
  for (int l = 0, a = 0, t = 0; l < r.num_mesh_lods(0); ++l) {
    const char* sep = l > 0 ? " | " : "";
    a += std::snprintf(agents + a, sizeof(agents) - a, "%s%d", sep, st.agents_per_lod[l]);
    t += std::snprintf(triangles + t, sizeof(triangles) - t, "%s%d", sep,
                       r.mesh_lod_triangles(0, l));
  }
  ImGui::Text("agents per level  %s", agents);
  ImGui::TextDisabled("triangles each    %s", triangles);
}

void DemoApp::panel_agent() {
  if (selected_id_ < 0) {
    ImGui::TextDisabled("click an agent to follow it");
    return;
  }
  if (scrubbing()) {
    // The recorded moment: what the record holds of this agent.
    const auto a = recorder_->agent(scrub_, 0, selected_id_);
    if (!a) {
      ImGui::Text("agent %lld is not in the scene at t = %.2f s",
                  static_cast<long long>(selected_id_), recorder_->time_s(scrub_));
      return;
    }
    ImGui::Text("agent %lld at t = %.2f s (recorded)", static_cast<long long>(selected_id_),
                recorder_->time_s(scrub_));
    ImGui::Text("position (%.2f, %.2f) m  speed %.2f m/s", a->root_xz.x, a->root_xz.y,
                glm::length(a->velocity_xz));
    ImGui::Text("playback rate %.2fx  %s", a->playback_rate, a->posed ? "" : "(not posed)");
    return;
  }
  const AgentFrame& frame = session_->frame();
  int index = -1;
  for (size_t i = 0; i < frame.size(); ++i) {
    if (frame.ids[i] == selected_id_) index = static_cast<int>(i);
  }
  if (index < 0) {
    ImGui::Text("agent %lld is not in the scene", static_cast<long long>(selected_id_));
    return;
  }
  const AnimationPlans& plans = session_->mediator().plans();
  const int slot = plans.slot_of_agent[index];
  ImGui::Text("agent %lld  speed %.2f m/s  %s", static_cast<long long>(selected_id_),
              plans.speed_m_s[slot], plans.standing[slot] ? "(standing)" : "");
  bool follow = director_.following();
  if (ImGui::Checkbox("follow", &follow)) {
    if (follow) {
      director_.follow(selected_id_);
    } else {
      director_.stop_following();
    }
  }
  ImGui::Text("phase %.2f  playback rate %.2fx  blend %.2f", plans.phase[slot],
              plans.playback_rate[slot], plans.blend_progress[slot]);
  ImGui::Text("torsion %.1f deg", session_->poses().torsion(slot) * 57.29578f);
  const auto& clips = session_->library().clips;
  for (int k = 0; k < kMaxBlendLayers; ++k) {
    const int c = plans.layer_clip[slot * kMaxBlendLayers + k];
    const float w = plans.layer_weight[slot * kMaxBlendLayers + k];
    if (c < 0 || c >= static_cast<int>(clips.size()) || w <= 0.0f) continue;
    ImGui::ProgressBar(w, ImVec2(120.0f, 0.0f));
    ImGui::SameLine();
    ImGui::Text("%s", clips[c].clip.name.c_str());
  }
  const FootLocks& locks = session_->poses().foot_locks();
  static constexpr const char* kLock[] = {"free", "locked", "releasing", "stepping"};
  ImGui::Text("left foot %s, right foot %s",
              kLock[std::min<int>(static_cast<int>(locks.lock[slot * 2].state), 3)],
              kLock[std::min<int>(static_cast<int>(locks.lock[slot * 2 + 1].state), 3)]);
}

void DemoApp::panel_params() {
  MediatorParams p = session_->params();
  bool changed = false;
  for (const ParamInfo& info : mediator_param_infos()) {
    ImGui::PushID(info.name);
    row(param_label(info.name));
    const bool label_hovered = ImGui::IsItemHovered();
    if (info.kind == ParamInfo::Kind::kBool) {
      changed |= ImGui::Checkbox("##value", &(p.*info.b));
    } else {
      // A range over two decades or more (a halflife, an acceleration) is logarithmic: on a
      // linear slider its default sat in the first pixel or two.
      const bool decades = info.min_value > 0.0f && info.max_value >= 100.0f * info.min_value;
      char format[48];
      std::snprintf(format, sizeof(format), info.max_value >= 1000.0f ? "%%.0f %s" : "%%.3f %s",
                    info.unit);
      changed |= ImGui::SliderFloat(
          "##value", &(p.*info.f), info.min_value, info.max_value, format,
          ImGuiSliderFlags_AlwaysClamp | (decades ? ImGuiSliderFlags_Logarithmic : 0));
    }
    if (label_hovered || ImGui::IsItemHovered()) {
      if (info.kind == ParamInfo::Kind::kBool) {
        ImGui::SetTooltip("%s\n%s (on/off)", info.help, info.name);
      } else {
        ImGui::SetTooltip("%s\n%s [%s], limits %g..%g", info.help, info.name, info.unit,
                          info.min_value, info.max_value);
      }
    }
    ImGui::PopID();
  }
  if (ImGui::Button("defaults")) {
    const MediatorMode mode = p.mode;
    const uint64_t seed = p.seed;
    p = MediatorParams{};
    p.mode = mode;
    p.seed = seed;
    changed = true;
  }
  ImGui::SameLine();
  if (ImGui::Button("save...")) {
    browser_.open("Save parameters", params_path_, {".json"}, FileBrowser::Mode::kSave, false,
                  kBrowseSaveParams);
  }
  ImGui::SameLine();
  if (ImGui::Button("load...")) {
    browser_.open("Load parameters", params_path_, {".json"}, FileBrowser::Mode::kOpen, false,
                  kBrowseLoadParams);
  }
  if (!note_.empty()) ImGui::TextWrapped("%s", note_.c_str());
  if (changed && validate_mediator_params(p).ok()) session_->set_params(p);
}

void DemoApp::handle_browser() {
  if (!browser_.draw()) return;
  const std::string& path = browser_.chosen();
  switch (browser_.tag()) {
    case kBrowseClips:
      clip_path_ = path;
      apply_crowd();
      break;
    case kBrowseTrajectory:
      replay_path_ = path;
      apply_crowd();
      break;
    case kBrowseRoles:
      roles_path_ = path;
      if (!clip_path_.empty()) apply_crowd();  // else it applies when the clips are chosen
      break;
    case kBrowseSaveParams: {
      params_path_ = path;
      std::ofstream out(path);
      out << mediator_params_to_json(session_->params());
      note_ = out ? "saved " + path : path + ": cannot write the file";
      break;
    }
    case kBrowseLoadParams: {
      params_path_ = path;
      MediatorParams p = session_->params();
      const Status s = load_mediator_params_json(path, &p);
      if (s.ok()) session_->set_params(p);
      note_ = s.ok() ? "loaded " + path : s.message();
      break;
    }
  }
}

}  // namespace gk::app
