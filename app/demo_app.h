#pragma once
// The interactive demo: a GLFW window with the crowd and a Dear ImGui panel. The panel rebuilds
// the session when the crowd changes (scenario, simulator, agents, clips), sets mediator
// parameters live, pauses / steps / scales time, toggles overlays and the naive | apm split
// screen, and plots live metrics and stage timings. Camera: right drag orbits, middle drag pans,
// the wheel zooms, a left click on an agent follows it.

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "app/crowd_session.h"
#include "app/live_metrics.h"
#include "app/overlays.h"
#include "app/scene_view.h"
#include "render/frame_capture.h"
#include "render/gl_context.h"

namespace gk::app {

struct DemoOptions {
  CrowdOptions crowd;
  std::string size = "1280x720";
  bool compare = false;
  std::vector<std::string> overlays;
  // For tests and pictures: run this many frames, save the window (panel included), quit.
  std::string frames;
  std::string screenshot;
  std::string select;  // agent id to select and follow from the start
  std::string click;   // "X,Y": a left click at this window pixel on the last frame (tests)
  std::string report;  // JSON: panel rectangle and the agents' pixels on the last frame
};

// Width of the panel docked at the right edge of the window [px]; the 3D view fills the rest.
inline constexpr int kPanelWidth_px = 380;

class DemoApp {
 public:
  explicit DemoApp(DemoOptions options);
  ~DemoApp();
  // Returns the exit code. No display: a message and 1.
  int run();

 private:
  bool rebuild();  // a new session from crowd_; false (message kept) when the options are bad
  void simulate();
  Status render_scene();
  void draw_panel();  // app/demo_panel.cc
  void panel_crowd();
  void panel_params();
  void panel_view();
  void panel_metrics();
  void panel_agent();
  void handle_input();
  void pick(glm::vec2 mouse_px);
  void follow_selected();
  glm::ivec2 scene_size() const;  // the window left of the panel
  glm::ivec2 view_size() const;   // the viewport of one lane (half the scene in compare)
  void write_report(const std::string& path) const;

  DemoOptions options_;
  CrowdOptions crowd_;  // what the panel edits; applied by rebuild()
  std::string status_;  // last rebuild error, shown in the panel
  std::unique_ptr<GlContext> context_;
  std::unique_ptr<CrowdSession> session_;
  std::unique_ptr<SceneView> view_;
  std::optional<OverlayHistory> history_, compare_history_;
  LiveMetrics metrics_;
  LiveMetrics compare_metrics_;  // the naive lane, shown beside the primary in compare mode
  OverlayToggles overlays_;
  OrbitCamera camera_;
  bool camera_set_ = false;
  bool paused_ = false;
  bool step_once_ = false;
  float time_scale_ = 1.0f;
  bool compare_ = false;
  int64_t selected_id_ = -1;
  bool follow_ = false;
  bool imgui_ready_ = false;
  glm::vec2 last_mouse_{0.0f};
  std::vector<std::string> scenario_names_;
  int sim_kind_ = 0;  // 0 social, 1 detour, 2 replay of a trajectory file
  std::string replay_path_;
  bool builtin_clips_ = true;
  std::string clip_path_;
  int agents_ = 0;
  glm::vec4 panel_rect_{0.0f};  // x, y, w, h [px] of the panel window, for the report
  FrameCapture capture_;
};

}  // namespace gk::app
