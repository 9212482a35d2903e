#include "pipeline/lod.h"

#include <cmath>
#include <cstdlib>

#include <glm/geometric.hpp>

namespace gk {

Status validate(const LodParams& p) {
  const auto& d = p.distances_m;
  if (!std::isfinite(p.focus.x) || !std::isfinite(p.focus.y)) {
    return Status::Error("LodParams::focus: expected finite coordinates");
  }
  for (size_t k = 0; k < d.size(); ++k) {
    if (!std::isfinite(d[k]) || d[k] < 0.0f || (k > 0 && d[k] < d[k - 1])) {
      return Status::Error(
          "LodParams::distances_m: expected three finite distances >= 0 in increasing order [m]");
    }
  }
  if (!(p.hysteresis_m >= 0.0f && p.hysteresis_m <= 100.0f)) {
    return Status::Error("LodParams::hysteresis_m: expected a value in [0, 100] m");
  }
  return Status::Ok();
}

Status parse_lod_distances(const std::string& text, const std::string& option, LodParams* params) {
  LodParams p = *params;
  size_t start = 0;
  for (size_t k = 0; k < p.distances_m.size(); ++k) {
    const size_t comma = text.find(',', start);
    const bool last = k + 1 == p.distances_m.size();
    if ((comma == std::string::npos) != last) {
      return Status::Error(option + ": expected three distances a,b,c [m], got '" + text + "'");
    }
    const std::string item = text.substr(start, last ? std::string::npos : comma - start);
    char* end = nullptr;
    const float v = std::strtof(item.c_str(), &end);
    if (item.empty() || end != item.c_str() + item.size()) {
      return Status::Error(option + ": '" + item + "' is not a number (expected a,b,c [m])");
    }
    p.distances_m[k] = v;
    start = comma + 1;
  }
  if (Status s = validate(p); !s.ok()) return Status::Error(option + ": " + s.message());
  *params = p;
  return Status::Ok();
}

LodPolicy::LodPolicy(size_t capacity)
    : level_(capacity, 0), in_use_(capacity, 0), offset_(capacity, 0), due_(capacity, 1), detail_(capacity, 0),
      full_(capacity, 1) {}

int LodPolicy::level_of(float d, const LodParams& p) {
  int level = 0;
  while (level < kNumLodLevels - 1 && d >= p.distances_m[level]) ++level;
  return level;
}

int LodPolicy::next_level(int level, float d, const LodParams& p) {
  while (level < kNumLodLevels - 1 && d > p.distances_m[level] + p.hysteresis_m) ++level;
  while (level > 0 && d < p.distances_m[level - 1] - p.hysteresis_m) --level;
  return level;
}

void LodPolicy::assign(const AnimationPlans& plans, const LodParams& p, int64_t frame) {
  counts_.fill(0);
  const size_t n = std::min(level_.size(), plans.agent_of_slot.size());
  for (size_t slot = 0; slot < n; ++slot) {
    const bool used = plans.agent_of_slot[slot] >= 0;
    int level = 0;
    if (p.enabled) {
      const float d = glm::length(plans.root_xz[slot] - p.focus);
      // NaN distances cannot happen (the mediator sanitises roots); an infinite one is level 3.
      level = in_use_[slot] && used ? next_level(level_[slot], d, p) : level_of(d, p);
    }
    const int64_t period = kLodPeriod[level];
    if (used && (!in_use_[slot] || level != level_[slot])) {
      offset_[slot] = static_cast<uint8_t>(next_offset_[level]++ % period);
    }
    level_[slot] = static_cast<uint8_t>(level);
    full_[slot] = level == 0;
    in_use_[slot] = used;
    due_[slot] = (offset_[slot] + frame) % period == 0;
    PoseDetail detail = level == 0   ? PoseDetail::kFull
                        : level == 1 ? PoseDetail::kNoFootLocks
                                     : PoseDetail::kLight;
    if (!due_[slot]) detail = PoseDetail::kHold;
    detail_[slot] = static_cast<uint8_t>(detail);
    if (used) ++counts_[level];
  }
}

}  // namespace gk
