// `gaitkeeper bench`: runs a crowd headless for a number of frames at 60 Hz and reports per-stage
// timings (METRICS.md, "Performance") and crowd statistics, as text and optionally as JSON.
// The frame loop is CrowdPipeline's (through CrowdSession), which also records the metrics and
// the joint dump; --render adds the upload and render stages, offscreen.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <limits>
#include <memory>
#include <span>
#include <string>

#include <CLI/CLI.hpp>
#include <glm/geometric.hpp>

#include "app/bench_report.h"
#include "app/commands.h"
#include "app/crowd_session.h"
#include "app/offscreen.h"
#include "crowd/social_forces.h"
#include "crowd/spatial_grid.h"
#include "mediator/joint_dump.h"
#include "mediator/mediator.h"
#include "mediator/metrics.h"
#include "mediator/pose_synthesis.h"
#include "mediator/quantile_sketch.h"
#include "render/crowd_renderer.h"

namespace gk::app {
namespace {

constexpr int kWarmupFrames = 30;
constexpr float kMinPairSearch_m = 3.0f;  // closest-approach search radius of the statistics
// The metrics and stage timings are streamed in fixed memory: a run of any length keeps flat
// memory (bench/soak.sh checks it).
constexpr int kMaxFrames = 10'000'000;

struct BenchOptions {
  CrowdOptions crowd;
  std::string frames = "600";
  std::string json;
  std::string dump_joints;
  std::string dump_joint_names;
  bool render = false;
  std::string size = "1280x720";
  std::string mesh_lod = "on";
  std::string progress_every = "0";
  bool lod = false;
  std::string lod_distances;
  std::string lod_focus;
};

// --lod, --lod-distances a,b,c and --lod-focus X,Z (default: the centre of the scenario's region).
LodParams lod_params(const BenchOptions& o, const CrowdSession& session) {
  LodParams p;
  p.enabled = o.lod;
  p.focus = 0.5f * (session.bounds_min() + session.bounds_max());
  if (!o.lod_distances.empty()) {
    if (Status s = parse_lod_distances(o.lod_distances, "--lod-distances", &p); !s.ok()) {
      app::fail("bench", 2, s.message());
    }
  }
  if (!o.lod_focus.empty()) {
    float x = 0.0f, z = 0.0f;
    char tail = 0;
    if (std::sscanf(o.lod_focus.c_str(), "%f,%f%c", &x, &z, &tail) != 2 || !std::isfinite(x) ||
        !std::isfinite(z)) {
      app::fail("bench", 2, "--lod-focus: expected X,Z [m], got '" + o.lod_focus + "'");
    }
    p.focus = glm::vec2(x, z);
  }
  return p;
}

// One line of --progress-every: the window of frames since the previous line.
struct ProgressWindow {
  int frames = 0;
  int64_t agent_frames = 0;
  double total_ms_sum = 0.0, total_ms_max = 0.0;
  double cpu_ms_sum = 0.0;  // CPU time of the process (all threads) in the pipeline
  StageTimer::Clock::time_point start;
  int64_t non_finite_crowd = 0;  // since the start of the run
};

// CPU time of this process, all threads [ms]: unlike wall time, it does not count the time the
// process waits while other programs run (a soak on a shared machine).
double process_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

// Resident memory of this process [KiB] (VmRSS of /proc/self/status), -1 where unavailable.
int64_t resident_kib() {
  std::FILE* f = std::fopen("/proc/self/status", "r");
  if (!f) return -1;
  char line[256];
  int64_t kib = -1;
  while (std::fgets(line, sizeof(line), f)) {
    long long v = 0;
    if (std::sscanf(line, "VmRSS: %lld kB", &v) == 1) {
      kib = v;
      break;
    }
  }
  std::fclose(f);
  return kib;
}

int64_t count_non_finite(std::span<const float> values) {
  int64_t n = 0;
  for (float v : values) n += !std::isfinite(v);
  return n;
}

// NaN or infinite values in the world transforms of the frame's agents.
int64_t non_finite_poses(const AgentFrame& frame, const Mediator& mediator,
                         const PoseSynthesizer& poses) {
  int64_t n = 0;
  for (size_t i = 0; i < frame.size(); ++i) {
    for (const glm::mat4& m : poses.world(mediator.plans().slot_of_agent[i])) {
      n += count_non_finite({&m[0][0], 16});
    }
  }
  return n;
}

[[noreturn]] void fail(int code, const std::string& message) { app::fail("bench", code, message); }

// Smallest centre distance below kMinPairSearch_m among the agents, if any pair is that close.
std::optional<double> min_pair_distance(std::span<const glm::vec2> positions) {
  if (positions.size() < 2) return std::nullopt;
  glm::vec2 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
  for (const glm::vec2& p : positions) lo = glm::min(lo, p), hi = glm::max(hi, p);
  auto grid = UniformGrid::create(lo, hi, kMinPairSearch_m, positions.size());
  if (!grid.ok()) return std::nullopt;
  grid->build(positions);
  const auto order = grid->order();
  double best = kMinPairSearch_m;
  bool found = false;
  for (size_t i = 0; i < positions.size(); ++i) {
    const auto [cx, cz] = grid->cell_of(positions[i]);
    for (int z = cz - 1; z <= cz + 1; ++z) {
      const auto [b, e] = grid->row_range(z, cx - 1, cx + 1);
      for (uint32_t k = b; k < e; ++k) {
        if (order[k] <= i) continue;  // each pair once
        const double d = glm::length(positions[i] - positions[order[k]]);
        if (d < best) best = d, found = true;
      }
    }
  }
  return found ? std::optional<double>(best) : std::nullopt;
}

std::vector<std::string> split_names(const std::string& list) {
  std::vector<std::string> out;
  size_t start = 0;
  while (start <= list.size() && !list.empty()) {
    const size_t comma = list.find(',', start);
    const std::string name = list.substr(start, comma == std::string::npos ? comma : comma - start);
    if (!name.empty()) out.push_back(name);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

// --render: what the renderer drew on the timed frames and the render stage's CPU time (all the
// process's threads: the software rasteriser's too), which a loaded machine does not inflate.
struct RenderTally {
  int frames = 0;
  int64_t agent_triangles = 0;
  std::array<int64_t, kMaxMeshLods> agents_per_lod{};
  QuantileSketch cpu_ms;

  void add(const RenderStats& stats, double cpu_ms_of_frame) {
    ++frames;
    agent_triangles += stats.agent_triangles;
    for (int l = 0; l < kMaxMeshLods; ++l) agents_per_lod[l] += stats.agents_per_lod[l];
    cpu_ms.add(cpu_ms_of_frame);
  }
  nlohmann::json to_json(const CrowdRenderer& renderer, bool mesh_lod, glm::ivec2 size) const {
    const double n = std::max(frames, 1);
    nlohmann::json levels = nlohmann::json::array();
    nlohmann::json per_level = nlohmann::json::array();
    for (int l = 0; l < renderer.num_mesh_lods(0); ++l) {
      levels.push_back({{"triangles", renderer.mesh_lod_triangles(0, l)},
                        {"error_m", renderer.mesh_lod_error_m(0, l)}});
      per_level.push_back(static_cast<double>(agents_per_lod[l]) / n);
    }
    return {{"size", std::to_string(size.x) + "x" + std::to_string(size.y)},
            {"mesh_lod", mesh_lod},
            {"mesh_levels", levels},
            {"agents_per_level", per_level},
            {"agent_triangles_per_frame", static_cast<double>(agent_triangles) / n},
            {"cpu_ms", frames > 0 ? nlohmann::json{{"median", cpu_ms.nearest_rank(0.5)},
                                                   {"p95", cpu_ms.nearest_rank(0.95)}}
                                  : nlohmann::json(nullptr)}};
  }
};

void run_bench(const BenchOptions& o) {
  const int frames = parse_number<int>("bench", o.frames, "--frames", 1, kMaxFrames);
  // Output paths are checked before the work starts, not after minutes of simulation.
  check_output_file_option("bench", o.json, "--json");
  check_output_file_option("bench", o.dump_joints, "--dump-joints");
  std::unique_ptr<CrowdSession> session = CrowdSession::create(o.crowd, /*record_metrics=*/true);
  CrowdSource& crowd = session->crowd();
  if (frames <= kWarmupFrames) {
    std::fprintf(stderr, "gaitkeeper bench: only %d frames; the first %d are warm-up and untimed\n",
                 frames, kWarmupFrames);
  }
  const LodParams lod = lod_params(o, *session);
  if (!o.lod && (!o.lod_distances.empty() || !o.lod_focus.empty())) {
    fail(2, "--lod-distances and --lod-focus need --lod");
  }
  if (Status s = session->pipeline().set_lod(lod); !s.ok()) fail(2, s.message());
  LodReport lod_stats;
  int64_t lod_frames = 0;
  const LocomotionLibrary& library = session->library();
  const MediatorParams& params = session->params();
  const MetricsRecorder& metrics = *session->pipeline().metrics();
  std::optional<JointDumpWriter> dump;
  if (!o.dump_joints.empty()) {
    auto opened =
        JointDumpWriter::open(o.dump_joints, *library.skeleton, split_names(o.dump_joint_names));
    if (!opened.ok()) fail(2, opened.message());
    dump.emplace(std::move(*opened));
    // Frame f (from 0) ends at (f + 1) frame times.
    session->pipeline().add_frame_hook([&dump](const CrowdPipeline& p) {
      const int64_t f = p.frames_run() - 1;
      return dump->write_frame(static_cast<int>(f), static_cast<double>(f + 1) * kFrameTime_s,
                               p.frame(), p.mediator(), p.poses());
    });
  }
  // --render: the upload and render stages, offscreen, timed to completion with glFinish.
  std::optional<OffscreenScene> scene;
  if (o.render) scene.emplace(open_offscreen_scene("bench", *session, o.size));
  if (scene) scene->view->renderer().settings().mesh_lod = o.mesh_lod == "on";
  RenderTally render_tally;

  StageTimer timer(kWarmupFrames);
  CrowdReport crowd_stats;
  double live_sum = 0.0, speed_sum = 0.0;
  int64_t speed_samples = 0;
  const auto started = StageTimer::Clock::now();
  auto last_progress = started;
  const int progress_every =
      parse_number<int>("bench", o.progress_every, "--progress-every", 0, kMaxFrames);
  ProgressWindow window;
  window.start = started;
  for (int f = 0; f < frames; ++f) {
    const auto frame_start = StageTimer::Clock::now();
    const double frame_cpu_start_ms = progress_every > 0 ? process_cpu_ms() : 0.0;
    const Status stepped = session->step(kFrameTime_s);
    if (!stepped.ok()) fail(1, "frame " + std::to_string(f) + ": " + stepped.message());
    timer.record(Stage::kSim, f, session->times().sim_ms);
    timer.record(Stage::kMediator, f, session->times().mediator_ms);
    timer.record(Stage::kPose, f, session->times().pose_ms);
    // The metrics and the joint dump run inside the step but are measurement, not pipeline.
    const PipelineTimes& measured_in_step = session->pipeline().times();
    if (scene) {
      session->collect();
      const Status uploaded = timer.time(Stage::kUpload, f, [&] {
        Status s = scene->view->upload(*session, session->lane());
        glFinish();
        return s;
      });
      if (!uploaded.ok()) fail(1, "frame " + std::to_string(f) + ": " + uploaded.message());
      const double render_cpu_start_ms = process_cpu_ms();
      const Status drawn = timer.time(Stage::kRender, f, [&] {
        scene->context->begin_frame();
        Status s = scene->view->draw(session->lane(), glm::ivec2(0), scene->size);
        glFinish();
        return s;
      });
      if (!drawn.ok()) fail(1, "frame " + std::to_string(f) + ": " + drawn.message());
      if (f >= kWarmupFrames) {
        render_tally.add(scene->view->renderer().stats(), process_cpu_ms() - render_cpu_start_ms);
      }
    }
    const double frame_total_ms = StageTimer::ms_since(frame_start) - measured_in_step.measure_ms;
    if (o.lod && f >= kWarmupFrames) {
      const LodPolicy& levels = session->pipeline().lod();
      for (int k = 0; k < kNumLodLevels; ++k) {
        lod_stats.mean_agents_per_level[k] += static_cast<double>(levels.counts()[k]);
      }
      const AnimationPlans& pl = session->pipeline().plans();
      int64_t updated = 0;
      for (size_t i = 0; i < session->frame().size(); ++i) {
        const int slot = pl.slot_of_agent[i];
        updated += levels.due()[slot] || pl.fresh[slot];
      }
      lod_stats.mean_agents_updated += static_cast<double>(updated);
      ++lod_frames;
    }
    const double frame_cpu_ms =
        progress_every > 0 ? process_cpu_ms() - frame_cpu_start_ms - measured_in_step.measure_cpu_ms
                           : 0.0;
    timer.record(Stage::kTotal, f, frame_total_ms);

    // Statistics of the crowd frame as planned (before feedback), not part of the timed pipeline.
    const AgentFrame frame = session->frame();
    const Mediator& mediator = session->mediator();
    const PoseSynthesizer& poses = session->poses();
    live_sum += static_cast<double>(frame.size());
    crowd_stats.max_live_agents = std::max<int64_t>(crowd_stats.max_live_agents, frame.size());
    for (const glm::vec2& v : frame.velocities) {
      const double speed = glm::length(v);
      speed_sum += speed;
      crowd_stats.max_speed_m_s = std::max(crowd_stats.max_speed_m_s, speed);
    }
    speed_samples += static_cast<int64_t>(frame.size());
    if (f % crowd_stats.pair_distance_every_frames == 0) {
      if (auto d = min_pair_distance(frame.positions)) {
        crowd_stats.min_pair_distance_m =
            std::min(crowd_stats.min_pair_distance_m.value_or(kMinPairSearch_m), *d);
      }
    }
    for (size_t i = 0; i < frame.size(); ++i) {
      window.non_finite_crowd +=
          !std::isfinite(frame.positions[i].x) + !std::isfinite(frame.positions[i].y) +
          !std::isfinite(frame.velocities[i].x) + !std::isfinite(frame.velocities[i].y) +
          !std::isfinite(frame.thetas[i]);
    }
    const auto now = StageTimer::Clock::now();
    if (progress_every > 0) {
      // One JSON line per window on stderr, for bench/soak.sh: memory, time per frame, NaN.
      ++window.frames;
      window.agent_frames += static_cast<int64_t>(frame.size());
      window.total_ms_sum += frame_total_ms;
      window.total_ms_max = std::max(window.total_ms_max, frame_total_ms);
      window.cpu_ms_sum += frame_cpu_ms;
      if ((f + 1) % progress_every == 0 || f + 1 == frames) {
        const double wall_ms =
            std::chrono::duration<double, std::milli>(now - window.start).count();
        std::fprintf(stderr,
                     "{\"frame\": %d, \"sim_time_s\": %.3f, \"wall_s\": %.3f, "
                     "\"live_agents\": %zu, \"live_tracks\": %zu, \"frame_ms\": %.4f, "
                     "\"frame_ms_max\": %.4f, \"wall_ms_per_frame\": %.4f, "
                     "\"us_per_agent_frame\": %.4f, \"cpu_ms\": %.4f, "
                     "\"cpu_us_per_agent_frame\": %.4f, \"rss_kib\": %lld, "
                     "\"non_finite\": {\"crowd\": %lld, \"poses\": %lld, \"joints\": %lld}}\n",
                     f + 1, crowd.time_s(), std::chrono::duration<double>(now - started).count(),
                     frame.size(), metrics.num_live_tracks(), window.total_ms_sum / window.frames,
                     window.total_ms_max, wall_ms / window.frames,
                     window.agent_frames > 0
                         ? 1000.0 * window.total_ms_sum / static_cast<double>(window.agent_frames)
                         : 0.0,
                     window.cpu_ms_sum / window.frames,
                     window.agent_frames > 0
                         ? 1000.0 * window.cpu_ms_sum / static_cast<double>(window.agent_frames)
                         : 0.0,
                     static_cast<long long>(resident_kib()),
                     static_cast<long long>(window.non_finite_crowd),
                     static_cast<long long>(non_finite_poses(frame, mediator, poses)),
                     static_cast<long long>(metrics.num_non_finite()));
        std::fflush(stderr);
        const int64_t keep_crowd = window.non_finite_crowd;
        window = ProgressWindow();
        window.start = now;
        window.non_finite_crowd = keep_crowd;
      }
    } else if (now - last_progress >= std::chrono::seconds(1)) {
      last_progress = now;
      std::fprintf(stderr, "\rbench: frame %d/%d, %.3f ms/frame (wall, incl. statistics)   ", f + 1,
                   frames,
                   std::chrono::duration<double, std::milli>(now - started).count() / (f + 1));
      std::fflush(stderr);
    }
  }
  if (last_progress != started) std::fprintf(stderr, "\n");

  BenchReport report;
  report.gaitkeeper_version = GK_VERSION;
  report.scenario = session->setup().scenario_name;
  report.sim = crowd.name();
  report.agents = session->setup().agents;
  report.frames = frames;
  report.frame_time_s = kFrameTime_s;
  report.threads = parse_number<int>("bench", o.crowd.threads, "--threads", 0, 256);
  report.seed = parse_number<uint64_t>("bench", o.crowd.seed, "--seed", 0,
                                       std::numeric_limits<uint64_t>::max());
  for (size_t s = 0; s < kNumStages; ++s) report.timing_ms[s] = timer.stat(static_cast<Stage>(s));
  if (const auto& total = report.timing_ms[static_cast<size_t>(Stage::kTotal)];
      total && report.agents > 0) {
    report.us_per_agent = total->median_ms / static_cast<double>(report.agents) * 1000.0;
  }
  crowd_stats.mean_live_agents = live_sum / frames;
  crowd_stats.mean_speed_m_s = speed_samples ? speed_sum / static_cast<double>(speed_samples) : 0.0;
  if (const SocialForces* social = session->setup().social) {
    const SocialForceStats st = social->stats();
    crowd_stats.reached_goal = static_cast<int64_t>(st.reached_goal);
    crowd_stats.removed = static_cast<int64_t>(st.removed);
  }
  report.crowd = crowd_stats;
  if (o.lod) {
    lod_stats.focus_x_m = lod.focus.x;
    lod_stats.focus_z_m = lod.focus.y;
    for (int k = 0; k < kNumLodLevels - 1; ++k) lod_stats.distances_m[k] = lod.distances_m[k];
    lod_stats.hysteresis_m = lod.hysteresis_m;
    const double n = static_cast<double>(std::max<int64_t>(lod_frames, 1));
    for (double& v : lod_stats.mean_agents_per_level) v /= n;
    lod_stats.mean_agents_updated /= n;
    report.lod = lod_stats;
  }
  if (scene) {
    report.render = render_tally.to_json(scene->view->renderer(), o.mesh_lod == "on", scene->size);
  }
  report.mode = std::string(mediator_mode_name(params.mode));
  report.joints = library.skeleton->num_joints();
  report.clips = library.clip_names();
  report.takes = describe_takes(library);
  report.left_out = describe_left_out(library);
  report.doubtful = describe_doubts(library);
  report.gaps = describe_gaps(library, params);
  {
    BenchReport::Transitions t;
    const auto counts = session->mediator().transition_counts();
    t.starts = static_cast<int64_t>(counts[kStartsSeen]);
    t.starts_played = static_cast<int64_t>(counts[kStartsPlayed]);
    t.stops = static_cast<int64_t>(counts[kStopsSeen]);
    t.stops_played = static_cast<int64_t>(counts[kStopsPlayed]);
    t.creep_stops = static_cast<int64_t>(counts[kCreepStops]);
    for (const Transition& tr : library.transitions) {
      ++(tr.kind == TransitionKind::kStart ? t.start_clips : t.stop_clips);
    }
    report.transitions = t;
  }
  const MetricsReport measured = metrics.finish();
  report.metrics = metrics_to_json(measured, library);
  if (dump) {
    if (Status s = dump->close(); !s.ok()) fail(1, s.message());
  }
  std::fputs(summary(report).c_str(), stdout);
  // METRICS.md v1's contact band is decided FootSlideStream::kLag_s late (docs/metrics.md).
  std::printf("  v1 contact band excess (0 = METRICS.md exactly): toe %.3f mm, ankle %.3f mm\n",
              1000.0 * measured.slide_toe_band_excess_m,
              1000.0 * measured.slide_ankle_band_excess_m);
  if (report.render) {
    const nlohmann::json& r = *report.render;
    std::string levels;
    for (const auto& n : r["agents_per_level"]) {
      char v[32];
      std::snprintf(v, sizeof(v), " %.1f", n.get<double>());
      levels += v;
    }
    std::printf("  render %s, mesh lod %s: %.0f agent triangles per frame, agents per level:%s",
                r["size"].get<std::string>().c_str(), o.mesh_lod.c_str(),
                r["agent_triangles_per_frame"].get<double>(), levels.c_str());
    if (!r["cpu_ms"].is_null()) {
      std::printf("; CPU median %.2f ms", r["cpu_ms"]["median"].get<double>());
    }
    std::printf("\n");
  }
  if (measured.non_finite > 0) {
    std::printf("  NaN or infinite joint coordinates or samples: %lld\n",
                static_cast<long long>(measured.non_finite));
  }
  if (!o.json.empty()) {
    if (const Status written = write_report_json(report, o.json); !written.ok()) {
      fail(1, written.message());
    }
    std::printf("  report written to %s\n", o.json.c_str());
  }
}

}  // namespace

void add_bench_command(CLI::App& app) {
  auto options = std::make_shared<BenchOptions>();
  CLI::App* cmd = app.add_subcommand(
      "bench",
      "Run a crowd and the mediator headless at 60 Hz; report stage timings, crowd statistics and "
      "the animation metrics of METRICS.md.");
  add_crowd_options(cmd, &options->crowd, /*scenario_required=*/true);
  cmd->add_option("--frames", options->frames,
                  "Frames to simulate (default 600; the first 30 "
                  "are warm-up and not timed)");
  cmd->add_option("--json", options->json, "Write the report (METRICS.md schema) to this file");
  cmd->add_flag("--render", options->render,
                "Also render every frame offscreen (EGL) and time the upload and render stages");
  cmd->add_option("--size", options->size, "Frame size of --render, WxH (default 1280x720)");
  cmd->add_option("--mesh-lod", options->mesh_lod,
                  "With --render: lighter meshes for agents small on screen, on (default) or off")
      ->check(CLI::IsMember({"on", "off"}));
  cmd->add_flag("--loop", options->crowd.loop,
                "Run the crowd round and round: a replayed file starts over after its last "
                "sample; a scenario whose agents leave at their goal starts a new round (seed + 1, "
                "...) when the last has left");
  cmd->add_option("--progress-every", options->progress_every,
                  "Every N frames, one JSON line on stderr: frame, sim_time_s, wall_s, "
                  "live_agents, live_tracks, frame_ms (mean pipeline time of those frames), "
                  "frame_ms_max, wall_ms_per_frame, us_per_agent_frame, cpu_ms and "
                  "cpu_us_per_agent_frame (process CPU time of the pipeline), rss_kib, non_finite "
                  "counts (0 = off)");
  cmd->add_flag("--lod", options->lod,
                "Level of detail by distance to a focus point: agents planned and posed every "
                "frame (level 0, full detail) or every 2nd / 4th / 8th frame with fewer details "
                "(no new foot locks, those held are let go through their releases; from level "
                "2 no spine twist and no fingers, toes or face joints); the metrics then cover "
                "level 0 agents only (docs/pipeline.md)");
  cmd->add_option("--lod-distances", options->lod_distances,
                  "With --lod: level boundaries a,b,c [m] (default 15,30,60)");
  cmd->add_option("--lod-focus", options->lod_focus,
                  "With --lod: the focus point X,Z [m] (default: the centre of the scenario)");
  cmd->add_option("--dump-joints", options->dump_joints,
                  "Write world joint positions per frame and agent to this CSV");
  cmd->add_option("--dump-joint-names", options->dump_joint_names,
                  "Comma-separated joints to dump (default: left/right ankle and toe, knees, hip joints, hips)");
  cmd->callback([options] { run_bench(*options); });
}

}  // namespace gk::app
