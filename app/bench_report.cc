#include "app/bench_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>

namespace gk::app {
namespace {

using nlohmann::json;

template <typename T>
json or_null(const std::optional<T>& v) {
  return v ? json(*v) : json(nullptr);
}

std::string fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", digits, v);
  return buf;
}

}  // namespace

const char* stage_name(Stage stage) {
  static constexpr const char* kNames[kNumStages] = {"sim",    "mediator", "pose",
                                                     "upload", "render",   "total"};
  return kNames[static_cast<size_t>(stage)];
}

StageTimer::StageTimer(int warmup_frames, int expected_frames) : warmup_frames_(warmup_frames) {
  const auto timed = static_cast<size_t>(std::max(0, expected_frames - warmup_frames));
  for (auto& s : samples_ms_) s.reserve(timed);
}

void StageTimer::record(Stage stage, int frame, double ms) {
  if (frame < warmup_frames_) return;
  samples_ms_[static_cast<size_t>(stage)].push_back(ms);
}

std::optional<TimingStat> StageTimer::stat(Stage stage) const {
  std::vector<double> v = samples_ms_[static_cast<size_t>(stage)];
  if (v.empty()) return std::nullopt;
  std::sort(v.begin(), v.end());
  // Nearest-rank percentiles: an actual sample, no interpolation between frames.
  auto rank = [&](double q) {
    const auto k = static_cast<size_t>(std::ceil(q * static_cast<double>(v.size())));
    return v[std::clamp<size_t>(k, 1, v.size()) - 1];
  };
  return TimingStat{rank(0.5), rank(0.95)};
}

json to_json(const BenchReport& r) {
  json timing = json::object();
  for (size_t s = 0; s < kNumStages; ++s) {
    const auto& t = r.timing_ms[s];
    timing[stage_name(static_cast<Stage>(s))] =
        t ? json{{"median", t->median_ms}, {"p95", t->p95_ms}} : json(nullptr);
  }
  json out = {
      {"gaitkeeper_version", r.gaitkeeper_version},
      {"scenario", r.scenario},
      {"mode", r.mode},
      {"sim", r.sim},
      {"agents", r.agents},
      {"frames", r.frames},
      {"frame_time_s", r.frame_time_s},
      {"threads", r.threads},
      {"seed", r.seed},
      {"joints", or_null(r.joints)},
      {"clips", r.clips},
      {"timing_ms", timing},
      {"us_per_agent", or_null(r.us_per_agent)},
      {"metrics", r.metrics ? *r.metrics : json(nullptr)},
  };
  if (r.crowd) {
    const CrowdReport& c = *r.crowd;
    out["crowd"] = {
        {"mean_live_agents", c.mean_live_agents},
        {"max_live_agents", c.max_live_agents},
        {"mean_speed_m_s", c.mean_speed_m_s},
        {"max_speed_m_s", c.max_speed_m_s},
        {"reached_goal", or_null(c.reached_goal)},
        {"removed", or_null(c.removed)},
        {"min_pair_distance_m", or_null(c.min_pair_distance_m)},
        {"pair_distance_every_frames", c.pair_distance_every_frames},
    };
  } else {
    out["crowd"] = nullptr;
  }
  return out;
}

Status write_report_json(const BenchReport& report, const std::string& path) {
  std::ofstream out(path);
  if (!out) return Status::Error(path + ": cannot open for writing");
  out << to_json(report).dump(2) << "\n";
  out.close();
  if (!out) return Status::Error(path + ": write failed");
  return Status::Ok();
}

std::string summary(const BenchReport& r) {
  std::string s = "gaitkeeper bench: " + r.scenario + " with " + r.sim + ", " +
                  std::to_string(r.agents) + " agents, " + std::to_string(r.frames) +
                  " frames of " + fixed(r.frame_time_s * 1000.0, 2) + " ms, " +
                  std::to_string(r.threads) + " thread(s), seed " + std::to_string(r.seed) + "\n";
  bool any = false;
  for (size_t i = 0; i < kNumStages; ++i) {
    const auto& t = r.timing_ms[i];
    if (!t) continue;
    any = true;
    char line[128];
    std::snprintf(line, sizeof(line), "  %-8s median %8.3f ms   p95 %8.3f ms\n",
                  stage_name(static_cast<Stage>(i)), t->median_ms, t->p95_ms);
    s += line;
  }
  if (!any) s += "  (no timed frames: all frames were warm-up)\n";
  if (r.us_per_agent) s += "  us per agent per frame: " + fixed(*r.us_per_agent, 3) + "\n";
  if (r.crowd) {
    const CrowdReport& c = *r.crowd;
    s += "  crowd: live agents mean " + fixed(c.mean_live_agents, 1) + " max " +
         std::to_string(c.max_live_agents) + "; speed mean " + fixed(c.mean_speed_m_s, 2) +
         " max " + fixed(c.max_speed_m_s, 2) + " m/s";
    if (c.reached_goal) s += "; reached goal " + std::to_string(*c.reached_goal);
    if (c.removed) s += "; removed " + std::to_string(*c.removed);
    s += "; min pair distance " +
         (c.min_pair_distance_m ? fixed(*c.min_pair_distance_m, 3) + " m" : std::string("n/a")) +
         "\n";
  }
  return s;
}

}  // namespace gk::app
