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
#include "crowd/trajectory_replay.h"

namespace gk::app {
namespace {

using Clock = std::chrono::steady_clock;
float ms_since(Clock::time_point t) {
  return std::chrono::duration<float, std::milli>(Clock::now() - t).count();
}

constexpr const char* kNoDisplay = "no display: use `gaitkeeper render` or `gaitkeeper bench`";
// Wall time one frame may spend on simulation steps before the rest is dropped (SimClock): the
// window keeps drawing (and answering) on a machine that cannot simulate in real time.
constexpr float kStepBudget_ms = 40.0f;

}  // namespace

DemoApp::DemoApp(DemoOptions options) : options_(std::move(options)) {
  crowd_ = options_.crowd;
  crowd_.command = "demo";
  mesh_lod_ = options_.mesh_lod != "off";
  if (const Lesson* l = find_lesson(options_.lesson)) crowd_.scenario = l->scenario;
  showcase_ = crowd_.scenario.empty();
  if (showcase_) {
    // The point at a glance: feet at a crowded door, naive beside apm, trails on the ground.
    crowd_.scenario = kShowcaseScenario;
    options_.compare = true;
    if (options_.overlays.empty()) options_.overlays = {"trails"};
    pick_showcase_ = options_.select.empty();
  } else if (options_.overlays.empty()) {
    overlays_.torso = true;  // only the selected agent has a fan: nothing shows until a click
  }
  compare_ = options_.compare;
  if (is_trajectory_file_name(crowd_.scenario)) sim_kind_ = 2, replay_path_ = crowd_.scenario;
  if (crowd_.sim == "detour") sim_kind_ = 1;
  builtin_clips_ = crowd_.clips.empty();
  if (!builtin_clips_) clip_path_ = crowd_.clips.front();
  roles_path_ = crowd_.roles;
  agents_edited_ = !crowd_.agents.empty();
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(scenario_dir(), ec)) {
    if (e.path().extension() == ".json") scenario_names_.push_back(e.path().stem().string());
  }
  std::sort(scenario_names_.begin(), scenario_names_.end());
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
    gaps_.valid = false;
    view_ = std::move(view).value();
  } catch (const ExitRequest&) {
    status_ = last_failure();
    return false;
  }
  status_.clear();
  const size_t capacity = session_->crowd().capacity();
  history_.emplace(*session_, capacity);
  compare_history_.emplace(*session_, capacity);
  if (compare_) enable_split();
  reset_recorder();
  metrics_.reset();
  compare_metrics_.reset();
  clock_.reset();
  selected_id_ = -1;
  director_.stop_following();
  agents_ = static_cast<int>(session_->setup().agents);
  if (!camera_set_) overview_yaw_.reset();
  director_.set_overview(frame_bounds(session_->bounds_min(), session_->bounds_max(), view_size()));
  if (!camera_set_) camera_ = director_.overview();
  return true;
}

void DemoApp::restart() {
  restart_requested_ = false;
  const MediatorParams keep = session_->params();
  const int64_t selected = selected_id_;
  const bool following = director_.following();
  crowd_.sets.clear();
  crowd_.params_file.clear();
  crowd_.mode = std::string(mediator_mode_name(keep.mode));
  camera_set_ = true;  // the same place: keep looking where the user looked
  const bool ok = rebuild();
  camera_set_ = false;
  if (!ok) return;
  session_->set_params(keep);
  if (showcase_ && crowd_.scenario == kShowcaseScenario && selected < 0) {
    pick_showcase_ = true;  // the showcase's shot again: close on the door, then the room
    return;
  }
  if (selected >= 0) {
    selected_id_ = selected;  // the same seed brings the same agent back
    if (following) director_.follow(selected, camera_.distance_m, camera_.pitch_rad);
  }
}

glm::ivec2 DemoApp::scene_size() const {
  const glm::ivec2 fb = context_->framebuffer_size();
  return {std::max(fb.x - kPanelWidth_px, 16), fb.y};
}

glm::ivec2 DemoApp::view_size() const {
  const glm::ivec2 scene = scene_size();
  return session_ && session_->has_compare() ? glm::ivec2(scene.x / 2, scene.y) : scene;
}

