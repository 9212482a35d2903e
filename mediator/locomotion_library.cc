#include "mediator/locomotion_library.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <tuple>

#include <glm/gtx/quaternion.hpp>

#include "animation/mirror.h"
#include "animation/pose_jobs.h"
#include "animation/segmentation.h"
#include "common/ascii.h"
#include "common/stats.h"
#include "mediator/springs.h"

namespace gk {
namespace {

// Standing kept beside a start or stop [s], and the shortest transition worth playing [s].
constexpr float kTransitionRest = 0.4f;
constexpr float kMinTransition = 0.5f;

constexpr float kPi = std::numbers::pi_v<float>;
constexpr float kMinGaitSpeed = 0.25f;  // [m/s] slower "gaits" are treated as standing clips
constexpr float kMaxGaitSpeed = 12.0f;  // [m/s] faster ones are not locomotion
constexpr float kMetricRateHz = 60.0f;

// Clips whose names say they are not walking/running are left out of the blend space.
constexpr std::array<const char*, 24> kNonLocomotion = {
    "crouch",   "swim", "jump", "sit",   "crawl", "climb",  "death", "dead",
    "punch",    "kick", "roll", "fall",  "hit",   "pistol", "sword", "spell",
    "interact", "push", "pick", "dance", "tpose", "t-pose", "driv",  "ride"};

bool name_excluded(const std::string& name) {
  const std::string n = lower_ascii(name);
  for (const char* k : kNonLocomotion) {
    if (n.find(k) != std::string::npos) return true;
  }
  return false;
}

std::vector<glm::mat4> rest_model(const Skeleton& sk) {
  std::vector<glm::mat4> m(sk.num_joints());
  LocalToModelJob{&sk, sk.rest_rotations, sk.rest_translations, glm::mat4(1.0f), m}.run();
  return m;
}

float leg_length(const Skeleton& sk, const std::vector<glm::mat4>& rest, Side s) {
  const glm::vec3 h = translation_of(rest[sk.hip(s)]), k = translation_of(rest[sk.knee(s)]),
                  a = translation_of(rest[sk.ankle(s)]);
  return glm::length(k - h) + glm::length(a - k);
}

// Removes the clip's mean travel from the root and turns its facing to +z (about the origin), so
// the pose keeps only the pelvis's own sway and bob.
// The hips' ground track (y = 0) of every frame of a clip.
std::vector<glm::vec3> hips_ground_track(const Clip& c, const Skeleton& sk) {
  const int hips = sk.role(JointRole::kHips);
  std::vector<glm::mat4> model(c.num_joints);
  std::vector<glm::vec3> hips_xz(c.num_frames);
  for (int f = 0; f < c.num_frames; ++f) {
    clip_frame_model(c, sk, f, model);
    hips_xz[f] = translation_of(model[hips]);
    hips_xz[f].y = 0.0f;
  }
  return hips_xz;
}

Clip make_in_place(const Clip& src, const Skeleton& sk, const ClipAnalysis& a, float facing_rad) {
  Clip c = src;
  const int n = c.num_frames, nj = c.num_joints;
  std::vector<glm::mat4> model(nj);
  const std::vector<glm::vec3> hips_xz = hips_ground_track(c, sk);
  // Travel: mean velocity of the hips (zero for in-place clips), centred on the mean position.
  const glm::vec3 vel =
      a.in_place || n < 2 ? glm::vec3(0.0f) : (hips_xz[n - 1] - hips_xz[0]) * (c.fps / (n - 1));
  glm::vec3 centre(0.0f);
  for (int f = 0; f < n; ++f) centre += hips_xz[f] - vel * (f / c.fps);
  centre /= static_cast<float>(n);
  const glm::quat yaw = glm::angleAxis(-facing_rad, glm::vec3(0, 1, 0));
  for (int f = 0; f < n; ++f) {
    glm::quat& r = c.rotations[static_cast<size_t>(f) * nj];
    glm::vec3& t = c.translations[static_cast<size_t>(f) * nj];
    r = yaw * r;
    t = yaw * (t - centre - vel * (f / c.fps));
    t.y -= a.ground_slope_m_s * (f / c.fps);  // level the capture floor
  }
  return c;
}

// Facing of the character in a clip: perpendicular to the right->left hip vector, averaged.
float clip_facing(const Clip& c, const Skeleton& sk) {
  std::vector<glm::mat4> model(sk.num_joints());
  glm::vec3 sum(0.0f);
  for (int f = 0; f < c.num_frames; ++f) {
    clip_frame_model(c, sk, f, model);
    const glm::vec3 lr =
        translation_of(model[sk.hip(Side::kLeft)]) - translation_of(model[sk.hip(Side::kRight)]);
    sum += glm::cross(lr, glm::vec3(0, 1, 0));
  }
  return std::atan2(sum.x, sum.z);
}

// Fills the phase table from the analysis's per-frame phase over one cycle starting at start_s.
bool build_phase_table(LocomotionClip* lc) {
  const ClipAnalysis& a = lc->analysis;
  const int n = a.num_frames;
  if (n < 4 || a.phase.size() != static_cast<size_t>(n)) return false;
  const float fps = a.fps;
  int f0 = static_cast<int>(std::lround(lc->cycle_start_s * fps));
  f0 = std::clamp(f0, 0, n - 1);
  // Walk frames from the cycle start accumulating positive phase increments until one full cycle.
  std::vector<float> ts{f0 / fps}, ps{0.0f};
  float acc = 0.0f;
  const float start_phase = a.phase[f0];
  float prev = start_phase;
  const bool loops = lc->clip.loops;
  for (int k = 1; k <= 4 * n && acc < 1.0f; ++k) {
    const int f = f0 + k;
    if (!loops && f >= n) break;
    const float ph = a.phase[f % n];
    float d = ph - prev;
    if (d < -0.5f) d += 1.0f;
    if (d < 0.0f) d = 0.0f;  // phase never runs backward
    prev = ph;
    acc += d;
    ts.push_back(f / fps);
    ps.push_back(acc);
  }
  if (acc < 0.95f) return false;
  // Phase of the first sample is start_phase, which need not be exactly 0: shift so table starts
  // at phase 0 of the gait (the left contact).
  for (int k = 0; k <= kPhaseTableSize; ++k) {
    const float target = static_cast<float>(k) / kPhaseTableSize * acc / std::max(acc, 1.0f);
    size_t i = 1;
    while (i + 1 < ps.size() && ps[i] < target) ++i;
    const float span = std::max(ps[i] - ps[i - 1], 1e-6f);
    const float u = std::clamp((target - ps[i - 1]) / span, 0.0f, 1.0f);
    lc->phase_to_time[k] = ts[i - 1] + u * (ts[i] - ts[i - 1]);
  }
  lc->cycle_s = lc->phase_to_time[kPhaseTableSize] - lc->phase_to_time[0];
  return lc->cycle_s > 0.0f;
}

// Per frame, whether clip analysis has this foot in contact (`all_if_none`: every frame when the
// foot has no contact at all, as in a synthesised standing clip).
std::vector<uint8_t> contact_frames(const ClipAnalysis& a, int side, int n, float fps,
                                    bool all_if_none) {
  std::vector<uint8_t> down(n, all_if_none && a.contacts[side].empty() ? 1 : 0);
  for (const TimeInterval& iv : a.contacts[side]) {
    const int first = static_cast<int>(std::lround(iv.start_s * fps));
    const int last = static_cast<int>(std::lround(iv.end_s * fps));
    for (int f = first; f <= last; ++f) down[((f % n) + n) % n] = 1;
  }
  return down;
}

// The runs of frames between two contacts of a foot, as (first frame, length); a loop's run across
// its end continues at its start (first + k taken modulo the frame count). A take's runs cut by
// its first or last frame count as well.
std::vector<std::pair<int, int>> swing_runs(const std::vector<uint8_t>& down, bool loops) {
  const int n = static_cast<int>(down.size());
  std::vector<std::pair<int, int>> runs;
  int start = 0;
  if (loops) {  // start the scan on a contact frame so no run is split by the wrap
    while (start < n && !down[start]) ++start;
    if (start == n) return {{0, n}};
  }
  for (int k = 0; k < n;) {
    const int f = (start + k) % n;
    if (down[f]) {
      ++k;
      continue;
    }
    int len = 0;
    while (k + len < n && !down[(start + k + len) % n]) ++len;
    runs.emplace_back(f, len);
    k += len;
  }
  return runs;
}

// Per frame of an in-place clip, each foot's toe and ankle in its model space.
struct FootTracks {
  std::vector<glm::vec3> toe[2], ankle[2];
};
FootTracks foot_tracks(const Clip& c, const Skeleton& sk) {
  FootTracks t;
  std::vector<glm::mat4> model(sk.num_joints());
  for (int f = 0; f < c.num_frames; ++f) {
    clip_frame_model(c, sk, f, model);
    for (int s = 0; s < 2; ++s) {
      t.toe[s].push_back(translation_of(model[sk.toe(static_cast<Side>(s))]));
      t.ankle[s].push_back(translation_of(model[sk.ankle(static_cast<Side>(s))]));
    }
  }
  return t;
}

// The in-place clip's feet move backward under the body at this velocity: added back, they stand.
glm::vec3 travel_velocity(const LocomotionClip& lc) {
  return lc.speed_m_s * glm::vec3(std::sin(lc.direction_rad), 0.0f, std::cos(lc.direction_rad));
}

// How fast the in-place clip's planted balls are carried backward under the body [m/s]: the
// median, over the frames a lock may start on (the ball at rest), of the toe's speed along the
// travel direction (a median: the frames where the ball comes to rest or starts to roll off count
// for little). The speed at which its feet stand still on the ground: a clean capture's is
// its root speed; a retargeted take whose feet slide in its own root motion has another, and the
// pinned feet follow this one. 0 without such frames.
float stance_sweep_speed(const LocomotionClip& lc, const Skeleton& sk) {
  const Clip& c = lc.clip;
  const int n = c.num_frames;
  if (n < 3) return 0.0f;
  const FootTracks tracks = foot_tracks(c, sk);
  const glm::vec3 dir(std::sin(lc.direction_rad), 0.0f, std::cos(lc.direction_rad));
  std::vector<float> sweep;
  for (int s = 0; s < 2; ++s) {
    for (int f = 0; f < n; ++f) {
      if (!lc.plant[s][f]) continue;
      // Centred difference; across a loop's wrap the frames are a frame apart as anywhere else.
      const int a = f > 0 ? f - 1 : (c.loops ? n - 1 : f);
      const int b = f + 1 < n ? f + 1 : (c.loops ? 0 : f);
      const int frames = (b - a + n) % n;
      if (frames == 0) continue;
      sweep.push_back(-glm::dot(tracks.toe[s][b] - tracks.toe[s][a], dir) * c.fps /
                      static_cast<float>(frames));
    }
  }
  return sweep.empty() ? 0.0f : percentile(std::move(sweep), 0.5);
}

constexpr float kGravity = 9.81f;          // [m/s^2]
constexpr float kTransitionFroude = 0.5f;  // walk-run transition (Alexander; GAIT.md's 2 m/s)

// Where a clip's ball rests, so a lock may start: slower than contact analysis's still speed at
// the body's travel speed, and than max_rest_m_s (LocomotionLibrary::max_rest_speed_m_s: a
// runner's ball rests as a walker's does) [m/s]. Gait clips and transitions alike.
float lock_rest_speed(float travel_m_s, float max_rest_m_s) {
  return std::min(still_speed_m_s(travel_m_s), max_rest_m_s);
}

// max_rest_m_s: LocomotionLibrary::max_rest_speed_m_s.
void fill_contacts_and_heights(LocomotionClip* lc, const Skeleton& sk, float max_rest_m_s) {
  // Each foot's contacts as clip analysis finds them.
  const std::vector<uint8_t> down[2] = {
      contact_frames(lc->analysis, 0, lc->clip.num_frames, lc->clip.fps, false),
      contact_frames(lc->analysis, 1, lc->clip.num_frames, lc->clip.fps, false)};
  // A walk has double support: both feet in contact on some frame (a run has a flight instead).
  lc->double_support = false;
  for (int f = 0; f < lc->clip.num_frames; ++f) {
    lc->double_support = lc->double_support || (down[0][f] && down[1][f]);
  }
  const Clip& c = lc->clip;
  const int n = c.num_frames;
  const FootTracks tracks = foot_tracks(c, sk);
  const std::vector<glm::vec3>(&toe)[2] = tracks.toe;
  const std::vector<glm::vec3>(&ankle)[2] = tracks.ankle;
  const glm::vec3 travel = travel_velocity(*lc);
  for (int s = 0; s < 2; ++s) {
    lc->plant[s].assign(n, 0);
    lc->hold[s].assign(n, 0);
    lc->toe_height_m[s].assign(n, 0.0f);
    float min_t = 1e9f, min_a = 1e9f;
    for (int f = 0; f < n; ++f) {
      min_t = std::min(min_t, toe[s][f].y);
      min_a = std::min(min_a, ankle[s][f].y);
    }
    lc->toe_floor_m[s] = min_t;
    lc->ankle_floor_m[s] = min_a;
    // A lock may start where clip analysis has the foot in contact.
    lc->plant[s] = down[s];
    // It is kept while the ball of the foot still bears weight: no higher above the ground, and
    // no faster over it, than it ever is in this clip's own contacts (the heel may rise: the foot
    // pivots on the ball at heel-off).
    std::vector<float> speed(n);
    for (int f = 0; f < n; ++f) {
      const int g = f + 1 < n ? f + 1 : (c.loops ? 0 : f - 1);
      glm::vec3 vel = (toe[s][g] - toe[s][f]) * (g > f ? c.fps : -c.fps) + travel;
      if (g == 0) vel = travel;  // across a loop's wrap: no reliable difference
      speed[f] = std::hypot(vel.x, vel.z);
      lc->toe_height_m[s][f] = toe[s][f].y - min_t;
    }
    lc->toe_speed_m_s[s] = speed;
    // Across a loop's wrap the speed above is the travel speed: the frame before's is nearer.
    if (c.loops && n > 1) lc->toe_speed_m_s[s][n - 1] = speed[n - 2];
    // A lock pins the ball: it may start only where the ball itself has come to rest (slower
    // than half the travel speed, as contact analysis judges a planted point), not while the heel
    // strikes or the foot rolls off its tip with the ball still moving: each contact's ends are
    // trimmed to where the ball rests. (Clips authored in place are judged by the direction their
    // stance foot is carried, not its speed over the ground, which keyframes need not keep.)
    if (!lc->analysis.in_place) {
      const float rest = lock_rest_speed(glm::length(travel), max_rest_m_s);
      std::vector<uint8_t>& pl = lc->plant[s];
      int first_free = -1;
      for (int f = 0; f < n && first_free < 0; ++f) {
        if (!pl[f]) first_free = f;
      }
      if (first_free >= 0) {
        const int span = c.loops ? n : n - first_free;
        for (int dir : {1, -1}) {
          bool trimming = false;
          for (int k = 0; k < span; ++k) {
            const int f = dir > 0 ? (first_free + k) % n : ((first_free - k) % n + n) % n;
            if (!c.loops && (f < first_free) == (dir > 0)) continue;
            if (!pl[f]) {
              trimming = true;  // a contact begins (or, backward, ends) after this frame
              continue;
            }
            if (trimming && speed[f] > rest) {
              // Keep the contact's last frame: never trim one away.
              const int next = dir > 0 ? (f + 1) % n : (f - 1 + n) % n;
              if (pl[next]) {
                pl[f] = 0;
                continue;
              }
            }
            trimming = false;
          }
        }
      }
    }
    std::vector<float> contact_h, contact_v;
    for (int f = 0; f < n; ++f) {
      if (!lc->plant[s][f]) continue;
      contact_h.push_back(lc->toe_height_m[s][f]);
      contact_v.push_back(speed[f]);
    }
    if (contact_h.empty()) continue;
    // The 90th percentile, not the maximum: one jittery capture frame must not hold a swing.
    const float max_h = percentile(std::move(contact_h), 0.9), max_v = percentile(contact_v, 0.9);
    // Swing progress between the end of one contact and the start of the next.
    lc->swing_progress[s].assign(n, 0.0f);
    for (const auto& [first, len] : swing_runs(lc->plant[s], c.loops)) {
      for (int k = 0; k < len; ++k) lc->swing_progress[s][(first + k) % n] = (k + 0.5f) / len;
    }
    // While the other foot is down too (double support), a ball still as low as in contact keeps
    // its weight however fast the clip moves it: a foot on the floor does not slide, it pushes off
    // until it lifts (a keyframed trailing toe that sweeps forward along the floor as the lead heel
    // lands is lifted later, in the air, by the release).
    for (int f = 0; f < n; ++f) {
      const bool low = lc->toe_height_m[s][f] <= max_h;
      lc->hold[s][f] = lc->plant[s][f] || (low && (speed[f] <= max_v || down[1 - s][f] != 0));
    }
  }
}

float max_rotation_step(const Clip& c, int num_joints) {
  const float dt = 1.0f / kMetricRateHz;
  std::vector<glm::quat> r0(num_joints), r1(num_joints);
  std::vector<glm::vec3> t(num_joints);
  float best = 0.0f;
  const float duration = c.duration_s();
  const int steps = static_cast<int>(duration / dt);
  SampleClipJob{&c, 0.0f, r0, t}.run();
  for (int i = 1; i <= steps; ++i) {
    SampleClipJob{&c, i * dt, r1, t}.run();
    for (int j = 1; j < num_joints; ++j) {  // joint 0 carries the facing, not a local bend
      const float d = std::abs(glm::dot(r0[j], r1[j]));
      best = std::max(best, 2.0f * std::acos(std::min(1.0f, d)));
    }
    std::swap(r0, r1);
  }
  return best;
}

// Heights [m] of each foot's toe and ankle on the frames clip analysis marks as contact (every
// frame for a clip without contacts of that foot, e.g. a standing clip).
struct ContactHeights {
  std::vector<float> toe[2], ankle[2];
};

void add_contact_heights(const LocomotionClip& lc, const Skeleton& sk, ContactHeights* out) {
  const Clip& c = lc.clip;
  std::vector<glm::mat4> model(sk.num_joints());
  const std::vector<uint8_t> contact[2] = {
      contact_frames(lc.analysis, 0, c.num_frames, c.fps, true),
      contact_frames(lc.analysis, 1, c.num_frames, c.fps, true)};
  for (int f = 0; f < c.num_frames; ++f) {
    if (!contact[0][f] && !contact[1][f]) continue;
    clip_frame_model(c, sk, f, model);
    for (int s = 0; s < 2; ++s) {
      if (!contact[s][f]) continue;
      out->toe[s].push_back(model[sk.toe(static_cast<Side>(s))][3].y);
      out->ankle[s].push_back(model[sk.ankle(static_cast<Side>(s))][3].y);
    }
  }
}

// LocomotionLibrary::knee_bend_local from the gait clips (every frame whose knee is bent by at
// least kBent).
void lib_knee_bends(const Skeleton& sk, const std::vector<LocomotionClip>& clips,
                    glm::vec3 (&out)[2]) {
  const float kBent = std::cos(20.0f * std::numbers::pi_v<float> / 180.0f);
  glm::vec3 sum[2] = {glm::vec3(0.0f), glm::vec3(0.0f)};
  std::vector<glm::mat4> model(sk.num_joints());
  for (const LocomotionClip& lc : clips) {
    if (!lc.gait) continue;
    for (int f = 0; f < lc.clip.num_frames; ++f) {
      clip_frame_model(lc.clip, sk, f, model);
      for (int s = 0; s < 2; ++s) {
        const Side sd = static_cast<Side>(s);
        const glm::vec3 hip(model[sk.hip(sd)][3]), knee(model[sk.knee(sd)][3]),
            ankle(model[sk.ankle(sd)][3]);
        const glm::vec3 thigh = knee - hip, shin = ankle - knee;
        const float lt = glm::length(thigh), ls = glm::length(shin);
        if (!(lt > 1e-4f && ls > 1e-4f) || glm::dot(thigh, shin) > kBent * lt * ls) continue;
        const glm::vec3 axis = glm::normalize(ankle - hip);
        const glm::vec3 off = thigh - axis * glm::dot(thigh, axis);
        const float lo = glm::length(off);
        if (!(lo > 1e-6f)) continue;
        const glm::quat hip_q = glm::normalize(glm::quat_cast(glm::mat3(model[sk.hip(sd)])));
        sum[s] += glm::inverse(hip_q) * (off / lo);
      }
    }
  }
  for (int s = 0; s < 2; ++s) {
    const float l = glm::length(sum[s]);
    out[s] = l > 1e-6f ? sum[s] / l : glm::vec3(0.0f);
  }
}

// Where a clip puts a flat foot's toe: a low percentile of its toe heights over its contact frames
// (both feet); the rest of a contact rolls onto the heel or the ball, higher.
constexpr float kFlatPercentile = 0.1f;
float flat_toe_height(const LocomotionClip& lc, const Skeleton& sk) {
  ContactHeights h;
  add_contact_heights(lc, sk, &h);
  std::vector<float> both = h.toe[0];
  both.insert(both.end(), h.toe[1].begin(), h.toe[1].end());
  return percentile(std::move(both), kFlatPercentile);
}

// Moves a clip up or down by dy [m] (the root joint's translation), keeping everything else.
// A doubtful clip is played as captured: no lock is planted or held on contacts that cannot be
// trusted.
void drop_doubtful_locks(LocomotionClip* lc) {
  if (lc->doubts.empty()) return;
  for (int s = 0; s < 2; ++s) {
    std::fill(lc->plant[s].begin(), lc->plant[s].end(), uint8_t{0});
    std::fill(lc->hold[s].begin(), lc->hold[s].end(), uint8_t{0});
  }
}

void raise_clip(LocomotionClip* lc, float dy) {
  for (Clip* c : {&lc->clip, &lc->source}) {  // the take as captured stands on the same floor
    for (int f = 0; f < c->num_frames; ++f) {
      c->translations[static_cast<size_t>(f) * c->num_joints].y += dy;
    }
  }
}

// How many times a clip is upsampled for playback (LocomotionClip::played): a capture below
// kPlaybackFps to at least that (24 fps to 72, 30 fps to 60), at most kMaxUpsampling times (a
// file that claims a frame every few seconds is not made into millions of frames); authored keys
// never (a glTF's LINEAR keys are meant to be joined by straight segments), nor a capture at 60
// fps or more.
int playback_upsampling(const Clip& c) {
  constexpr float kPlaybackFps = 60.0f;
  constexpr int kMaxUpsampling = 4;
  if (!c.sampled_capture || !(c.fps > 0.0f) || c.fps >= kPlaybackFps) return 1;
  return std::min(kMaxUpsampling, static_cast<int>(std::ceil(kPlaybackFps / c.fps - 1e-3f)));
}

// A standing clip taken from the frame of a gait clip where both feet are planted closest
// together, for libraries without an idle (e.g. a walk and a run).
LocomotionClip synthesise_idle(const LocomotionClip& gait, const Skeleton& sk) {
  const Clip& g = gait.clip;
  std::vector<glm::mat4> model(sk.num_joints());
  int best = 0;
  float best_score = 1e9f;
  for (int f = 0; f < g.num_frames; ++f) {
    clip_frame_model(g, sk, f, model);
    glm::vec3 d =
        translation_of(model[sk.toe(Side::kLeft)]) - translation_of(model[sk.toe(Side::kRight)]);
    const float planted = gait.toe_height_m[0][f] + gait.toe_height_m[1][f] +
                          (gait.plant[0][f] && gait.plant[1][f] ? 0.0f : 1.0f);
    const float score = std::hypot(d.x, d.z) + 4.0f * planted;
    if (score < best_score) {
      best_score = score;
      best = f;
    }
  }
  LocomotionClip idle;
  idle.clip.name = "idle (from " + g.name + ")";
  idle.clip.source = g.source;
  idle.clip.fps = g.fps;
  idle.clip.num_frames = 2;
  idle.clip.num_joints = g.num_joints;
  idle.clip.loops = true;
  for (int k = 0; k < 2; ++k) {
    idle.clip.rotations.insert(idle.clip.rotations.end(), g.frame_rotations(best),
                               g.frame_rotations(best) + g.num_joints);
    idle.clip.translations.insert(idle.clip.translations.end(), g.frame_translations(best),
                                  g.frame_translations(best) + g.num_joints);
  }
  idle.cycle_s = idle.clip.duration_s();
  for (int s = 0; s < 2; ++s) {
    idle.plant[s].assign(2, 1);
    idle.hold[s].assign(2, 1);
    idle.toe_height_m[s].assign(2, 0.0f);
    idle.toe_speed_m_s[s].assign(2, 0.0f);
  }
  return idle;
}

// A take's stretch (a start or a stop, with its root motion) as a transition clip: facing turned
// to +z, the root's travel taken out frame by frame along its path smoothed over a quarter
// second (the pelvis keeps its sway), contacts and toe heights from clip analysis of the take's
// stretch. `speed` gets that smoothed path's speed per frame. max_rest_m_s:
// LocomotionLibrary::max_rest_speed_m_s.
LocomotionClip make_transition_clip(const Clip& span, const Skeleton& sk, std::vector<float>* speed,
                                    float max_rest_m_s) {
  LocomotionClip lc;
  lc.analysis = analyze_clip(span, sk);
  lc.source = span;
  lc.transition = true;
  Clip c = span;
  c.loops = false;
  const int n = c.num_frames, nj = c.num_joints;
  std::vector<glm::mat4> model(nj);
  const std::vector<glm::vec3> hips_xz = hips_ground_track(c, sk);
  const int half = std::max(1, static_cast<int>(std::lround(0.125f * c.fps)));
  std::vector<glm::vec3> path(n);
  for (int f = 0; f < n; ++f) {
    // Centred on the frame (narrower near the ends, so the path does not lag there).
    const int h = std::min({half, f, n - 1 - f});
    glm::vec3 sum(0.0f);
    for (int k = f - h; k <= f + h; ++k) sum += hips_xz[k];
    path[f] = sum / static_cast<float>(2 * h + 1);
  }
  speed->assign(n, 0.0f);
  for (int f = 0; f < n; ++f) {
    const int a = std::max(0, f - 1), b = std::min(n - 1, f + 1);
    const glm::vec3 d = path[b] - path[a];
    (*speed)[f] = b > a ? std::hypot(d.x, d.z) * c.fps / static_cast<float>(b - a) : 0.0f;
  }
  const glm::quat yaw = glm::angleAxis(-clip_facing(c, sk), glm::vec3(0, 1, 0));
  for (int f = 0; f < n; ++f) {
    glm::quat& r = c.rotations[static_cast<size_t>(f) * nj];
    glm::vec3& t = c.translations[static_cast<size_t>(f) * nj];
    r = yaw * r;
    t = yaw * (t - path[f]);
  }
  lc.clip = std::move(c);
  lc.cycle_s = lc.clip.duration_s();
  // Contacts as clip analysis finds them in the take. As for a gait clip, a lock may start only
  // where the ball has come to rest over the ground (slower than half the root's speed, and never
  // a stricter limit than contact analysis's, nor faster than the library's largest rest speed:
  // a jog's ball is still landing at half its speed), not while the heel strikes or rolls off;
  // it is kept through the contact while the ball is no faster than in 90% of those frames.
  // Toe heights and swing progress as for a gait clip.
  const FootTracks tracks = foot_tracks(lc.clip, sk);
  const FootTracks world = foot_tracks(span, sk);  // with the take's root motion
  const std::vector<uint8_t> down[2] = {contact_frames(lc.analysis, 0, n, lc.clip.fps, false),
                                        contact_frames(lc.analysis, 1, n, lc.clip.fps, false)};
  for (int s = 0; s < 2; ++s) {
    const std::vector<uint8_t>& contact = down[s];
    const std::vector<uint8_t>& other = down[1 - s];
    std::vector<float> ground(n, 0.0f);
    for (int f = 0; f < n; ++f) {
      const int a = std::max(0, f - 1), b = std::min(n - 1, f + 1);
      const glm::vec3 d = world.toe[s][b] - world.toe[s][a];
      ground[f] = b > a ? std::hypot(d.x, d.z) * lc.clip.fps / static_cast<float>(b - a) : 0.0f;
    }
    lc.plant[s].assign(n, 0);
    lc.hold[s].assign(n, 0);
    lc.toe_speed_m_s[s] = ground;
    std::vector<float> rested;
    for (int f = 0; f < n; ++f) {
      const float rest = lock_rest_speed((*speed)[f], max_rest_m_s);
      lc.plant[s][f] = contact[f] && ground[f] <= rest;
      if (lc.plant[s][f]) rested.push_back(ground[f]);
    }
    const float max_v = rested.empty() ? 0.0f : percentile(std::move(rested), 0.9);
    // As in a gait clip, a ball in contact while the other foot is down too pushes off, however
    // fast the take moves it, until it leaves the ground.
    for (int f = 0; f < n; ++f) {
      lc.hold[s][f] = lc.plant[s][f] || (contact[f] && (ground[f] <= max_v || other[f]));
    }
    lc.toe_height_m[s].assign(n, 0.0f);
    float min_t = 1e9f, min_a = 1e9f;
    for (int f = 0; f < n; ++f) {
      min_t = std::min(min_t, tracks.toe[s][f].y);
      min_a = std::min(min_a, tracks.ankle[s][f].y);
    }
    for (int f = 0; f < n; ++f) lc.toe_height_m[s][f] = tracks.toe[s][f].y - min_t;
    lc.toe_floor_m[s] = min_t;
    lc.ankle_floor_m[s] = min_a;
    lc.swing_progress[s].assign(n, 0.0f);
    for (const auto& [first, len] : swing_runs(lc.plant[s], false)) {
      for (int k = 0; k < len; ++k) lc.swing_progress[s][first + k] = (k + 0.5f) / len;
    }
  }
  for (int f = 0; f < n; ++f) {
    lc.double_support = lc.double_support || (lc.plant[0][f] && lc.plant[1][f]);
  }
  return lc;
}

// The gait phase at which a cycle's foot `side` lands (its contact begins), or -1 without one.
float landing_phase(const LocomotionClip& cycle, int side) {
  const float dur = cycle.clip.duration_s();
  for (const TimeInterval& c : cycle.analysis.contacts[side]) {
    float u = (c.start_s - cycle.phase_to_time[0]) / std::max(cycle.cycle_s, 1e-4f);
    u -= std::floor(u);
    if (cycle.clip.loops || c.start_s < dur) return u;
  }
  return -1.0f;
}

// Transition::phase_track of a transition clip `lc` joining `cycle` (its landings: contacts that
// begin after the clip's first frame, which is a cut, not a landing).
std::vector<float> transition_phase_track(const LocomotionClip& lc, const LocomotionClip& cycle,
                                          float fps, float frame_s) {
  struct Landing {
    float t;
    int side;
  };
  std::vector<Landing> landings;
  for (int s = 0; s < 2; ++s) {
    float last = -1e9f;
    for (const TimeInterval& c : lc.analysis.contacts[s]) {
      // A foot that lands again within half a cycle of its last landing scuffed: not a step.
      if (c.start_s >= 0.5f * frame_s && landing_phase(cycle, s) >= 0.0f &&
          c.start_s - last >= 0.5f * cycle.cycle_s) {
        landings.push_back({c.start_s, s});
      }
      last = c.start_s;
    }
  }
  // In time; on one frame the left first.
  std::sort(landings.begin(), landings.end(), [](const Landing& a, const Landing& b) {
    return a.t < b.t || (a.t == b.t && a.side < b.side);
  });
  // Unwrapped: each landing is the cycle's landing of that foot, the next one on from the last
  // (half a cycle for the other foot; the same foot twice in a row, a whole cycle).
  std::vector<float> at(landings.size());
  for (size_t i = 0; i < landings.size(); ++i) {
    const float p = landing_phase(cycle, landings[i].side);
    if (i == 0) {
      at[i] = p;
      continue;
    }
    float d = p - at[i - 1];
    d -= std::floor(d);
    if (d < 0.25f) d += 1.0f;
    at[i] = at[i - 1] + d;
  }
  const int n = lc.clip.num_frames;
  std::vector<float> track(static_cast<size_t>(std::max(n, 0)), 0.0f);
  for (int f = 0; f < n; ++f) {
    const float t = static_cast<float>(f) / fps;
    if (landings.empty()) {
      track[f] = t / cycle.cycle_s;
    } else if (t <= landings.front().t) {
      track[f] = at.front() - (landings.front().t - t) / cycle.cycle_s;
    } else if (t >= landings.back().t) {
      track[f] = at.back() + (t - landings.back().t) / cycle.cycle_s;
    } else {
      size_t i = 1;
      while (landings[i].t < t) ++i;
      const float u = (t - landings[i - 1].t) / std::max(landings[i].t - landings[i - 1].t, 1e-6f);
      track[f] = at[i - 1] + u * (at[i] - at[i - 1]);
    }
  }
  return track;
}
}  // namespace

const char* transition_kind_name(TransitionKind kind) {
  return kind == TransitionKind::kStart ? "start" : "stop";
}

float Transition::speed_at(float t_s) const {
  if (speed_m_s.empty()) return 0.0f;
  const float x = std::clamp(t_s * fps, 0.0f, static_cast<float>(speed_m_s.size() - 1));
  const size_t i = std::min(static_cast<size_t>(x), speed_m_s.size() - 1);
  const size_t j = std::min(i + 1, speed_m_s.size() - 1);
  return speed_m_s[i] + (x - static_cast<float>(i)) * (speed_m_s[j] - speed_m_s[i]);
}

float Transition::phase_at(float t_s) const {
  const size_t n = phase_track.size();
  if (n == 0) return 0.0f;
  if (n == 1) return phase_track[0] - std::floor(phase_track[0]);
  // Between frames linearly (beyond the ends along the end's slope, the cycle's rate; the clock
  // that reads it stops at the clip's end).
  const float x = t_s * fps;
  const size_t i = x <= 0.0f ? 0 : std::min(static_cast<size_t>(x), n - 2);
  const float p =
      phase_track[i] + (x - static_cast<float>(i)) * (phase_track[i + 1] - phase_track[i]);
  return p - std::floor(p);
}

float Transition::phase_rate_at(float t_s) const {
  const size_t n = phase_track.size();
  if (n < 2) return 1.0f;
  const float x = t_s * fps;
  const size_t i = x <= 0.0f ? 0 : std::min(static_cast<size_t>(x), n - 2);
  return std::max((phase_track[i + 1] - phase_track[i]) * fps, 1e-3f);
}

float LocomotionClip::time_at_phase(float phase) const {
  const float x = std::clamp(phase - std::floor(phase), 0.0f, 1.0f) * kPhaseTableSize;
  const int i = std::min(static_cast<int>(x), kPhaseTableSize - 1);
  const float u = x - i;
  return phase_to_time[i] + u * (phase_to_time[i + 1] - phase_to_time[i]);
}

float LocomotionClip::time_per_phase(float phase) const {
  const float x = std::clamp(phase - std::floor(phase), 0.0f, 1.0f) * kPhaseTableSize;
  const int i = std::min(static_cast<int>(x), kPhaseTableSize - 1);
  return (phase_to_time[i + 1] - phase_to_time[i]) * kPhaseTableSize;
}

std::vector<std::string> describe_takes(const LocomotionLibrary& library) {
  std::vector<std::string> out;
  for (const TakeReport& t : library.takes) {
    std::string line = t.name + ":";
    char buf[96];
    for (const TakeSegment& s : t.segmentation.segments) {
      std::snprintf(buf, sizeof buf, " %s %.2f-%.2f s", segment_kind_name(s.kind), s.span.start_s,
                    s.span.end_s);
      line += buf;
    }
    line += "; cut into:";
    if (t.clips.empty()) line += " nothing";
    for (const std::string& c : t.clips) line += " '" + c + "'";
    for (const std::string& p : t.segmentation.problems) line += "; " + p;
    out.push_back(std::move(line));
  }
  return out;
}

void set_lift_phases(LocomotionClip* lc) {
  const int nf = lc->clip.num_frames;
  for (int s = 0; s < 2; ++s) {
    lc->lift_phase[s] = -1.0f;
    // Doubtful contacts (no foot lock is planted on them) give no lift to set off from either.
    if (!lc->doubts.empty()) continue;
    if (lc->swing_progress[s].size() != static_cast<size_t>(nf) || nf < 2) continue;
    // The phase sample whose frame is earliest in a swing (the least progress above 0).
    float least = 2.0f;
    for (int k = 0; k < kPhaseTableSize; ++k) {
      const float phase = static_cast<float>(k) / kPhaseTableSize;
      const int f =
          lc->wrap_frame(static_cast<int>(std::lround(lc->time_at_phase(phase) * lc->clip.fps)));
      const float progress = lc->swing_progress[s][f];
      if (progress > 0.0f && progress < least) {
        least = progress;
        lc->lift_phase[s] = phase;
      }
    }
  }
}

std::vector<std::string> gait_doubts(const LocomotionClip& lc) {
  std::vector<std::string> doubts;
  const ClipAnalysis& a = lc.analysis;
  const float duration = lc.clip.duration_s();
  const bool loops = lc.clip.loops;
  const float t0 = lc.phase_to_time[0], cycle = lc.cycle_s;
  if (!(cycle > 0.0f) || duration <= 0.0f) return {"no gait cycle"};
  const char* names[2] = {"left", "right"};
  const float half_frame = 0.5f / lc.clip.fps;
  char buf[256];
  // Contact starts of each foot inside the cycle [t0, t0 + cycle) (a loop's contacts repeat every
  // duration), and the time each foot is down in it.
  std::vector<float> starts[2];
  float down[2] = {0.0f, 0.0f};
  for (int s = 0; s < 2; ++s) {
    for (const TimeInterval& c : a.contacts[s]) {
      for (int k = loops ? -2 : 0; k <= (loops ? 2 : 0); ++k) {
        const float b = c.start_s + k * duration, e = c.end_s + k * duration;
        // Half a frame early: the cycle starts on a landing, and ends where the next one is.
        if (b >= t0 - half_frame && b < t0 + cycle - half_frame) starts[s].push_back(b);
        down[s] += std::max(0.0f, std::min(e, t0 + cycle) - std::max(b, t0));
      }
    }
    std::sort(starts[s].begin(), starts[s].end());
  }
  // A stride holds one landing of each foot.
  for (int s = 0; s < 2; ++s) {
    if (starts[s].size() != 1) {
      std::snprintf(buf, sizeof(buf),
                    "its cycle of %.2f s holds %zu landings of the %s foot (one stride holds one "
                    "of each foot)",
                    cycle, starts[s].size(), names[s]);
      doubts.emplace_back(buf);
    }
  }
  // The feet take turns half a stride apart (a limp shifts that a little, a hop or a gallop
  // lands both together).
  if (starts[0].size() == 1 && starts[1].size() == 1) {
    float offset = std::fmod((starts[1][0] - starts[0][0]) / cycle, 1.0f);
    if (offset < 0.0f) offset += 1.0f;
    if (offset < 0.25f || offset > 0.75f) {
      std::snprintf(buf, sizeof(buf),
                    "the right foot lands %.0f%% of a stride after the left (feet that take "
                    "turns land about 50%% apart)",
                    100.0f * offset);
      doubts.emplace_back(buf);
    }
  }
  // Over the whole clip, between two landings of one foot the other foot lands.
  std::vector<std::pair<float, int>> all;
  for (int s = 0; s < 2; ++s) {
    for (const TimeInterval& c : a.contacts[s]) all.emplace_back(c.start_s, s);
  }
  std::sort(all.begin(), all.end());
  for (size_t i = 1; i < all.size(); ++i) {
    if (all[i].second != all[i - 1].second) continue;
    std::snprintf(buf, sizeof(buf),
                  "contacts do not alternate: the %s foot lands at %.2f s and %.2f s with no "
                  "landing of the other between",
                  names[all[i].second], all[i - 1].first, all[i].first);
    doubts.emplace_back(buf);
    break;
  }
  // Both feet of a gait are down about as long (a walk about 60% of the stride each, a run 35%).
  const float longer = std::max(down[0], down[1]), shorter = std::min(down[0], down[1]);
  if (longer > 0.0f && shorter < 0.5f * longer) {
    std::snprintf(buf, sizeof(buf),
                  "the left foot is down %.2f s of the stride and the right %.2f s (the feet of "
                  "a gait are down about as long)",
                  down[0], down[1]);
    doubts.emplace_back(buf);
  }
  return doubts;
}

std::vector<std::string> describe_doubts(const LocomotionLibrary& library) {
  std::vector<std::string> lines;
  for (const LocomotionClip& c : library.clips) {
    if (c.doubts.empty()) continue;
    std::string line = c.clip.name + ": ";
    for (size_t i = 0; i < c.doubts.size(); ++i) line += (i ? "; " : "") + c.doubts[i];
    lines.push_back(std::move(line) + "; played without foot locks");
  }
  if (gait_analysis_doubtful(library)) {
    lines.push_back("every gait clip is doubtful: apm plays this library as naive does");
  }
  return lines;
}

std::vector<std::string> describe_gaps(const LocomotionLibrary& library,
                                       const MediatorParams& params) {
  std::vector<std::string> lines;
  if (library.forward_group < 0 ||
      library.forward_group >= static_cast<int>(library.groups.size())) {
    return lines;
  }
  const float min_rate = params.min_playback_rate, max_rate = params.max_playback_rate;
  int walk = -1, run = -1;  // the fastest walk and the slowest run, by speed
  for (int c : library.groups[library.forward_group].clips) {
    const LocomotionClip& clip = library.clips[c];
    if (!clip.gait) continue;
    if (clip.double_support) {
      walk = c;
    } else if (run < 0) {
      run = c;
    }
  }
  char buf[512];
  if (walk < 0 && run >= 0) {
    const LocomotionClip& r = library.clips[run];
    std::snprintf(buf, sizeof(buf),
                  "no walking clip (every forward gait clip has a flight phase): agents slower "
                  "than %.2f m/s (%s, %.2f m/s, at the slowest playback rate, %.2fx) are shown "
                  "running slowly, blended with standing below that; a run's flight and push-off "
                  "at walking speeds float and slide (METRICS.md float_ratio, support slide)",
                  r.speed_m_s * min_rate, r.clip.name.c_str(), r.speed_m_s, min_rate);
    lines.emplace_back(buf);
  } else if (walk >= 0 && run >= 0) {
    const LocomotionClip& w = library.clips[walk];
    const LocomotionClip& r = library.clips[run];
    const float top = w.speed_m_s * max_rate, bottom = r.speed_m_s * min_rate;
    if (top < bottom) {
      std::snprintf(buf, sizeof(buf),
                    "no clip plays alone between %.2f m/s (%s, %.2f m/s, at the fastest playback "
                    "rate, %.2fx) and %.2f m/s (%s, %.2f m/s, at the slowest, %.2fx): a walk and "
                    "a run are blended there, the walk's double support with the run's flight",
                    top, w.clip.name.c_str(), w.speed_m_s, max_rate, bottom, r.clip.name.c_str(),
                    r.speed_m_s, min_rate);
      lines.emplace_back(buf);
    }
  }
  if (walk >= 0 && run < 0) {
    // The feedback pass's top speed: the fastest forward clip at the fastest rate, stretched.
    const LocomotionClip& w = library.clips[walk];
    const float top = w.speed_m_s * max_rate * (1.0f + params.max_stride_warp);
    std::snprintf(buf, sizeof(buf),
                  "no running clip: agents faster than %.2f m/s (%s, %.2f m/s, at the fastest "
                  "playback rate, %.2fx) are slowed to it through feedback where the simulator "
                  "takes it; a recorded crowd takes none, and its faster pedestrians' stance feet "
                  "are dragged and land hard (METRICS.md support slide, limb pops)",
                  top, w.clip.name.c_str(), w.speed_m_s, max_rate);
    lines.emplace_back(buf);
  }
  return lines;
}

bool gait_analysis_doubtful(const LocomotionLibrary& library) {
  int gait = 0;
  for (const LocomotionClip& c : library.clips) {
    if (!c.gait) continue;
    ++gait;
    if (c.doubts.empty()) return false;
  }
  return gait > 0;
}

std::vector<std::string> describe_left_out(const LocomotionLibrary& library) {
  std::vector<std::string> lines;
  std::vector<std::pair<std::string, std::string>> keys;  // (file, why) in order of appearance
  for (const LocomotionLibrary::LeftOut& l : library.left_out) {
    const auto key = std::make_pair(l.file, l.why);
    const size_t k = std::find(keys.begin(), keys.end(), key) - keys.begin();
    if (k == keys.size()) {
      keys.push_back(key);
      lines.push_back(l.file + ": " + l.why + ": " + l.clip);
    } else {
      lines[k] += ", " + l.clip;
    }
  }
  return lines;
}

std::vector<std::string> LocomotionLibrary::clip_names() const {
  std::vector<std::string> names;
  for (const LocomotionClip& c : clips) names.push_back(c.clip.name);
  return names;
}

std::vector<int> retarget_joint_map(const Skeleton& src, const Skeleton& dst) {
  const int nd = dst.num_joints(), ns = src.num_joints();
  std::vector<int> map(nd, -1);
  std::vector<uint8_t> used(ns, 0);
  auto take = [&](int d, int s) {
    if (d < 0 || s < 0 || map[d] >= 0 || used[s]) return;
    map[d] = s;
    used[s] = 1;
  };
  // Roles first (they hold whatever the naming convention), then equal names.
  for (int r = 0; r < kNumJointRoles; ++r) {
    take(dst.role(static_cast<JointRole>(r)), src.role(static_cast<JointRole>(r)));
  }
  for (int d = 0; d < nd; ++d) take(d, src.find(dst.names[d]));
  // Then down unmapped chains from mapped joints (elbows and wrists below the shoulders, a neck
  // between chest and head): the child with the most descendants on each side.
  auto descendants = [](const Skeleton& sk) {
    std::vector<int> n(sk.num_joints(), 0);
    for (int j = sk.num_joints() - 1; j > 0; --j) {
      if (sk.parents[j] >= 0) n[sk.parents[j]] += n[j] + 1;
    }
    return n;
  };
  const std::vector<int> dn = descendants(dst), sn = descendants(src);
  for (int d = 0; d < nd; ++d) {  // parents come before children: chains extend in one pass
    if (map[d] < 0) continue;
    int best_d = -1, best_s = -1;
    for (int c = 0; c < nd; ++c) {
      if (dst.parents[c] == d && map[c] < 0 && (best_d < 0 || dn[c] > dn[best_d])) best_d = c;
    }
    for (int c = 0; c < ns; ++c) {
      if (src.parents[c] == map[d] && !used[c] && (best_s < 0 || sn[c] > sn[best_s])) best_s = c;
    }
    // Only where each side has a single way down (a hand's five fingers stay at rest).
    int kids_d = 0, kids_s = 0;
    for (int c = 0; c < nd; ++c) kids_d += dst.parents[c] == d && map[c] < 0;
    for (int c = 0; c < ns; ++c) kids_s += src.parents[c] == map[d] && !used[c];
    if (kids_d == 1 && kids_s == 1) take(best_d, best_s);
  }
  return map;
}

Clip retarget_clip(const Clip& clip, const Skeleton& src, const Skeleton& dst, float root_scale) {
  Clip out;
  out.name = clip.name;
  out.source = clip.source;
  out.fps = clip.fps;
  out.num_frames = clip.num_frames;
  out.num_joints = dst.num_joints();
  out.loops = clip.loops;
  out.sampled_capture = clip.sampled_capture;
  const int nd = dst.num_joints();
  const std::vector<int> map = retarget_joint_map(src, dst);
  // Rest-pose aware: a mapped joint takes the source joint's model-space rotation relative to the
  // source rest pose, applied to the destination rest pose (skeletons whose joint frames differ
  // still bend alike); unmapped joints keep their rest rotation under their parent.
  const std::vector<glm::mat4> src_rest = rest_model(src), dst_rest = rest_model(dst);
  std::vector<glm::quat> src_rest_inv(src.num_joints()), dst_rest_rot(nd);
  for (int j = 0; j < src.num_joints(); ++j) {
    src_rest_inv[j] = glm::inverse(glm::normalize(glm::quat_cast(glm::mat3(src_rest[j]))));
  }
  for (int j = 0; j < nd; ++j)
    dst_rest_rot[j] = glm::normalize(glm::quat_cast(glm::mat3(dst_rest[j])));
  // Rest poses need not agree (arms along the body in one, out to the sides in the other): each
  // mapped bone is first turned, in model space, from its own rest direction onto the source
  // bone's rest direction (toward the one mapped child both have), so that the source's rest pose
  // gives the source's shape. A bone without a mapped child (a hand) or with several (the hips)
  // keeps its parent's turn.
  std::vector<glm::quat> align(nd, glm::quat(1, 0, 0, 0));
  for (int j = 0; j < nd; ++j) {
    const int parent = dst.parents[j];
    if (parent >= 0) align[j] = align[parent];
    if (map[j] < 0) continue;
    int child = -1, mapped_children = 0;
    for (int c = j + 1; c < nd; ++c) {
      if (dst.parents[c] == j && map[c] >= 0) {
        child = c;
        ++mapped_children;
      }
    }
    if (mapped_children != 1) continue;
    const glm::vec3 d_dst = translation_of(dst_rest[child]) - translation_of(dst_rest[j]);
    const glm::vec3 d_src = translation_of(src_rest[map[child]]) - translation_of(src_rest[map[j]]);
    if (glm::length(d_dst) < 1e-6f || glm::length(d_src) < 1e-6f) continue;
    align[j] = glm::rotation(glm::normalize(d_dst), glm::normalize(d_src));
  }
  const int src_hips = src.role(JointRole::kHips), dst_hips = dst.role(JointRole::kHips);
  out.rotations.resize(static_cast<size_t>(out.num_frames) * nd);
  out.translations.resize(out.rotations.size());
  std::vector<glm::mat4> model(src.num_joints());
  std::vector<glm::quat> dst_model(nd);
  for (int f = 0; f < clip.num_frames; ++f) {
    clip_frame_model(clip, src, f, model);
    for (int j = 0; j < nd; ++j) {
      const size_t o = static_cast<size_t>(f) * nd + j;
      const int parent = dst.parents[j];
      const int s = map[j];
      if (s >= 0) {
        const glm::quat src_rot = glm::normalize(glm::quat_cast(glm::mat3(model[s])));
        dst_model[j] = glm::normalize(src_rot * src_rest_inv[s] * align[j] * dst_rest_rot[j]);
      } else {
        dst_model[j] =
            (parent < 0 ? glm::quat(1, 0, 0, 0) : dst_model[parent]) * dst.rest_rotations[j];
      }
      out.rotations[o] = parent < 0
                             ? dst_model[j]
                             : glm::normalize(glm::inverse(dst_model[parent]) * dst_model[j]);
      out.translations[o] = dst.rest_translations[j];
    }
    // The root travels as the source hips do, scaled by the ratio of leg lengths (an extra root
    // above the hips on either side is carried along).
    const size_t root = static_cast<size_t>(f) * nd;
    if (src_hips >= 0 && dst_hips >= 0) {
      const glm::vec3 hips = translation_of(model[src_hips]) * root_scale;
      // Root -> hips offset in the root's frame (rest pose of any joints in between).
      const glm::vec3 chain = glm::inverse(dst_rest_rot[0]) *
                              (translation_of(dst_rest[dst_hips]) - translation_of(dst_rest[0]));
      out.translations[root] = hips - dst_model[0] * chain;
    } else if (map[0] >= 0) {
      out.translations[root] = clip.frame_translations(f)[map[0]] * root_scale;
    }
  }
  return out;
}

Result<LocomotionLibrary> build_locomotion_library(const std::vector<ClipSet>& sets) {
  if (sets.empty()) return Status::Error("clip library: no clip sets given");
  LocomotionLibrary lib;
  lib.skeleton = sets[0].skeleton;
  lib.mesh = sets[0].mesh;
  const Skeleton& sk = *lib.skeleton;
  if (!sk.has_locomotion_roles()) {
    return Status::Error(sets[0].source +
                         ": skeleton lacks the hips/leg joints the mediator needs (no joint found "
                         "for " +
                         missing_locomotion_roles(sk) + "); " + role_manifest_hint());
  }
  const std::vector<glm::mat4> rest = rest_model(sk);
  for (int s = 0; s < 2; ++s) lib.leg_length_m[s] = leg_length(sk, rest, static_cast<Side>(s));
  const float dst_leg = 0.5f * (lib.leg_length_m[0] + lib.leg_length_m[1]);
  lib.max_rest_speed_m_s = still_speed_m_s(std::sqrt(kTransitionFroude * kGravity * dst_leg));

  // Every clip that does not make it into the library is named with the reason, never dropped
  // silently.
  auto leave_out = [&](const Clip& c, const std::string& why) {
    lib.left_out.push_back({c.name, c.source, why});
  };
  std::vector<LocomotionClip> idles;
  struct Fallback {
    Clip loop, take;
    // The loop's contacts where they are known (a step and its mirror image), else analysed.
    bool has_contacts = false;
    std::array<std::vector<TimeInterval>, 2> contacts;
  };
  std::vector<Fallback> fallbacks;
  struct PendingTransition {
    Clip span;
    TransitionKind kind;
  };
  std::vector<PendingTransition> pending;
  std::vector<int16_t> mirror_map;  // made when a take needs a mirrored step
  // One clip of the library: analysed, made in place, classified as gait or standing.
  // `take`: the capture it was cut from, on a level floor (the metrics' reference; null for a
  // clip authored in place or a second cut of the same take).
  auto add = [&](Clip c, const Clip* take,
                 const std::array<std::vector<TimeInterval>, 2>* contacts = nullptr) {
    LocomotionClip lc;
    lc.analysis = analyze_clip(c, sk);
    if (contacts != nullptr) {
      lc.analysis.contacts[0] = (*contacts)[0];
      lc.analysis.contacts[1] = (*contacts)[1];
    }
    const float facing = clip_facing(c, sk);
    lc.speed_m_s = lc.analysis.native_speed_m_s;
    lc.direction_rad = lc.analysis.direction_rad;
    lc.clip = make_in_place(c, sk, lc.analysis, facing);
    if (take != nullptr) lc.source = *take;
    fill_contacts_and_heights(&lc, sk, lib.max_rest_speed_m_s);
    const bool both_feet = !lc.analysis.contacts[0].empty() && !lc.analysis.contacts[1].empty();
    char speed[64];  // "%.2f" of any float fits
    std::snprintf(speed, sizeof(speed), "%.2f m/s", lc.speed_m_s);
    const std::string no_contacts =
        std::string("clip analysis finds no foot contact on ") +
        (lc.analysis.contacts[0].empty() && lc.analysis.contacts[1].empty()
             ? "either foot"
             : (lc.analysis.contacts[0].empty() ? "the left foot" : "the right foot"));
    if (lc.speed_m_s < kMinGaitSpeed) {
      if (!both_feet) {
        return leave_out(lc.clip, "standing (" + std::string(speed) + ") but " + no_contacts);
      }
      lc.cycle_s = lc.clip.duration_s();
      idles.push_back(std::move(lc));
      return;
    }
    if (lc.speed_m_s > kMaxGaitSpeed) {
      return leave_out(lc.clip, "travels at " + std::string(speed) + ", faster than any gait");
    }
    if (!both_feet) {
      return leave_out(lc.clip, "travels at " + std::string(speed) + " but " + no_contacts);
    }
    lc.gait = true;
    // A take with root motion travels at its root's speed; its planted feet may not keep to it
    // (a retargeted capture's slide in its own root motion). The mediator plays a clip at the
    // speed its feet stand still at: a foot pinned where the clip plants it then stays under the
    // clip's foot through the stance, and the leg is not stretched past its reach by the stance's
    // end. (A clip authored in place has its speed from its stance foot already.)
    if (!lc.analysis.in_place) {
      const float sweep = stance_sweep_speed(lc, sk);
      if (sweep > kMinGaitSpeed) lc.speed_m_s = sweep;
    }
    lc.cycle_start_s = lc.analysis.contacts[0][0].start_s;
    if (!lc.clip.loops) lc.cycle_start_s = lc.analysis.cycle.start_s;
    if (!build_phase_table(&lc)) {
      return leave_out(lc.clip, "no full gait cycle (the contacts do not make one stride)");
    }
    lc.doubts = gait_doubts(lc);
    drop_doubtful_locks(&lc);
    lib.clips.push_back(std::move(lc));
  };
  for (const ClipSet& set : sets) {
    const Skeleton& src = *set.skeleton;
    if (!src.has_locomotion_roles()) {
      return Status::Error(set.source + ": cannot retarget its clips onto the library skeleton (" +
                           sets[0].source + "): its skeleton lacks the hips/leg joints (no joint " +
                           "found for " + missing_locomotion_roles(src) + "); " +
                           role_manifest_hint());
    }
    const std::vector<glm::mat4> src_rest = rest_model(src);
    const float src_leg =
        0.5f * (leg_length(src, src_rest, Side::kLeft) + leg_length(src, src_rest, Side::kRight));
    const bool same = set.skeleton == lib.skeleton;
    for (const Clip& original : set.clips) {
      if (name_excluded(original.name)) {
        leave_out(original, "its name says it is not walking or running");
        continue;
      }
      if (original.num_frames < 2) {
        leave_out(original, "a single frame");
        continue;
      }
      Clip clip = same ? original : retarget_clip(original, src, sk, dst_leg / src_leg);
      const ClipAnalysis whole = analyze_clip(clip, sk);
      if (clip.loops || whole.in_place) {
        const Clip as_captured = clip;
        add(std::move(clip), whole.in_place ? nullptr : &as_captured);
        continue;
      }
      // A take with root motion: levelled onto its fitted floor, then cut into its steady cycles
      // (loops) and its standing stretches (a still pose); starts, stops and turns are reported.
      for (int f = 0; f < clip.num_frames; ++f) {
        clip.translations[static_cast<size_t>(f) * clip.num_joints].y -=
            whole.ground_slope_m_s * (f / clip.fps);
      }
      const ClipAnalysis levelled = analyze_clip(clip, sk);
      const TakeSegmentation seg = segment_take(clip, sk, levelled);
      TakeReport report{clip.name, seg, {}};
      if (seg.fallback_cycle && seg.mirror_step >= 0) {
        // No steady stride, but a step that walks: it and its mirror image make the cycle (only
        // for a library without any steady cycle), with the contacts the take has in that step.
        if (mirror_map.empty()) mirror_map = mirror_joint_map(sk);
        MirroredCycle mc =
            extract_mirrored_cycle(clip, sk, levelled, seg.steps[seg.mirror_step], mirror_map);
        Fallback fb{std::move(mc.loop), clip, true, std::move(mc.contacts)};
        fallbacks.push_back(std::move(fb));
      }
      for (size_t k = 0; k < seg.cycles.size() && !(seg.fallback_cycle && seg.mirror_step >= 0);
           ++k) {
        const Stride& stride = seg.strides[seg.cycles[k]];
        Clip loop = extract_cycle(clip, sk, levelled, stride);
        if (k > 0) loop.name += " #" + std::to_string(k + 1);
        if (seg.fallback_cycle) {
          // A stride that speeds up or slows down walks at no one speed: only for a library
          // without any steady cycle. (Analysed as a loop of its own: where that finds its
          // contacts doubtful, it is played without foot locks.)
          fallbacks.push_back({std::move(loop), clip});
          continue;
        }
        // A steady cycle keeps the contacts the take's analysis found in its stride.
        const int first = std::clamp(static_cast<int>(std::lround(stride.span.start_s * clip.fps)),
                                     0, clip.num_frames - 1);
        const auto contacts = stride_contacts(levelled, first, loop.num_frames, clip.fps);
        report.clips.push_back(loop.name);
        add(std::move(loop), k == 0 ? &clip : nullptr, &contacts);
      }
      for (const TakeSegment& s : seg.segments) {
        if (s.kind != SegmentKind::kIdle || s.span.end_s - s.span.start_s < 0.2f) continue;
        // Standing: the stretch's middle frame held still.
        const float mid = 0.5f * (s.span.start_s + s.span.end_s);
        Clip still = extract_span(clip, {mid, mid});
        still.loops = true;
        still.rotations.insert(still.rotations.end(), still.rotations.begin(),
                               still.rotations.end());
        still.translations.insert(still.translations.end(), still.translations.begin(),
                                  still.translations.end());
        still.num_frames = 2;
        still.name += " (standing)";
        report.clips.push_back(still.name);
        add(std::move(still), nullptr);
      }
      // Starts and stops: kept as transitions (made once the library's cycles are known), each
      // with a little of the standing beside it (a start from rest, a stop that comes to rest).
      for (size_t k = 0; k < seg.segments.size(); ++k) {
        const TakeSegment& s = seg.segments[k];
        if (s.kind != SegmentKind::kStart && s.kind != SegmentKind::kStop) continue;
        const bool start = s.kind == SegmentKind::kStart;
        const TakeSegment* idle =
            start ? (k > 0 ? &seg.segments[k - 1] : nullptr)
                  : (k + 1 < seg.segments.size() ? &seg.segments[k + 1] : nullptr);
        if (idle != nullptr && idle->kind != SegmentKind::kIdle) idle = nullptr;
        TimeInterval span = s.span;
        if (idle != nullptr) {
          if (start)
            span.start_s = std::max(idle->span.start_s, span.start_s - kTransitionRest);
          else
            span.end_s = std::min(idle->span.end_s, span.end_s + kTransitionRest);
        }
        if (span.end_s - span.start_s < kMinTransition) continue;
        Clip cut = extract_span(clip, span);
        cut.name += start ? " (start)" : " (stop)";
        report.clips.push_back(cut.name);
        if (!start) {
          // A stop ends on the foot it lands last; its mirror image ends on the other, so an
          // agent that slows down can begin the stop on whichever foot lands first rather than
          // wait up to a stride for one of them.
          if (mirror_map.empty()) mirror_map = mirror_joint_map(sk);
          const TravelPlane plane = travel_plane(cut, sk);
          Clip mirrored = mirror_clip(cut, sk, mirror_map, plane.point, plane.normal);
          mirrored.name = clip.name + " (stop, mirrored)";
          report.clips.push_back(mirrored.name);
          pending.push_back({std::move(mirrored), TransitionKind::kStop});
        }
        pending.push_back({std::move(cut), start ? TransitionKind::kStart : TransitionKind::kStop});
      }
      if (report.clips.empty() && seg.cycles.empty() && seg.mirror_step < 0) {
        leave_out(clip, "a take with no stride to loop and no standing stretch (see its segments)");
      }
      lib.takes.push_back(std::move(report));
    }
  }
  if (lib.clips.empty()) {
    for (Fallback& f : fallbacks) {
      add(std::move(f.loop), &f.take, f.has_contacts ? &f.contacts : nullptr);
    }
  } else {
    for (const Fallback& f : fallbacks) {
      leave_out(f.loop, f.has_contacts ? "a step and its mirror image (the take has no steady "
                                         "stride), not needed beside steady cycles"
                                       : "a stride that speeds up or slows down, not needed "
                                         "beside steady cycles");
    }
  }
  if (lib.clips.empty()) {
    std::string why;
    for (const std::string& l : describe_left_out(lib)) why += "; " + l;
    return Status::Error(std::string("clip library: no walking or running clip found (a clip ") +
                         "needs a travel speed of 0.25-12 m/s and foot contacts on both feet)" +
                         why);
  }
  // Direction groups: forward, left, right, backward, or their own direction.
  for (int i = 0; i < static_cast<int>(lib.clips.size()); ++i) {
    float d = lib.clips[i].direction_rad;
    for (float snap : {0.0f, kPi / 2, -kPi / 2, kPi}) {
      if (std::abs(wrap_pi(d - snap)) < glm::radians(30.0f)) d = snap == -kPi ? kPi : snap;
    }
    if (std::abs(wrap_pi(d - kPi)) < 1e-4f) d = kPi;
    auto it = std::find_if(lib.groups.begin(), lib.groups.end(), [&](const DirectionGroup& g) {
      return std::abs(g.direction_rad - d) < 1e-4f;
    });
    if (it == lib.groups.end()) {
      lib.groups.push_back({d, {}});
      it = lib.groups.end() - 1;
    }
    it->clips.push_back(i);
    lib.clips[i].direction_offset_rad = wrap_pi(lib.clips[i].direction_rad - d);
    lib.max_speed_m_s = std::max(lib.max_speed_m_s, lib.clips[i].speed_m_s);
  }
  std::sort(lib.groups.begin(), lib.groups.end(),
            [](const DirectionGroup& a, const DirectionGroup& b) {
              return a.direction_rad < b.direction_rad;
            });
  for (size_t g = 0; g < lib.groups.size(); ++g) {
    auto& v = lib.groups[g].clips;
    std::sort(v.begin(), v.end(),
              [&](int a, int b) { return lib.clips[a].speed_m_s < lib.clips[b].speed_m_s; });
    if (lib.groups[g].direction_rad == 0.0f) lib.forward_group = static_cast<int>(g);
  }
  if (lib.forward_group < 0) {
    return Status::Error(
        "clip library: no forward walking clip found (all clips travel sideways or "
        "backward)");
  }
  // Idle: the calmest standing clip, else a standing frame of the slowest forward clip.
  if (!idles.empty()) {
    // A clip named idle first (the plainest name: "Idle_Loop" before "Idle_Talking_Loop"), then
    // the calmest feet.
    auto rank = [](const LocomotionClip& c) {
      return std::make_tuple(lower_ascii(c.clip.name).find("idle") == std::string::npos ? 1 : 0,
                             c.clip.name.size(), c.analysis.floor.mean_cm_s);
    };
    auto calm = std::min_element(idles.begin(), idles.end(),
                                 [&](const auto& a, const auto& b) { return rank(a) < rank(b); });
    for (const LocomotionClip& other : idles) {
      if (&other != &*calm) {
        leave_out(other.clip, "standing; the library stands with " + calm->clip.name);
      }
    }
    lib.clips.push_back(std::move(*calm));
  } else {
    lib.clips.push_back(
        synthesise_idle(lib.clips[lib.groups[lib.forward_group].clips.front()], sk));
  }
  lib.idle = static_cast<int>(lib.clips.size()) - 1;

  // Transitions, after the standing clip: each joins the forward cycle nearest its moving speed,
  // at the phase where that cycle's foot landed as long before as the transition's own did.
  for (PendingTransition& p : pending) {
    Transition tr;
    tr.kind = p.kind;
    LocomotionClip lc = make_transition_clip(p.span, sk, &tr.speed_m_s, lib.max_rest_speed_m_s);
    tr.fps = lc.clip.fps;
    tr.duration_s = lc.clip.duration_s();
    const bool start = p.kind == TransitionKind::kStart;
    {
      // Over its moving end's last (first) quarter second.
      const int nf = static_cast<int>(tr.speed_m_s.size());
      const int k = std::clamp(static_cast<int>(std::lround(0.25f * tr.fps)), 1, nf);
      float sum = 0.0f;
      for (int f = 0; f < k; ++f) sum += tr.speed_m_s[start ? nf - 1 - f : f];
      tr.moving_speed_m_s = sum / static_cast<float>(k);
    }
    {
      const float still = SegmentationThresholds{}.idle_speed_m_s;
      const int nf = static_cast<int>(tr.speed_m_s.size());
      int a = 0, b = nf - 1;
      if (start) {
        for (int f = 0; f < nf; ++f) {
          if (tr.speed_m_s[f] < still) a = std::min(f + 1, nf - 1);
        }
      } else {
        for (int f = nf - 1; f >= 0; --f) {
          if (tr.speed_m_s[f] < still) b = std::max(f - 1, 0);
        }
      }
      tr.moving_from_s = a / tr.fps;
      tr.moving_to_s = b / tr.fps;
    }
    // The moving end's landing: a start's last contact to begin, a stop's first (one that
    // begins after the stretch's first frame, so it is a landing, not the cut).
    const float frame = 1.0f / tr.fps;
    int side = -1;
    float land = 0.0f;
    for (int s = 0; s < 2; ++s) {
      for (const TimeInterval& c : lc.analysis.contacts[s]) {
        if (c.start_s < 0.5f * frame) continue;
        if (side < 0 || (start ? c.start_s > land : c.start_s < land)) {
          side = s;
          land = c.start_s;
        }
      }
    }
    // The lead foot: a start's first to lift off, a stop's last to land.
    if (start) {
      float lift = 1e9f;
      for (int s = 0; s < 2; ++s) {
        for (const TimeInterval& c : lc.analysis.contacts[s]) {
          if (c.end_s < tr.duration_s - 0.5f * frame && c.end_s < lift) {
            lift = c.end_s;
            tr.lead_foot = s;
          }
        }
      }
    } else {
      float last = -1.0f;
      for (int s = 0; s < 2; ++s) {
        for (const TimeInterval& c : lc.analysis.contacts[s]) {
          if (c.start_s > last) {
            last = c.start_s;
            tr.lead_foot = s;
          }
        }
      }
    }
    const DirectionGroup& fg = lib.groups[lib.forward_group];
    float best = 1e9f;
    for (int c : fg.clips) {
      const float d = std::abs(lib.clips[c].speed_m_s - tr.moving_speed_m_s);
      if (d < best) {
        best = d;
        tr.cycle_clip = c;
      }
    }
    const float lp = side >= 0 ? landing_phase(lib.clips[tr.cycle_clip], side) : -1.0f;
    if (lp < 0.0f || tr.moving_speed_m_s < kMinGaitSpeed) {
      leave_out(lc.clip, std::string("a ") + transition_kind_name(p.kind) +
                             " whose moving end has no landing or no speed to join a cycle at");
      continue;
    }
    const float cycle_s = lib.clips[tr.cycle_clip].cycle_s;
    float phase = start ? lp + (tr.duration_s - land) / cycle_s : lp - land / cycle_s;
    tr.cycle_phase = phase - std::floor(phase);
    tr.phase_track = transition_phase_track(lc, lib.clips[tr.cycle_clip], tr.fps, frame);
    tr.clip = static_cast<int>(lib.clips.size());
    lib.clips.push_back(std::move(lc));
    lib.transitions.push_back(std::move(tr));
  }

  // One floor for every clip: captures (and actors) stand at different heights, so each clip is
  // raised or lowered until its flat feet stand where the clips' flat feet stand on the median.
  {
    std::vector<float> planted(lib.clips.size());
    std::vector<float> gait_planted;
    for (size_t i = 0; i < lib.clips.size(); ++i) {
      planted[i] = flat_toe_height(lib.clips[i], sk);
      if (lib.clips[i].gait) gait_planted.push_back(planted[i]);
    }
    const float common = percentile(std::move(gait_planted), 0.5);
    for (size_t i = 0; i < lib.clips.size(); ++i) {
      LocomotionClip& c = lib.clips[i];
      if (std::abs(common - planted[i]) < 1e-6f) continue;
      raise_clip(&c, common - planted[i]);
      if (c.gait) {
        fill_contacts_and_heights(&c, sk, lib.max_rest_speed_m_s);
        drop_doubtful_locks(&c);  // the refill above set them again
      } else {
        for (int s = 0; s < 2; ++s) {
          c.toe_floor_m[s] += common - planted[i];
          c.ankle_floor_m[s] += common - planted[i];
        }
      }
    }
    // The floor of METRICS.md v2: where planted feet are, over the locomotion clips.
    ContactHeights h;
    for (const LocomotionClip& c : lib.clips) {
      if (c.gait) add_contact_heights(c, sk, &h);
    }
    for (int s = 0; s < 2; ++s) {
      lib.planted_toe_m[s] = percentile(h.toe[s], 0.5);
      lib.planted_ankle_m[s] = percentile(h.ankle[s], 0.5);
    }
    lib_knee_bends(sk, lib.clips, lib.knee_bend_local);
    // The METRICS.md floor is the median height of planted toes, which roll onto heel and ball
    // above a flat foot: the feet are drawn this much higher so a flat foot stands on that floor.
    lib.ground_lift_m =
        std::max(0.0f, 0.5f * (lib.planted_toe_m[0] + lib.planted_toe_m[1]) - common);
    // Swing height: the peak toe height of every swing (between two contacts) of the slowest
    // forward clip (toe_height_m is above the clip's lowest toe, toe_floor_m).
    const LocomotionClip& slow = lib.clips[lib.groups[lib.forward_group].clips.front()];
    std::vector<float> peaks;
    for (int s = 0; s < 2; ++s) {
      const int nf = slow.clip.num_frames;
      for (const auto& [first, len] : swing_runs(slow.plant[s], slow.clip.loops)) {
        float peak = 0.0f;
        for (int k = 0; k < len; ++k) peak = std::max(peak, slow.toe_height_m[s][(first + k) % nf]);
        peak += slow.toe_floor_m[s] - lib.planted_toe_m[s];
        if (peak > 0.0f) peaks.push_back(peak);
      }
    }
    if (!peaks.empty()) lib.swing_height_m = percentile(std::move(peaks), 0.5);
    // Swing speed: the peak horizontal speed of the toe over the ground in each swing of that
    // clip, played at its native speed (the median over its swings).
    {
      const int nf = slow.clip.num_frames;
      const glm::vec3 travel = travel_velocity(slow);
      const FootTracks tracks = foot_tracks(slow.clip, sk);
      const std::vector<glm::vec3>(&toe)[2] = tracks.toe;
      std::vector<float> speeds;
      for (int s = 0; s < 2; ++s) {
        for (const auto& [first, len] : swing_runs(slow.plant[s], slow.clip.loops)) {
          float peak = 0.0f;
          for (int k = 0; k + 1 < len; ++k) {
            const int f = (first + k) % nf, g = (first + k + 1) % nf;
            if (g < f) continue;  // across a loop's wrap: no reliable difference
            const glm::vec3 v = (toe[s][g] - toe[s][f]) * slow.clip.fps + travel;
            peak = std::max(peak, std::hypot(v.x, v.z));
          }
          if (peak > 0.0f) speeds.push_back(peak);
        }
      }
      if (!speeds.empty()) lib.swing_speed_m_s = percentile(std::move(speeds), 0.5);
    }
  }
  for (int s = 0; s < 2; ++s) {
    lib.toe_floor_m[s] = 1e9f;
    lib.ankle_floor_m[s] = 1e9f;
    for (const LocomotionClip& c : lib.clips) {
      if (!c.gait) continue;
      lib.toe_floor_m[s] = std::min(lib.toe_floor_m[s], c.toe_floor_m[s]);
      lib.ankle_floor_m[s] = std::min(lib.ankle_floor_m[s], c.ankle_floor_m[s]);
    }
  }
  for (const LocomotionClip& c : lib.clips) {
    lib.max_rotation_step_rad =
        std::max(lib.max_rotation_step_rad, max_rotation_step(c.clip, sk.num_joints()));
  }
  for (LocomotionClip& c : lib.clips) {
    if (c.gait) set_lift_phases(&c);
  }
  for (LocomotionClip& c : lib.clips) {
    const int k = playback_upsampling(c.clip);
    if (k > 1) c.played = upsample_clip(c.clip, k, sk);
  }
  {
    const float hip_height = 0.5f * (lib.leg_length_m[0] + lib.leg_length_m[1] +
                                     lib.planted_ankle_m[0] + lib.planted_ankle_m[1]);
    if (hip_height > 0.0f) {
      lib.walk_run_speed_m_s = std::sqrt(kTransitionFroude * kGravity * hip_height);
    }
  }
  return lib;
}

}  // namespace gk
