// `gaitkeeper render`: runs a session and renders it offscreen (EGL) into a PNG (the last frame),
// a folder of numbered PNG frames, or an H.264 video streamed into ffmpeg (no temporary files).
// --compare splits the screen: the naive crowd on the left, the chosen mode on the right, on the
// same crowd frames.
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "app/camera_director.h"
#include "app/commands.h"
#include "app/crowd_session.h"
#include "app/lessons.h"
#include "app/offscreen.h"
#include "app/overlays.h"
#include "common/file_io.h"
#include "render/frame_capture.h"
#include "render/label_font.h"

namespace gk::app {
namespace {

constexpr const char* kCmd = "render";

struct RenderOptions {
  CrowdOptions crowd;
  std::string frames = "120";
  std::string out;
  std::string size = "1280x720";
  bool compare = false;
  std::string camera;
  std::vector<std::string> overlays;
  std::string follow;
  std::string pull_out;
  std::string report;
  std::string lesson;
  std::string mesh_lod = "on";
};

std::string upper(std::string_view text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return out;
}

enum class OutputKind { kPng, kVideo, kFolder };

// "--camera yaw_deg,pitch_deg,distance_m[,target_x,target_z]" overrides the automatic framing.
void apply_camera(const std::string& text, OrbitCamera* camera) {
  std::vector<float> v;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    v.push_back(parse_number<float>(kCmd, item, "--camera", -1e4f, 1e4f));
  }
  if (v.size() != 3 && v.size() != 5) {
    fail(kCmd, 2,
         "--camera: expected yaw_deg,pitch_deg,distance_m[,target_x,target_z], got '" + text + "'");
  }
  camera->yaw_rad = glm::radians(v[0]);
  camera->pitch_rad =
      std::clamp(glm::radians(v[1]), -OrbitCamera::kMaxPitchRad, OrbitCamera::kMaxPitchRad);
  camera->distance_m = std::max(v[2], 0.5f);
  if (v.size() == 5) camera->target = glm::vec3(v[3], 0.0f, v[4]);
}

OverlayToggles parse_overlays(const std::vector<std::string>& names) {
  OverlayToggles t;
  for (const std::string& n : names) {
    if (!enable_overlay(n, &t)) {
      fail(kCmd, 2, std::string("--overlay: expected ") + kOverlayNames + ", got '" + n + "'");
    }
  }
  return t;
}

// A label centred above `head` [m] in the half (or whole) image at `origin_x` of width `view.x`,
// kept inside that half when the head is near or beyond its edge.
void stamp_above(const char* text, glm::vec3 head, const OrbitCamera& camera, glm::ivec2 view,
                 int origin_x, int scale, FrameCapture* capture, glm::ivec2 image) {
  const ProjectedPoint p = camera.project(head, view);
  if (!p.in_front) return;
  const int w = label_width(text, scale);
  const int margin = 2 * scale;
  const int x = std::clamp(static_cast<int>(p.pixel.x) - w / 2, margin,
                           std::max(margin, view.x - w - margin));
  // Below the half's name in the top left corner, above the caption along the bottom.
  const int top = 18 * scale;
  const int y = std::clamp(static_cast<int>(p.pixel.y) - 9 * scale, top,
                           std::max(top, view.y - 20 * scale));
  const glm::ivec2 at(origin_x + x, y);
  stamp_label(capture->mutable_rgba(), image, at, text, scale);
}

// The followed agent's readouts above its head: the torso fan's twist, the legs' angle to the
// simulator's path.
void stamp_readouts(const CrowdSession& s, const AnimationLane& lane, int64_t id,
                    const OverlayToggles& overlays, const OrbitCamera& camera, glm::ivec2 view,
                    int origin_x, int scale, FrameCapture* capture, glm::ivec2 image) {
  char text[64];
  if (overlays.torso) {
    if (const std::optional<TorsoReadout> t = torso_readout(s, lane, id)) {
      std::snprintf(text, sizeof(text), "TWIST %.0f / LIMIT %.0f DEG", std::abs(t->twist_deg),
                    t->limit_deg);
      stamp_above(text, t->head, camera, view, origin_x, scale, capture, image);
    }
  }
  if (overlays.legs) {
    if (const std::optional<LegsReadout> l = legs_readout(s, lane, id)) {
      std::snprintf(text, sizeof(text), "SIM %.1f M/S, LEGS MAX %.1f", l->speed_m_s,
                    l->legs_max_m_s);
      stamp_above(text, l->head, camera, view, origin_x, scale, capture, image);
    }
  }
}

// Last frame's agents: ids, ground positions and where their hips (0.9 m up) land in the image,
// so tests can look at the right pixels.
void write_report(const std::string& path, const CrowdSession& s, const OrbitCamera& camera,
                  glm::ivec2 size, bool split, const Exhibits& exhibits, int64_t follow,
                  const Lesson* lesson) {
  nlohmann::json agents = nlohmann::json::array();
  const glm::ivec2 view = split ? glm::ivec2(size.x / 2, size.y) : size;
  const auto draws = s.lane().draw_span();
  for (size_t i = 0; i < draws.size(); ++i) {
    const AgentDraw& d = draws[i];
    const ProjectedPoint p = camera.project(d.position + glm::vec3(0, 0.9f, 0), view);
    agents.push_back({{"id", s.frame().ids[i]},
                      {"x", d.position.x},
                      {"z", d.position.z},
                      {"px", p.pixel.x},
                      {"py", p.pixel.y},
                      {"in_front", p.in_front}});
  }
  nlohmann::json shown = nlohmann::json::array();
  for (const glm::vec3& c : exhibits.canvas_centers) {
    const ProjectedPoint p = camera.project(c, view);
    shown.push_back({{"x", c.x}, {"z", c.z}, {"px", p.pixel.x}, {"py", p.pixel.y},
                     {"in_front", p.in_front}});
  }
  nlohmann::json j = {{"width", size.x},
                      {"height", size.y},
                      {"split", split},
                      {"camera",
                       {{"target", {camera.target.x, camera.target.y, camera.target.z}},
                        {"distance_m", camera.distance_m},
                        {"fov_y_deg", camera.fov_y_deg}}},
                      {"agents", agents},
                      {"exhibits", shown},
                      {"follow_id", follow},
                      {"lesson", lesson ? lesson->name : ""}};
  if (split && s.has_compare()) {
    j["compare_params"] = nlohmann::json::parse(mediator_params_to_json(s.compare_lane().params()));
    j["compare_own_crowd"] = s.compare_has_own_crowd();
  }
  j["params"] = nlohmann::json::parse(mediator_params_to_json(s.params()));
  if (const std::optional<TorsoReadout> t = torso_readout(s, s.lane(), follow)) {
    const ProjectedPoint head = camera.project(t->head, view);
    j["followed"] = {{"id", follow},
                     {"twist_deg", t->twist_deg},
                     {"theta_deg", t->theta_deg},
                     {"limit_deg", t->limit_deg},
                     {"head_px", head.pixel.x},
                     {"head_py", head.pixel.y}};
  }
  // The followed agent's places in both halves of a split whose halves run their own crowds.
  if (const std::optional<FollowedAgent> f = followed_agent(s, follow); f && f->twin) {
    nlohmann::json places = nlohmann::json::array();
    for (const glm::vec3& p : {f->position, *f->twin}) {
      const ProjectedPoint feet = camera.project(p, view);
      const ProjectedPoint head = camera.project(p + glm::vec3(0.0f, 1.8f, 0.0f), view);
      places.push_back({{"x", p.x}, {"z", p.z}, {"feet_px", feet.pixel.x},
                        {"feet_py", feet.pixel.y}, {"head_px", head.pixel.x},
                        {"head_py", head.pixel.y}, {"in_front", feet.in_front && head.in_front}});
    }
    j["followed_places"] = places;  // [0] the right half (primary), [1] the left
  }
  std::ofstream out(path);
  out << j.dump(1) << "\n";
  if (!out) fail(kCmd, 1, path + ": cannot write the report");
}

void run_render(RenderOptions& o) {
  o.crowd.command = kCmd;
  const Lesson* lesson = nullptr;
  if (!o.lesson.empty()) {
    lesson = find_lesson(o.lesson);
    if (!lesson) fail(kCmd, 2, "--lesson: expected " + lesson_names() + ", got '" + o.lesson + "'");
    if (!o.crowd.scenario.empty()) fail(kCmd, 2, "--lesson sets the scenario: drop --scenario");
    o.crowd.scenario = lesson->scenario;
    if (lesson->walk_clips_only && !o.crowd.clips.empty()) {
      fail(kCmd, 2, "--lesson " + o.lesson + " uses the built-in forward clips: drop --clips");
    }
    o.crowd.builtin_walks_only = lesson->walk_clips_only;
    if (o.crowd.agents.empty() && lesson->agents > 0) o.crowd.agents = std::to_string(lesson->agents);
    o.compare = true;
    const OverlayToggles& t = lesson->overlays;
    const std::pair<bool, const char*> on[] = {
        {t.velocity, "velocity"}, {t.theta, "theta"}, {t.facing, "facing"}, {t.planted, "planted"},
        {t.trails, "trails"},     {t.paths, "paths"}, {t.torso, "torso"},   {t.legs, "legs"}};
    for (const auto& [set, name] : on) {
      if (set) o.overlays.emplace_back(name);
    }
  }
  if (o.crowd.scenario.empty()) o.crowd.scenario = "crossing";
  const int frames = parse_number<int>(kCmd, o.frames, "--frames", 1, 1'000'000);
  OutputKind kind = OutputKind::kFolder;
  if (ends_with(o.out, ".png"))
    kind = OutputKind::kPng;
  else if (ends_with(o.out, ".mp4"))
    kind = OutputKind::kVideo;
  const OverlayToggles overlays = parse_overlays(o.overlays);
  int64_t follow =
      o.follow.empty() ? -1 : parse_number<int>(kCmd, o.follow, "--follow", 0, 1 << 30);
  // A lesson follows the agent nearest the scene's middle once the crowd has its first frame.
  bool pick_follow = lesson && lesson->follow && follow < 0;
  for (const char* selected_only : {"torso", "legs"}) {
    if (follow < 0 && !pick_follow &&
        o.overlays.end() != std::find(o.overlays.begin(), o.overlays.end(), selected_only)) {
      fail(kCmd, 2,
           std::string("--overlay ") + selected_only +
               " draws on the followed agent: add --follow ID");
    }
  }
  const double pull_out_s =
      o.pull_out.empty() ? -1.0 : parse_number<float>(kCmd, o.pull_out, "--pull-out", 0.0f, 1e6f);
  if (pull_out_s >= 0.0 && follow < 0 && !pick_follow) {
    fail(kCmd, 2, "--pull-out: pulls out from a followed agent: add --follow ID");
  }
  // Output paths are checked before the work starts, not after seconds of simulation.
  if (kind == OutputKind::kFolder) {
    if (Status s = check_output_folder(o.out, "--out"); !s.ok()) fail(kCmd, 2, s.message());
  } else {
    check_output_file_option(kCmd, o.out, "--out");
  }
  check_output_file_option(kCmd, o.report, "--report");
  std::unique_ptr<CrowdSession> session = CrowdSession::create(o.crowd);
  // What the library does not use, or uses without trusting its contacts: said before rendering.
  for (const std::string& l : describe_left_out(session->library())) {
    std::fprintf(stderr, "render: left out: %s\n", l.c_str());
  }
  for (const std::string& d : describe_doubts(session->library())) {
    std::fprintf(stderr, "render: doubtful: %s\n", d.c_str());
  }
  for (const std::string& g : describe_gaps(session->library(), session->params())) {
    std::fprintf(stderr, "render: library gap: %s\n", g.c_str());
  }
  if (follow >= 0) check_agent_id(kCmd, session->setup(), follow, "--follow");
  if (kind == OutputKind::kFolder) {
    std::error_code ec;
    std::filesystem::create_directories(o.out, ec);
    if (ec) fail(kCmd, 1, o.out + ": cannot create the folder: " + ec.message());
  }
  if (lesson) {
    MediatorParams p = session->params();
    lesson->on(&p);
    session->set_params(p);
    session->enable_compare(lesson->off, lesson->own_crowd);
  } else if (o.compare) {
    session->enable_compare(MediatorMode::kNaive);
  }
  OffscreenScene scene = open_offscreen_scene(kCmd, *session, o.size);
  if (o.compare) {
    // Each half is its own, narrower view of the whole scene.
    scene.view->camera() = frame_bounds(session->bounds_min(), session->bounds_max(),
                                        {scene.size.x / 2, scene.size.y});
  }
  const glm::ivec2 size = scene.size;
  // With --follow the camera rides on the agent: --camera then sets its angles and distance.
  CameraDirector director;
  director.set_overview(scene.view->camera());
  director.set_view(o.compare ? glm::ivec2(scene.size.x / 2, scene.size.y) : scene.size);
  if (lesson) {
    OrbitCamera overview = director.overview();
    overview.yaw_rad = glm::radians(lesson->yaw_deg);
    director.set_overview(overview);
    scene.view->camera().yaw_rad = overview.yaw_rad;
  }
  auto start_following = [&] {
    OrbitCamera& c = scene.view->camera();
    c.pitch_rad = kFollowPitch_rad;
    c.distance_m = lesson ? lesson->distance_m : kFollowDistance_m;
    if (!o.camera.empty()) {
      apply_camera(o.camera, &c);
      // The pull-out ends on the whole scene seen from the same side.
      OrbitCamera overview = director.overview();
      overview.yaw_rad = c.yaw_rad;
      director.set_overview(overview);
    }
    director.follow(follow, c.distance_m, c.pitch_rad);
    director.snap();
    if (pull_out_s >= 0.0) director.pull_out_at(pull_out_s);
  };
  if (follow >= 0) {
    start_following();
  } else if (!o.camera.empty()) {
    apply_camera(o.camera, &scene.view->camera());
  }
  const Exhibits exhibits =
      make_exhibits(session->setup(), 0.5f * (session->bounds_min() + session->bounds_max()),
                    scene.view->renderer().settings().wall_thickness_m);
  // Overlays are teaching aids: they stay visible through the bodies.
  scene.view->renderer().settings().lines_on_top = overlays.any();
  scene.view->renderer().settings().mesh_lod = o.mesh_lod == "on";

  FILE* video = nullptr;
  if (kind == OutputKind::kVideo) {
    if (std::system("command -v ffmpeg > /dev/null 2>&1") != 0) {
      fail(kCmd, 1, "ffmpeg not found: install it (apt-get install ffmpeg) or write PNG frames");
    }
    // A dying ffmpeg must end in an error message, not in SIGPIPE.
    std::signal(SIGPIPE, SIG_IGN);
    const std::string cmd = "ffmpeg -loglevel error -y -f rawvideo -pix_fmt rgb24 -s " +
                            std::to_string(size.x) + "x" + std::to_string(size.y) +
                            " -r 60 -i - -c:v libx264 -pix_fmt yuv420p '" + o.out + "'";
    video = popen(cmd.c_str(), "w");
    if (!video) fail(kCmd, 1, "cannot start ffmpeg");
  }

  std::optional<OverlayHistory> history, compare_history;
  if (overlays.any() || follow >= 0 || pick_follow) {
    history.emplace(*session, session->crowd().capacity());
    if (o.compare) compare_history.emplace(*session, session->crowd().capacity());
  }
  const bool split = o.compare;
  FrameCapture capture;
  const int label_scale = std::max(2, size.y / 240);
  const std::string left_label = lesson ? upper(lesson->off_label) : "NAIVE";
  const std::string right_label =
      upper(lesson ? lesson->on_label : mediator_mode_name(session->params().mode));
  const bool tty = isatty(fileno(stderr)) != 0;
  for (int f = 0; f < frames; ++f) {
    if (Status s = session->step(kFrameTime_s); !s.ok()) {
      if (video) pclose(video);
      fail(kCmd, 1, "frame " + std::to_string(f) + ": " + s.message());
    }
    if (history) history->record(*session, session->lane(), kFrameTime_s);
    if (compare_history) compare_history->record(*session, session->compare_lane(), kFrameTime_s);
    if (pick_follow && session->frame().size() > 0) {
      pick_follow = false;
      follow = agent_nearest(session->frame(),
                             0.5f * (session->bounds_min() + session->bounds_max()));
      start_following();
    }
    const bool needed = kind != OutputKind::kPng || f == frames - 1;
    if (!needed && follow < 0) continue;
    session->collect();  // also the followed agent's drawn position
    if (follow >= 0) {
      director.update(session->crowd().time_s(), static_cast<float>(kFrameTime_s),
                      followed_agent(*session, follow), &scene.view->camera());
    }
    if (!needed) continue;
    scene.context->begin_frame();
    Status drawn;
    CrowdRenderer& r = scene.view->renderer();
    if (split) {
      const int left = size.x / 2;
      drawn = scene.view->upload(*session, session->compare_lane());
      if (drawn.ok() && compare_history) {
        compare_history->draw(*session, session->compare_lane(), overlays, follow, &r);
      }
      if (drawn.ok()) drawn = scene.view->draw(session->compare_lane(), {0, 0}, {left, size.y});
      if (drawn.ok()) drawn = scene.view->upload(*session, session->lane());
      if (drawn.ok() && history) history->draw(*session, session->lane(), overlays, follow, &r);
      if (drawn.ok()) drawn = scene.view->draw(session->lane(), {left, 0}, {size.x - left, size.y});
    } else {
      drawn = scene.view->upload(*session, session->lane());
      if (drawn.ok() && history) history->draw(*session, session->lane(), overlays, follow, &r);
      if (drawn.ok()) drawn = scene.view->draw(session->lane(), {0, 0}, size);
    }
    if (!drawn.ok()) fail(kCmd, 1, "frame " + std::to_string(f) + ": " + drawn.message());
    scene.context->finish_frame();
    if (Status s = capture.grab(size); !s.ok()) fail(kCmd, 1, s.message());
    if ((overlays.torso || overlays.legs) && follow >= 0) {
      const glm::ivec2 view = split ? glm::ivec2(size.x / 2, size.y) : size;
      const int scale = std::max(2, label_scale - 1);
      stamp_readouts(*session, session->lane(), follow, overlays, scene.view->camera(), view,
                     split ? size.x / 2 : 0, scale, &capture, size);
      if (split) {
        stamp_readouts(*session, session->compare_lane(), follow, overlays, scene.view->camera(),
                       view, 0, scale, &capture, size);
      }
    }
    if (split) {
      stamp_label(capture.mutable_rgba(), size, {8 * label_scale, 8 * label_scale}, left_label,
                  label_scale);
      stamp_label(capture.mutable_rgba(), size, {size.x / 2 + 8 * label_scale, 8 * label_scale},
                  right_label, label_scale);
      // The divider.
      for (int y = 0; y < size.y; ++y) {
        for (int x = size.x / 2 - 1; x <= size.x / 2; ++x) {
          uint8_t* p = &capture.mutable_rgba()[(static_cast<size_t>(y) * size.x + x) * 4];
          p[0] = p[1] = p[2] = 20;
        }
      }
    }
    if (lesson) {
      // What to look at, along the bottom edge (the window shows the whole text).
      const int scale = std::max(1, label_scale - 1);
      stamp_label(capture.mutable_rgba(), size, {8 * scale, size.y - 14 * scale},
                  lesson->caption, scale, {255, 220, 120});
    }
    Status written;
    if (kind == OutputKind::kVideo) {
      written = capture.write_rgb(video);
    } else if (kind == OutputKind::kFolder) {
      char name[32];
      std::snprintf(name, sizeof(name), "/frame_%05d.png", f);
      written = capture.save_png(o.out + name);
    } else {
      written = capture.save_png(o.out);
    }
    if (!written.ok()) {
      if (video) pclose(video);
      fail(kCmd, 1, written.message());
    }
    // Progress: one updating line on a terminal, a line per tenth in a log.
    if (kind != OutputKind::kPng || f == frames - 1) {
      if (tty) {
        std::fprintf(stderr, "\rrender: frame %d/%d   ", f + 1, frames);
        std::fflush(stderr);
      } else if (f == frames - 1 || (f + 1) % std::max(1, frames / 10) == 0) {
        std::fprintf(stderr, "render: frame %d/%d\n", f + 1, frames);
      }
    }
  }
  if (tty) std::fprintf(stderr, "\n");
  if (video) {
    const int status = pclose(video);
    if (status != 0)
      fail(kCmd, 1, "ffmpeg failed writing " + o.out + " (exit " + std::to_string(status) + ")");
  }
  if (!o.report.empty()) {
    write_report(o.report, *session, scene.view->camera(), size, split, exhibits, follow, lesson);
  }
  std::printf("render: %d frames of %s (%d agents, %s%s%s) written to %s\n", frames,
              session->setup().scenario_name.c_str(), static_cast<int>(session->frame().size()),
              std::string(mediator_mode_name(session->params().mode)).c_str(),
              split ? ", left " : "", split ? (lesson ? lesson->off_label : "naive") : "",
              o.out.c_str());
}

}  // namespace

