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

StageTimer::StageTimer(int warmup_frames) : warmup_frames_(warmup_frames) {}

void StageTimer::record(Stage stage, int frame, double ms) {
  if (frame < warmup_frames_) return;
  samples_ms_[static_cast<size_t>(stage)].add(ms);
}

std::optional<TimingStat> StageTimer::stat(Stage stage) const {
  const QuantileSketch& v = samples_ms_[static_cast<size_t>(stage)];
  if (v.count() == 0) return std::nullopt;
  // Nearest-rank percentiles: an actual sample (to the sketch's 0.1%), no interpolation.
  return TimingStat{v.nearest_rank(0.5), v.nearest_rank(0.95)};
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
      {"takes", r.takes},
      {"left_out", r.left_out},
      {"doubtful_clips", r.doubtful},
      {"library_gaps", r.gaps},
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
  if (r.lod) {
    const LodReport& l = *r.lod;
    out["lod"] = {
        {"focus_m", {l.focus_x_m, l.focus_z_m}},
        {"distances_m", l.distances_m},
        {"hysteresis_m", l.hysteresis_m},
        {"periods_frames", {1, 2, 4, 8}},
        {"mean_agents_per_level", l.mean_agents_per_level},
        {"mean_agents_updated", l.mean_agents_updated},
        {"metrics_cover", "level 0 (full detail) agents only"},
    };
  } else {
    out["lod"] = nullptr;
  }
  if (r.transitions) {
    const BenchReport::Transitions& t = *r.transitions;
    out["transitions"] = {{"starts", t.starts},           {"starts_played", t.starts_played},
                          {"stops", t.stops},             {"stops_played", t.stops_played},
                          {"creep_stops", t.creep_stops}, {"start_clips", t.start_clips},
                          {"stop_clips", t.stop_clips}};
  } else {
    out["transitions"] = nullptr;
  }
  out["render"] = r.render ? *r.render : json(nullptr);
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
  if (r.lod) {
    const LodReport& l = *r.lod;
    s += "  lod: focus (" + fixed(l.focus_x_m, 1) + ", " + fixed(l.focus_z_m, 1) + ") m, levels at " +
         fixed(l.distances_m[0], 1) + " / " + fixed(l.distances_m[1], 1) + " / " +
         fixed(l.distances_m[2], 1) + " m; agents per level (every 1/2/4/8 frames) " +
         fixed(l.mean_agents_per_level[0], 0) + " / " + fixed(l.mean_agents_per_level[1], 0) +
         " / " + fixed(l.mean_agents_per_level[2], 0) + " / " +
         fixed(l.mean_agents_per_level[3], 0) + ", updated per frame " +
         fixed(l.mean_agents_updated, 0) + "; metrics: level 0 agents only\n";
  }
  if (r.transitions) {
    const BenchReport::Transitions& t = *r.transitions;
    s += "  transitions (library: " + std::to_string(t.start_clips) + " start, " +
         std::to_string(t.stop_clips) + " stop clips): starts " + std::to_string(t.starts) +
         ", played " + std::to_string(t.starts_played) + "; stops " + std::to_string(t.stops) +
         ", played " + std::to_string(t.stops_played) + "; rests from a creep (below 0.15 m/s) " +
         std::to_string(t.creep_stops) + "\n";
  }
  if (r.metrics) {
    const nlohmann::json& m = *r.metrics;
    auto num = [&](const nlohmann::json& v, int digits) {
      return v.is_number() ? fixed(v.get<double>(), digits) : std::string("n/a");
    };
    s += "  mode " + r.mode + ", " + std::to_string(r.joints.value_or(0)) + " joints, clips:";
    for (const std::string& c : r.clips) s += " " + c;
    for (const std::string& t : r.takes) s += "\n  take " + t;
    for (const std::string& l : r.left_out) s += "\n  left out: " + l;
    for (const std::string& d : r.doubtful) s += "\n  doubtful: " + d;
    for (const std::string& g : r.gaps) s += "\n  library gap: " + g;
    s += "\n  foot slide " + num(m["foot_slide_cm_s"], 2) + " cm/s (p95 " +
         num(m["foot_slide_p95_cm_s"], 2) + ", clips' floor " + num(m["foot_slide_floor_cm_s"], 2) +
         "), skate ratio " + num(m["skate_ratio"], 4) + ", drift " +
         num(m["foot_drift_cm_per_step"], 2) + " cm/step\n";
    s += "  torsion mean/p95/max " + num(m["torsion_deg"]["mean"], 1) + "/" +
         num(m["torsion_deg"]["p95"], 1) + "/" + num(m["torsion_deg"]["max"], 1) +
         " deg; facing error p95 " + num(m["facing_error_deg"]["p95"], 1) + " (within limit " +
         num(m["facing_error_deg"]["within_limit_p95"], 1) + ")" + " deg; heading error p95 " +
         num(m["heading_error_deg"]["p95"], 1) + " deg\n";
    s += "  root error mean/max " + num(m["root_error_cm"]["mean"], 2) + "/" +
         num(m["root_error_cm"]["max"], 2) + " cm; playback rate " +
         num(m["playback_rate"]["min"], 2) + ".." + num(m["playback_rate"]["max"], 2) +
         " (outside limits " + num(m["playback_rate"]["outside_limits"], 4) + "); pops " +
         num(m["pop_count"], 0) + "; feedback speed change " + num(m["feedback_speed_change"], 3) +
         "\n";
    const nlohmann::json& fl = m["feet_floor"];
    s += "  v2 feet (clips' floor in brackets): support slide " + num(m["support_slide_cm_s"], 2) +
         " cm/s [" + num(fl["support_slide_cm_s"], 2) + "], p95 " +
         num(m["support_slide_p95_cm_s"], 2) + ", support skate " +
         num(m["support_skate_ratio"], 4) + " [" + num(fl["support_skate_ratio"], 4) +
         "], gmd skate " + num(m["gmd_skate_ratio"], 4) + " [" + num(fl["gmd_skate_ratio"], 4) +
         "]\n";
    s += "  float " + num(m["float_ratio"], 4) + " [" + num(fl["float_ratio"], 4) +
         "], penetration p99/max " + num(m["penetration_cm"]["p99"], 2) + "/" +
         num(m["penetration_cm"]["max"], 2) + " cm [" + num(fl["penetration_cm"]["max"], 2) +
         "], limb pops " + num(m["limb_pop_rate"], 2) + " per agent-minute [" +
         num(fl["limb_pop_rate"], 2) + "]\n";
  }
  return s;
}

