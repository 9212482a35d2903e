#include "animation/segmentation.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <glm/gtc/quaternion.hpp>

#include "animation/mirror.h"
#include "animation/pose_jobs.h"

namespace gk {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

float wrap(float a) {
  while (a > kPi) a -= 2.0f * kPi;
  while (a < -kPi) a += 2.0f * kPi;
  return a;
}

// Horizontal hips position and facing (perpendicular to the right->left hip line) per frame, the
// facing unwrapped so that differences over a turn are continuous.
struct TakeTrack {
  std::vector<glm::vec2> hips;
  std::vector<float> facing;
};

TakeTrack track_take(const Clip& c, const Skeleton& sk) {
  TakeTrack t;
  std::vector<glm::mat4> model(sk.num_joints());
  const int hips = std::max(sk.role(JointRole::kHips), 0);
  for (int f = 0; f < c.num_frames; ++f) {
    clip_frame_model(c, sk, f, model);
    const glm::vec3 h = translation_of(model[hips]);
    t.hips.emplace_back(h.x, h.z);
    const glm::vec3 lr = translation_of(model[sk.hip(Side::kLeft)]) -
                         translation_of(model[sk.hip(Side::kRight)]);
    const glm::vec3 fwd = glm::cross(lr, glm::vec3(0, 1, 0));
    float yaw = std::atan2(fwd.x, fwd.z);
    if (f > 0) yaw = t.facing.back() + wrap(yaw - t.facing.back());
    t.facing.push_back(yaw);
  }
  return t;
}

// Smoothed horizontal root speed per frame: displacement over +-half_s (shortened at the ends).
std::vector<float> smoothed_speed(const TakeTrack& t, float fps, float half_s) {
  const int n = static_cast<int>(t.hips.size());
  const int k = std::max(1, static_cast<int>(std::lround(half_s * fps)));
  std::vector<float> v(n, 0.0f);
  for (int f = 0; f < n; ++f) {
    const int lo = std::max(0, f - k), hi = std::min(n - 1, f + k);
    if (hi > lo) v[f] = glm::length(t.hips[hi] - t.hips[lo]) * fps / (hi - lo);
  }
  return v;
}

int frame_at(float t_s, float fps, int n) {
  return std::clamp(static_cast<int>(std::lround(t_s * fps)), 0, n - 1);
}

float path_length(const TakeTrack& t, int a, int b) {
  float len = 0.0f;
  for (int f = a; f < b; ++f) len += glm::length(t.hips[f + 1] - t.hips[f]);
  return len;
}

// How well a stride loops: rotation difference of every joint below the root between its first and
// last frame, plus the root's height difference [rad, with metres counted as 10 rad/m].
float seam_cost(const Clip& c, int a, int b) {
  const glm::quat* ra = c.frame_rotations(a);
  const glm::quat* rb = c.frame_rotations(b);
  float cost = 0.0f;
  for (int j = 1; j < c.num_joints; ++j) {
    cost += 2.0f * std::acos(std::min(1.0f, std::abs(glm::dot(ra[j], rb[j]))));
  }
  cost += 10.0f * std::abs(c.frame_translations(a)[0].y - c.frame_translations(b)[0].y);
  return cost;
}

// Per joint, the side of the leg it belongs to (a descendant of that hip), or -1.
std::vector<int> leg_sides(const Skeleton& sk) {
  std::vector<int> leg(static_cast<size_t>(sk.num_joints()), -1);
  for (int j = 0; j < sk.num_joints(); ++j) {
    for (int s = 0; s < 2; ++s) {
      for (int q = j; q >= 0; q = sk.parents[q]) {
        if (q == sk.hip(static_cast<Side>(s))) leg[j] = s;
      }
    }
  }
  return leg;
}

// 0 -> 1 with zero slope at both ends (u clamped to [0, 1]).
float smooth01(float u) {
  u = std::clamp(u, 0.0f, 1.0f);
  return u * u * (3.0f - 2.0f * u);
}

// The hips' position (model space, with the clip's root motion) on one frame.
glm::vec3 clip_hips(const Clip& c, const Skeleton& sk, int frame) {
  std::vector<glm::mat4> model(sk.num_joints());
  clip_frame_model(c, sk, frame, model);
  return translation_of(model[std::max(sk.role(JointRole::kHips), 0)]);
}

// A clip named and timed as the take, with no frames yet.
Clip clip_like(const Clip& take, int frames, bool loops) {
  Clip c;
  c.name = take.name;
  c.source = take.source;
  c.fps = take.fps;
  c.num_frames = frames;
  c.num_joints = take.num_joints;
  c.loops = loops;
  c.sampled_capture = take.sampled_capture;
  return c;
}

// Frames on either side of a take's edge that contact analysis cannot trust: a contact cut by the
// first frame did not start there.
bool starts_inside(const TimeInterval& c, float fps) { return c.start_s > 0.5f / fps; }

}  // namespace

