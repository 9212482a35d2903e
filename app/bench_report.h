#pragma once
// The benchmark report of `gaitkeeper bench` (schema in docs METRICS.md, "Report schema"): stage
// timings per frame, the crowd's statistics and, once the mediator exists, the metrics. Values
// that were not measured are std::nullopt and serialise as JSON null, never as 0.

#include <array>
#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/status.h"
#include "mediator/locomotion_library.h"
#include "mediator/metrics.h"
#include "mediator/quantile_sketch.h"

namespace gk::app {

// The pipeline stages of METRICS.md, in report order. kTotal is the whole frame.
enum class Stage : uint8_t { kSim, kMediator, kPose, kUpload, kRender, kTotal };
inline constexpr size_t kNumStages = 6;
const char* stage_name(Stage stage);

struct TimingStat {
  double median_ms = 0.0;
  double p95_ms = 0.0;
};

// Collects one duration per stage per frame, ignoring the first `warmup_frames` frames (caches,
// page faults, thread start-up), into a fixed QuantileSketch per stage: memory does not grow with
// the frames and timing does not allocate. Median and p95 are within 0.1% of the exact ones.
class StageTimer {
 public:
  using Clock = std::chrono::steady_clock;
  explicit StageTimer(int warmup_frames);

  void record(Stage stage, int frame, double ms);
  // Runs fn() and records its duration for `stage` on `frame`; returns what fn returns.
  template <typename Fn>
  auto time(Stage stage, int frame, Fn&& fn) {
    const auto start = Clock::now();
    if constexpr (std::is_void_v<decltype(fn())>) {
      fn();
      record(stage, frame, ms_since(start));
    } else {
      auto result = fn();
      record(stage, frame, ms_since(start));
      return result;
    }
  }
  static double ms_since(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  }
  // Median and 95th percentile (nearest rank) of a stage; nullopt when it never ran after warm-up.
  std::optional<TimingStat> stat(Stage stage) const;
  int warmup_frames() const { return warmup_frames_; }

 private:
  int warmup_frames_;
  std::array<QuantileSketch, kNumStages> samples_ms_;
};

// Agent statistics over the run (all frames, warm-up included).
struct CrowdReport {
  double mean_live_agents = 0.0;
  int64_t max_live_agents = 0;
  double mean_speed_m_s = 0.0;  // over all agent-frames
  double max_speed_m_s = 0.0;
  std::optional<int64_t> reached_goal;  // agents that reached their final waypoint (social only)
  std::optional<int64_t> removed;       // agents removed at their goal (social only)
  // Smallest centre distance below kMinPairSearch_m found on the sampled frames; null if none.
  std::optional<double> min_pair_distance_m;
  int pair_distance_every_frames = 10;
};

// Level of detail of the run (pipeline/lod.h), when --lod was given.
struct LodReport {
  double focus_x_m = 0.0, focus_z_m = 0.0;
  std::array<double, 3> distances_m{};
  double hysteresis_m = 0.0;
  // Live agents at each level, mean over the timed frames (after warm-up).
  std::array<double, 4> mean_agents_per_level{};
  // Planned and posed agents per frame (due), mean over the timed frames.
  double mean_agents_updated = 0.0;
};

struct BenchReport {
  std::string gaitkeeper_version;
  std::string scenario;
  std::string mode = "apm";  // naive | rate | apm
  std::string sim;           // CrowdSource::name()
  int64_t agents = 0;
  int64_t frames = 0;
  double frame_time_s = 1.0 / 60.0;
  int threads = 1;
  uint64_t seed = 1;
  std::optional<int> joints;  // skeleton joint count once poses are synthesised
  std::vector<std::string> clips;
  // What the library made of takes with root motion: "take: segments; problems" (doubtful
  // analysis is reported, never silent).
  std::vector<std::string> takes;
  // Clips of the given files that are not in the library: "file: why: clip, clip, ...".
  std::vector<std::string> left_out;
  // Gait clips whose contact analysis is doubtful, and why: "clip: why; ...; played without foot
  // locks".
  std::vector<std::string> doubtful;
  // What the library's forward clips cannot play (describe_gaps): "no walking clip ...".
  std::vector<std::string> gaps;
  std::array<std::optional<TimingStat>, kNumStages> timing_ms;
  std::optional<double> us_per_agent;     // median total / agents * 1000
  std::optional<nlohmann::json> metrics;  // METRICS.md metrics, once the mediator exists
  std::optional<CrowdReport> crowd;
  std::optional<LodReport> lod;  // null without --lod
  // Starts and stops the mediator saw (an agent's speed rising past the stop speed after standing
  // a quarter second, or falling below it after moving as long), and how many played a start or
  // stop clip of the library (transitions; none without takes that have them).
  struct Transitions {
    int64_t starts = 0, starts_played = 0, stops = 0, stops_played = 0;
    int64_t creep_stops = 0;  // agents that came to rest from a creep (not counted in stops)
    int64_t start_clips = 0, stop_clips = 0;  // in the library
  };
  std::optional<Transitions> transitions;
  // --render: what was drawn (mesh levels, triangles, agents per level) and the render stage's
  // CPU time; null without --render.
  std::optional<nlohmann::json> render;
};

nlohmann::json to_json(const BenchReport& report);
// The "metrics" object of the METRICS.md schema, plus the clips' own foot-slide floors.
nlohmann::json metrics_to_json(const MetricsReport& m, const LocomotionLibrary& library);
Status write_report_json(const BenchReport& report, const std::string& path);
// Human-readable summary for stdout.
std::string summary(const BenchReport& report);

}  // namespace gk::app
