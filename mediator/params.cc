#include "mediator/params.h"

#include <charconv>
#include <cmath>
#include <sstream>

#include <nlohmann/json.hpp>

#include "common/file_io.h"
#include "common/json_text.h"
#include "common/text_snippet.h"

namespace gk {
namespace {

constexpr uint64_t kMaxParamFileBytes = 1u << 20;  // a parameter file is a few hundred bytes

using K = ParamInfo::Kind;
using P = MediatorParams;

constexpr ParamInfo kInfos[] = {
    {"velocity_halflife_s", "s", "smoothing of the simulator's velocity (removes zig-zag)", 0.01f,
     1.0f, K::kFloat, &P::velocity_halflife_s},
    {"theta_halflife_s", "s", "smoothing of the desired torso orientation", 0.01f, 1.0f, K::kFloat,
     &P::theta_halflife_s},
    {"torsion_limit_deg", "deg", "hard limit on the twist between pelvis and upper chest", 0.0f,
     90.0f, K::kFloat, &P::torsion_limit_deg},
    {"lower_turn_rate_deg_s", "deg/s",
     "fastest turn of the lower body toward the walking direction", 30.0f, 1440.0f, K::kFloat,
     &P::lower_turn_rate_deg_s},
    {"lower_turn_accel_deg_s2", "deg/s^2",
     "fastest change of the lower body's turn rate (it speeds up and slows down its turns)", 100.0f,
     1000000.0f, K::kFloat, &P::lower_turn_accel_deg_s2},
    {"blend_time_s", "s", "cross-fade time when the chosen clips change", 0.05f, 1.0f, K::kFloat,
     &P::blend_time_s},
    {"min_playback_rate", "x", "slowest clip playback relative to real time", 0.1f, 1.0f, K::kFloat,
     &P::min_playback_rate},
    {"max_playback_rate", "x", "fastest clip playback relative to real time", 1.0f, 3.0f, K::kFloat,
     &P::max_playback_rate},
    {"max_stride_warp", "x",
     "stride stretch the feedback allows beyond the fastest clip at the fastest rate", 0.0f, 0.5f,
     K::kFloat, &P::max_stride_warp},
    {"stop_speed_m_s", "m/s", "below this speed the agent stands (idle)", 0.0f, 0.5f, K::kFloat,
     &P::stop_speed_m_s},
    {"foot_locking", "on/off", "pin planted feet in world space with two-bone IK", 0.0f, 1.0f,
     K::kBool, nullptr, &P::foot_locking},
    {"lock_release_s", "s",
     "shortest time a released foot takes to rejoin the clip's swing (half of it: a landing's "
     "settling halflife; a quarter: a moving foot's glide to its pin)",
     0.02f, 0.5f, K::kFloat, &P::lock_release_s},
    {"max_leg_stretch", "x leg", "a pinned foot needing a longer leg raises its heel, then steps",
     0.9f, 1.0f, K::kFloat, &P::max_leg_stretch},
    {"idle_step_distance_m", "m", "standing: foot drift that makes the agent re-plant it", 0.02f,
     0.5f, K::kFloat, &P::idle_step_distance_m},
    {"idle_step_time_s", "s", "duration of a re-planting step while standing or turning", 0.1f,
     1.0f, K::kFloat, &P::idle_step_time_s},
    {"support_hold", "on/off",
     "hold the body within reach of a foot that carries it alone, fed back to the simulator "
     "(needs feedback; slows walking too)",
     0.0f, 1.0f, K::kBool, nullptr, &P::support_hold},
    {"quicken_steps", "on/off",
     "step faster (within the rate limits) while the body would leave the reach of a foot that "
     "carries it alone before the other foot lands",
     0.0f, 1.0f, K::kBool, nullptr, &P::quicken_steps},
    {"stand_through_jitter", "on/off",
     "recordings (no feedback): a standing agent walks only once p leaves where it stands by "
     "more than 3 times its jitter (a re-planting step at most)",
     0.0f, 1.0f, K::kBool, nullptr, &P::stand_through_jitter},
    {"feedback", "on/off", "send the p/v/theta the animation can deliver back to the simulator",
     0.0f, 1.0f, K::kBool, nullptr, &P::feedback},
    {"turn_feedback_deg", "deg",
     "forward clips only: feedback turns the simulator's velocity to within this of where the "
     "legs face (180 = off)",
     0.0f, 180.0f, K::kFloat, &P::turn_feedback_deg},
    {"max_accel_m_s2", "m/s2",
     "feedback holds the simulator's speed-up to what legs deliver (a start takes about a second)",
     0.1f, 20.0f, K::kFloat, &P::max_accel_m_s2},
    {"stride_variation", "x", "per-agent spread of stride length (crowd variety)", 0.0f, 0.2f,
     K::kFloat, &P::stride_variation},
};

Status set_value(const ParamInfo& info, double value, const std::string& where, P* params) {
  if (!std::isfinite(value) || value < info.min_value || value > info.max_value) {
    std::ostringstream os;
    os << where << ": expected " << info.min_value << ".." << info.max_value << " " << info.unit
       << ", got " << value;
    return Status::Error(os.str());
  }
  if (info.kind == K::kBool) {
    params->*info.b = value != 0.0;
  } else {
    params->*info.f = static_cast<float>(value);
  }
  return Status::Ok();
}

const ParamInfo* find_info(std::string_view name) {
  for (const ParamInfo& i : kInfos) {
    if (name == i.name) return &i;
  }
  return nullptr;
}

std::string known_names() {
  std::string s = "mode, seed";
  for (const ParamInfo& i : kInfos) s += std::string(", ") + i.name;
  return s;
}

}  // namespace

std::string_view mediator_mode_name(MediatorMode mode) {
  switch (mode) {
    case MediatorMode::kNaive:
      return "naive";
    case MediatorMode::kRate:
      return "rate";
    case MediatorMode::kApm:
      return "apm";
  }
  return "?";
}

Result<MediatorMode> parse_mediator_mode(std::string_view name) {
  if (name == "naive") return MediatorMode::kNaive;
  if (name == "rate") return MediatorMode::kRate;
  if (name == "apm") return MediatorMode::kApm;
  return Status::Error("mode: expected naive, rate or apm, got " + quoted_snippet(name));
}

std::span<const ParamInfo> mediator_param_infos() { return kInfos; }

Status set_mediator_param(std::string_view assignment, MediatorParams* params) {
  const size_t eq = assignment.find('=');
  if (eq == std::string_view::npos) {
    return Status::Error("--set '" + std::string(assignment) + "': expected name=value");
  }
  const std::string name(assignment.substr(0, eq));
  const std::string text(assignment.substr(eq + 1));
  if (name == "mode") {
    Result<MediatorMode> m = parse_mediator_mode(text);
    if (!m.ok()) return m.status();
    params->mode = *m;
    return Status::Ok();
  }
  if (name == "seed") {
    try {
      size_t used = 0;
      const unsigned long long v = std::stoull(text, &used);
      if (used != text.size()) throw std::invalid_argument("trailing");
      params->seed = v;
      return Status::Ok();
    } catch (const std::exception&) {
      return Status::Error("seed: expected a non-negative integer, got '" + text + "'");
    }
  }
  const ParamInfo* info = find_info(name);
  if (!info) {
    return Status::Error("--set " + name + ": unknown parameter (known: " + known_names() + ")");
  }
  double value = 0.0;
  if (info->kind == K::kBool && (text == "true" || text == "on" || text == "1")) {
    value = 1.0;
  } else if (info->kind == K::kBool && (text == "false" || text == "off" || text == "0")) {
    value = 0.0;
  } else {
    try {
      size_t used = 0;
      value = std::stod(text, &used);
      if (used != text.size()) throw std::invalid_argument("trailing");
    } catch (const std::exception&) {
      return Status::Error(name + ": expected a number in " + info->unit + ", got '" + text + "'");
    }
  }
  GK_RETURN_IF_ERROR(set_value(*info, value, name, params));
  return validate_mediator_params(*params);
}

Status load_mediator_params_json(const std::string& path, MediatorParams* params) {
  Result<std::string> text = read_file_bytes(path, kMaxParamFileBytes, "parameter file");
  if (!text.ok()) return text.status();
  return parse_mediator_params_json(*text, path, params);
}

Status parse_mediator_params_json(std::string_view json_text, const std::string& path,
                                  MediatorParams* params) {
  Result<nlohmann::json> parsed = parse_json_text(json_text, path);
  if (!parsed.ok()) return parsed.status();
  const nlohmann::json& j = *parsed;
  if (!j.is_object()) return Status::Error(path + ": expected a JSON object of parameters");
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string where = path + ": " + printable_snippet(it.key(), 80);
    if (it.key() == "mode") {
      if (!it->is_string())
        return Status::Error(where + ": expected \"naive\", \"rate\" or \"apm\"");
      Result<MediatorMode> m = parse_mediator_mode(it->get<std::string>());
      if (!m.ok()) return Status::Error(path + ": " + m.message());
      params->mode = *m;
      continue;
    }
    if (it.key() == "seed") {
      if (!it->is_number_unsigned())
        return Status::Error(where + ": expected a non-negative integer");
      params->seed = it->get<uint64_t>();
      continue;
    }
    const ParamInfo* info = find_info(it.key());
    if (!info) return Status::Error(where + ": unknown parameter (known: " + known_names() + ")");
    double value;
    if (info->kind == K::kBool && it->is_boolean()) {
      value = it->get<bool>() ? 1.0 : 0.0;
    } else if (it->is_number()) {
      value = it->get<double>();
    } else {
      return Status::Error(where + ": expected a " +
                           (info->kind == K::kBool ? std::string("boolean")
                                                   : "number in " + std::string(info->unit)));
    }
    GK_RETURN_IF_ERROR(set_value(*info, value, where, params));
  }
  const Status v = validate_mediator_params(*params);
  if (!v.ok()) return Status::Error(path + ": " + v.message());
  return Status::Ok();
}

Status validate_mediator_params(const MediatorParams& p) {
  if (p.min_playback_rate > p.max_playback_rate) {
    return Status::Error("min_playback_rate must not exceed max_playback_rate");
  }
  return Status::Ok();
}

std::string mediator_params_to_json(const MediatorParams& params) {
  nlohmann::ordered_json j = nlohmann::ordered_json::object();
  for (const ParamInfo& info : kInfos) {
    if (info.kind == K::kBool) {
      j[info.name] = params.*info.b;
      continue;
    }
    // Shortest decimal of the float ("0.05", not 0.05000000074505806); as a double it still
    // rounds back to the same float (double has more than twice float's precision).
    char text[32];
    const auto end = std::to_chars(text, text + sizeof(text), params.*info.f).ptr;
    j[info.name] = std::stod(std::string(text, end));
  }
  j["mode"] = std::string(mediator_mode_name(params.mode));
  j["seed"] = params.seed;
  return j.dump(2) + "\n";
}

}  // namespace gk
