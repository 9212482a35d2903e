// `gaitkeeper analyze-clip FILE... [--scale S] [--roles F] [--plot F.png] [--json]`: loads
// BVH/glTF clips (or the built-in set, FILE = "builtin") and prints each clip's unit scale, the
// IK-style feet re-parented at load (if any), its analysis (speed, direction, cycle, foot
// contacts, the foot-slide floor of METRICS.md) and, for a take, its segments, strides, the loops
// cut from it and its problems; --plot draws them.

#include <cmath>
#include <cstdio>
#include <iostream>
#include <numbers>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "animation/analysis.h"
#include "animation/clip_library.h"
#include "animation/mirror.h"
#include "animation/procedural.h"
#include "animation/segmentation.h"
#include "app/clip_plot.h"
#include "app/commands.h"
#include "app/crowd_setup.h"
#include "mediator/locomotion_library.h"
#include "mediator/params.h"

namespace gk::app {
namespace {

struct AnalyzeOptions {
  std::vector<std::string> files;
  float scale = 0.0f;
  std::string roles;
  std::string plot;
  bool json = false;
};

nlohmann::json intervals_json(const std::vector<TimeInterval>& v) {
  nlohmann::json out = nlohmann::json::array();
  for (const TimeInterval& c : v) out.push_back({c.start_s, c.end_s});
  return out;
}

constexpr float kDeg = 180.0f / std::numbers::pi_v<float>;

// Strides and steps alike: span, the foot down first, speed, speed change, turn, direction.
nlohmann::json strides_json(const std::vector<Stride>& v) {
  nlohmann::json out = nlohmann::json::array();
  for (const Stride& st : v) {
    out.push_back({{"start_s", st.span.start_s},
                   {"end_s", st.span.end_s},
                   {"foot", st.side == 0 ? "left" : "right"},
                   {"speed_m_s", st.speed_m_s},
                   {"speed_change", st.speed_change},
                   {"turn_deg", st.turn_rad * kDeg},
                   {"direction_deg", st.direction_rad * kDeg},
                   {"steady", st.steady}});
  }
  return out;
}

nlohmann::json segmentation_json(const TakeSegmentation& seg) {
  const nlohmann::json strides = strides_json(seg.strides);
  nlohmann::json segments = nlohmann::json::array();
  for (const TakeSegment& s : seg.segments) {
    nlohmann::json j = {{"kind", segment_kind_name(s.kind)},
                        {"start_s", s.span.start_s},
                        {"end_s", s.span.end_s},
                        {"speed_m_s", s.speed_m_s},
                        {"speed_in_m_s", s.speed_in_m_s},
                        {"speed_out_m_s", s.speed_out_m_s},
                        {"turn_deg", s.turn_rad * kDeg}};
    if (s.cycle >= 0) j["cycle_stride"] = s.cycle;
    segments.push_back(std::move(j));
  }
  return {{"strides", strides},
          {"steps", strides_json(seg.steps)},
          {"segments", segments},
          {"cycles", seg.cycles},
          {"mirror_step", seg.mirror_step},
          {"problems", seg.problems}};
}

nlohmann::json analysis_json(const ClipSet& set, const Clip& clip, const ClipAnalysis& a,
                             const TakeSegmentation& seg) {
  return {
      {"take", segmentation_json(seg)},
      {"file", set.source},
      {"name", clip.name},
      {"frames", clip.num_frames},
      {"fps", clip.fps},
      {"duration_s", a.duration_s},
      {"joints", clip.num_joints},
      {"loops", clip.loops},
      {"scale", set.scale_m_per_unit},
      {"scale_reason", set.scale_reason},
      {"rig", set.rig_reason},
      {"up", set.up_reason},
      {"in_place", a.in_place},
      {"native_speed_m_s", a.native_speed_m_s},
      {"direction_deg", a.direction_rad * 180.0f / std::numbers::pi_v<float>},
      {"cycle", {{"start_s", a.cycle.start_s}, {"end_s", a.cycle.end_s}}},
      {"contacts",
       {{"left", intervals_json(a.contacts[0])}, {"right", intervals_json(a.contacts[1])}}},
      {"foot_slide_floor_cm_s", a.floor.mean_cm_s},
      {"foot_slide_floor_p95_cm_s", a.floor.p95_cm_s},
      {"skate_ratio_floor", a.floor.skate_ratio},
      {"foot_drift_floor_cm_per_step", a.floor.drift_cm_per_step},
  };
}

void print_text(const nlohmann::json& j) {
  std::printf("%s  [%s]\n", j["name"].get<std::string>().c_str(),
              j["file"].get<std::string>().c_str());
  std::printf("  frames %d @ %.3g fps, %.3f s, %d joints, scale %.6g m/unit (%s)%s\n",
              j["frames"].get<int>(), j["fps"].get<double>(), j["duration_s"].get<double>(),
              j["joints"].get<int>(), j["scale"].get<double>(),
              j["scale_reason"].get<std::string>().c_str(),
              j["loops"].get<bool>() ? ", loops" : "");
  if (!j["up"].get<std::string>().empty()) {
    std::printf("  up: %s\n", j["up"].get<std::string>().c_str());
  }
  if (!j["rig"].get<std::string>().empty()) {
    std::printf("  rig: %s\n", j["rig"].get<std::string>().c_str());
  }
  std::printf("  speed %.3f m/s%s, direction %.1f deg, cycle %.3f-%.3f s\n",
              j["native_speed_m_s"].get<double>(),
              j["in_place"].get<bool>() ? " (in place: from stance foot)" : "",
              j["direction_deg"].get<double>(), j["cycle"]["start_s"].get<double>(),
              j["cycle"]["end_s"].get<double>());
  for (const char* side : {"left", "right"}) {
    std::printf("  contacts %-5s:", side);
    for (const auto& c : j["contacts"][side]) {
      std::printf(" [%.3f, %.3f]", c[0].get<double>(), c[1].get<double>());
    }
    std::printf("\n");
  }
  std::printf("  foot-slide floor %.2f cm/s (p95 %.2f, skate ratio %.3f, drift %.2f cm/step)\n",
              j["foot_slide_floor_cm_s"].get<double>(),
              j["foot_slide_floor_p95_cm_s"].get<double>(), j["skate_ratio_floor"].get<double>(),
              j["foot_drift_floor_cm_per_step"].get<double>());
  const nlohmann::json& take = j["take"];
  const nlohmann::json& strides = take["strides"];
  for (const auto& s : take["segments"]) {
    std::printf("  segment %-10s %6.3f-%6.3f s  speed %.2f m/s (%.2f -> %.2f), turn %+.0f deg",
                s["kind"].get<std::string>().c_str(), s["start_s"].get<double>(),
                s["end_s"].get<double>(), s["speed_m_s"].get<double>(),
                s["speed_in_m_s"].get<double>(), s["speed_out_m_s"].get<double>(),
                s["turn_deg"].get<double>());
    if (s.contains("cycle_stride")) {
      const auto& st = strides[s["cycle_stride"].get<size_t>()];
      std::printf("  -> loop %.3f-%.3f s (%.2f m/s, direction %+.0f deg)",
                  st["start_s"].get<double>(), st["end_s"].get<double>(),
                  st["speed_m_s"].get<double>(), st["direction_deg"].get<double>());
    }
    std::printf("\n");
  }
  int steady = 0;
  for (const auto& st : strides) steady += st["steady"].get<bool>();
  std::printf("  strides %zu (%d steady)\n", strides.size(), steady);
  for (const auto& l : take["loops"]) {
    if (l.contains("step")) {
      std::printf("  loop of step %d and its mirror image: %d frames, %.3f m/s, direction %+.1f "
                  "deg, foot-slide floor %.2f cm/s\n",
                  l["step"].get<int>(), l["frames"].get<int>(), l["speed_m_s"].get<double>(),
                  l["direction_deg"].get<double>(), l["foot_slide_floor_cm_s"].get<double>());
    } else {
      std::printf("  loop of stride %d: %d frames, %.3f m/s, direction %+.1f deg, foot-slide "
                  "floor %.2f cm/s\n",
                  l["stride"].get<int>(), l["frames"].get<int>(), l["speed_m_s"].get<double>(),
                  l["direction_deg"].get<double>(), l["foot_slide_floor_cm_s"].get<double>());
    }
    for (const char* side : {"left", "right"}) {
      std::printf("    contacts %-5s:", side);
      for (const auto& c : l["contacts"][side]) {
        std::printf(" [%.3f, %.3f]", c[0].get<double>(), c[1].get<double>());
      }
      std::printf("\n");
    }
  }
  for (const auto& p : take["problems"]) std::printf("  problem: %s\n", p.get<std::string>().c_str());
}

// What a library of this file alone keeps (as `--clips FILE` builds it): its clips, the clips
// whose contacts it cannot trust, and what it leaves out.
void print_library(const ClipSet& set) {
  std::vector<ClipSet> one{set};
  Result<LocomotionLibrary> lib = build_locomotion_library(one);
  if (!lib.ok()) {
    std::printf("as a library (%s alone): refused: %s\n", set.source.c_str(),
                lib.message().c_str());
    return;
  }
  std::printf("as a library (%s alone): %zu clips:", set.source.c_str(), lib->clips.size());
  for (const std::string& c : lib->clip_names()) std::printf(" %s", c.c_str());
  std::printf("\n");
  // Captures below 60 fps are played from their upsampling (LocomotionClip::played).
  int upsampled = 0;
  float from_fps = 0.0f, to_fps = 0.0f;
  for (const LocomotionClip& c : lib->clips) {
    if (c.played.num_frames == 0) continue;
    ++upsampled;
    from_fps = c.clip.fps;
    to_fps = c.played.fps;
  }
  if (upsampled > 0) {
    std::printf(
        "  played at %g fps: %d clip(s) captured at %g fps, upsampled on a monotone cubic "
        "through their frames (analysis and contacts use the captured frames)\n",
        to_fps, upsampled, from_fps);
  }
  for (const std::string& d : describe_doubts(*lib)) std::printf("  doubtful: %s\n", d.c_str());
  for (const std::string& g : describe_gaps(*lib, MediatorParams{})) {
    std::printf("  gap: %s\n", g.c_str());
  }
  for (const std::string& l : describe_left_out(*lib)) std::printf("  left out: %s\n", l.c_str());
}

int run_analyze(const AnalyzeOptions& opt) {
  std::vector<std::string> files;
  bool builtin = false;
  std::vector<std::string> paths;
  for (const std::string& f : opt.files) {
    if (f == "builtin") {
      builtin = true;
    } else {
      paths.push_back(f);
    }
  }
  if (!paths.empty()) {
    Result<std::vector<std::string>> expanded = expand_clip_paths(paths);
    if (!expanded.ok()) {
      std::fprintf(stderr, "gaitkeeper analyze-clip: %s\n", expanded.message().c_str());
      return 1;
    }
    files = *expanded;
  }
  check_output_file_option("analyze-clip", opt.plot, "--plot");
  std::vector<ClipSet> sets;
  if (builtin) sets.push_back(make_builtin_clip_set());
  LoadOptions load;
  load.scale_m_per_unit = opt.scale;
  load.role_manifest = opt.roles;
  int failures = 0;
  for (const std::string& f : files) {
    Result<ClipSet> set = load_clip_file(f, load);
    if (!set.ok()) {
      std::fprintf(stderr, "gaitkeeper analyze-clip: %s\n", set.message().c_str());
      ++failures;
      continue;
    }
    sets.push_back(std::move(*set));
  }
  nlohmann::json all = nlohmann::json::array();
  struct Plotted {
    const Clip* clip;
    const Skeleton* skeleton;
    ClipAnalysis analysis;
    TakeSegmentation segmentation;
  };
  std::vector<Plotted> plotted;
  for (const ClipSet& set : sets) {
    if (!set.skeleton->has_locomotion_roles()) {
      std::fprintf(stderr,
                   "gaitkeeper analyze-clip: %s: skeleton lacks hips/leg joints the analysis needs "
                   "(no joint found for %s); %s\n",
                   set.source.c_str(), missing_locomotion_roles(*set.skeleton).c_str(),
                   role_manifest_hint().c_str());
      ++failures;
      continue;
    }
    for (const Clip& clip : set.clips) {
      const ClipAnalysis a = analyze_clip(clip, *set.skeleton);
      const TakeSegmentation seg = segment_take(clip, *set.skeleton, a);
      nlohmann::json j = analysis_json(set, clip, a, seg);
      // Each cycle cut out as a loop, analysed as the library will use it.
      nlohmann::json loops = nlohmann::json::array();
      // A loop as the library will use it: its length, its own speed, direction and foot-slide
      // floor, and the contacts it is played with.
      auto loop_json = [&](const char* key, int index, const Clip& loop,
                           const std::array<std::vector<TimeInterval>, 2>* contacts) {
        const ClipAnalysis la = analyze_clip(loop, *set.skeleton);
        const std::vector<TimeInterval>& left = contacts ? (*contacts)[0] : la.contacts[0];
        const std::vector<TimeInterval>& right = contacts ? (*contacts)[1] : la.contacts[1];
        nlohmann::json j = {{"frames", loop.num_frames},
                            {"speed_m_s", la.native_speed_m_s},
                            {"direction_deg", la.direction_rad * kDeg},
                            {"contacts",
                             {{"left", intervals_json(left)}, {"right", intervals_json(right)}}},
                            {"foot_slide_floor_cm_s", la.floor.mean_cm_s}};
        j[key] = index;
        return j;
      };
      if (seg.fallback_cycle && seg.mirror_step >= 0) {
        // The library's cycle: the steadiest step and its mirror image, with the step's contacts.
        const MirroredCycle mc =
            extract_mirrored_cycle(clip, *set.skeleton, a, seg.steps[seg.mirror_step],
                                   mirror_joint_map(*set.skeleton));
        loops.push_back(loop_json("step", seg.mirror_step, mc.loop, &mc.contacts));
      } else {
        for (int ci : seg.cycles) {
          const Stride& st = seg.strides[ci];
          const Clip loop = extract_cycle(clip, *set.skeleton, a, st);
          // A steady loop keeps the take's contacts of its stride (as the library plays it); a
          // fallback stride is analysed alone.
          const int first = std::clamp(static_cast<int>(std::lround(st.span.start_s * clip.fps)),
                                       0, clip.num_frames - 1);
          const auto contacts = stride_contacts(a, first, loop.num_frames, clip.fps);
          loops.push_back(loop_json("stride", ci, loop, seg.fallback_cycle ? nullptr : &contacts));
        }
      }
      j["take"]["loops"] = std::move(loops);
      if (!opt.plot.empty()) plotted.push_back({&clip, set.skeleton.get(), a, seg});
      if (!opt.json) print_text(j);
      all.push_back(std::move(j));
    }
    if (!opt.json) print_library(set);
  }
  if (opt.json) std::cout << all.dump(2) << "\n";
  if (!plotted.empty()) {
    std::vector<ClipPlotInput> in;
    for (const Plotted& p : plotted) in.push_back({p.clip, p.skeleton, &p.analysis, &p.segmentation});
    if (Status s = write_clip_plot(opt.plot, in); !s.ok()) {
      std::fprintf(stderr, "gaitkeeper analyze-clip: --plot %s\n", s.message().c_str());
      return 1;
    }
    if (!opt.json) std::printf("wrote %s (%zu clips)\n", opt.plot.c_str(), in.size());
  }
  return failures > 0 ? 1 : 0;
}

}  // namespace

void add_analyze_clip_command(CLI::App& app) {
  auto opt = std::make_shared<AnalyzeOptions>();
  CLI::App* cmd = app.add_subcommand(
      "analyze-clip",
      "Analyse clips: unit scale, up axis (a Z-up or X-up BVH stood up along +y), IK-style feet "
      "re-parented under the shins (and a BVH foot without a toe joint given one at its End "
      "Site), native speed and direction, gait cycle, foot contacts, foot-slide floor; a take's "
      "segments (idle, start, steady, turn, stop) and the loops cut from it (without a steady "
      "stride: its steadiest step and that step's mirror image); per file, what a library of it "
      "alone keeps, leaves out, doubts, and cannot play (gaps: no walk, no run, a walk and a run "
      "too far apart in speed).");
  cmd->add_option("files", opt->files,
                  "BVH, glTF or GLB files, folders of them, or 'builtin' for the built-in set")
      ->required();
  cmd->add_option("--scale", opt->scale,
                  "metres per file unit (default: detected from the leg length)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--roles", opt->roles,
                  "JSON role manifest for the files' skeletons, e.g. {\"roles\": {\"left_knee\": "
                  "\"Knee_L\", ...}} (default: roles detected from names and geometry)");
  cmd->add_option("--plot", opt->plot,
                  "write a PNG: per clip, each toe's height and speed over time with the contacts "
                  "shaded, and the take's segments (idle, start, steady, turn, stop) with the "
                  "loops cut out of it (white; yellow: the step whose mirror image completes the "
                  "loop)");
  cmd->add_flag("--json", opt->json, "print a JSON array instead of text");
  cmd->callback([opt] {
    const int code = run_analyze(*opt);
    if (code != 0) throw ExitRequest{code};
  });
}

}  // namespace gk::app
