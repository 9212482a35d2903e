#include "animation/analysis.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "animation/foot_metrics.h"
#include "animation/pose_jobs.h"
#include "common/stats.h"

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
  // Two points no rig has a joint for. The toe tip: the toe joint's bone tip (its End Site, else
  // its first child), the last point to leave the ground as the foot rolls off. The heel: a point
  // fixed to the ankle where the floor was under it when the foot stood flat (the take's frame
  // with the ball lowest), the first to touch at a heel strike while the ankle still rolls
  // forward. Without a tip, the ball stands in for it.
  std::vector<glm::vec3> tip[2], heel[2];
  std::vector<glm::mat4> ankle_m[2];  // the ankles' model transforms (for the heels)
};

Tracks track_clip_frames(const Clip& clip, const Skeleton& sk) {
  Tracks t;
  std::vector<glm::mat4> model(sk.num_joints());
  const int hips = std::max(sk.role(JointRole::kHips), 0);
  std::vector<glm::mat4> ankle_m[2];
  glm::vec3 tip_local[2] = {glm::vec3(0.0f), glm::vec3(0.0f)};
  for (int s = 0; s < 2; ++s) {
    const int toe = sk.toe(static_cast<Side>(s));
    if (toe >= 0 && static_cast<size_t>(toe) < sk.end_sites.size()) tip_local[s] = sk.end_sites[toe];
    if (glm::length(tip_local[s]) < 1e-6f) {
      for (int j = toe + 1; j < sk.num_joints(); ++j) {
        if (sk.parents[j] == toe) {
          tip_local[s] = sk.rest_translations[j];
          break;
        }
      }
    }
  }
  for (int f = 0; f < clip.num_frames; ++f) {
    clip_frame_model(clip, sk, f, model);
    t.root.push_back(translation_of(model[hips]));
    for (int s = 0; s < 2; ++s) {
      const Side side = static_cast<Side>(s);
      t.toe[s].push_back(translation_of(model[sk.toe(side)]));
      t.ankle[s].push_back(translation_of(model[sk.ankle(side)]));
      t.hip[s].push_back(translation_of(model[sk.hip(side)]));
      t.tip[s].push_back(glm::vec3(model[sk.toe(side)] * glm::vec4(tip_local[s], 1.0f)));
      ankle_m[s].push_back(model[sk.ankle(side)]);
    }
  }
  for (int s = 0; s < 2; ++s) t.ankle_m[s] = std::move(ankle_m[s]);
  return t;
}

