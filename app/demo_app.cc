#include "app/demo_app.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>
#include <nlohmann/json.hpp>

#include "app/commands.h"
#include "app/offscreen.h"

namespace gk::app {
namespace {

using Clock = std::chrono::steady_clock;
float ms_since(Clock::time_point t) {
  return std::chrono::duration<float, std::milli>(Clock::now() - t).count();
}

constexpr const char* kNoDisplay = "no display: use `gaitkeeper render` or `gaitkeeper bench`";

}  // namespace

DemoApp::DemoApp(DemoOptions options) : options_(std::move(options)) {
  crowd_ = options_.crowd;
  crowd_.command = "demo";
  // The gallery shows the mediator at a glance: visitors walk one way and look at the exhibits.
  if (crowd_.scenario.empty()) crowd_.scenario = "gallery";
  compare_ = options_.compare;
  if (ends_with(crowd_.scenario, ".txt")) sim_kind_ = 2, replay_path_ = crowd_.scenario;
  if (crowd_.sim == "detour") sim_kind_ = 1;
  builtin_clips_ = crowd_.clips.empty();
  if (!builtin_clips_) clip_path_ = crowd_.clips.front();
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(scenario_dir(), ec)) {
    if (e.path().extension() == ".json") scenario_names_.push_back(e.path().stem().string());
  }
  std::sort(scenario_names_.begin(), scenario_names_.end());
  for (const std::string& n : options_.overlays) {
    overlays_.velocity |= n == "velocity" || n == "all";
    overlays_.theta |= n == "theta" || n == "all";
    overlays_.facing |= n == "facing" || n == "all";
    overlays_.planted |= n == "planted" || n == "all";
    overlays_.trails |= n == "trails" || n == "all";
    overlays_.paths |= n == "paths" || n == "all";
  }
}

DemoApp::~DemoApp() {
  if (imgui_ready_) {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
  }
  view_.reset();  // GL objects go while the context is still alive
  context_.reset();
}

bool DemoApp::rebuild() {
  try {
    std::unique_ptr<CrowdSession> session = CrowdSession::create(crowd_);
    auto view = SceneView::create(*session);
    if (!view.ok()) {
      status_ = "renderer: " + view.message();
      return false;
    }
    view_.reset();
    session_ = std::move(session);
    view_ = std::move(view).value();
  } catch (const ExitRequest&) {
    status_ = last_failure();
    return false;
  }
  status_.clear();
  if (compare_) session_->enable_compare(MediatorMode::kNaive);
  const size_t capacity = session_->crowd().capacity();
  history_.emplace(*session_, capacity);
  compare_history_.emplace(*session_, capacity);
  metrics_.reset();
  compare_metrics_.reset();
  selected_id_ = -1;
  follow_ = false;
  agents_ = static_cast<int>(session_->setup().agents);
  if (!camera_set_) {
    camera_ = frame_bounds(session_->bounds_min(), session_->bounds_max(), view_size());
  }
  return true;
}

glm::ivec2 DemoApp::scene_size() const {
  const glm::ivec2 fb = context_->framebuffer_size();
  return {std::max(fb.x - kPanelWidth_px, 16), fb.y};
}

glm::ivec2 DemoApp::view_size() const {
  const glm::ivec2 scene = scene_size();
  return session_ && session_->has_compare() ? glm::ivec2(scene.x / 2, scene.y) : scene;
}

void DemoApp::simulate() {
  if (paused_ && !step_once_) return;
  step_once_ = false;
  const double dt = kFrameTime_s * time_scale_;
  if (Status s = session_->step(dt); !s.ok()) {
    status_ = "simulation stopped: " + s.message();
    paused_ = true;
    return;
  }
  history_->record(*session_, session_->lane(), static_cast<float>(dt));
  if (session_->has_compare()) {
    compare_history_->record(*session_, session_->compare_lane(), static_cast<float>(dt));
    compare_metrics_.record(*session_, session_->compare_lane(), *compare_history_);
  }
  metrics_.record(*session_, session_->lane(), *history_);
  const SessionTimes& t = session_->times();
  metrics_.record_stage(LiveStage::kSim, static_cast<float>(t.sim_ms));
  metrics_.record_stage(LiveStage::kMediator, static_cast<float>(t.mediator_ms));
  metrics_.record_stage(LiveStage::kPose, static_cast<float>(t.pose_ms));
}