bool DemoApp::step_once(double dt) {
  if (Status s = session_->step(dt); !s.ok()) {
    status_ = "simulation stopped: " + s.message();
    paused_ = true;
    return false;
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
  record_gait();
  if (recorder_->lanes() != (session_->has_compare() ? 2 : 1)) reset_recorder();
  recorder_->record(*session_, selected_id_);
  return true;
}

void DemoApp::simulate(double real_dt_s, bool scripted) {
  if (scrubbing() && !paused_) scrub_ = -1;  // running again: the live crowd
  if (scrubbing()) {
    if (step_requested_) step_requested_ = false, scrub_by(1);
    clock_.reset();
    return;
  }
  if (step_requested_) {
    step_requested_ = false;
    step_once(SimClock::step_s(time_scale_));
    clock_.reset();
    return;
  }
  if (paused_) {
    clock_.reset();  // nothing is owed for the time spent paused
    return;
  }
  const int steps = clock_.begin_frame(real_dt_s, time_scale_);
  const auto start = Clock::now();
  int ran = 0;
  while (ran < steps) {
    // A scripted run is reproducible: every step it asked for runs.
    if (!scripted && ran > 0 && ms_since(start) > kStepBudget_ms) break;
    if (!step_once(SimClock::step_s(time_scale_))) break;
    ++ran;
  }
  clock_.end_frame(ran);
  if (pick_showcase_ && session_->frame().size() > 0) {
    // The agent nearest the middle of the room: it queues at the door for several seconds.
    pick_showcase_ = false;
    const glm::vec2 centre = 0.5f * (session_->bounds_min() + session_->bounds_max());
    const AgentFrame& frame = session_->frame();
    float best = 1e30f;
    int64_t id = -1;
    for (size_t i = 0; i < frame.size(); ++i) {
      const float d = glm::length(frame.positions[i] - centre);
      if (d < best) best = d, id = frame.ids[i];
    }
    if (id >= 0) {
      selected_id_ = id;
      camera_.yaw_rad = kShowcaseYaw_rad;
      overview_yaw_ = kShowcaseYaw_rad;
      director_.follow(id);
      director_.snap();
      director_.pull_out_at(kShowcasePullOut_s);
    }
  }
  if (pick_lesson_agent_ && lesson_ && session_->frame().size() > 0) {
    pick_lesson_agent_ = false;
    const int64_t id = agent_nearest(
        session_->frame(), 0.5f * (session_->bounds_min() + session_->bounds_max()));
    if (id >= 0) {
      selected_id_ = id;
      director_.follow(id, lesson_->distance_m, kFollowPitch_rad);
      director_.snap();
    }
  }
}

Status DemoApp::render_scene(float real_dt_s) {
  session_->collect();
  OrbitCamera overview = frame_bounds(session_->bounds_min(), session_->bounds_max(), view_size());
  if (overview_yaw_) overview.yaw_rad = *overview_yaw_;
  director_.set_overview(overview);
  // A twin (the feedback lesson) is framed above the lesson's text box (last frame's).
  const int text_top = static_cast<int>(lesson_text_rect_.y);
  director_.set_view(view_size(), lesson_text_rect_.w > 0.0f && text_top > 0
                                      ? std::max(0, view_size().y - text_top)
                                      : 0);
  director_.update(session_->crowd().time_s(), real_dt_s,
                   shown_followed(), &camera_);
  view_->camera() = camera_;
  view_->renderer().settings().lines_on_top = overlays_.any();
  view_->renderer().settings().mesh_lod = mesh_lod_;
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
    // A recorded moment has no overlay history: its bodies and the selected agent's ring only.
    if (!scrubbing()) {
      history.draw(*session_, lane, overlays_, selected_id_, &view_->renderer());
    } else {
      const auto draws = lane.draw_span();
      const bool compare = &lane == &replay_[1];
      for (size_t i = 0; i < draws.size(); ++i) {
        if (shown_id(compare, i) != selected_id_) continue;
        draw_selection_ring(draws[i].position + glm::vec3(0.0f, 0.03f, 0.0f), &view_->renderer());
      }
    }
    GK_RETURN_IF_ERROR(view_->draw(lane, origin, size));
    glFinish();
    render_ms += ms_since(t);
    return Status::Ok();
  };
  if (session_->has_compare()) {
    const int left = fb.x / 2;
    GK_RETURN_IF_ERROR(lane_pass(shown_lane(true), *compare_history_, {0, 0}, {left, fb.y}));
    GK_RETURN_IF_ERROR(lane_pass(shown_lane(false), *history_, {left, 0}, {fb.x - left, fb.y}));
  } else {
    GK_RETURN_IF_ERROR(lane_pass(shown_lane(false), *history_, {0, 0}, fb));
  }
  metrics_.record_stage(LiveStage::kUpload, upload_ms);
  metrics_.record_stage(LiveStage::kRender, render_ms);
  return Status::Ok();
}

