#pragma once
// The interactive demo: a GLFW window with the crowd and a Dear ImGui panel. The panel rebuilds
// the session when the crowd changes (scenario, simulator, agents, clips), sets mediator
// parameters live (and saves / loads them as JSON), pauses / steps / scales time, toggles overlays
// and the naive | apm split screen, and plots live metrics and stage timings. The simulation runs
// on a fixed step decoupled from the draw rate (SimClock) and says when it cannot keep real time.
//
// Camera: right drag orbits, middle drag pans, the wheel zooms toward the cursor, a left click
// on an agent selects and follows it (CameraDirector). Keys: Space pauses, H shows the help,
// R restarts the crowd, Esc quits.
//
// Without --scenario the window opens on the showcase: the bottleneck's door in the naive | apm
// split with foot trails, the camera close on an agent queuing at the door, pulling out to the
// whole room after kShowcasePullOut_s of simulated time.

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "app/camera_director.h"
#include "app/crowd_recorder.h"
#include "app/crowd_session.h"
#include "app/file_browser.h"
#include "app/lessons.h"
#include "app/live_metrics.h"
#include "app/overlays.h"
#include "app/scene_view.h"
#include "app/sim_clock.h"
#include "render/frame_capture.h"
#include "render/gl_context.h"

namespace gk::app {

struct DemoOptions {
  CrowdOptions crowd;
  std::string size = "1280x720";
  bool compare = false;
  std::vector<std::string> overlays;
  std::string pull_out;  // seconds of simulated time, then the camera pulls out (with --select)
  // For tests and pictures: run this many frames, save the window (panel included), quit.
  // Scripted runs step the simulation once per frame, so they are reproducible.
  std::string frames;
  std::string screenshot;
  std::string select;  // agent id to select and follow from the start
  std::string click;   // "X,Y": a left click at this window pixel on the last frame (tests)
  // "FRAME:key:NAME", "FRAME:click:X,Y", "FRAME:wheel:X,Y,STEPS": input fed to Dear ImGui at the
  // start of a frame, exactly where a real key press, click or wheel turn arrives (tests).
  std::vector<std::string> inputs;
  std::string report;  // JSON: panel rectangle and the agents' pixels on the last frame
  std::string lesson;  // open on this lesson (app/lessons.h)
  std::string mesh_lod = "on";  // lighter meshes for agents small on screen: on | off
};

// Width of the panel docked at the right edge of the window [px]; the 3D view fills the rest.
inline constexpr int kPanelWidth_px = 380;
// The showcase: the scenario, the point whose nearest agent is followed, and when it pulls out.
inline constexpr const char* kShowcaseScenario = "bottleneck";
inline constexpr float kShowcasePullOut_s = 10.0f;
// Seen from the side (the eye south of the agent): feet walking toward the door cross the view.
inline constexpr float kShowcaseYaw_rad = 3.14159265f;

class DemoApp {
 public:
  explicit DemoApp(DemoOptions options);
  ~DemoApp();
  // Returns the exit code. No display: a message and 1.
  int run();

 private:
  struct ScriptedInput {
    int frame = 0;
    enum class Kind { kKey, kClick, kWheel } kind = Kind::kKey;
    int key = 0;  // GLFW key code
    glm::vec2 pos{0.0f};
    float wheel = 0.0f;
  };

  bool rebuild();  // a new session from crowd_; false (message kept) when the options are bad
  void restart();  // rebuild with the same options, keeping the parameters (R)
  void simulate(double real_dt_s, bool scripted);
  bool step_once(double dt_s);
  Status render_scene(float real_dt_s);
  void draw_overlay_text();  // app/demo_hud.cc: labels, twist, notes, hints, help
  void draw_help();
  void start_lesson(const Lesson& lesson);  // app/demo_lessons.cc
  void enable_split();  // the lesson's split, or naive | the chosen mode
  void record_gait();   // the selected agent's stride and cadence, both lanes
  void panel_gait();    // their plot against speed
  void draw_lesson_text(float bottom_px);
  void lessons_menu();
  // app/demo_timeline.cc: the last minute kept in a CrowdRecorder, scrubbed from the panel.
  void reset_recorder();
  void panel_timeline();
  void scrub_to(int k);  // k: a held record; past the newest: live again
  void scrub_by(int records);
  bool scrubbing() const { return scrub_ >= 0; }
  // What is drawn: the recorded lane while scrubbing, else the session's. `ids` are the draws'.
  const AnimationLane& shown_lane(bool compare) const;
  int64_t shown_id(bool compare, size_t i) const;
  std::optional<FollowedAgent> shown_followed() const;  // the Lessons menu in the panel's menu bar
  void draw_panel();  // app/demo_panel.cc
  void panel_crowd();
  void apply_crowd();  // rebuild from the crowd the panel shows, keeping the parameters
  void panel_clips();
  void panel_params();
  void panel_view();
  void panel_metrics();
  void panel_mesh_lod();  // triangles drawn and agents per mesh level, the LOD switch
  void panel_agent();
  void panel_lod();  // level of detail of the primary lane, focused on the camera
  void handle_browser();
  void handle_input();  // app/demo_input.cc
  void feed_scripted_input(int frame);
  void parse_inputs();
  void pick(glm::vec2 mouse_px);
  void select(int64_t id);
  const char* hint() const;  // the note over an empty scene, or ""
  glm::ivec2 scene_size() const;  // the window left of the panel
  glm::ivec2 view_size() const;   // the viewport of one lane (half the scene in compare)
  void write_report(const std::string& path) const;