const char* segment_kind_name(SegmentKind kind) {
  switch (kind) {
    case SegmentKind::kIdle: return "idle";
    case SegmentKind::kStart: return "start";
    case SegmentKind::kSteady: return "steady";
    case SegmentKind::kTurn: return "turn";
    case SegmentKind::kStop: return "stop";
    case SegmentKind::kTransition: return "transition";
  }
  return "?";
}

TakeSegmentation segment_take(const Clip& take, const Skeleton& sk, const ClipAnalysis& a,
                              const SegmentationThresholds& th) {
  TakeSegmentation out;
  const int n = take.num_frames;
  const float fps = take.fps;
  if (n < 2) return out;
  if (take.loops || a.in_place || !sk.has_locomotion_roles()) {
    TakeSegment whole;
    whole.kind = a.native_speed_m_s > 0.0f ? SegmentKind::kSteady : SegmentKind::kIdle;
    whole.span = {0.0f, take.duration_s()};
    whole.speed_m_s = whole.speed_in_m_s = whole.speed_out_m_s = a.native_speed_m_s;
    out.segments.push_back(whole);
    return out;
  }
  const TakeTrack tr = track_take(take, sk);
  const std::vector<float> speed = smoothed_speed(tr, fps, 0.25f);

  // A stride or a step from t0 to t1 (side: the foot down at t0) measured: its speed, its two
  // halves' speeds (v1, v2), its turn and its travel direction; steady when the halves' speeds
  // differ by less than steady_speed_change, it turns less than max_turn and both halves move.
  // False when it spans fewer than two frames.
  auto measure = [&](float t0, float t1, int side, float max_turn, Stride* st, float* v1,
                     float* v2) {
    const int f0 = frame_at(t0, fps, n), f1 = frame_at(t1, fps, n);
    if (f1 - f0 < 2) return false;
    const int fm = (f0 + f1) / 2;
    st->span = {t0, t1};
    st->side = side;
    const glm::vec2 d = tr.hips[f1] - tr.hips[f0];
    st->speed_m_s = glm::length(d) * fps / (f1 - f0);
    *v1 = glm::length(tr.hips[fm] - tr.hips[f0]) * fps / std::max(1, fm - f0);
    *v2 = glm::length(tr.hips[f1] - tr.hips[fm]) * fps / std::max(1, f1 - fm);
    st->speed_change = st->speed_m_s > 1e-3f ? (*v2 - *v1) / st->speed_m_s : 0.0f;
    st->turn_rad = tr.facing[f1] - tr.facing[f0];
    const float mean_facing = 0.5f * (tr.facing[f0] + tr.facing[f1]);
    st->direction_rad =
        st->speed_m_s > 1e-3f ? wrap(std::atan2(d.x, d.y) - mean_facing) : 0.0f;
    st->steady = std::abs(st->speed_change) < th.steady_speed_change &&
                 std::abs(st->turn_rad) < max_turn && *v1 > th.idle_speed_m_s &&
                 *v2 > th.idle_speed_m_s;
    return true;
  };
  // Strides: from each contact start of a foot to its next, with exactly one contact start of the
  // other foot between them (the feet alternate).
  for (int s = 0; s < 2; ++s) {
    const auto& mine = a.contacts[s];
    const auto& other = a.contacts[1 - s];
    for (size_t i = 0; i + 1 < mine.size(); ++i) {
      if (!starts_inside(mine[i], fps)) continue;
      const float t0 = mine[i].start_s, t1 = mine[i + 1].start_s;
      const float dur = t1 - t0;
      if (dur < th.min_stride_s || dur > th.max_stride_s) continue;
      int between = 0;
      for (const TimeInterval& o : other) between += o.start_s > t0 && o.start_s < t1;
      if (between != 1) continue;
      Stride st;
      float v1 = 0.0f, v2 = 0.0f;
      if (measure(t0, t1, s, th.steady_turn_rad, &st, &v1, &v2)) out.strides.push_back(st);
    }
  }
  std::sort(out.strides.begin(), out.strides.end(),
            [](const Stride& x, const Stride& y) { return x.span.start_s < y.span.start_s; });
  // Steps: from each contact start of a foot to the other foot's next, with no contact start of
  // the first foot between them; measured as strides are. A step walks when both its halves move
  // faster than standing and it turns less than half a steady stride does.
  std::vector<std::pair<Stride, bool>> steps;
  for (int s = 0; s < 2; ++s) {
    for (const TimeInterval& c : a.contacts[s]) {
      if (!starts_inside(c, fps)) continue;
      const float t0 = c.start_s;
      float t1 = -1.0f;
      for (const TimeInterval& o : a.contacts[1 - s]) {
        if (o.start_s > t0 && (t1 < 0.0f || o.start_s < t1)) t1 = o.start_s;
      }
      if (t1 < 0.0f) continue;
      bool again = false;
      for (const TimeInterval& m : a.contacts[s]) again = again || (m.start_s > t0 && m.start_s < t1);
      const float dur = t1 - t0;
      if (again || dur < 0.5f * th.min_stride_s || dur > 0.5f * th.max_stride_s) continue;
      Stride st;
      float v1 = 0.0f, v2 = 0.0f;
      if (!measure(t0, t1, s, 0.5f * th.steady_turn_rad, &st, &v1, &v2)) continue;
      const bool walks = v1 > th.idle_speed_m_s && v2 > th.idle_speed_m_s &&
                         std::abs(st.turn_rad) < 0.5f * th.steady_turn_rad;
      steps.emplace_back(st, walks);
    }
  }
  std::sort(steps.begin(), steps.end(), [](const auto& x, const auto& y) {
    return x.first.span.start_s < y.first.span.start_s;
  });
  for (const auto& [st, walks] : steps) out.steps.push_back(st);

  // Per-frame labels: steady where a steady stride covers the frame; idle where the root stands;
  // the rest is told apart per run (start, stop, turn, transition).
  std::vector<SegmentKind> label(n, SegmentKind::kTransition);
  std::vector<uint8_t> steady(n, 0);
  for (const Stride& st : out.strides) {
    if (!st.steady) continue;
    for (int f = frame_at(st.span.start_s, fps, n); f <= frame_at(st.span.end_s, fps, n); ++f) {
      steady[f] = 1;
    }
  }
  for (int f = 0; f < n; ++f) {
    if (steady[f]) {
      label[f] = SegmentKind::kSteady;
    } else if (speed[f] < th.idle_speed_m_s) {
      label[f] = SegmentKind::kIdle;
    }
  }
  // Runs shorter than min_segment_s join the run before them (or after, at the take's start).
  const int min_run = std::max(1, static_cast<int>(std::lround(th.min_segment_s * fps)));
  auto runs = [&] {
    std::vector<std::pair<int, int>> r;  // [first, last]
    for (int f = 0; f < n;) {
      int g = f;
      while (g + 1 < n && label[g + 1] == label[f]) ++g;
      r.push_back({f, g});
      f = g + 1;
    }
    return r;
  };
  for (int pass = 0; pass < 4; ++pass) {
    bool changed = false;
    const auto r = runs();
    for (size_t i = 0; i < r.size() && r.size() > 1; ++i) {
      const auto [f, g] = r[i];
      if (g - f + 1 >= min_run) continue;
      const SegmentKind into = i > 0 ? label[r[i - 1].second] : label[r[i + 1].first];
      for (int k = f; k <= g; ++k) label[k] = into;
      changed = true;
      break;
    }
    if (!changed) break;
  }
  // Non-steady, non-idle runs: a turn where the body turns more than a steady stride does, else a
  // start where the root speeds up, a stop where it slows down, otherwise a transition.
  for (const auto& [f, g] : runs()) {
    if (label[f] != SegmentKind::kTransition) continue;
    const float turn = tr.facing[g] - tr.facing[f];
    const float s0 = speed[f], s1 = speed[g];
    const float mean = std::max(0.5f * (s0 + s1), 1e-3f);
    SegmentKind k = SegmentKind::kTransition;
    if (std::abs(turn) >= th.steady_turn_rad) {
      k = SegmentKind::kTurn;
    } else if ((s1 - s0) / mean >= th.steady_speed_change) {
      k = SegmentKind::kStart;
    } else if ((s0 - s1) / mean >= th.steady_speed_change) {
      k = SegmentKind::kStop;
    }
    for (int q = f; q <= g; ++q) label[q] = k;
  }
  // A transition beside steady gait that neither starts, stops nor turns is the same gait where no
  // full stride fits (the take's first and last steps) or where the pace wavers: steady.
  for (int pass = 0; pass < 2; ++pass) {
    const auto r = runs();
    for (size_t i = 0; i < r.size(); ++i) {
      if (label[r[i].first] != SegmentKind::kTransition) continue;
      const bool beside = (i > 0 && label[r[i - 1].second] == SegmentKind::kSteady) ||
                          (i + 1 < r.size() && label[r[i + 1].first] == SegmentKind::kSteady);
      if (!beside) continue;
      for (int k = r[i].first; k <= r[i].second; ++k) label[k] = SegmentKind::kSteady;
    }
  }
  for (const auto& [f, g] : runs()) {
    TakeSegment seg;
    seg.kind = label[f];
    // Segments meet: each ends where the next begins.
    seg.span = {f / fps, (g + 1 < n ? g + 1 : g) / fps};
    const int last = g + 1 < n ? g + 1 : g;
    seg.speed_m_s = last > f ? path_length(tr, f, last) * fps / (last - f) : 0.0f;
    seg.speed_in_m_s = speed[f];
    seg.speed_out_m_s = speed[last];
    seg.turn_rad = tr.facing[last] - tr.facing[f];
    out.segments.push_back(seg);
  }

  // Cycles: in each steady segment, one per pace it walks or runs at, the stride whose ends
  // match best. Strides of one pace differ in speed as little as a steady stride's two halves
  // may (th.steady_speed_change): a take that walks, then walks faster, gives both.
  for (TakeSegment& seg : out.segments) {
    if (seg.kind != SegmentKind::kSteady) continue;
    std::vector<int> inside;
    for (size_t i = 0; i < out.strides.size(); ++i) {
      const Stride& st = out.strides[i];
      if (st.steady && st.span.start_s >= seg.span.start_s - 0.5f / fps &&
          st.span.end_s <= seg.span.end_s + 0.5f / fps) {
        inside.push_back(static_cast<int>(i));
      }
    }
    std::stable_sort(inside.begin(), inside.end(), [&](int a_i, int b_i) {
      return out.strides[a_i].speed_m_s < out.strides[b_i].speed_m_s;
    });
    float best_all = 1e30f;
    for (size_t from = 0; from < inside.size();) {
      const float slowest = out.strides[inside[from]].speed_m_s;
      size_t to = from;
      while (to < inside.size() &&
             out.strides[inside[to]].speed_m_s <= slowest * (1.0f + th.steady_speed_change)) {
        ++to;
      }
      int pick = -1;
      float best = 1e30f;
      for (size_t k = from; k < to; ++k) {
        const Stride& st = out.strides[inside[k]];
        const float cost =
            seam_cost(take, frame_at(st.span.start_s, fps, n), frame_at(st.span.end_s, fps, n));
        if (cost < best) {
          best = cost;
          pick = inside[k];
        }
      }
      out.cycles.push_back(pick);
      if (best < best_all) {  // the segment's own loop: the best seam of all its paces
        best_all = best;
        seg.cycle = pick;
      }
      from = to;
    }
  }
  if (out.cycles.empty() && (!out.strides.empty() || !out.steps.empty())) {
    int least = -1;
    for (size_t i = 0; i < out.strides.size(); ++i) {
      const Stride& st = out.strides[i];
      if (least < 0 || std::abs(st.speed_change) < std::abs(out.strides[least].speed_change)) {
        least = static_cast<int>(i);
      }
    }
    if (least >= 0) out.cycles.push_back(least);
    out.fallback_cycle = true;
    // The steadiest step that walks (both halves faster than standing, a turn no bigger than half
    // a steady stride's): with its mirror image, a stride of one pace.
    for (size_t i = 0; i < steps.size(); ++i) {
      const auto& [st, walks] = steps[i];
      if (!walks) continue;
      if (out.mirror_step < 0 ||
          std::abs(st.speed_change) < std::abs(out.steps[out.mirror_step].speed_change)) {
        out.mirror_step = static_cast<int>(i);
      }
    }
    char buf[320];
    if (out.mirror_step >= 0) {
      const Stride& st = out.steps[out.mirror_step];
      std::snprintf(buf, sizeof buf,
                    "no steady stride (the body speeds up, slows down or turns in every one): the "
                    "steadiest step, %.2f-%.2f s (%s foot down first, %.2f m/s, speed change "
                    "%.0f%%), and its mirror image make the cycle if the library has no steady one",
                    st.span.start_s, st.span.end_s, st.side == 0 ? "left" : "right", st.speed_m_s,
                    100.0f * st.speed_change);
    } else if (least >= 0) {
      std::snprintf(buf, sizeof buf,
                    "no steady stride (the body speeds up, slows down or turns in every one): the "
                    "least unsteady stride, %.2f-%.2f s (speed change %.0f%%), is the cycle if the "
                    "library has no steady one",
                    out.strides[least].span.start_s, out.strides[least].span.end_s,
                    100.0f * out.strides[least].speed_change);
    } else {
      std::snprintf(buf, sizeof buf, "no stride and no step that walks: no gait cycle can be made");
    }
    out.problems.push_back(buf);
  }
  if (out.strides.empty()) {
    out.problems.push_back(
        "no full stride (a foot's contact, a contact of the other foot, the first foot's next "
        "contact): no gait cycle can be cut out");
  }
  return out;
}

