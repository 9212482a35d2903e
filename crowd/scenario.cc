// Scenario JSON loading and validation. Every value is checked before use; errors carry the file
// and the JSON field path. The expansion into agents lives in scenario_expand.cc.
#include "crowd/scenario.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <initializer_list>
#include <limits>

#include <glm/common.hpp>
#include <nlohmann/json.hpp>

#include "common/file_io.h"
#include "common/json_text.h"
#include "common/text_snippet.h"

namespace gk {
namespace {

using nlohmann::json;

constexpr size_t kMaxFileBytes = 16u << 20;  // a scenario is a few kB; refuse anything absurd
constexpr size_t kMaxWalls = 100'000;
constexpr size_t kMaxGroups = 256;
constexpr size_t kMaxWaypoints = 1'000;
constexpr float kMaxCoordinate = 1.0e5f;  // [m]; beyond this float precision ruins the simulation

// Allowed interval of a number, and how to say it in an error message.
struct Range {
  float lo = -std::numeric_limits<float>::infinity();
  float hi = std::numeric_limits<float>::infinity();
  bool lo_open = false;
  const char* text = "a number";
  bool contains(double v) const {
    return std::isfinite(v) && (lo_open ? v > lo : v >= lo) && v <= hi;
  }
};
constexpr Range kAnyCoordinate{-kMaxCoordinate, kMaxCoordinate, false, "a number in [-1e5, 1e5]"};
constexpr Range kPositive{0.0f, kMaxCoordinate, true, "a number > 0"};
constexpr Range kUnit{0.0f, 1.0f, false, "a number in [0, 1]"};

class Parser {
 public:
  explicit Parser(std::string file) : file_(std::move(file)) {}

  Status error(const std::string& path, const std::string& what) const {
    // Keys come from the file: quote them printably.
    return Status::AtField(file_, printable_snippet(path, 200), what);
  }

  // Rejects keys that are not in `allowed`, so a typo does not silently fall back to a default.
  Status check_keys(const json& obj, const std::string& path,
                    std::initializer_list<const char*> allowed) const {
    if (!obj.is_object()) return error(path, "expected an object");
    for (const auto& item : obj.items()) {
      bool known = false;
      for (const char* key : allowed) known = known || item.key() == key;
      if (!known) return error(join(path, item.key()), "unknown field");
    }
    return Status::Ok();
  }

  Status number(const json& v, const std::string& path, const Range& range, float* out) const {
    if (!v.is_number() || !range.contains(v.get<double>())) {
      return error(path, std::string("expected ") + range.text);
    }
    *out = v.get<float>();
    return Status::Ok();
  }
  // Optional field: leaves *out (the default) when absent.
  Status number_field(const json& obj, const char* key, const std::string& path, const Range& range,
                      float* out) const {
    if (!obj.contains(key)) return Status::Ok();
    return number(obj[key], join(path, key), range, out);
  }
  Status bool_field(const json& obj, const char* key, const std::string& path, bool* out) const {
    if (!obj.contains(key)) return Status::Ok();
    if (!obj[key].is_boolean()) return error(join(path, key), "expected true or false");
    *out = obj[key].get<bool>();
    return Status::Ok();
  }
  Status string_field(const json& obj, const char* key, const std::string& path,
                      std::string* out) const {
    if (!obj.contains(key)) return Status::Ok();
    if (!obj[key].is_string()) return error(join(path, key), "expected a string");
    *out = obj[key].get<std::string>();
    return Status::Ok();
  }
  Status vec2(const json& v, const std::string& path, glm::vec2* out) const {
    if (!v.is_array() || v.size() != 2 || !v[0].is_number() || !v[1].is_number() ||
        !kAnyCoordinate.contains(v[0].get<double>()) ||
        !kAnyCoordinate.contains(v[1].get<double>())) {
      return error(path, "expected [x, z]: two numbers in [-1e5, 1e5]");
    }
    *out = glm::vec2(v[0].get<float>(), v[1].get<float>());
    return Status::Ok();
  }
  Status points(const json& v, const std::string& path, size_t min_count,
                std::vector<glm::vec2>* out) const {
    if (!v.is_array() || v.size() < min_count || v.size() > kMaxWalls) {
      return error(path,
                   "expected an array of at least " + std::to_string(min_count) + " points [x, z]");
    }
    out->resize(v.size());
    for (size_t i = 0; i < v.size(); ++i)
      GK_RETURN_IF_ERROR(vec2(v[i], index(path, i), &(*out)[i]));
    return Status::Ok();
  }

  static std::string join(const std::string& path, const std::string& key) {
    return path.empty() ? key : path + "." + key;
  }
  static std::string index(const std::string& path, size_t i) {
    return path + "[" + std::to_string(i) + "]";
  }