Status DemoApp::render_scene() {
  session_->collect();
  follow_selected();
  view_->camera() = camera_;
  view_->renderer().settings().lines_on_top = overlays_.any();
  context_->begin_frame();
  // The panel is drawn over the right edge; clear it too, the renderer clears only its regions.
  glClearColor(0.1f, 0.1f, 0.12f, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  const glm::ivec2 fb = scene_size();
  float upload_ms = 0.0f, render_ms = 0.0f;
  // glFinish after each stage so the panel's numbers are the GPU's work, not the queueing.
  auto lane_pass = [&](const AnimationLane& lane, const OverlayHistory& history, glm::ivec2 origin,
                       glm::ivec2 size) -> Status {
    auto t = Clock::now();
    GK_RETURN_IF_ERROR(view_->upload(*session_, lane));
    glFinish();
    upload_ms += ms_since(t);
    t = Clock::now();
    history.draw(*session_, lane, overlays_, selected_id_, &view_->renderer());
    GK_RETURN_IF_ERROR(view_->draw(lane, origin, size));
    glFinish();
    render_ms += ms_since(t);
    return Status::Ok();
  };
  if (session_->has_compare()) {
    const int left = fb.x / 2;
    GK_RETURN_IF_ERROR(
        lane_pass(session_->compare_lane(), *compare_history_, {0, 0}, {left, fb.y}));
    GK_RETURN_IF_ERROR(lane_pass(session_->lane(), *history_, {left, 0}, {fb.x - left, fb.y}));
  } else {
    GK_RETURN_IF_ERROR(lane_pass(session_->lane(), *history_, {0, 0}, fb));
  }
  metrics_.record_stage(LiveStage::kUpload, upload_ms);
  metrics_.record_stage(LiveStage::kRender, render_ms);
  return Status::Ok();
}

void DemoApp::follow_selected() {
  if (!follow_ || selected_id_ < 0) return;
  const AgentFrame& frame = session_->frame();
  const auto draws = session_->lane().draw_span();
  for (size_t i = 0; i < draws.size(); ++i) {
    if (frame.ids[i] != selected_id_) continue;
    // Eased so that the stride's sway does not shake the view.
    camera_.target = glm::mix(camera_.target, draws[i].position + glm::vec3(0, 0.9f, 0), 0.15f);
    return;
  }
  follow_ = false;  // the agent left the scene
}

void DemoApp::pick(glm::vec2 mouse_px) {
  glm::vec2 px = mouse_px;
  const glm::ivec2 size = view_size();
  if (session_->has_compare() && px.x >= size.x) px.x -= static_cast<float>(size.x);
  const Ray ray = camera_.pick_ray(px, size);
  const AgentFrame& frame = session_->frame();
  const auto draws = session_->lane().draw_span();
  float best = 0.6f;  // [m] from the ray to the body's axis point at hip height
  int64_t picked = -1;
  for (size_t i = 0; i < draws.size(); ++i) {
    const glm::vec3 c = draws[i].position + glm::vec3(0, 0.9f, 0);
    const float along = glm::dot(c - ray.origin, ray.direction);
    if (along <= 0.0f) continue;
    const float d = glm::length(c - (ray.origin + along * ray.direction));
    if (d < best) best = d, picked = frame.ids[i];
  }
  selected_id_ = picked;
  follow_ = picked >= 0;
  // Close enough to see the feet of the followed agent.
  if (follow_) camera_.distance_m = std::min(camera_.distance_m, 9.0f);
}

void DemoApp::handle_input() {
  const ImGuiIO& io = ImGui::GetIO();
  if (io.WantCaptureMouse) return;
  const glm::vec2 mouse(io.MousePos.x, io.MousePos.y);
  const glm::vec2 delta(io.MouseDelta.x, io.MouseDelta.y);
  if (ImGui::IsMouseDragging(ImGuiMouseButton_Right, 0.0f)) {
    camera_.orbit(-delta.x * 0.006f, delta.y * 0.006f);
  }
  if (ImGui::IsMouseDragging(ImGuiMouseButton_Middle, 0.0f)) {
    camera_.pan(delta, view_size());
    follow_ = false;
  }
  if (io.MouseWheel != 0.0f) camera_.zoom(std::pow(0.88f, io.MouseWheel));
  if (ImGui::IsMouseClicked(ImGuiMouseButton_Left)) pick(mouse);
}

void DemoApp::write_report(const std::string& path) const {
  nlohmann::json agents = nlohmann::json::array();
  const glm::ivec2 size = view_size();
  const float offset = session_->has_compare() ? static_cast<float>(size.x) : 0.0f;
  const auto draws = session_->lane().draw_span();
  for (size_t i = 0; i < draws.size(); ++i) {
    const ProjectedPoint p = camera_.project(draws[i].position + glm::vec3(0, 0.9f, 0), size);
    agents.push_back({{"id", session_->frame().ids[i]},
                      {"px", p.pixel.x + offset},
                      {"py", p.pixel.y},
                      {"in_front", p.in_front}});
  }
  const glm::ivec2 fb = context_->framebuffer_size();
  const glm::ivec2 scene = scene_size();
  const nlohmann::json j = {{"scene_width", scene.x},
                            {"width", fb.x},
                            {"height", fb.y},
                            {"compare", session_->has_compare()},
                            {"selected", selected_id_},
                            {"panel", {panel_rect_.x, panel_rect_.y, panel_rect_.z, panel_rect_.w}},
                            {"agents", agents}};
  std::ofstream out(path);
  out << j.dump(1) << "\n";
  if (!out) fail("demo", 1, path + ": cannot write the report");
}

int DemoApp::run() {
  const char* display = std::getenv("DISPLAY");
  const char* wayland = std::getenv("WAYLAND_DISPLAY");
  if ((!display || !*display) && (!wayland || !*wayland)) {
    std::fprintf(stderr, "gaitkeeper: %s\n", kNoDisplay);
    return 1;
  }
  const glm::ivec2 size = parse_size("demo", options_.size);
  const int frames_to_run =
      options_.frames.empty() ? -1
                              : parse_number<int>("demo", options_.frames, "--frames", 1, 1 << 30);
  // Output paths are checked before the window opens and the frames run.
  check_output_file_option("demo", options_.screenshot, "--screenshot");
  check_output_file_option("demo", options_.report, "--report");
  ContextOptions co;
  co.width = size.x;
  co.height = size.y;
  co.title = "Gaitkeeper - crowd animation without foot skating";
  // A scripted run (tests, pictures) must not wait for the display's refresh.
  co.vsync = frames_to_run < 0;
  auto context = GlContext::create_window(co);
  if (!context.ok()) {
    std::fprintf(stderr, "gaitkeeper: %s (%s)\n", kNoDisplay, context.message().c_str());
    return 1;
  }
  context_ = std::move(context).value();
  if (!rebuild()) {
    // Bad options were already reported by fail(); other errors (the renderer) were not.
    if (status_ != last_failure()) std::fprintf(stderr, "gaitkeeper demo: %s\n", status_.c_str());
    return 2;
  }
  if (!options_.select.empty()) {
    selected_id_ = parse_number<int>("demo", options_.select, "--select", 0, 1 << 30);
    check_agent_id("demo", session_->setup(), selected_id_, "--select");
    follow_ = true;
    camera_.distance_m = std::min(camera_.distance_m, 9.0f);
  }
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini left in the working directory
  ImGui::StyleColorsDark();
  ImGui_ImplGlfw_InitForOpenGL(context_->window(), true);
  ImGui_ImplOpenGL3_Init("#version 330 core");
  imgui_ready_ = true;

  int frame = 0;
  while (!context_->should_close()) {
    const auto frame_start = Clock::now();
    context_->poll_events();
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    draw_panel();
    if (session_->has_compare()) {
      // Which half is which, on top of the 3D view.
      ImDrawList* fg = ImGui::GetForegroundDrawList();
      const float half = static_cast<float>(view_size().x);
      const std::string right(mediator_mode_name(session_->params().mode));
      fg->AddRectFilled(ImVec2(8, 8), ImVec2(70, 30), IM_COL32(0, 0, 0, 150));
      fg->AddText(ImVec2(14, 11), IM_COL32(255, 255, 255, 255), "naive");
      fg->AddRectFilled(ImVec2(half + 8, 8), ImVec2(half + 70, 30), IM_COL32(0, 0, 0, 150));
      fg->AddText(ImVec2(half + 14, 11), IM_COL32(255, 255, 255, 255), right.c_str());
      fg->AddLine(ImVec2(half, 0), ImVec2(half, static_cast<float>(view_size().y)),
                  IM_COL32(20, 20, 20, 255), 2.0f);
    }
    handle_input();
    simulate();
    if (Status s = render_scene(); !s.ok()) {
      std::fprintf(stderr, "gaitkeeper demo: %s\n", s.message().c_str());
      return 1;
    }
    ImGui::Render();
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    ++frame;
    if (frames_to_run > 0 && frame >= frames_to_run) {
      if (!options_.screenshot.empty()) {
        context_->finish_frame();
        Status s = capture_.grab(context_->framebuffer_size());
        if (s.ok()) s = capture_.save_png(options_.screenshot);
        if (!s.ok()) {
          std::fprintf(stderr, "gaitkeeper demo: %s\n", s.message().c_str());
          return 1;
        }
      }
      if (!options_.click.empty()) {
        // The scripted click goes through the same picking as the mouse, after the last frame
        // was drawn with the camera the report describes.
        const size_t comma = options_.click.find(',');
        const float x =
            parse_number<float>("demo", options_.click.substr(0, comma), "--click", 0.0f, 1e5f);
        const float y = comma == std::string::npos
                            ? -1.0f
                            : parse_number<float>("demo", options_.click.substr(comma + 1),
                                                  "--click", 0.0f, 1e5f);
        if (y < 0.0f) fail("demo", 2, "--click: expected X,Y in window pixels");
        pick({x, y});
      }
      if (!options_.report.empty()) write_report(options_.report);
      break;
    }
    context_->present();
    metrics_.record_stage(LiveStage::kFrame, ms_since(frame_start));
  }
  return 0;
}

}  // namespace gk::app