Clip extract_cycle(const Clip& take, const Skeleton& sk, const ClipAnalysis& an,
                   const Stride& stride) {
  const int n = take.num_frames, nj = take.num_joints;
  const float fps = take.fps;
  const int a = frame_at(stride.span.start_s, fps, n);
  const int b = frame_at(stride.span.end_s, fps, n);
  const int len = std::max(1, b - a);
  Clip c = clip_like(take, len, true);
  // Frames a..b: the stride and the frame that closes it (where the loop must come back to).
  std::vector<glm::quat> rot(take.frame_rotations(a),
                             take.frame_rotations(a) + static_cast<size_t>(len + 1) * nj);
  std::vector<glm::vec3> tra(take.frame_translations(a),
                             take.frame_translations(a) + static_cast<size_t>(len + 1) * nj);
  auto R = [&](int k, int j) -> glm::quat& { return rot[static_cast<size_t>(k) * nj + j]; };
  auto T = [&](int k, int j) -> glm::vec3& { return tra[static_cast<size_t>(k) * nj + j]; };
  if (len >= 4 && b < n && sk.has_locomotion_roles()) {
    // 1. The stride's turn, taken back a little each frame about the foot that bears the weight
    //    (the slower toe): a planted foot stays where it is while the body swings round it, and
    //    the loop keeps one heading.
    const TakeTrack tr = track_take(take, sk);
    const float turn = tr.facing[b] - tr.facing[a];
    std::vector<glm::mat4> model(sk.num_joints());
    std::vector<glm::vec2> toe[2];
    for (int k = 0; k <= len; ++k) {
      LocalToModelJob{&sk, {&R(k, 0), static_cast<size_t>(nj)}, {&T(k, 0), static_cast<size_t>(nj)},
                      glm::mat4(1.0f), model}
          .run();
      for (int s = 0; s < 2; ++s) {
        const glm::vec3 p = translation_of(model[sk.toe(static_cast<Side>(s))]);
        toe[s].emplace_back(p.x, p.z);
      }
    }
    const float step = -turn / len;
    float angle = 0.0f;  // frame k's map: x -> R(angle) x + shift
    glm::vec2 shift(0.0f);
    for (int k = 0; k <= len; ++k) {
      const glm::quat q = glm::angleAxis(angle, glm::vec3(0, 1, 0));
      const glm::vec3 rt = q * glm::vec3(T(k, 0).x, 0.0f, T(k, 0).z);
      T(k, 0) = glm::vec3(rt.x + shift.x, T(k, 0).y, rt.z + shift.y);
      R(k, 0) = glm::normalize(q * R(k, 0));
      const int k1 = std::min(k + 1, len), k0 = std::max(k - 1, 0);
      const int s = glm::length(toe[0][k1] - toe[0][k0]) <= glm::length(toe[1][k1] - toe[1][k0])
                        ? 0
                        : 1;
      const glm::vec3 pm = q * glm::vec3(toe[s][k].x, 0.0f, toe[s][k].y);
      const glm::vec2 pivot(pm.x + shift.x, pm.z + shift.y);
      const glm::vec3 d = glm::angleAxis(step, glm::vec3(0, 1, 0)) *
                          glm::vec3(shift.x - pivot.x, 0.0f, shift.y - pivot.y);
      shift = glm::vec2(d.x + pivot.x, d.z + pivot.y);
      angle += step;
    }
    // 2. Closing the loop: frame len must become frame 0 again. Each joint's mismatch is taken up
    //    gradually: a leg's joints only while that foot swings (a planted foot never moves for
    //    it), the rest of the body over the whole stride. A leg's mismatch is taken up in its
    //    longest swing, from none to all of it (frame len is frame 0 with all of it) or from all of
    //    it taken back (frame 0 is frame len with none of it) to none: whichever leaves the fewer
    //    stance frames changed. A stance between the swing and the seam must carry the mismatch
    //    (or its inverse) to keep the seam closed; one on the other side never does.
    const std::vector<int> leg = leg_sides(sk);
    int swing_from[2] = {0, 0}, swing_to[2] = {len, len};
    float before[2] = {0.0f, 0.0f};  // the share of the mismatch before the swing (0 or -1)
    for (int s = 0; s < 2; ++s) {
      std::vector<uint8_t> down(len + 1, 0);
      for (const TimeInterval& iv : an.contacts[s]) {
        const int f0 = static_cast<int>(std::lround(iv.start_s * fps)) - a;
        const int f1 = static_cast<int>(std::lround(iv.end_s * fps)) - a;
        for (int k = std::max(0, f0); k <= std::min(len, f1); ++k) down[k] = 1;
      }
      int best = 0;
      for (int k = 0; k <= len;) {
        if (down[k]) {
          ++k;
          continue;
        }
        int e = k;
        while (e + 1 <= len && !down[e + 1]) ++e;
        if (e - k + 1 > best) {
          best = e - k + 1;
          swing_from[s] = k;
          swing_to[s] = e + 1;
        }
        k = e + 1;
      }
      int stance_before = 0, stance_after = 0;  // frames 1..len-1 (0 and len are the seam)
      for (int k = 1; k < len; ++k) {
        stance_before += down[k] && k < swing_from[s];
        stance_after += down[k] && k >= swing_to[s];
      }
      if (stance_before < stance_after) before[s] = -1.0f;
    }
    for (int j = 0; j < nj; ++j) {
      glm::quat diff = R(0, j) * glm::inverse(R(len, j));
      if (diff.w < 0.0f) diff = -diff;
      const glm::vec3 dt = T(0, j) - T(len, j);
      for (int k = leg[j] >= 0 ? 0 : 1; k <= len; ++k) {
        float w = static_cast<float>(k) / len;
        if (leg[j] >= 0) {
          const int s = leg[j];
          w = before[s] + smooth01(static_cast<float>(k - swing_from[s]) /
                                   std::max(1, swing_to[s] - swing_from[s]));
        }
        if (w == 0.0f) continue;
        const glm::quat turn =
            glm::slerp(glm::quat(1, 0, 0, 0), w > 0.0f ? diff : glm::inverse(diff), std::abs(w));
        R(k, j) = glm::normalize(turn * R(k, j));
        if (j == 0) {
          T(k, j).y += w * dt.y;  // the root's travel stays its own; its height closes
        } else {
          T(k, j) += w * dt;
        }
      }
    }
    // 3. The root's travel: sampling carries a loop's root on by its last-minus-first step scaled
    //    to a whole loop; a ramp (millimetres) makes that the stride's own displacement.
    glm::vec3 want = T(len, 0) - T(0, 0);
    want.y = 0.0f;
    glm::vec3 have = (T(len - 1, 0) - T(0, 0)) * (static_cast<float>(len) / (len - 1));
    have.y = 0.0f;
    const glm::vec3 e = (want - have) * (static_cast<float>(len - 1) / len);
    for (int k = 0; k < len; ++k) T(k, 0) += e * (static_cast<float>(k) / (len - 1));
  }
  c.rotations.assign(rot.begin(), rot.begin() + static_cast<size_t>(len) * nj);
  c.translations.assign(tra.begin(), tra.begin() + static_cast<size_t>(len) * nj);
  return c;
}

