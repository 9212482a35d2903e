#include "app/crowd_setup.h"

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <limits>

#include <CLI/CLI.hpp>

#include "animation/clip_library.h"
#include "animation/gait_generator.h"
#include "animation/procedural.h"
#include "app/commands.h"
#include "common/file_io.h"
#include "crowd/detour_crowd.h"
#include "crowd/restarting_crowd.h"
#include "crowd/social_forces.h"
#include "crowd/trajectory_replay.h"

namespace gk::app {

namespace {
std::string& last_failure_text() {
  static std::string text;
  return text;
}
}  // namespace

const std::string& last_failure() { return last_failure_text(); }

void fail(const std::string& command, int code, const std::string& message) {
  last_failure_text() = message;
  std::fprintf(stderr, "gaitkeeper %s: %s\n", command.c_str(), message.c_str());
  throw ExitRequest{code};
}

template <typename T>
T parse_number(const std::string& command, const std::string& text, const char* option, T lo,
               T hi) {
  T value{};
  const char* end = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (ec != std::errc() || ptr != end || !(value >= lo && value <= hi)) {
    fail(command, 2,
         std::string(option) + ": expected a number in [" + std::to_string(lo) + ", " +
             std::to_string(hi) + "], got '" + text + "'");
  }
  return value;
}
template int parse_number<int>(const std::string&, const std::string&, const char*, int, int);
template float parse_number<float>(const std::string&, const std::string&, const char*, float,
                                   float);
template uint64_t parse_number<uint64_t>(const std::string&, const std::string&, const char*,
                                         uint64_t, uint64_t);

int max_cli_agents() {
  return static_cast<int>(std::min<size_t>(SocialForceParams{}.max_agents, kMaxScenarioAgents));
}

void check_agent_id(const std::string& command, const CrowdSetup& setup, int64_t id,
                    const std::string& option) {
  const std::string what = option + " " + std::to_string(id) + ": ";
  if (!setup.replay_ids.empty()) {
    const auto& ids = setup.replay_ids;
    if (id >= 0 && id <= std::numeric_limits<uint32_t>::max() &&
        std::binary_search(ids.begin(), ids.end(), static_cast<uint32_t>(id))) {
      return;
    }
    fail(command, 2,
         what + "no pedestrian with that id in " + setup.scenario_name + " (its " +
             std::to_string(ids.size()) + " pedestrian ids run from " +
             std::to_string(ids.front()) + " to " + std::to_string(ids.back()) + ")");
  }
  if (setup.agents <= 0) fail(command, 2, what + "the crowd has no agents");
  if (id < 0 || id >= setup.agents) {
    fail(command, 2,
         what + "no agent with that id; expected an id in [0, " + std::to_string(setup.agents - 1) +
             "] (" + setup.scenario_name + " has " + std::to_string(setup.agents) + " agents)");
  }
}

void check_output_file_option(const std::string& command, const std::string& path,
                              const std::string& option) {
  if (path.empty()) return;
  if (Status s = check_output_file(path, option); !s.ok()) fail(command, 2, s.message());
}

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

void add_crowd_options(CLI::App* cmd, CrowdOptions* o, bool scenario_required) {
  CLI::Option* scenario = cmd->add_option(
      "--scenario", o->scenario,
      "Scenario name (data/scenarios, or $GAITKEEPER_SCENARIOS), a scenario .json file, "
      "or a trajectory file to replay (.txt, .csv, .tsv or .dat: ETH/UCY's frame id x y, the ETH "
      "authors' 8-column obsmat.txt, or CSV with a header naming frame or time, id, x and y)");
  if (scenario_required) scenario->required();
  cmd->add_option("--sim", o->sim, "Crowd simulator: social (default) or detour");
  cmd->add_option("--agents", o->agents,
                  "Number of agents (default: the scenario's default_agents); the scenario's "
                  "geometry grows to keep its spawn density");
  cmd->add_option("--seed", o->seed, "Seed of the agents' spawn positions, speeds, goals");
  cmd->add_option("--threads", o->threads,
                  "Worker threads of the simulator, mediator and pose passes (1 = single-threaded, "
                  "default; 0 = all cores)");
  cmd->add_option("--trajectory-frame-time", o->trajectory_frame_time,
                  "Seconds between two samples of a replayed trajectory (default 0.4; a CSV "
                  "whose header names a time column is replayed at its times)");
  cmd->add_option("--mode", o->mode,
                  "naive (nearest clip at native rate), rate (speed-matched playback only) or "
                  "apm (the whole mediator; default)");
  cmd->add_option("--clips", o->clips,
                  "BVH/glTF/GLB files or folders forming the clip library (default: built-in)");
  cmd->add_flag("--walk-clips-only", o->builtin_walks_only,
                "Without --clips: the built-in standing and forward walking clips only (no jog, "
                "run, strafe or backward clips): a small library whose legs cannot run or step "
                "sideways, where feedback has to act");
  cmd->add_option("--roles", o->roles,
                  "JSON role manifest for the --clips files' skeletons, e.g. {\"roles\": "
                  "{\"left_knee\": \"Knee_L\", ...}} (default: roles detected from names and "
                  "geometry)");
  cmd->add_option("--set", o->sets,
                  "Mediator parameter, e.g. --set torsion_limit_deg=40 (repeatable)");
  cmd->add_option("--params", o->params_file, "JSON file of mediator parameters");
}

namespace {

// The scenario's agents drawn for `seed` on the named simulator; out_social (optional) receives
// the social-forces simulator when that is the one built.
Result<std::unique_ptr<CrowdSource>> make_simulation(const Scenario& scenario, int num_agents,
                                                     uint64_t seed, const std::string& sim,
                                                     int threads, SocialForces** out_social) {
  auto agents = expand_agents(scenario, num_agents, seed);
  if (!agents.ok()) return agents.status();
  if (sim == "social") {
    SocialForceParams params;
    params.threads = threads;
    auto social = SocialForces::create(scenario, *agents, params);
    if (!social.ok()) return social.status();
    if (out_social) *out_social = social->get();
    return std::unique_ptr<CrowdSource>(std::move(social).value());
  }
  DetourParams params;
  params.seed = seed;
  auto detour = make_detour_crowd(scenario, *agents, params);
  if (!detour.ok()) return detour.status();
  return std::unique_ptr<CrowdSource>(std::move(detour).value());
}

}  // namespace

CrowdSetup make_crowd(const CrowdOptions& o, int threads, uint64_t seed, float body_radius_m) {
  const std::string& cmd = o.command;
  if (o.sim != "social" && o.sim != "detour") {
    fail(cmd, 2, "--sim: expected 'social' or 'detour', got '" + o.sim + "'");
  }
  CrowdSetup src;
  if (ends_with(o.scenario, ".vsp")) {
    fail(cmd, 2,
         o.scenario +
             ": UCY spline annotations (.vsp, pixels) are not read; replay the file in metres "
             "(frame id x y per line, e.g. ../shared/data/trajectories/zara1/crowds_zara01.txt)");
  }
  if (is_trajectory_file_name(o.scenario)) {
    if (o.sim != "social") {
      fail(cmd, 2, "--sim " + o.sim + " needs a scenario, not a trajectory file");
    }
    if (!o.agents.empty()) {
      std::fprintf(stderr, "gaitkeeper %s: --agents ignored for replay\n", cmd.c_str());
    }
    ReplayOptions replay;
    replay.loop = o.loop;
    replay.frame_time_s =
        parse_number<float>(cmd, o.trajectory_frame_time, "--trajectory-frame-time", 1e-3f, 60.0f);
    auto loaded = load_trajectory_replay(o.scenario, replay, &src.replay_ids);
    if (!loaded.ok()) fail(cmd, 2, loaded.message());
    src.crowd = std::move(loaded).value();
    src.scenario_name = o.scenario;
    src.agents = static_cast<int64_t>(src.crowd->capacity());
    return src;
  }
  auto loaded = load_scenario_by_name(o.scenario, scenario_dir());
  if (!loaded.ok()) fail(cmd, 2, loaded.message());
  // Checked before any setup work: expanding and building a crowd beyond the simulator's limit
  // takes many seconds only to be refused.
  const int num_agents = o.agents.empty()
                             ? loaded->default_agents
                             : parse_number<int>(cmd, o.agents, "--agents", 0, max_cli_agents());
  if (num_agents > max_cli_agents()) {
    fail(cmd, 2,
         loaded->source + ": default_agents " + std::to_string(num_agents) +
             " exceeds the limit of " + std::to_string(max_cli_agents()) +
             " agents; pass a smaller --agents");
  }
  apply_body_radius(&*loaded, body_radius_m);
  const Scenario scenario = scale_scenario(*loaded, num_agents);
  src.scenario_name = loaded->name;
  src.agents = num_agents;
  src.walls = scenario.walls;
  src.attention_targets = scenario.attention_targets;
  src.bounds_min = scenario.bounds_min;
  src.bounds_max = scenario.bounds_max;
  src.has_bounds = true;
  if (o.loop) {
    // Round k draws the scenario's agents with seed + k; a round begins when the last one left.
    const std::string sim_name = o.sim;
    auto rounds =
        RestartingCrowd::create([scenario, num_agents, seed, sim_name, threads](int round) {
          return make_simulation(scenario, num_agents, seed + static_cast<uint64_t>(round),
                                 sim_name, threads, nullptr);
        });
    if (!rounds.ok()) fail(cmd, 2, rounds.message());
    src.crowd = std::move(rounds).value();
    return src;
  }
  auto sim = make_simulation(scenario, num_agents, seed, o.sim, threads, &src.social);
  if (!sim.ok()) fail(cmd, 2, sim.message());
  src.crowd = std::move(sim).value();
  return src;
}

LocomotionLibrary load_library(const CrowdOptions& o) {
  std::vector<ClipSet> sets;
  if (!o.roles.empty() && o.clips.empty()) {
    fail(o.command, 2, "--roles " + o.roles + ": needs --clips (the built-in clips know their roles)");
  }
  if (o.builtin_walks_only && !o.clips.empty()) {
    fail(o.command, 2, "--walk-clips-only: applies to the built-in clips; drop --clips");
  }
  if (o.clips.empty()) {
    ClipSet builtin = make_builtin_clip_set();
    if (o.builtin_walks_only) {
      // builtin_gait_params() lists the clips in the set's order.
      const std::vector<GaitParams> gaits = builtin_gait_params();
      std::vector<Clip> walks;
      for (size_t i = 0; i < builtin.clips.size() && i < gaits.size(); ++i) {
        const GaitParams& g = gaits[i];
        const bool forward_walk =
            g.kind == GaitKind::kWalk && g.direction.z > 0.0f && !g.reverse_time;
        if (g.kind == GaitKind::kIdle || forward_walk) walks.push_back(std::move(builtin.clips[i]));
      }
      builtin.clips = std::move(walks);
    }
    sets.push_back(std::move(builtin));
  } else {
    auto files = expand_clip_paths(o.clips);
    if (!files.ok()) fail(o.command, 2, files.message());
    if (files->empty()) fail(o.command, 2, "--clips: no .bvh, .gltf or .glb file found");
    LoadOptions load;
    load.role_manifest = o.roles;
    for (const std::string& f : *files) {
      auto set = load_clip_file(f, load);
      if (!set.ok()) fail(o.command, 2, set.message());
      sets.push_back(std::move(*set));
    }
  }
  auto lib = build_locomotion_library(sets);
  if (!lib.ok()) fail(o.command, 2, lib.message());
  return std::move(*lib);
}

MediatorParams make_params(const CrowdOptions& o, uint64_t seed) {
  MediatorParams p;
  p.seed = seed;
  if (!o.params_file.empty()) {
    if (Status s = load_mediator_params_json(o.params_file, &p); !s.ok()) {
      fail(o.command, 2, s.message());
    }
  }
  auto mode = parse_mediator_mode(o.mode);
  if (!mode.ok()) fail(o.command, 2, "--mode: expected naive, rate or apm, got '" + o.mode + "'");
  p.mode = *mode;
  for (const std::string& a : o.sets) {
    if (Status s = set_mediator_param(a, &p); !s.ok()) fail(o.command, 2, s.message());
  }
  return p;
}

}  // namespace gk::app
