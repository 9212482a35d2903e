#pragma once
// The crowd options shared by `bench`, `render` and the demo (scenario, simulator, agents, seed,
// threads, mode, clips, mediator parameters) and the pieces built from them: the CrowdSource, the
// clip library and the mediator parameters. Bad options end the program through ExitRequest with
// "gaitkeeper <command>: <what was expected>" on stderr and exit code 2.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "crowd/crowd_source.h"
#include "crowd/scenario.h"
#include "mediator/locomotion_library.h"
#include "mediator/params.h"

namespace CLI {
class App;
}

namespace gk {
class SocialForces;
}

namespace gk::app {

inline constexpr double kFrameTime_s = 1.0 / 60.0;

struct CrowdOptions {
  std::string command = "bench";  // names the command in error messages
  std::string scenario;
  std::string sim = "social";
  std::string agents, seed = "1", threads = "1", trajectory_frame_time = "0.4";
  std::string mode = "apm";
  std::vector<std::string> clips;
  std::string roles;  // JSON role manifest applied to every clip file (empty: roles detected)
  // Without `clips`: the built-in standing and forward walking clips only (no jog, run, strafe or
  // backward clips), a small library whose legs cannot run or step sideways, so the mediator has
  // to feed back what they can deliver (the feedback lesson).
  bool builtin_walks_only = false;
  std::vector<std::string> sets;
  std::string params_file;
  // Run the crowd round and round: a replayed file starts over after its last sample, a scenario
  // starts a new round (seed + 1, ...) when every agent has left (bench --loop).
  bool loop = false;
};

// Registers the options above on a subcommand. `scenario_required`: bench needs one; render and
// the demo default to `o->scenario` as set by the caller.
void add_crowd_options(CLI::App* cmd, CrowdOptions* o, bool scenario_required);

// Prints "gaitkeeper <command>: message" and ends the command with `code`.
[[noreturn]] void fail(const std::string& command, int code, const std::string& message);
// The message of the last fail() (the demo shows it in its panel instead of exiting).
const std::string& last_failure();

// Numbers are parsed here rather than by CLI11 so that every bad value gets exit code 2 and a
// message that names the option and its range.
template <typename T>
T parse_number(const std::string& command, const std::string& text, const char* option, T lo, T hi);

struct CrowdSetup {
  std::unique_ptr<CrowdSource> crowd;
  // Set when the source is the social-forces simulator (not with `loop`, whose rounds each have
  // their own).
  SocialForces* social = nullptr;
  std::string scenario_name;
  int64_t agents = 0;
  // Geometry for the renderer and the camera; a replayed file has no walls and its bounds are
  // those of its tracks (estimated from the first frames by the session).
  std::vector<WallSegment> walls;
  std::vector<AttentionTarget> attention_targets;  // exhibits the agents look at (scaled)
  glm::vec2 bounds_min{-10.0f}, bounds_max{10.0f};
  bool has_bounds = false;
  // A replayed file's pedestrian ids (sorted); empty for a simulated crowd, whose ids are
  // 0 .. agents - 1.
  std::vector<uint32_t> replay_ids;
};

// The largest crowd the command line accepts (--agents, or a scenario's default_agents): the
// social-forces simulator's max_agents, so that a bigger crowd is refused before any setup work.
int max_cli_agents();

// `body_radius_m` > 0: the radius of the drawn body (body_radius of the clip library's skeleton),
// given to every scenario group whose file sets no "radius"; 0 keeps the scenario's radii.
CrowdSetup make_crowd(const CrowdOptions& o, int threads, uint64_t seed,
                      float body_radius_m = 0.0f);
// The clip library: the built-in set, or the given files and folders (one clip set per file).
LocomotionLibrary load_library(const CrowdOptions& o);
MediatorParams make_params(const CrowdOptions& o, uint64_t seed);

// Ends the command (exit 2) unless `id` names an agent that can appear in this crowd: an id in
// [0, agents) for a simulated scenario, a pedestrian id of the file for a replay. `option` names
// the option in the message ("--follow").
void check_agent_id(const std::string& command, const CrowdSetup& setup, int64_t id,
                    const std::string& option);

// Ends the command (exit 2) unless a file can be written at `path` (its folder exists and is
// writable; it is not a folder), so that a bad output path fails before the work starts. An empty
// path (option not given) passes.
void check_output_file_option(const std::string& command, const std::string& path,
                              const std::string& option);

bool ends_with(const std::string& s, const std::string& suffix);

}  // namespace gk::app