TravelPlane travel_plane(const Clip& clip, const Skeleton& sk) {
  TravelPlane plane;
  if (clip.num_frames < 1 || !sk.has_locomotion_roles()) return plane;
  const TakeTrack tr = track_take(clip, sk);
  const float facing = 0.5f * (tr.facing.front() + tr.facing.back());
  const glm::vec2 mid = 0.5f * (tr.hips.front() + tr.hips.back());
  plane.point = glm::vec3(mid.x, 0.0f, mid.y);
  plane.normal = glm::vec3(std::cos(facing), 0.0f, -std::sin(facing));
  return plane;
}

MirroredCycle extract_mirrored_cycle(const Clip& take, const Skeleton& sk, const ClipAnalysis& an,
                                     const Stride& step, const std::vector<int16_t>& mirror_map) {
  MirroredCycle out;
  const int n = take.num_frames, nj = take.num_joints;
  const float fps = take.fps;
  const int a = frame_at(step.span.start_s, fps, n);
  const int b = frame_at(step.span.end_s, fps, n);
  const int len = b - a;
  const int x = step.side, y = 1 - step.side;  // x lands at the step's start, y at its end
  if (len < 2 || !sk.has_locomotion_roles() || nj != sk.num_joints() ||
      static_cast<int>(mirror_map.size()) != nj) {
    out.loop = extract_span(take, step.span);
    out.loop.loops = true;
    return out;
  }
  // Where each foot leaves the ground within the step, in frames from its start: y, down when x
  // lands, lifts at lift_y (0: already in the air, as in a run); x lifts at lift_x (len: still
  // down when y lands, as in a walk).
  const float tol = 0.5f / fps;
  int lift_y = 0, lift_x = len;
  for (const TimeInterval& c : an.contacts[y]) {
    if (c.start_s <= step.span.start_s + tol && c.end_s >= step.span.start_s - tol) {
      lift_y = std::clamp(static_cast<int>(std::lround((c.end_s - step.span.start_s) * fps)), 0,
                          len - 1);
    }
  }
  for (const TimeInterval& c : an.contacts[x]) {
    if (std::abs(c.start_s - step.span.start_s) <= tol) {
      lift_x = std::clamp(static_cast<int>(std::lround((c.end_s - step.span.start_s) * fps)), 1,
                          len);
    }
  }
  // The step, and its mirror image in the vertical plane along its travel (through the middle of
  // the hips' path: their sway to either side is mirrored onto the other), moved on to where the
  // step ends.
  const Clip step_clip = extract_span(take, step.span);  // frames a..b
  const TravelPlane plane = travel_plane(step_clip, sk);
  const Clip mirrored = mirror_clip(step_clip, sk, mirror_map, plane.point, plane.normal);
  const glm::vec3 end = clip_hips(step_clip, sk, len), start = clip_hips(mirrored, sk, 0);
  const glm::vec2 shift(end.x - start.x, end.z - start.z);
  // The two as one take: frames 0..len the step, len..2 len its mirror (its first frame is the
  // step's last).
  Clip both = clip_like(take, 2 * len + 1, false);
  both.rotations.assign(step_clip.rotations.begin(), step_clip.rotations.end());
  both.translations.assign(step_clip.translations.begin(), step_clip.translations.end());
  for (int k = 1; k <= len; ++k) {
    for (int j = 0; j < nj; ++j) {
      const size_t i = static_cast<size_t>(k) * nj + j;
      glm::vec3 t = mirrored.translations[i];
      if (sk.parents[j] < 0) t += glm::vec3(shift.x, 0.0f, shift.y);
      both.rotations.push_back(mirrored.rotations[i]);
      both.translations.push_back(t);
    }
  }
  auto R = [&](int k, int j) -> glm::quat& {
    return both.rotations[static_cast<size_t>(k) * nj + j];
  };
  auto T = [&](int k, int j) -> glm::vec3& {
    return both.translations[static_cast<size_t>(k) * nj + j];
  };
  // The join at frame len: the step ends as the mirror would begin. y's leg takes its mismatch up
  // while it swings into its landing (before the join); x's leg while it swings in the mirror
  // (after it); the rest of the body over the mirrored step.
  const std::vector<int> leg = leg_sides(sk);
  for (int j = 0; j < nj; ++j) {
    const glm::quat at_join = R(len, j);
    const glm::vec3 at_join_t = T(len, j);
    const glm::quat mirror_first = mirrored.rotations[static_cast<size_t>(j)];
    glm::vec3 mirror_first_t = mirrored.translations[static_cast<size_t>(j)];
    if (sk.parents[j] < 0) mirror_first_t += glm::vec3(shift.x, 0.0f, shift.y);
    if (leg[j] == y) {
      glm::quat diff = mirror_first * glm::inverse(at_join);
      if (diff.w < 0.0f) diff = -diff;
      const glm::vec3 dt = mirror_first_t - at_join_t;
      for (int k = lift_y + 1; k <= len; ++k) {
        const float w = smooth01(static_cast<float>(k - lift_y) / static_cast<float>(len - lift_y));
        R(k, j) = glm::normalize(glm::slerp(glm::quat(1, 0, 0, 0), diff, w) * R(k, j));
        T(k, j) += w * dt;
      }
      continue;
    }
    glm::quat diff = at_join * glm::inverse(mirror_first);
    if (diff.w < 0.0f) diff = -diff;
    glm::vec3 dt = at_join_t - mirror_first_t;
    if (sk.parents[j] < 0) dt.x = dt.z = 0.0f;  // the travel is continuous already
    for (int k = len + 1; k <= 2 * len; ++k) {
      float w = 1.0f - static_cast<float>(k - len) / static_cast<float>(len);
      if (leg[j] == x) {
        const int from = len + lift_y;  // x's swing in the mirror: as y's in the step
        w = 1.0f - smooth01(static_cast<float>(k - from) / static_cast<float>(2 * len - from));
      }
      R(k, j) = glm::normalize(glm::slerp(glm::quat(1, 0, 0, 0), diff, w) * R(k, j));
      T(k, j) += w * dt;
    }
  }
  // Contacts of the two steps (frames): x down from its landing until it lifts in the step, and
  // again in the mirror as y was in the step; y as x was, in the mirror.
  ClipAnalysis joined = an;
  const float f = 1.0f / fps;
  auto iv = [&](int from, int to) { return TimeInterval{from * f, to * f}; };
  joined.contacts[x].clear();
  joined.contacts[y].clear();
  if (lift_x >= len) {
    joined.contacts[x].push_back(iv(0, len + lift_y));
  } else {
    joined.contacts[x].push_back(iv(0, lift_x));
    if (lift_y > 0) joined.contacts[x].push_back(iv(len, len + lift_y));
  }
  joined.contacts[x].push_back(iv(2 * len, 2 * len));
  if (lift_y > 0) joined.contacts[y].push_back(iv(0, lift_y));
  joined.contacts[y].push_back(iv(len, len + lift_x));
  Stride stride = step;
  stride.span = {0.0f, 2 * len * f};
  out.loop = extract_cycle(both, sk, joined, stride);
  out.contacts = stride_contacts(joined, 0, 2 * len, fps);
  return out;
}