void add_render_command(CLI::App& app) {
  auto options = std::make_shared<RenderOptions>();
  CLI::App* cmd = app.add_subcommand(
      "render",
      "Render a crowd offscreen to a PNG (last frame), a folder of PNG frames or an MP4 video.");
  add_crowd_options(cmd, &options->crowd, /*scenario_required=*/false);
  cmd->add_option("--frames", options->frames, "Frames to simulate and render (default 120)");
  cmd->add_option("--out", options->out,
                  "FILE.png (the last frame), FILE.mp4 (H.264 through ffmpeg) or a folder")
      ->required();
  cmd->add_option("--size", options->size, "Image size WxH (default 1280x720)");
  cmd->add_flag("--compare", options->compare,
                "Split screen: naive on the left, --mode (default apm) on the right");
  cmd->add_option("--camera", options->camera,
                  "yaw_deg,pitch_deg,distance_m[,target_x,target_z] (default: frames the "
                  "scenario in a 3/4 view)");
  cmd->add_option("--overlay", options->overlays,
                  "Teaching overlays: velocity, theta, facing, planted, trails, paths, torso "
                  "(the followed agent's torso fan), legs (the followed agent's legs against its "
                  "path), all");
  cmd->add_option("--follow", options->follow,
                  "Agent id to follow: a ring at its feet, the camera close on it (--camera then "
                  "sets yaw, pitch and distance)");
  cmd->add_option("--pull-out", options->pull_out,
                  "With --follow: at this simulated time [s] the camera pulls out to the whole "
                  "scene");
  cmd->add_option("--lesson", options->lesson,
                  "A lesson's scene: " + lesson_names() +
                      " (scenario, follow camera, overlays, split of that one idea off | on, the "
                      "caption)");
  cmd->add_option("--mesh-lod", options->mesh_lod,
                  "Lighter meshes for agents small on screen, on (default) or off")
      ->check(CLI::IsMember({"on", "off"}));
  cmd->add_option("--report", options->report,
                  "Write the last frame's agent positions and image pixels as JSON");
  cmd->callback([options] { run_render(*options); });
}

}  // namespace gk::app