  // {"point": [x, z]} | {"rect": {"min": [x, z], "max": [x, z]}} |
  // {"circle": {"center": [x, z], "radius": r}} | {"ring": {...same...}}
  Status area(const json& v, const std::string& path, bool allow_point, bool allow_ring,
              Area* out) const {
    GK_RETURN_IF_ERROR(check_keys(v, path, {"point", "rect", "circle", "ring"}));
    if (v.size() != 1) return error(path, "expected exactly one of point, rect, circle, ring");
    const std::string key = v.begin().key();
    const json& body = v.begin().value();
    const std::string sub = join(path, key);
    if (key == "point") {
      if (!allow_point) return error(sub, "a point is not allowed here (use rect or circle)");
      out->shape = Area::Shape::kPoint;
      return vec2(body, sub, &out->center);
    }
    if (key == "rect") {
      out->shape = Area::Shape::kRect;
      GK_RETURN_IF_ERROR(check_keys(body, sub, {"min", "max"}));
      if (!body.contains("min") || !body.contains("max")) return error(sub, "expected min and max");
      GK_RETURN_IF_ERROR(vec2(body["min"], join(sub, "min"), &out->min));
      GK_RETURN_IF_ERROR(vec2(body["max"], join(sub, "max"), &out->max));
      if (!(out->min.x < out->max.x && out->min.y < out->max.y)) {
        return error(join(sub, "max"), "expected max > min in both coordinates");
      }
      out->center = 0.5f * (out->min + out->max);
      return Status::Ok();
    }
    if (key == "ring" && !allow_ring) return error(sub, "a ring is only allowed as a spawn area");
    out->shape = key == "ring" ? Area::Shape::kRing : Area::Shape::kCircle;
    GK_RETURN_IF_ERROR(check_keys(body, sub, {"center", "radius"}));
    if (!body.contains("center") || !body.contains("radius")) {
      return error(sub, "expected center and radius");
    }
    GK_RETURN_IF_ERROR(vec2(body["center"], join(sub, "center"), &out->center));
    return number(body["radius"], join(sub, "radius"), kPositive, &out->radius_m);
  }

  Status walls(const json& v, const std::string& path, std::vector<WallSegment>* out) const {
    if (!v.is_array() || v.size() > kMaxWalls) return error(path, "expected an array of walls");
    for (size_t i = 0; i < v.size(); ++i) {
      const std::string p = index(path, i);
      const json& w = v[i];
      GK_RETURN_IF_ERROR(check_keys(w, p, {"segment", "polyline", "closed", "rect"}));
      std::vector<glm::vec2> pts;
      bool closed = false;
      if (w.contains("segment")) {
        GK_RETURN_IF_ERROR(points(w["segment"], join(p, "segment"), 2, &pts));
        if (pts.size() != 2) return error(join(p, "segment"), "expected exactly two points");
      } else if (w.contains("polyline")) {
        GK_RETURN_IF_ERROR(points(w["polyline"], join(p, "polyline"), 2, &pts));
        GK_RETURN_IF_ERROR(bool_field(w, "closed", p, &closed));
      } else if (w.contains("rect")) {
        Area a;
        GK_RETURN_IF_ERROR(area(json{{"rect", w["rect"]}}, p, false, false, &a));
        pts = {a.min, {a.max.x, a.min.y}, a.max, {a.min.x, a.max.y}};
        closed = true;
      } else {
        return error(p, "expected one of segment, polyline, rect");
      }
      if (w.size() != 1 && !(w.contains("polyline") && w.size() == 2 && w.contains("closed"))) {
        return error(p, "expected exactly one of segment, polyline, rect");
      }
      const size_t num_segments = closed ? pts.size() : pts.size() - 1;
      for (size_t s = 0; s < num_segments; ++s) {
        const WallSegment seg{pts[s], pts[(s + 1) % pts.size()]};
        if (seg.a == seg.b) return error(p, "segment " + std::to_string(s) + " has zero length");
        out->push_back(seg);
      }
      if (out->size() > kMaxWalls) return error(path, "more than 100000 wall segments");
    }
    return Status::Ok();
  }

  Status speed(const json& v, const std::string& path, SpeedDistribution* out) const {
    GK_RETURN_IF_ERROR(check_keys(v, path, {"mean", "sd", "min", "max"}));
    constexpr Range kSpeed{0.0f, 10.0f, true, "a number in (0, 10]"};
    constexpr Range kSd{0.0f, 10.0f, false, "a number in [0, 10]"};
    GK_RETURN_IF_ERROR(number_field(v, "mean", path, kSpeed, &out->mean_m_s));
    GK_RETURN_IF_ERROR(number_field(v, "sd", path, kSd, &out->sd_m_s));
    GK_RETURN_IF_ERROR(number_field(v, "min", path, kSpeed, &out->min_m_s));
    GK_RETURN_IF_ERROR(number_field(v, "max", path, kSpeed, &out->max_m_s));
    if (out->min_m_s > out->mean_m_s) return error(join(path, "min"), "expected min <= mean");
    if (out->max_m_s < out->mean_m_s) return error(join(path, "max"), "expected max >= mean");
    return Status::Ok();
  }