std::array<std::vector<TimeInterval>, 2> stride_contacts(const ClipAnalysis& take, int first,
                                                         int frames, float fps) {
  std::array<std::vector<TimeInterval>, 2> out;
  const float from = first / fps, duration = frames / fps, tol = 0.5f / fps;
  for (int s = 0; s < 2; ++s) {
    for (const TimeInterval& c : take.contacts[s]) {
      const float a = std::max(c.start_s - from, 0.0f), b = std::min(c.end_s - from, duration);
      if (b - a >= 1.0f / fps) out[s].push_back({a, b});
    }
    std::vector<TimeInterval>& v = out[s];
    if (v.size() >= 2 && v.front().start_s <= tol && v.back().end_s >= duration - tol) {
      v.back().end_s = duration + v.front().end_s;
      v.erase(v.begin());
    }
  }
  return out;
}

Clip extract_span(const Clip& take, TimeInterval span) {
  const int n = take.num_frames, nj = take.num_joints;
  const int a = frame_at(span.start_s, take.fps, n);
  const int b = std::max(a, frame_at(span.end_s, take.fps, n));
  Clip c = clip_like(take, b - a + 1, false);
  c.rotations.assign(take.frame_rotations(a), take.frame_rotations(b) + nj);
  c.translations.assign(take.frame_translations(a), take.frame_translations(b) + nj);
  return c;
}

}  // namespace gk
