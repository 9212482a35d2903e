#pragma once
// The exact reference of METRICS.md v2 ("what a viewer sees of the feet") for the streaming
// tests: every sample of whole stored tracks kept in vectors, percentiles by sorting. It is the
// computation ViewerFeetAccumulator made before it streamed (double precision, the same ties).

#include <algorithm>
#include <cmath>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "common/stats.h"
#include "mediator/viewer_metrics.h"

namespace gk::test {

struct ExactFeet {
  std::vector<float> support_cm_s, depth_cm;
  int64_t support_skates = 0, float_samples = 0, float_frames = 0, deep = 0, pops = 0;
  int64_t gmd_frames = 0, gmd_skates = 0;
  double seconds = 0.0;

  double support_mean() const {
    double sum = 0.0;
    for (float v : support_cm_s) sum += v;
    return support_cm_s.empty() ? 0.0 : sum / support_cm_s.size();
  }
  double support_skate_ratio() const {
    return support_cm_s.empty() ? 0.0 : static_cast<double>(support_skates) / support_cm_s.size();
  }
  double support_p95() const { return percentile(support_cm_s, 0.95); }
  double float_ratio() const {
    return float_samples ? static_cast<double>(float_frames) / float_samples : 0.0;
  }
  double depth_max() const {
    return depth_cm.empty() ? 0.0 : *std::max_element(depth_cm.begin(), depth_cm.end());
  }
  double depth_p99() const { return percentile(depth_cm, 0.99); }
  double penetration_ratio() const {
    return depth_cm.empty() ? 0.0 : static_cast<double>(deep) / depth_cm.size();
  }
  double pop_rate() const { return seconds > 0.0 ? pops / (seconds / 60.0) : 0.0; }
  double gmd_skate_ratio() const {
    return gmd_frames ? static_cast<double>(gmd_skates) / gmd_frames : 0.0;
  }
};

inline void add_exact_track(const LimbTrack& t, const FeetReference& ref, float dt,
                            ExactFeet* out) {
  using A = ViewerFeetAccumulator;
  const size_t n = t.root.size();
  if (n == 0) return;
  const double floor_toe[2] = {ref.toe_floor_m[0], ref.toe_floor_m[1]};
  const double floor_ankle[2] = {ref.ankle_floor_m[0], ref.ankle_floor_m[1]};
  const auto& toe = t.joint[static_cast<int>(LimbJoint::kToe)];
  const auto& ankle = t.joint[static_cast<int>(LimbJoint::kAnkle)];
  auto rel = [&](int s, size_t f) { return static_cast<double>(toe[s][f].y) - floor_toe[s]; };
  auto support = [&](size_t f) { return rel(1, f) < rel(0, f) ? 1 : 0; };
  auto near = [&](int s, size_t f) { return rel(s, f) <= A::kNearFloorM; };
  auto horizontal = [](const glm::vec3& a, const glm::vec3& b) {
    return std::hypot(static_cast<double>(a.x) - b.x, static_cast<double>(a.z) - b.z);
  };
  out->seconds += n * static_cast<double>(dt);
  for (size_t f = 0; f < n; ++f) {
    for (int s = 0; s < 2; ++s) {
      const double depth =
          std::max({0.0, floor_toe[s] - toe[s][f].y, floor_ankle[s] - ankle[s][f].y});
      out->depth_cm.push_back(static_cast<float>(100.0 * depth));
      if (depth > A::kPenetrationCountM) ++out->deep;
    }
    if (f == 0) continue;
    const int sup = support(f);
    if (sup == support(f - 1) && near(sup, f) && near(sup, f - 1)) {
      const double v = 100.0 * horizontal(toe[sup][f], toe[sup][f - 1]) / dt;
      out->support_cm_s.push_back(static_cast<float>(v));
      if (v > A::kSkateCmS) ++out->support_skates;
    }
    const double root_speed = std::hypot(static_cast<double>(t.root[f].x) - t.root[f - 1].x,
                                         static_cast<double>(t.root[f].y) - t.root[f - 1].y) /
                              dt;
    if (root_speed >= A::kFloatMinSpeed && root_speed <= A::kFloatMaxSpeed) {
      ++out->float_samples;
      if (!near(0, f) && !near(1, f)) ++out->float_frames;
    }
    if (f + 1 < n) {
      bool pop = false;
      for (int j = 0; j < kNumLimbJoints && !pop; ++j) {
        for (int s = 0; s < 2 && !pop; ++s) {
          const auto& p = t.joint[j][s];
          const glm::dvec3 d2 =
              glm::dvec3(p[f + 1]) - 2.0 * glm::dvec3(p[f]) + glm::dvec3(p[f - 1]);
          const double a = glm::length(d2) / (static_cast<double>(dt) * dt);
          pop = a > 2.0f * ref.accel_m_s2[j][s];
        }
      }
      if (pop) ++out->pops;
    }
  }
  const double span_s = (n - 1) * static_cast<double>(dt);
  const int m = static_cast<int>(std::floor(span_s * A::kGmdRateHz + 1e-6)) + 1;
  auto toe_at = [&](int s, int k) {
    const double x = k / static_cast<double>(A::kGmdRateHz) / dt;
    const size_t i = std::min(static_cast<size_t>(x + 1e-9), n - 1);
    const size_t i1 = std::min(i + 1, n - 1);
    const double u = std::clamp(x - static_cast<double>(i), 0.0, 1.0);
    return glm::dvec3(toe[s][i]) + (glm::dvec3(toe[s][i1]) - glm::dvec3(toe[s][i])) * u;
  };
  glm::dvec3 prev[2] = {toe_at(0, 0), toe_at(1, 0)};
  for (int k = 1; k < m; ++k) {
    bool skates = false;
    for (int s = 0; s < 2; ++s) {
      const glm::dvec3 cur = toe_at(s, k);
      const bool contact =
          cur.y - floor_toe[s] <= A::kNearFloorM && prev[s].y - floor_toe[s] <= A::kNearFloorM;
      if (contact &&
          std::hypot(cur.x - prev[s].x, cur.z - prev[s].z) * A::kGmdRateHz > A::kGmdSkateM_S) {
        skates = true;
      }
      prev[s] = cur;
    }
    ++out->gmd_frames;
    if (skates) ++out->gmd_skates;
  }
}

inline ExactFeet exact_viewer_feet(const std::vector<LimbTrack>& tracks, const FeetReference& ref,
                                   float dt) {
  ExactFeet out;
  for (const LimbTrack& t : tracks) add_exact_track(t, ref, dt, &out);
  return out;
}

}  // namespace gk::test