  Status group(const json& v, const std::string& path, AgentGroup* out) const {
    GK_RETURN_IF_ERROR(check_keys(v, path,
                                  {"name", "fraction", "spawn", "waypoints", "random_goals", "loop",
                                   "at_goal", "speed", "radius", "goal_radius", "attention"}));
    GK_RETURN_IF_ERROR(string_field(v, "name", path, &out->name));
    GK_RETURN_IF_ERROR(number_field(v, "fraction", path, kPositive, &out->fraction));
    if (!v.contains("spawn")) return error(join(path, "spawn"), "missing (expected an area)");
    GK_RETURN_IF_ERROR(area(v["spawn"], join(path, "spawn"), false, true, &out->spawn));
    if (v.contains("waypoints")) {
      const std::string wp = join(path, "waypoints");
      const json& arr = v["waypoints"];
      if (!arr.is_array() || arr.size() > kMaxWaypoints) {
        return error(wp, "expected an array of at most 1000 waypoints");
      }
      for (size_t i = 0; i < arr.size(); ++i) {
        WaypointSpec spec;
        if (arr[i].is_object() && arr[i].contains("antipode")) {
          GK_RETURN_IF_ERROR(check_keys(arr[i], index(wp, i), {"antipode"}));
          spec.kind = WaypointSpec::Kind::kAntipode;
          GK_RETURN_IF_ERROR(
              vec2(arr[i]["antipode"], index(wp, i) + ".antipode", &spec.area.center));
        } else {
          GK_RETURN_IF_ERROR(area(arr[i], index(wp, i), true, false, &spec.area));
        }
        out->waypoints.push_back(spec);
      }
    }
    if (v.contains("random_goals")) {
      const std::string rg = join(path, "random_goals");
      const json& r = v["random_goals"];
      GK_RETURN_IF_ERROR(check_keys(r, rg, {"area", "count"}));
      if (!r.contains("area") || !r.contains("count")) return error(rg, "expected area and count");
      GK_RETURN_IF_ERROR(area(r["area"], join(rg, "area"), false, false, &out->random_goal_area));
      if (!r["count"].is_number_integer() || r["count"].get<int64_t>() < 1 ||
          r["count"].get<int64_t>() > static_cast<int64_t>(kMaxWaypoints)) {
        return error(join(rg, "count"), "expected an integer in [1, 1000]");
      }
      out->random_goal_count = r["count"].get<int>();
    }
    if (out->waypoints.empty() && out->random_goal_count == 0) {
      return error(join(path, "waypoints"), "expected at least one waypoint or random_goals");
    }
    GK_RETURN_IF_ERROR(bool_field(v, "loop", path, &out->loop));
    if (v.contains("at_goal")) {
      const json& g = v["at_goal"];
      if (!g.is_string() || (g != "stop" && g != "remove")) {
        return error(join(path, "at_goal"), "expected \"stop\" or \"remove\"");
      }
      out->remove_at_goal = g == "remove";
    }
    if (v.contains("speed"))
      GK_RETURN_IF_ERROR(speed(v["speed"], join(path, "speed"), &out->speed));
    GK_RETURN_IF_ERROR(
        number_field(v, "radius", path, {0.0f, 1.0f, true, "a number in (0, 1]"}, &out->radius_m));
    out->radius_given = v.contains("radius");
    GK_RETURN_IF_ERROR(number_field(v, "goal_radius", path, kPositive, &out->goal_radius_m));
    return number_field(v, "attention", path, kUnit, &out->attention);
  }