const char* DemoApp::hint() const {
  if (!session_ || !status_.empty()) return "";
  if (session_->frames_run() == 0 && paused_) {
    return "Paused: press Space (or untick pause) to start.\nThe new crowd appears on its first "
           "step.";
  }
  if (session_->frames_run() > 0 && session_->frame().size() == 0) {
    return "Nobody is left in the scene: press R to restart it.";
  }
  return "";
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
  const bool scripted = frames_to_run > 0;
  for (const std::string& n : options_.overlays) {
    if (!enable_overlay(n, &overlays_)) {
      fail("demo", 2, std::string("--overlay: expected ") + kOverlayNames + ", got '" + n + "'");
    }
  }
  const float pull_out_s =
      options_.pull_out.empty()
          ? -1.0f
          : parse_number<float>("demo", options_.pull_out, "--pull-out", 0.0f, 1e6f);
  if (pull_out_s >= 0.0f && options_.select.empty()) {
    fail("demo", 2, "--pull-out: pulls out from a followed agent: add --select ID");
  }
  parse_inputs();
  if (!scripted && (!scripted_.empty() || !options_.click.empty())) {
    fail("demo", 2, "--input and --click script a run: add --frames N");
  }
  // Output paths are checked before the window opens and the frames run.
  check_output_file_option("demo", options_.screenshot, "--screenshot");
  check_output_file_option("demo", options_.report, "--report");
  ContextOptions co;
  co.width = size.x;
  co.height = size.y;
  co.title = "Gaitkeeper - crowd animation without foot skating";
  // A scripted run (tests, pictures) must not wait for the display's refresh.
  co.vsync = !scripted;
  auto context = GlContext::create_window(co);
  if (!context.ok()) {
    std::fprintf(stderr, "gaitkeeper: %s (%s)\n", kNoDisplay, context.message().c_str());
    return 1;
  }
  context_ = std::move(context).value();
  const Lesson* lesson = nullptr;
  if (!options_.lesson.empty()) {
    lesson = find_lesson(options_.lesson);
    if (!lesson) {
      fail("demo", 2, "--lesson: expected " + lesson_names() + ", got '" + options_.lesson + "'");
    }
    if (!options_.select.empty()) fail("demo", 2, "--lesson chooses the agent: drop --select");
  }
  if (lesson) start_lesson(*lesson);
  if (lesson ? !lesson_ : !rebuild()) {
    // Bad options were already reported by fail(); other errors (the renderer) were not.
    if (status_ != last_failure()) std::fprintf(stderr, "gaitkeeper demo: %s\n", status_.c_str());
    return 2;
  }
  if (!options_.select.empty()) {
    const int64_t id = parse_number<int>("demo", options_.select, "--select", 0, 1 << 30);
    check_agent_id("demo", session_->setup(), id, "--select");
    selected_id_ = id;
    director_.follow(id);
    director_.snap();
    if (pull_out_s >= 0.0f) director_.pull_out_at(pull_out_s);
  }
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini left in the working directory
  ImGui::StyleColorsDark();
  ImGui_ImplGlfw_InitForOpenGL(context_->window(), true);
  ImGui_ImplOpenGL3_Init("#version 330 core");
  imgui_ready_ = true;

  auto last_frame = Clock::now();
  while (!context_->should_close() && !quit_) {
    const auto frame_start = Clock::now();
    // A scripted run's frames are 1/60 s apart whatever the machine: reproducible pictures.
    const float wall_dt = std::chrono::duration<float>(frame_start - last_frame).count();
    const float real_dt = scripted ? static_cast<float>(kFrameTime_s) : wall_dt;
    last_frame = frame_start;
    context_->poll_events();
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    feed_scripted_input(frames_drawn_);
    ImGui::NewFrame();
    draw_panel();
    handle_browser();
    handle_input();
    if (quit_) break;
    if (restart_requested_) restart();
    simulate(real_dt, scripted);
    if (Status s = render_scene(real_dt); !s.ok()) {
      std::fprintf(stderr, "gaitkeeper demo: %s\n", s.message().c_str());
      return 1;
    }
    draw_overlay_text();
    ImGui::Render();
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    ++frames_drawn_;
    // Measured on the wall clock, also in scripted runs (whose simulated frames are fixed).
    fps_window_s_ += wall_dt;
    ++fps_frames_;
    if (fps_window_s_ >= 0.5f) {
      fps_ = static_cast<float>(fps_frames_) / fps_window_s_;
      fps_window_s_ = 0.0f;
      fps_frames_ = 0;
    }
    if (scripted && frames_drawn_ >= frames_to_run) {
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
      break;
    }
    context_->present();
    metrics_.record_stage(LiveStage::kFrame, ms_since(frame_start));
  }
  // Also after Esc, so a scripted run can show that it quit.
  if (!options_.report.empty()) write_report(options_.report);
  return 0;
}

}  // namespace gk::app
