// `gaitkeeper bench`: runs a crowd headless for a number of frames at 60 Hz and reports per-stage
// timings (METRICS.md, "Performance") and crowd statistics, as text and optionally as JSON.
// Only the `sim` stage exists so far; the mediator and pose stages slot in next to it.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <string>

#include <CLI/CLI.hpp>
#include <glm/geometric.hpp>

#include <tbb/global_control.h>

#include "animation/analysis.h"
#include "animation/clip_library.h"
#include "animation/procedural.h"
#include "app/bench_report.h"
#include "app/commands.h"
#include "crowd/detour_crowd.h"
#include "crowd/scenario.h"
#include "crowd/social_forces.h"
#include "crowd/spatial_grid.h"
#include "crowd/trajectory_replay.h"
#include "mediator/joint_dump.h"
#include "mediator/mediator.h"
#include "mediator/metrics.h"
#include "mediator/pose_synthesis.h"

namespace gk::app {
namespace {

constexpr double kFrameTime_s = 1.0 / 60.0;
constexpr int kWarmupFrames = 30;
constexpr float kMinPairSearch_m = 3.0f;  // closest-approach search radius of the statistics
constexpr int kMaxFrames = 10'000'000;

struct BenchOptions {
  std::string scenario;
  std::string sim = "social";
  std::string agents, frames = "600", seed = "1", threads = "1", trajectory_frame_time = "0.4";
  std::string json;
  std::string mode = "apm";
  std::vector<std::string> clips;
  std::vector<std::string> sets;
  std::string params_file;
  std::string dump_joints;
  std::string dump_joint_names;
};

[[noreturn]] void fail(int code, const std::string& message) {
  std::fprintf(stderr, "gaitkeeper bench: %s\n", message.c_str());
  throw ExitRequest{code};
}

// Numbers are parsed here rather than by CLI11 so that every bad value gets exit code 2 and a
// message that names the option and its range.
template <typename T>
T parse_number(const std::string& text, const char* option, T lo, T hi) {
  T value{};
  const char* end = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (ec != std::errc() || ptr != end || !(value >= lo && value <= hi)) {
    fail(2, std::string(option) + ": expected a number in [" + std::to_string(lo) + ", " +
                std::to_string(hi) + "], got '" + text + "'");
  }
  return value;
}

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

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

struct Source {
  std::unique_ptr<CrowdSource> crowd;
  SocialForces* social = nullptr;  // set when the source is the social-forces simulator
  std::string scenario_name;
  int64_t agents = 0;
};

Source make_source(const BenchOptions& o, int threads, uint64_t seed) {
  Source src;
  if (ends_with(o.scenario, ".txt")) {
    if (o.sim != "social") fail(2, "--sim " + o.sim + " needs a scenario, not a trajectory file");
    if (!o.agents.empty()) std::fprintf(stderr, "gaitkeeper bench: --agents ignored for replay\n");
    ReplayOptions replay;
    replay.frame_time_s =
        parse_number<float>(o.trajectory_frame_time, "--trajectory-frame-time", 1e-3f, 60.0f);
    auto loaded = load_trajectory_replay(o.scenario, replay);
    if (!loaded.ok()) fail(2, loaded.message());
    src.crowd = std::move(loaded).value();
    src.scenario_name = o.scenario;
    src.agents = static_cast<int64_t>(src.crowd->capacity());
    return src;
  }
  auto loaded = load_scenario_by_name(o.scenario, scenario_dir());
  if (!loaded.ok()) fail(2, loaded.message());
  const int num_agents = o.agents.empty()
                             ? loaded->default_agents
                             : parse_number<int>(o.agents, "--agents", 0, kMaxScenarioAgents);
  const Scenario scenario = scale_scenario(*loaded, num_agents);
  auto agents = expand_agents(scenario, num_agents, seed);
  if (!agents.ok()) fail(2, agents.message());
  src.scenario_name = loaded->name;
  src.agents = num_agents;
  if (o.sim == "social") {
    SocialForceParams params;
    params.threads = threads;
    auto sim = SocialForces::create(scenario, *agents, params);
    if (!sim.ok()) fail(2, sim.message());
    src.social = sim->get();
    src.crowd = std::move(sim).value();
  } else {
    DetourParams params;
    params.seed = seed;
    auto sim = make_detour_crowd(scenario, *agents, params);
    if (!sim.ok()) fail(2, sim.message());
    src.crowd = std::move(sim).value();
  }
  return src;
}

// The clip library: the built-in set, or the given files and folders (one clip set per file).
LocomotionLibrary load_library(const std::vector<std::string>& clips) {
  std::vector<ClipSet> sets;
  if (clips.empty()) {
    sets.push_back(make_builtin_clip_set());
  } else {
    auto files = expand_clip_paths(clips);
    if (!files.ok()) fail(2, files.message());
    if (files->empty()) fail(2, "--clips: no .bvh, .gltf or .glb file found");
    for (const std::string& f : *files) {
      auto set = load_clip_file(f);
      if (!set.ok()) fail(2, set.message());
      sets.push_back(std::move(*set));
    }
  }
  auto lib = build_locomotion_library(sets);
  if (!lib.ok()) fail(2, lib.message());
  return std::move(*lib);
}

MediatorParams make_params(const BenchOptions& o, uint64_t seed) {
  MediatorParams p;
  p.seed = seed;
  if (!o.params_file.empty()) {
    if (Status s = load_mediator_params_json(o.params_file, &p); !s.ok()) fail(2, s.message());
  }
  auto mode = parse_mediator_mode(o.mode);
  if (!mode.ok()) fail(2, "--mode: expected naive, rate or apm, got '" + o.mode + "'");
  p.mode = *mode;
  for (const std::string& a : o.sets) {
    if (Status s = set_mediator_param(a, &p); !s.ok()) fail(2, s.message());
  }
  return p;
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

void run_bench(const BenchOptions& o) {
  if (o.sim != "social" && o.sim != "detour") {
    fail(2, "--sim: expected 'social' or 'detour', got '" + o.sim + "'");
  }
  const int frames = parse_number<int>(o.frames, "--frames", 1, kMaxFrames);
  const auto seed =
      parse_number<uint64_t>(o.seed, "--seed", 0, std::numeric_limits<uint64_t>::max());
  const int threads = parse_number<int>(o.threads, "--threads", 0, 256);
  Source src = make_source(o, threads, seed);
  CrowdSource& crowd = *src.crowd;
  if (frames <= kWarmupFrames) {
    std::fprintf(stderr, "gaitkeeper bench: only %d frames; the first %d are warm-up and untimed\n",
                 frames, kWarmupFrames);
  }

  const LocomotionLibrary library = load_library(o.clips);
  const MediatorParams params = make_params(o, seed);
  // The mediator and pose passes run on TBB: cap its workers at --threads (0 = all cores).
  std::optional<tbb::global_control> thread_cap;
  if (threads > 0) thread_cap.emplace(tbb::global_control::max_allowed_parallelism, threads);
  const size_t capacity = std::max<size_t>(crowd.capacity(), 1);
  Mediator mediator(library, params, capacity);
  PoseSynthesizer poses(library, capacity, /*make_palettes=*/true);
  MetricsRecorder metrics(library, static_cast<float>(kFrameTime_s), capacity,
                          static_cast<size_t>(frames));
  std::optional<JointDumpWriter> dump;
  if (!o.dump_joints.empty()) {
    auto opened = JointDumpWriter::open(o.dump_joints, *library.skeleton, split_names(o.dump_joint_names));
    if (!opened.ok()) fail(2, opened.message());
    dump.emplace(std::move(*opened));
  }

  StageTimer timer(kWarmupFrames, frames);
  CrowdReport crowd_stats;
  double live_sum = 0.0, speed_sum = 0.0;
  int64_t speed_samples = 0;
  const auto started = StageTimer::Clock::now();
  auto last_progress = started;
  for (int f = 0; f < frames; ++f) {
    const auto frame_start = StageTimer::Clock::now();
    const Status stepped = timer.time(Stage::kSim, f, [&] { return crowd.step(kFrameTime_s); });
    if (!stepped.ok()) fail(1, "frame " + std::to_string(f) + ": " + stepped.message());
    const AgentFrame frame = crowd.frame();
    const Status planned = timer.time(Stage::kMediator, f, [&] {
      GK_RETURN_IF_ERROR(mediator.plan(frame, static_cast<float>(kFrameTime_s)));
      return crowd.apply_feedback(mediator.feedback().view(frame.size()));
    });
    if (!planned.ok()) fail(1, "frame " + std::to_string(f) + ": " + planned.message());
    timer.time(Stage::kPose, f, [&] { poses.run(mediator, static_cast<float>(kFrameTime_s)); });
    timer.record(Stage::kTotal, f, StageTimer::ms_since(frame_start));

    // Measurement, not part of the timed pipeline.
    metrics.record(frame, mediator, poses);
    if (dump) {
      if (Status s = dump->write_frame(f, (f + 1) * kFrameTime_s, frame, mediator, poses); !s.ok()) {
        fail(1, s.message());
      }
    }
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
    const auto now = StageTimer::Clock::now();
    if (now - last_progress >= std::chrono::seconds(1)) {
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
  report.scenario = src.scenario_name;
  report.sim = crowd.name();
  report.agents = src.agents;
  report.frames = frames;
  report.frame_time_s = kFrameTime_s;
  report.threads = threads;
  report.seed = seed;
  for (size_t s = 0; s < kNumStages; ++s) report.timing_ms[s] = timer.stat(static_cast<Stage>(s));
  if (const auto& total = report.timing_ms[static_cast<size_t>(Stage::kTotal)];
      total && report.agents > 0) {
    report.us_per_agent = total->median_ms / static_cast<double>(report.agents) * 1000.0;
  }
  crowd_stats.mean_live_agents = live_sum / frames;
  crowd_stats.mean_speed_m_s = speed_samples ? speed_sum / static_cast<double>(speed_samples) : 0.0;
  if (src.social) {
    const SocialForceStats st = src.social->stats();
    crowd_stats.reached_goal = static_cast<int64_t>(st.reached_goal);
    crowd_stats.removed = static_cast<int64_t>(st.removed);
  }
  report.crowd = crowd_stats;
  report.mode = std::string(mediator_mode_name(params.mode));
  report.joints = library.skeleton->num_joints();
  report.clips = library.clip_names();
  report.metrics = metrics_to_json(metrics.finish(), library);
  if (dump) {
    if (Status s = dump->close(); !s.ok()) fail(1, s.message());
  }
  std::fputs(summary(report).c_str(), stdout);
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
  cmd->add_option(
         "--scenario", options->scenario,
         "Scenario name (data/scenarios, or $GAITKEEPER_SCENARIOS), a scenario .json file, "
         "or an ETH/UCY trajectory .txt file to replay")
      ->required();
  cmd->add_option("--sim", options->sim, "Crowd simulator: social (default) or detour");
  cmd->add_option("--agents", options->agents,
                  "Number of agents (default: the scenario's default_agents); the scenario's "
                  "geometry grows to keep its spawn density");
  cmd->add_option("--frames", options->frames,
                  "Frames to simulate (default 600; the first 30 "
                  "are warm-up and not timed)");
  cmd->add_option("--seed", options->seed, "Seed of the agents' spawn positions, speeds, goals");
  cmd->add_option("--threads", options->threads,
                  "Threads of the simulator (1 = single-threaded, default; 0 = all cores)");
  cmd->add_option("--trajectory-frame-time", options->trajectory_frame_time,
                  "Seconds between two samples of a replayed trajectory (default 0.4)");
  cmd->add_option("--json", options->json, "Write the report (METRICS.md schema) to this file");
  cmd->add_option("--mode", options->mode,
                  "naive (nearest clip at native rate), rate (speed-matched playback only) or "
                  "apm (the whole mediator; default)");
  cmd->add_option("--clips", options->clips,
                  "BVH/glTF/GLB files or folders forming the clip library (default: built-in)");
  cmd->add_option("--set", options->sets,
                  "Mediator parameter, e.g. --set torsion_limit_deg=40 (repeatable)");
  cmd->add_option("--params", options->params_file, "JSON file of mediator parameters");
  cmd->add_option("--dump-joints", options->dump_joints,
                  "Write world joint positions per frame and agent to this CSV");
  cmd->add_option("--dump-joint-names", options->dump_joint_names,
                  "Comma-separated joints to dump (default: left/right ankle and toe)");
  cmd->callback([options] { run_bench(*options); });
}

}  // namespace gk::app