  DemoOptions options_;
  CrowdOptions crowd_;  // what the panel edits; applied by rebuild()
  std::string status_;  // last rebuild error, shown in the panel
  std::string note_;    // last parameter file saved / loaded
  std::unique_ptr<GlContext> context_;
  std::unique_ptr<CrowdSession> session_;
  // What the loaded clips cannot play (describe_gaps), shown every frame in two places of the
  // panel: made again only for a new session or new playback-rate limits or stride stretch.
  struct LibraryGaps {
    bool valid = false;
    float min_rate = 0.0f, max_rate = 0.0f, stride_warp = 0.0f;
    std::vector<std::string> lines;
  };
  LibraryGaps gaps_;
  const std::vector<std::string>& library_gaps();
  std::unique_ptr<SceneView> view_;
  std::optional<OverlayHistory> history_, compare_history_;
  LiveMetrics metrics_;
  LiveMetrics compare_metrics_;  // the naive lane, shown beside the primary in compare mode
  OverlayToggles overlays_;
  OrbitCamera camera_;
  LodParams lod_;  // the panel's level of detail; its focus follows the camera
  CameraDirector director_;
  SimClock clock_;
  bool camera_set_ = false;
  bool showcase_ = false;         // opened without --scenario
  bool pick_showcase_ = false;    // follow the showcase agent once the crowd has its first frame
  std::optional<float> overview_yaw_;  // the overview's yaw when not frame_bounds' 3/4 view
  bool paused_ = false;
  bool step_requested_ = false;
  bool help_ = false;
  bool mesh_lod_ = true;  // the renderer's mesh levels of detail (View panel, --mesh-lod)
  bool help_focused_ = false;  // the help window was brought to the front since it opened
  bool quit_ = false;
  bool restart_requested_ = false;
  float time_scale_ = 1.0f;
  bool compare_ = false;
  int64_t selected_id_ = -1;
  bool imgui_ready_ = false;
  std::vector<std::string> scenario_names_;
  int sim_kind_ = 0;  // 0 social, 1 detour, 2 replay of a trajectory file
  std::string replay_path_;
  bool builtin_clips_ = true;
  std::string clip_path_;
  std::string roles_path_;  // role manifest for the clip files (--roles); empty: detected
  int agents_ = 0;
  bool agents_edited_ = false;  // the count typed in the panel overrides the scenario's default
  std::string params_path_ = "gaitkeeper_params.json";
  FileBrowser browser_;
  std::vector<ScriptedInput> scripted_;
  int frames_drawn_ = 0;
  float fps_ = 0.0f;  // drawn frames per second over the last half second
  float fps_window_s_ = 0.0f;
  int fps_frames_ = 0;
  glm::vec4 panel_rect_{0.0f};  // x, y, w, h [px] of the panel window, for the report
  glm::vec4 help_rect_{0.0f};   // x, y, w, h [px] of the help window while shown
  FrameCapture capture_;
  std::optional<CrowdRecorder> recorder_;
  int scrub_ = -1;  // the record shown, or -1: live
  AnimationLane replay_[2];  // [0] primary, [1] compare: draws and palettes of the scrubbed record
  std::vector<int64_t> replay_ids_[2];
  const Lesson* lesson_ = nullptr;
  bool pick_lesson_agent_ = false;  // follow the lesson's agent once the crowd has a frame
  glm::vec4 lessons_menu_rect_{0.0f};
  glm::vec4 lesson_text_rect_{0.0f};  // x, y, w, h [px] of the lesson's text box  // x, y, w, h [px] of the Lessons menu header
  std::vector<glm::vec4> lesson_item_rects_;  // the menu's items while it is open (tests)
  // The selected agent's gait, per lane (0 primary, 1 compare): speed [m/s], stride length [m]
  // (one gait cycle), cadence [steps/min]; a ring of the last kGaitSamples frames.
  struct GaitSample {
    float speed_m_s, stride_m, cadence_spm;
  };
  static constexpr int kGaitSamples = 240;
  std::vector<GaitSample> gait_[2];
  int gait_count_ = 0;
  int64_t gait_id_ = -1;
  float native_stride_m_ = 0.0f, native_cadence_spm_ = 0.0f, native_speed_m_s_ = 0.0f;
};

}  // namespace gk::app