nlohmann::json metrics_to_json(const MetricsReport& m, const LocomotionLibrary& library) {
  using json = nlohmann::json;
  auto or_null = [](const Summary& s, double v) { return s.count ? json(v) : json(nullptr); };
  double floor_sum = 0.0;
  int floor_n = 0;
  json floors = json::object();
  for (const LocomotionClip& c : library.clips) {
    if (!c.gait) continue;
    floors[c.clip.name] = c.analysis.floor.mean_cm_s;
    floor_sum += c.analysis.floor.mean_cm_s;
    ++floor_n;
  }
  const bool slid = m.slide.num_samples > 0;
  // METRICS.md v2, with the library's own clips (their floor) beside.
  const Skeleton& sk = *library.skeleton;
  json floor_m = json::object(), accel_ref = json::object();
  for (int s = 0; s < 2; ++s) {
    const Side side = static_cast<Side>(s);
    floor_m[limb_joint_name(sk, LimbJoint::kToe, side)] = m.feet_reference.toe_floor_m[s];
    floor_m[limb_joint_name(sk, LimbJoint::kAnkle, side)] = m.feet_reference.ankle_floor_m[s];
    for (int j = 0; j < kNumLimbJoints; ++j) {
      accel_ref[limb_joint_name(sk, static_cast<LimbJoint>(j), side)] =
          m.feet_reference.accel_m_s2[j][s];
    }
  }
  auto feet_json = [](const ViewerFeetStats& v) {
    const bool sup = v.support_samples > 0, fr = v.agent_frames > 0;
    return json{
        {"support_slide_cm_s", sup ? json(v.support_slide_cm_s) : json(nullptr)},
        {"support_slide_p95_cm_s", sup ? json(v.support_slide_p95_cm_s) : json(nullptr)},
        {"support_skate_ratio", sup ? json(v.support_skate_ratio) : json(nullptr)},
        {"float_ratio", v.float_samples ? json(v.float_ratio) : json(nullptr)},
        {"penetration_cm",
         {{"p99", fr ? json(v.penetration_p99_cm) : json(nullptr)},
          {"max", fr ? json(v.penetration_max_cm) : json(nullptr)}}},
        {"penetration_ratio", fr ? json(v.penetration_ratio) : json(nullptr)},
        {"limb_pop_rate", fr ? json(v.limb_pop_rate) : json(nullptr)},
        {"gmd_skate_ratio", v.gmd_frames ? json(v.gmd_skate_ratio) : json(nullptr)},
        {"support_slide_samples", v.support_samples},
        {"limb_pops", v.limb_pops},
    };
  };
  json out = {
      {"foot_slide_cm_s", slid ? json(m.slide.mean_cm_s) : json(nullptr)},
      {"foot_slide_p95_cm_s", slid ? json(m.slide.p95_cm_s) : json(nullptr)},
      {"skate_ratio", slid ? json(m.slide.skate_ratio) : json(nullptr)},
      {"foot_drift_cm_per_step", slid ? json(m.slide.drift_cm_per_step) : json(nullptr)},
      {"foot_slide_samples", m.slide_samples},
      {"foot_slide_floor_cm_s", floor_n ? json(floor_sum / floor_n) : json(nullptr)},
      {"foot_slide_floor_per_clip_cm_s", floors},
      {"torsion_deg",
       {{"mean", or_null(m.torsion_deg, m.torsion_deg.mean)},
        {"p95", or_null(m.torsion_deg, m.torsion_deg.p95)},
        {"max", or_null(m.torsion_deg, m.torsion_deg.max)}}},
      {"facing_error_deg",
       {{"mean", or_null(m.facing_error_deg, m.facing_error_deg.mean)},
        {"p95", or_null(m.facing_error_deg, m.facing_error_deg.p95)},
        {"within_limit_mean",
         or_null(m.facing_error_within_limit_deg, m.facing_error_within_limit_deg.mean)},
        {"within_limit_p95",
         or_null(m.facing_error_within_limit_deg, m.facing_error_within_limit_deg.p95)}}},
      {"heading_error_deg",
       {{"mean", or_null(m.heading_error_deg, m.heading_error_deg.mean)},
        {"p95", or_null(m.heading_error_deg, m.heading_error_deg.p95)}}},
      {"root_error_cm",
       {{"mean", or_null(m.root_error_cm, m.root_error_cm.mean)},
        {"p95", or_null(m.root_error_cm, m.root_error_cm.p95)},
        {"max", or_null(m.root_error_cm, m.root_error_cm.max)}}},
      {"feedback_speed_change",
       m.feedback_speed_change ? json(*m.feedback_speed_change) : json(nullptr)},
      {"playback_rate",
       {{"min", or_null(m.playback_rate, m.playback_rate.min)},
        {"mean", or_null(m.playback_rate, m.playback_rate.mean)},
        {"max", or_null(m.playback_rate, m.playback_rate.max)},
        {"outside_limits", m.playback_outside_limits}}},
      {"pop_count", m.pop_count},
      {"max_root_jerk", m.max_root_jerk},
      {"floor_m", floor_m},
      {"limb_accel_reference_m_s2", accel_ref},
      {"feet_floor", feet_json(m.feet_floor)},
  };
  out.update(feet_json(m.feet));  // the v2 figures of the run, beside those of the clips
  return out;
}

}  // namespace gk::app