// The heel points: fixed to the ankle where the floor was under it on the frame its ball is lowest
// over the fitted ground (y = ground_y0 + slope * t): the lowest ball over the whole take would be
// wherever a sloping or tilted floor is lowest, flat foot or not.
void add_heels(Tracks* t, float fps, float ground_y0, float slope) {
  for (int s = 0; s < 2; ++s) {
    const int n = static_cast<int>(t->toe[s].size());
    auto above = [&](int f) { return t->toe[s][f].y - (ground_y0 + slope * (f / fps)); };
    int flat = 0;
    for (int f = 1; f < n; ++f) {
      if (above(f) < above(flat)) flat = f;
    }
    const glm::vec3 a = t->ankle[s][flat];
    const float floor_y = std::min(t->toe[s][flat].y, t->tip[s][flat].y);
    const glm::vec3 heel_local = glm::vec3(glm::inverse(t->ankle_m[s][flat]) *
                                           glm::vec4(a.x, std::min(floor_y, a.y), a.z, 1.0f));
    t->heel[s].clear();
    for (int f = 0; f < n; ++f) {
      t->heel[s].push_back(glm::vec3(t->ankle_m[s][f] * glm::vec4(heel_local, 1.0f)));
    }
  }
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
      // A run cut by a take's first or last frame may be the end of a longer one: kept when it
      // lasts two frames (one frame there is a foot passing low, or arriving as the take ends).
      const bool touches_edge = !loops && (i == 0 || j == n);
      const int need = touches_edge ? std::min(2, min_frames) : min_frames;
      if (static_cast<int>(j - i) < need) {
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
std::vector<float> gait_phase(const ClipAnalysis& a, float period_s, bool loops) {
  struct Marker {
    float t, phase;
  };
  std::vector<Marker> m;
  // A contact cut by a take's first frame did not start there: it marks no phase.
  const float first = loops ? -1.0f : 0.5f / a.fps;
  for (const TimeInterval& c : a.contacts[0]) {
    if (c.start_s > first) m.push_back({c.start_s, 0.0f});
  }
  for (const TimeInterval& c : a.contacts[1]) {
    if (c.start_s > first) m.push_back({c.start_s, 0.5f});
  }
  std::vector<float> phase(a.num_frames, 0.0f);
  if (m.empty() || period_s <= 0.0f) return phase;
  if (loops && a.duration_s > 0.0f) {
    // A loop's contacts come round again after its duration: its frames near the seam lie
    // between a marker before it and one after, as everywhere else. (Carried past the last
    // marker at the cycle's mean rate instead, the phase at the loop's end did not meet the
    // phase at its start wherever the two steps of the stride differ in length, and a clip
    // played by phase skipped or repeated frames at every wrap.)
    const size_t own = m.size();
    for (size_t k = 0; k < own; ++k) {
      m.push_back({m[k].t - a.duration_s, m[k].phase});
      m.push_back({m[k].t + a.duration_s, m[k].phase});
    }
  }
  std::sort(m.begin(), m.end(), [](const Marker& x, const Marker& y) { return x.t < y.t; });
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

// Inside a contact, a joint slower than this times the still speed is still planted (jitter).
constexpr float kContactHysteresis = 1.5f;

// The capture's own position jitter [m, per axis and frame], from the feet's horizontal second
// differences: a planted foot has none in a clean capture and most frames of a gait plant one
// of the two feet, so their median is jitter (sigma_from_second_differences).
float capture_jitter_m(const Tracks& tr) {
  std::vector<float> d2;
  for (int s = 0; s < 2; ++s) {
    for (const std::vector<glm::vec3>* p : {&tr.toe[s], &tr.ankle[s]}) {
      for (size_t f = 1; f + 1 < p->size(); ++f) {
        const glm::vec3 d = (*p)[f + 1] - 2.0f * (*p)[f] + (*p)[f - 1];
        d2.push_back(std::hypot(d.x, d.z));
      }
    }
  }
  return sigma_from_second_differences(std::move(d2));
}

// Frames on either side for velocities: about 1/60 s (one frame up to 90 fps), longer where the
// capture's jitter would make a still foot's speed reach `still_m_s` (noise at most a third of
// it: a least-squares slope over k + 1 frames has a noise of jitter * fps / sqrt(k (k+1) (k+2) /
// 12)), up to 1/15 s. A clean capture keeps its contact edges to the frame; a jittery one at a
// high frame rate averages as many frames as its jitter needs.
int velocity_half_window(float fps, float jitter_m, float still_m_s) {
  const int k0 = std::max(1, static_cast<int>(std::lround(fps / 60.0f)));
  const int k_max = std::max(k0, static_cast<int>(std::lround(fps / 15.0f)));
  for (int k = k0; k < k_max; ++k) {
    const float sum_sq = static_cast<float>(k * (k + 1) * (k + 2)) / 12.0f;
    if (3.0f * jitter_m * fps / std::sqrt(sum_sq) <= still_m_s) return k;
  }
  return k_max;
}

// Horizontal velocity of track p at frame f relative to the clip's hips (in_place) or the world:
// the least-squares slope over frames f - back .. f + fwd (+-k by default; wrapping a loop, whose
// root jumps back by per_loop). Over two frames that is their difference; over more it averages
// every frame's jitter rather than the two ends' alone.
glm::vec3 track_velocity(const std::vector<glm::vec3>& p, const Tracks& tr, int f, int k,
                         const Clip& clip, bool relative_to_root, int back = -1, int fwd = -1) {
  if (back < 0) back = k;
  if (fwd < 0) fwd = k;
  const int n = static_cast<int>(p.size());
  const glm::vec3 per_loop = (tr.root[n - 1] - tr.root[0]) * (static_cast<float>(n) / (n - 1));
  auto at = [&](int i) {
    glm::vec3 shift(0.0f);
    if (clip.loops) {
      const int wraps = i < 0 ? -((-i + n - 1) / n) : i / n;
      i -= wraps * n;
      shift = per_loop * static_cast<float>(wraps);
    } else {
      i = std::clamp(i, 0, n - 1);
    }
    glm::vec3 q = p[i] + shift;
    if (relative_to_root) q -= tr.root[i] + shift;
    return q;
  };
  const int lo = clip.loops ? f - back : std::max(0, f - back);
  const int hi = clip.loops ? f + fwd : std::min(n - 1, f + fwd);
  if (hi == lo) return glm::vec3(0.0f);
  const float mid = 0.5f * static_cast<float>(lo + hi);
  glm::vec3 num(0.0f);
  float den = 0.0f;
  for (int i = lo; i <= hi; ++i) {
    const float t = static_cast<float>(i) - mid;
    num += t * at(i);
    den += t * t;
  }
  glm::vec3 v = num * (clip.fps / den);
  v.y = 0.0f;
  return v;
}

// Travel velocity of an in-place clip: its stance foot slides backward under the hips at it. The
// stance foot is the lower one on most frames of any gait, so the median over frames of the lower
// foot's velocity (relative to the hips) is minus the travel velocity.
glm::vec3 in_place_travel(const Tracks& tr, const Clip& clip) {
  const int n = static_cast<int>(tr.root.size());
  const int k = velocity_half_window(clip.fps, 0.0f, 0.0f);  // a median: jitter averages out
  std::vector<float> vx, vz;
  // "Lower" against each foot's own lowest heights (a rig's two toe joints need not be level).
  float low[2];
  for (int s = 0; s < 2; ++s) {
    std::vector<float> h(n);
    for (int f = 0; f < n; ++f) h[f] = tr.toe[s][f].y;
    low[s] = percentile(h, 0.05f);
  }
  for (int f = 0; f < n; ++f) {
    const int s = tr.toe[1][f].y - low[1] < tr.toe[0][f].y - low[0] ? 1 : 0;
    const glm::vec3 v = track_velocity(tr.toe[s], tr, f, k, clip, true);
    vx.push_back(v.x);
    vz.push_back(v.z);
  }
  glm::vec3 travel(-percentile(vx, 0.5), 0.0f, -percentile(vz, 0.5));
  if (glm::length(travel) < kInPlaceSpeed) travel = glm::vec3(0.0f);
  return travel;
}

// How fast the hips move along their path [m/s]: sampled every half second (about a step, so the
// pelvis's sway within a step is left out), path length over time; 0 for a take shorter than
// that.
float path_speed(const std::vector<glm::vec3>& root, float fps) {
  const int n = static_cast<int>(root.size());
  const int step = std::max(1, static_cast<int>(std::lround(0.5f * fps)));
  float len = 0.0f;
  int f = 0;
  for (; f + step < n; f += step) {
    glm::vec3 d = root[f + step] - root[f];
    d.y = 0.0f;
    len += glm::length(d);
  }
  return f > 0 ? len * fps / f : 0.0f;
}

// One foot's contact frames: its heel, ankle, ball or toe tip nearly still over the ground and low.
// "Still" is relative to the clip's own travel speed (a planted point moves slower than half the
// body's speed; a swing foot moves about twice it); "low" is relative to the point's own lowest
// heights over the fitted ground (a gate well below the swing's height, never the judge alone).
// `k`: frames on either side for velocities (velocity_half_window). `floor`: per frame, the floor
// under this foot (stance_floor), or null for the fitted line.
void detect_contacts(const Tracks& tr, int s, const Clip& clip, const ClipAnalysis& a,
                     const glm::vec3& travel_vel, const ContactThresholds& th, int k,
                     const std::vector<float>* floor, std::vector<uint8_t>* out) {
  const int n = static_cast<int>(tr.root.size());
  const float still = still_speed_m_s(glm::length(travel_vel), th);
  out->assign(n, 0);
  const std::vector<glm::vec3>* joints[4] = {&tr.toe[s], &tr.ankle[s], &tr.heel[s], &tr.tip[s]};
  std::vector<uint8_t> down[4];
  for (int j = 0; j < 4; ++j) {
    const std::vector<glm::vec3>& p = *joints[j];
    std::vector<float> h(n), speed(n);
    std::vector<uint8_t> backward(n, 0);
    const float travel = glm::length(travel_vel);
    for (int f = 0; f < n; ++f) {
      h[f] = p[f].y - (floor ? (*floor)[f] : a.ground_y0_m + a.ground_slope_m_s * (f / clip.fps));
      glm::vec3 v = track_velocity(p, tr, f, k, clip, a.in_place);
      // In place, a stance foot is carried backward under the hips and a swing foot forward: the
      // sign holds even for keyframed clips whose stance foot is not ground-consistent.
      if (a.in_place && travel > 0.0f) backward[f] = glm::dot(v, travel_vel) < 0.0f;
      // Still on either side: a foot that has just arrived stays from this frame on (its step in
      // was still fast), a foot about to leave came to this frame slowly; a centred difference
      // would blur a frame off each end of every contact.
      glm::vec3 vb = track_velocity(p, tr, f, k, clip, a.in_place, k, 0);
      glm::vec3 vf = track_velocity(p, tr, f, k, clip, a.in_place, 0, k);
      if (a.in_place) {
        vb += travel_vel;
        vf += travel_vel;
      }
      speed[f] = std::min(glm::length(vb), glm::length(vf));
    }
    const float low = percentile(h, 0.05f), high = percentile(h, 0.95f);
    const float gate = low + std::max(th.min_height_gate_m, th.height_gate_fraction * (high - low));
    // A run of frames that only jitter put above `still` (slower than kContactHysteresis times
    // it, and low) between two down frames is down too: a planted foot's jitter does not break
    // its contact in two. The contact's ends stay where they are.
    std::vector<uint8_t>& d = down[j];
    d.assign(n, 0);
    std::vector<uint8_t> weak(n, 0);
    for (int f = 0; f < n; ++f) {
      const bool low = h[f] <= gate;
      d[f] = low && (speed[f] < still || backward[f]);
      weak[f] = low && speed[f] < kContactHysteresis * still;
    }
    for (int f = 1; f < n; ++f) {
      if (d[f] || !d[f - 1]) continue;
      int e = f;
      while (e < n && !d[e] && weak[e]) ++e;
      if (e < n && d[e]) std::fill(d.begin() + f, d.begin() + e, uint8_t{1});
      f = e;
    }
  }
  for (int f = 0; f < n; ++f) (*out)[f] = down[0][f] || down[1][f] || down[2][f] || down[3][f];
}

// Stances of one foot: its runs of contact frames.
struct Stance {
  int first, last;
};
std::vector<Stance> stances_of(const std::vector<uint8_t>& contact) {
  std::vector<Stance> out;
  const int n = static_cast<int>(contact.size());
  for (int f = 0; f < n;) {
    if (!contact[f]) {
      ++f;
      continue;
    }
    Stance st{f, f};
    while (f < n && contact[f]) st.last = f++;
    out.push_back(st);
  }
  return out;
}

// How fast the floor drifts up over time [m/s]: a planted ball keeps its height on a tilted floor
// but rises with a drifting one, so the median over stances of the ball's height slope in the
// middle half of each stance (flat foot; heel strike and toe-off left out). 0 without stances.
float floor_drift(const std::vector<glm::vec3>* toe, const std::vector<uint8_t>* contact,
                  float fps) {
  std::vector<float> slopes;
  for (int s = 0; s < 2; ++s) {
    for (const Stance& st : stances_of(contact[s])) {
      const int len = st.last - st.first + 1;
      const int f0 = st.first + len / 4, f1 = st.last - len / 4;
      if (f1 - f0 < 3) continue;
      double mt = 0, my = 0;
      for (int f = f0; f <= f1; ++f) {
        mt += f / fps;
        my += toe[s][f].y;
      }
      mt /= f1 - f0 + 1;
      my /= f1 - f0 + 1;
      double num = 0, den = 0;
      for (int f = f0; f <= f1; ++f) {
        num += (f / fps - mt) * (toe[s][f].y - my);
        den += (f / fps - mt) * (f / fps - mt);
      }
      if (den > 0) slopes.push_back(static_cast<float>(num / den));
    }
  }
  return slopes.empty() ? 0.0f : percentile(slopes, 0.5);
}

// The floor under one foot, fitted per stance: where its ball stood (lowest, the floor's drift
// over time taken out) in each of its contacts, held over the contact and taken linearly from one
// stance to the next over the swing; the drift added back. A floor that tilts is then level under
// every planted foot, which one line in time is not (on a tilted floor the body moves on while a
// planted foot stays put). Empty when the foot has no contact.
std::vector<float> stance_floor(const std::vector<glm::vec3>& toe,
                                const std::vector<uint8_t>& contact, float drift_m_s, float fps) {
  const int n = static_cast<int>(contact.size());
  const std::vector<Stance> stances = stances_of(contact);
  if (stances.empty()) return {};
  std::vector<float> level(stances.size());
  for (size_t i = 0; i < stances.size(); ++i) {
    level[i] = 1e30f;
    for (int f = stances[i].first; f <= stances[i].last; ++f) {
      level[i] = std::min(level[i], toe[f].y - drift_m_s * (f / fps));
    }
  }
  std::vector<float> floor(n);
  for (int f = 0; f <= stances.front().last; ++f) floor[f] = level.front();
  for (size_t i = 0; i < stances.size(); ++i) {
    const Stance& st = stances[i];
    for (int f = st.first; f <= st.last; ++f) floor[f] = level[i];
    const int end = i + 1 < stances.size() ? stances[i + 1].first : n;
    for (int f = st.last + 1; f < end; ++f) {
      floor[f] = i + 1 < stances.size()
                     ? level[i] + (level[i + 1] - level[i]) * (f - st.last) / (end - st.last)
                     : level[i];
    }
  }
  for (int f = 0; f < n; ++f) floor[f] += drift_m_s * (f / fps);
  return floor;
}

// In a walk or a run the feet take turns: between two contacts of one foot the other foot lands.
// Two contacts of a foot with no landing of the other between them, parted by a gap shorter than
// half the foot's typical contact (a swing takes longer than that in any gait), are one contact
// broken by a jittery frame or a slipping capture: joined.
void merge_unalternated(std::vector<TimeInterval> contacts[2], float duration_s, bool loops) {
  std::vector<TimeInterval> merged[2];
  for (int s = 0; s < 2; ++s) {
    std::vector<TimeInterval>& mine = contacts[s];
    const std::vector<TimeInterval>& other = contacts[1 - s];
    if (mine.size() < 2 || other.empty()) {
      merged[s] = mine;
      continue;
    }
    std::vector<float> lengths;
    for (const TimeInterval& c : mine) lengths.push_back(c.end_s - c.start_s);
    const float typical = 0.5f * percentile(lengths, 0.5);
    auto lands_between = [&](float from, float to) {
      for (const TimeInterval& o : other) {
        for (float shift : {0.0f, loops ? duration_s : 0.0f, loops ? -duration_s : 0.0f}) {
          const float t = o.start_s + shift;
          if (t > from && t < to) return true;
        }
      }
      return false;
    };
    std::vector<TimeInterval> out{mine[0]};
    for (size_t i = 1; i < mine.size(); ++i) {
      TimeInterval& last = out.back();
      if (mine[i].start_s - last.end_s < typical && !lands_between(last.start_s, mine[i].start_s)) {
        last.end_s = std::max(last.end_s, mine[i].end_s);
      } else {
        out.push_back(mine[i]);
      }
    }
    // A loop's last contact may run into its first across the wrap.
    if (loops && out.size() >= 2) {
      const TimeInterval& first = out.front();
      const TimeInterval& last = out.back();
      const float gap = first.start_s + duration_s - last.end_s;
      if (gap >= 0.0f && gap < typical && !lands_between(last.start_s, first.start_s + duration_s)) {
        out.back().end_s = first.end_s + duration_s;
        out.erase(out.begin());
      }
    }
    merged[s] = std::move(out);
  }
  contacts[0] = std::move(merged[0]);
  contacts[1] = std::move(merged[1]);
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

  Tracks tr = track_clip_frames(clip, sk);
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
  if (a.in_place) root_vel = glm::vec3(0.0f);

  // Contacts, velocity first: a planted foot's ball (or heel) stops over the ground; a height
  // gate relative to the foot's own low heights keeps a slow swing foot out.
  fit_ground(tr, clip.fps, &a.ground_y0_m, &a.ground_slope_m_s);
  if (clip.loops) a.ground_slope_m_s = 0.0f;  // a loop returns to where it started
  add_heels(&tr, clip.fps, a.ground_y0_m, a.ground_slope_m_s);
  const glm::vec3 travel_vel = a.in_place ? in_place_travel(tr, clip) : root_vel;
  std::vector<uint8_t> contact[2];
  const int min_frames = std::max(2, static_cast<int>(std::lround(th.min_duration_s * clip.fps)));
  // Velocities over the window the capture's jitter needs at this still speed (found once).
  const int k = velocity_half_window(clip.fps, capture_jitter_m(tr),
                                     still_speed_m_s(glm::length(travel_vel), th));
  for (int s = 0; s < 2; ++s) {
    detect_contacts(tr, s, clip, a, travel_vel, th, k, nullptr, &contact[s]);
    filter_runs(contact[s], min_frames, clip.loops);
  }
  // A take's floor may tilt or drift: heights again, over the floor of each stance just found
  // (a loop's floor is level: it returns to where it started).
  if (!clip.loops) {
    const float drift = floor_drift(tr.toe, contact, clip.fps);
    for (int s = 0; s < 2; ++s) {
      const std::vector<float> floor = stance_floor(tr.toe[s], contact[s], drift, clip.fps);
      if (floor.empty()) continue;
      detect_contacts(tr, s, clip, a, travel_vel, th, k, &floor, &contact[s]);
      filter_runs(contact[s], min_frames, clip.loops);
    }
  }
  for (int s = 0; s < 2; ++s) a.contacts[s] = to_intervals(contact[s], clip.fps, clip.loops);
  merge_unalternated(a.contacts, a.duration_s, clip.loops);

  // A take's speed is the one along its path: a take that turns or stops covers more ground than
  // its net displacement says (the still threshold above stays with the net travel).
  a.native_speed_m_s = glm::length(travel_vel);
  if (!clip.loops && !a.in_place) {
    a.native_speed_m_s = std::max(a.native_speed_m_s, path_speed(tr.root, clip.fps));
  }
  a.direction_rad =
      a.native_speed_m_s > 0.0f ? wrap_angle(heading_of(travel_vel) - heading_of(facing)) : 0.0f;

  // Gait cycle: the loop for looping clips of one stride (one stride of a loop of several);
  // otherwise the first full stride of a foot, from one contact start to its next (a contact cut
  // by the take's first frame starts no stride).
  float period = a.duration_s;
  if (!clip.loops) {
    for (int s : {0, 1}) {
      std::vector<float> starts;
      for (const TimeInterval& c : a.contacts[s]) {
        if (c.start_s > 0.5f / clip.fps) starts.push_back(c.start_s);
      }
      if (starts.size() >= 2) {
        a.cycle = {starts[0], starts[1]};
        period = starts[1] - starts[0];
        break;
      }
    }
  }
  if (clip.loops && a.contacts[0].size() >= 2) {
    // A loop of several strides: the cycle is one of them, from a left contact's start.
    period = a.duration_s / a.contacts[0].size();
    a.cycle = {a.contacts[0][0].start_s, a.contacts[0][0].start_s + period};
  }
  a.phase = gait_phase(a, period, clip.loops);

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