  Status scenario(const json& root, Scenario* out) const {
    GK_RETURN_IF_ERROR(check_keys(root, "",
                                  {"name", "description", "default_agents", "max_spawn_density",
                                   "bounds", "walls", "attention_targets", "groups"}));
    GK_RETURN_IF_ERROR(string_field(root, "name", "", &out->name));
    GK_RETURN_IF_ERROR(string_field(root, "description", "", &out->description));
    if (root.contains("default_agents")) {
      const json& n = root["default_agents"];
      if (!n.is_number_integer() || n.get<int64_t>() < 0 || n.get<int64_t>() > kMaxScenarioAgents) {
        return error("default_agents", "expected an integer in [0, 500000]");
      }
      out->default_agents = n.get<int>();
    }
    GK_RETURN_IF_ERROR(number_field(root, "max_spawn_density", "",
                                    {0.0f, 4.0f, true, "a number in (0, 4]"},
                                    &out->max_spawn_density));
    if (root.contains("walls")) GK_RETURN_IF_ERROR(walls(root["walls"], "walls", &out->walls));
    if (root.contains("attention_targets")) {
      const json& arr = root["attention_targets"];
      if (!arr.is_array() || arr.size() > kMaxWaypoints) {
        return error("attention_targets", "expected an array of at most 1000 targets");
      }
      for (size_t i = 0; i < arr.size(); ++i) {
        const std::string p = index("attention_targets", i);
        AttentionTarget t;
        GK_RETURN_IF_ERROR(check_keys(arr[i], p, {"position", "radius"}));
        if (!arr[i].contains("position")) return error(join(p, "position"), "missing");
        GK_RETURN_IF_ERROR(vec2(arr[i]["position"], join(p, "position"), &t.position));
        GK_RETURN_IF_ERROR(number_field(arr[i], "radius", p, kPositive, &t.radius_m));
        out->attention_targets.push_back(t);
      }
    }
    if (!root.contains("groups") || !root["groups"].is_array() || root["groups"].empty() ||
        root["groups"].size() > kMaxGroups) {
      return error("groups", "expected an array of 1 to 256 agent groups");
    }
    for (size_t i = 0; i < root["groups"].size(); ++i) {
      out->groups.emplace_back();
      GK_RETURN_IF_ERROR(group(root["groups"][i], index("groups", i), &out->groups.back()));
    }
    if (root.contains("bounds")) {
      Area b;
      GK_RETURN_IF_ERROR(area(json{{"rect", root["bounds"]}}, "bounds", false, false, &b));
      out->bounds_min = b.min;
      out->bounds_max = b.max;
    } else {
      default_bounds(out);
    }
    return Status::Ok();
  }

 private:
  // Everything the file mentions plus a 2 m margin.
  static void default_bounds(Scenario* s) {
    glm::vec2 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
    auto add = [&](glm::vec2 p) {
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    };
    auto add_area = [&](const Area& a) {
      if (a.shape == Area::Shape::kRect) {
        add(a.min);
        add(a.max);
      } else {
        add(a.center - glm::vec2(a.radius_m));
        add(a.center + glm::vec2(a.radius_m));
      }
    };
    for (const WallSegment& w : s->walls) {
      add(w.a);
      add(w.b);
    }
    for (const AgentGroup& g : s->groups) {
      add_area(g.spawn);
      for (const WaypointSpec& w : g.waypoints) add_area(w.area);
      if (g.random_goal_count > 0) add_area(g.random_goal_area);
    }
    s->bounds_min = lo - glm::vec2(2.0f);
    s->bounds_max = hi + glm::vec2(2.0f);
  }

  std::string file_;
};

}  // namespace

Result<Scenario> parse_scenario(std::string_view json_text, const std::string& source_name) {
  const Parser parser(source_name);
  Result<json> root = parse_json_text(json_text, source_name, /*ignore_comments=*/true);
  if (!root.ok()) return root.status();
  Scenario scenario;
  scenario.source = source_name;
  GK_RETURN_IF_ERROR(parser.scenario(*root, &scenario));
  if (scenario.name.empty()) scenario.name = std::filesystem::path(source_name).stem().string();
  return scenario;
}

Result<Scenario> load_scenario(const std::string& path) {
  Result<std::string> text = read_file_bytes(path, kMaxFileBytes, "scenario file");
  if (!text.ok()) return text.status();
  return parse_scenario(*text, path);
}

Result<Scenario> load_scenario_by_name(const std::string& name_or_path,
                                       const std::string& scenarios_dir) {
  namespace fs = std::filesystem;
  const bool is_path =
      name_or_path.find('/') != std::string::npos || fs::path(name_or_path).extension() == ".json";
  if (is_path) return load_scenario(name_or_path);
  const fs::path file = fs::path(scenarios_dir) / (name_or_path + ".json");
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(scenarios_dir, ec)) {
      if (entry.path().extension() == ".json") names.push_back(entry.path().stem().string());
    }
    std::sort(names.begin(), names.end());
    std::string list;
    for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
    return Status::Error("unknown scenario '" + name_or_path + "' (no " + file.string() +
                         "); available: " + (list.empty() ? "none" : list));
  }
  return load_scenario(file.string());
}

std::string scenario_dir() {
  if (const char* env = std::getenv("GAITKEEPER_SCENARIOS"); env && *env) return env;
  return GK_SCENARIO_DIR;
}

}  // namespace gk
