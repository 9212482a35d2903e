#include "animation/analysis.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "animation/foot_metrics.h"
#include "animation/pose_jobs.h"

namespace gk {
namespace {

constexpr float kPlaybackRateHz = 60.0f;  // METRICS.md measures floors at 60 Hz
constexpr float kInPlaceSpeed = 0.1f;     // root speeds below this [m/s] count as in place

float wrap_angle(float a) {
  while (a > std::numbers::pi_v<float>) a -= 2.0f * std::numbers::pi_v<float>;
  while (a < -std::numbers::pi_v<float>) a += 2.0f * std::numbers::pi_v<float>;
  return a;
}

// World positions of the joints analysis needs, one row per frame.
struct Tracks {
  std::vector<glm::vec3> root, toe[2], ankle[2], hip[2];
};

Tracks track_clip_frames(const Clip& clip, const Skeleton& sk) {
  Tracks t;
  std::vector<glm::mat4> model(sk.num_joints());
  const int hips = std::max(sk.role(JointRole::kHips), 0);
  for (int f = 0; f < clip.num_frames; ++f) {
    LocalToModelJob fk{&sk,
                       {clip.frame_rotations(f), static_cast<size_t>(clip.num_joints)},
                       {clip.frame_translations(f), static_cast<size_t>(clip.num_joints)},
                       glm::mat4(1.0f),
                       model};
    fk.run();
    t.root.push_back(translation_of(model[hips]));
    for (int s = 0; s < 2; ++s) {
      const Side side = static_cast<Side>(s);
      t.toe[s].push_back(translation_of(model[sk.toe(side)]));
      t.ankle[s].push_back(translation_of(model[sk.ankle(side)]));
      t.hip[s].push_back(translation_of(model[sk.hip(side)]));
    }
  }
  return t;
}

// Fits y = a + b t to the lowest toe height of each ~0.4 s window (the ground under the stance
// foot), so contacts on a sloping or drifting capture floor are still found.
void fit_ground(const Tracks& tr, float fps, float* out_a, float* out_b) {
  const int n = static_cast<int>(tr.toe[0].size());
  const int window = std::max(2, static_cast<int>(0.4f * fps));
  std::vector<float> ts, ys;
  for (int start = 0; start < n; start += window) {
    float lowest = 1e9f;
    int at = start;
    for (int f = start; f < std::min(n, start + window); ++f) {
      for (int s = 0; s < 2; ++s) {
        if (tr.toe[s][f].y < lowest) {
          lowest = tr.toe[s][f].y;
          at = f;
        }
      }
    }
    ts.push_back(at / fps);
    ys.push_back(lowest);
  }
  *out_b = 0.0f;
  *out_a = *std::min_element(ys.begin(), ys.end());
  if (ts.size() < 3) return;
  double st = 0, sy = 0, stt = 0, sty = 0;
  for (size_t i = 0; i < ts.size(); ++i) {
    st += ts[i];
    sy += ys[i];
    stt += ts[i] * ts[i];
    sty += ts[i] * ys[i];
  }
  const double m = static_cast<double>(ts.size());
  const double den = m * stt - st * st;
  if (std::abs(den) < 1e-9) return;
  const double b = (m * sty - st * sy) / den;
  // Only a clear trend counts (a level floor fits to b ~ 0 anyway); keep the line under the minima.
  double a = (sy - b * st) / m;
  double worst = 0.0;
  for (size_t i = 0; i < ts.size(); ++i) worst = std::min(worst, ys[i] - (a + b * ts[i]));
  *out_a = static_cast<float>(a + worst);
  *out_b = static_cast<float>(b);
}

// Drops contact runs and gaps shorter than min_frames (capture jitter), in place.
void filter_runs(std::vector<uint8_t>& c, int min_frames, bool loops) {
  for (uint8_t value : {uint8_t{1}, uint8_t{0}}) {
    const size_t n = c.size();
    size_t i = 0;
    while (i < n) {
      if (c[i] != value) {
        ++i;
        continue;
      }
      size_t j = i;
      while (j < n && c[j] == value) ++j;
      const bool touches_edge = !loops && (i == 0 || j == n);
      if (static_cast<int>(j - i) < min_frames && !touches_edge) {
        std::fill(c.begin() + i, c.begin() + j, static_cast<uint8_t>(1 - value));
      }
      i = j;
    }
  }
}

std::vector<TimeInterval> to_intervals(const std::vector<uint8_t>& c, float fps, bool loops) {
  std::vector<TimeInterval> out;
  const size_t n = c.size();
  size_t i = 0;
  while (i < n) {
    if (!c[i]) {
      ++i;
      continue;
    }
    size_t j = i;
    while (j < n && c[j]) ++j;
    out.push_back({i / fps, (j - 1) / fps});
    i = j;
  }
  // A loop whose contact spans the wrap point is one interval that ends after the duration.
  if (loops && out.size() >= 2 && c.front() && c.back()) {
    out.back().end_s = out.front().end_s + n / fps;
    out.erase(out.begin());
  }
  return out;
}

// Phase markers: left contact starts at 0, right contact starts at 0.5; piecewise linear between.
std::vector<float> gait_phase(const ClipAnalysis& a, float period_s) {
  struct Marker {
    float t, phase;
  };
  std::vector<Marker> m;
  for (const TimeInterval& c : a.contacts[0]) m.push_back({c.start_s, 0.0f});
  for (const TimeInterval& c : a.contacts[1]) m.push_back({c.start_s, 0.5f});
  std::sort(m.begin(), m.end(), [](const Marker& x, const Marker& y) { return x.t < y.t; });
  std::vector<float> phase(a.num_frames, 0.0f);
  if (m.empty() || period_s <= 0.0f) return phase;
  // Unwrap marker phases so they increase by 0.5 per alternating step.
  std::vector<float> unwrapped(m.size());
  unwrapped[0] = m[0].phase;
  for (size_t k = 1; k < m.size(); ++k) {
    float d = m[k].phase - std::fmod(unwrapped[k - 1], 1.0f);
    if (d <= 0.0f) d += 1.0f;  // same foot twice in a row counts as a whole stride
    unwrapped[k] = unwrapped[k - 1] + d;
  }
  for (int f = 0; f < a.num_frames; ++f) {
    const float t = f / a.fps;
    float p;
    if (t <= m.front().t) {
      p = unwrapped.front() - (m.front().t - t) / period_s;
    } else if (t >= m.back().t) {
      p = unwrapped.back() + (t - m.back().t) / period_s;
    } else {
      size_t k = 0;
      while (m[k + 1].t < t) ++k;
      const float u = (t - m[k].t) / std::max(m[k + 1].t - m[k].t, 1e-6f);
      p = unwrapped[k] + u * (unwrapped[k + 1] - unwrapped[k]);
    }
    p = std::fmod(p, 1.0f);
    phase[f] = p < 0.0f ? p + 1.0f : p;
  }
  return phase;
}

}  // namespace

ClipAnalysis analyze_clip(const Clip& clip, const Skeleton& sk, const ContactThresholds& th) {
  ClipAnalysis a;
  a.name = clip.name;
  a.fps = clip.fps;
  a.num_frames = clip.num_frames;
  a.duration_s = clip.duration_s();
  a.cycle = {0.0f, a.duration_s};
  a.phase.assign(clip.num_frames, 0.0f);
  if (clip.num_frames < 2 || !sk.has_locomotion_roles()) return a;

  const Tracks tr = track_clip_frames(clip, sk);
  const int n = clip.num_frames;
  const float span_s = (n - 1) / clip.fps;

  // Facing: perpendicular to the right-hip -> left-hip vector (left is +x when facing +z).
  glm::vec3 facing(0.0f);
  for (int f = 0; f < n; ++f) {
    facing += glm::cross(tr.hip[0][f] - tr.hip[1][f], glm::vec3(0, 1, 0));
  }
  facing.y = 0.0f;
  facing = glm::length(facing) > 1e-6f ? glm::normalize(facing) : glm::vec3(0, 0, 1);

  // Root motion: mean horizontal velocity of the hips over the clip.
  glm::vec3 root_vel = (tr.root[n - 1] - tr.root[0]) / span_s;
  root_vel.y = 0.0f;
  a.in_place = glm::length(root_vel) < kInPlaceSpeed;

  // Contacts by height (METRICS.md thresholds), then velocity relative to the ground.
  glm::vec3 travel_vel = root_vel;
  std::vector<uint8_t> contact[2];
  fit_ground(tr, clip.fps, &a.ground_y0_m, &a.ground_slope_m_s);
  if (clip.loops) a.ground_slope_m_s = 0.0f;  // a loop returns to where it started
  for (int s = 0; s < 2; ++s) {
    std::vector<glm::vec3> toe = tr.toe[s], ankle = tr.ankle[s];
    for (int f = 0; f < n; ++f) {
      const float g = a.ground_slope_m_s * (f / clip.fps);
      toe[f].y -= g;
      ankle[f].y -= g;
    }
    contact[s].resize(n);
    measure_contacts(toe, ankle, contact[s]);
  }
  if (a.in_place) {
    // The stance foot of an in-place clip slides backward under the hips at the travel speed.
    glm::vec3 sum(0.0f);
    int count = 0;
    for (int s = 0; s < 2; ++s) {
      for (int f = 1; f < n; ++f) {
        if (!contact[s][f] || !contact[s][f - 1]) continue;
        glm::vec3 d = (tr.toe[s][f] - tr.root[f]) - (tr.toe[s][f - 1] - tr.root[f - 1]);
        d.y = 0.0f;
        sum += d * clip.fps;
        ++count;
      }
    }
    travel_vel = count > 0 ? -sum / static_cast<float>(count) : glm::vec3(0.0f);
    if (glm::length(travel_vel) < kInPlaceSpeed) travel_vel = glm::vec3(0.0f);
  }
  // Drop "contacts" where the toe moves fast over the ground (swing foot passing low).
  for (int s = 0; s < 2; ++s) {
    for (int f = 0; f < n; ++f) {
      const int g = f + 1 < n ? f + 1 : (clip.loops ? 0 : f - 1);
      if (g < 0 || g == f) continue;
      const float dir = g > f ? 1.0f : -1.0f;
      glm::vec3 d = (tr.toe[s][g] - tr.toe[s][f]) * dir * clip.fps;
      if (clip.loops && g == 0) d = glm::vec3(0.0f);  // skip the wrap's root jump
      if (a.in_place) d += travel_vel - (tr.root[g] - tr.root[f]) * dir * clip.fps;
      d.y = 0.0f;
      if (glm::length(d) > th.max_speed_m_s) contact[s][f] = 0;
    }
    filter_runs(contact[s],
                std::max(2, static_cast<int>(std::lround(th.min_duration_s * clip.fps))),
                clip.loops);
    a.contacts[s] = to_intervals(contact[s], clip.fps, clip.loops);
  }

  a.native_speed_m_s = glm::length(travel_vel);
  a.direction_rad =
      a.native_speed_m_s > 0.0f ? wrap_angle(heading_of(travel_vel) - heading_of(facing)) : 0.0f;

  // Gait cycle: the loop for looping clips; otherwise the first full stride of the left foot.
  float period = a.duration_s;
  if (!clip.loops && a.contacts[0].size() >= 2) {
    a.cycle = {a.contacts[0][0].start_s, a.contacts[0][1].start_s};
    period = a.cycle.end_s - a.cycle.start_s;
  } else if (!clip.loops && a.contacts[1].size() >= 2) {
    a.cycle = {a.contacts[1][0].start_s, a.contacts[1][1].start_s};
    period = a.cycle.end_s - a.cycle.start_s;
  }
  if (clip.loops && a.contacts[0].size() >= 2) period = a.duration_s / a.contacts[0].size();
  a.phase = gait_phase(a, period);

  // Floor: the clip played at 60 Hz with its own root motion (in-place clips with the inferred
  // travel velocity added), measured with the METRICS.md contact definition.
  const float dt = 1.0f / kPlaybackRateHz;
  const float play_s = clip.loops ? 2.0f * a.duration_s : span_s;
  const int steps = std::max(2, static_cast<int>(play_s / dt) + 1);
  // Root displacement per loop: the wrap moves the root from the last frame back to the first.
  glm::vec3 per_loop = (tr.root[n - 1] - tr.root[0]) * (static_cast<float>(n) / (n - 1));
  per_loop.y = 0.0f;
  std::vector<glm::quat> rot(sk.num_joints());
  std::vector<glm::vec3> trans(sk.num_joints());
  std::vector<glm::mat4> model(sk.num_joints());
  std::vector<glm::vec3> toe[2], ankle[2];
  for (int i = 0; i < steps; ++i) {
    const float t = i * dt;
    SampleClipJob{&clip, t, rot, trans}.run();
    glm::vec3 offset(0.0f);
    if (clip.loops) offset += per_loop * std::floor(t / a.duration_s);
    if (a.in_place) offset += travel_vel * t;
    glm::mat4 place(1.0f);
    place[3] = glm::vec4(offset, 1.0f);
    LocalToModelJob{&sk, rot, trans, place, model}.run();
    for (int s = 0; s < 2; ++s) {
      toe[s].push_back(translation_of(model[sk.toe(static_cast<Side>(s))]));
      ankle[s].push_back(translation_of(model[sk.ankle(static_cast<Side>(s))]));
    }
  }
  SlideAccumulator acc;
  for (int s = 0; s < 2; ++s) acc.add_track(toe[s], ankle[s], dt);
  a.floor = acc.finish();
  return a;
}

}  // namespace gk
