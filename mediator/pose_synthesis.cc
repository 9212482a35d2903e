#include "mediator/pose_synthesis.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "animation/fast_atan2.h"
#include "animation/joint_list_fk.h"
#include "animation/pose_jobs.h"
#include "animation/quat_sse.h"
#include "mediator/coarse_pose.h"
#include "mediator/heel_pivot.h"
#include "mediator/springs.h"

namespace gk {

struct PoseSynthesizer::Scratch {
  std::vector<glm::quat> rot;    // 2 * kMaxBlendLayers * joints (a layer and its seam sample)
  std::vector<glm::vec3> trans;  // 2 * kMaxBlendLayers * joints
  // The agent's local translations: needed only while it is posed, so kept per thread (in the
  // caches) rather than per slot (a crowd's worth of memory traffic each frame).
  std::vector<glm::vec3> local_trans;
  std::vector<glm::quat> coarse_rot;    // the coarse joints' blended pose (pose_coarse)
  std::vector<glm::vec3> coarse_trans;
  // The agent's world joints (when world_ is streamed: world_of) and local rotations while it is
  // posed (L1-resident throughout); kept in world_ and local_rot_ once it is posed.
  std::vector<glm::mat4> world;
  std::vector<glm::quat> local_rot;
};

namespace {

glm::mat4 root_placement(const glm::vec2& xz, float yaw) {
  glm::mat4 m = glm::mat4_cast(glm::angleAxis(yaw, glm::vec3(0, 1, 0)));
  m[3] = glm::vec4(xz.x, 0.0f, xz.y, 1.0f);
  return m;
}

// How far a foot must move over the floor along u (unit, horizontal) for a leg of `reach` to
// reach its ankle, at p from the hip: the smaller root of |p + t u| = reach; 0 when it reaches
// already, and the closest approach when no move does.
float move_to_reach(const glm::vec3& p, const glm::vec3& u, float reach) {
  const float pp = glm::dot(p, p);
  if (pp <= reach * reach) return 0.0f;
  const float pu = glm::dot(p, u);
  return std::max(0.0f, -pu - std::sqrt(std::max(0.0f, pu * pu - pp + reach * reach)));
}

glm::quat rotation_of(const glm::mat4& m) { return glm::normalize(glm::quat_cast(glm::mat3(m))); }

// The pelvis is lowered so pinned feet stay within kDropReach of the leg length, by at most
// kMaxDrop, on a critically damped spring of halflife kDropHalflife (no vertical snap).
constexpr float kDropReach = 0.99f;
constexpr float kMaxDrop = 0.04f;       // [m]
constexpr float kDropHalflife = 0.05f;  // [s]

// Legs straighten smoothly over the last part of their reach (soft IK): near full extension a
// knee's position changes ever faster with the foot's distance, and a hard clamp snaps it.
constexpr float kIkMaxExtension = 0.999f;
constexpr float kIkSoften = 0.98f;
// How far the leg IK's pole leans the way the clips' knees bend, beyond the drawn knee's own
// offset from the hip-ankle line [fraction of the leg's length]: the offset of a knee bent by
// about 12 degrees, so a knee bent more keeps the direction it is drawn with.
constexpr float kKneeBendBias = 0.05f;

// critical_spring, skipped when it is at rest on a goal of 0: it would stay there.
void settle_spring(float& x, float& v, float goal, const SpringStep& step) {
  if (x == 0.0f && v == 0.0f && goal == 0.0f) return;
  critical_spring(x, v, goal, step);
}

using heel_pivot::heel_off_pivot;
using heel_pivot::heel_to_floor;
using heel_pivot::on_heel;
constexpr float kHeelHalflife = 0.05f;    // [s] a raised heel settles back this fast
constexpr float kHeelUpHalflife = 0.02f;  // [s] and rises this fast

// A take (not a loop) replays one stride of itself: its last pose is not quite its first, so over
// the stride's last fifth the pose one stride earlier is blended in with this weight, and the wrap
// to the stride's start joins exactly.
float take_seam(const LocomotionClip& lc, float time) {
  if (!lc.gait || lc.clip.loops || time < lc.cycle_s) return 0.0f;
  const float u = (time - lc.phase_to_time[0]) / std::max(lc.cycle_s, 1e-4f);
  return smoothstep01((u - 0.8f) / 0.2f);
}

}  // namespace

float joint_heading(const glm::mat4& world, const glm::vec3& rest_forward) {
  // The world matrix's rotation applied to the rest-relative forward (no quaternion needed: the
  // joints' world matrices are rotations, and the heading ignores a length anyway).
  const float x =
      world[0].x * rest_forward.x + world[1].x * rest_forward.y + world[2].x * rest_forward.z;
  const float z =
      world[0].z * rest_forward.x + world[1].z * rest_forward.y + world[2].z * rest_forward.z;
  return fast_atan2(x, z);
}

PoseSynthesizer::PoseSynthesizer(const LocomotionLibrary& library, size_t capacity,
                                 bool make_palettes)
    : library_(library),
      skeleton_(*library.skeleton),
      num_joints_(library.skeleton->num_joints()),
      make_palettes_(make_palettes) {
  const size_t J = num_joints_;
  std::vector<glm::mat4> rest(J);
  LocalToModelJob{&skeleton_, skeleton_.rest_rotations, skeleton_.rest_translations,
                  glm::mat4(1.0f), rest}
      .run();
  rest_forward_.resize(J);
  for (size_t j = 0; j < J; ++j) {
    rest_forward_[j] = glm::inverse(rotation_of(rest[j])) * glm::vec3(0, 0, 1);
  }
  if (library.mesh && library.mesh->inverse_bind.size() == J) {
    inverse_bind_ = library.mesh->inverse_bind;
  } else {
    inverse_bind_.resize(J);
    for (size_t j = 0; j < J; ++j) inverse_bind_[j] = glm::inverse(rest[j]);
  }
  local_rot_.assign(capacity * J, glm::quat(1, 0, 0, 0));
  world_.assign(capacity * J, glm::mat4(1.0f));
  if (make_palettes_) {
    palette_.assign(capacity * J, glm::mat4(1.0f));
    palette_due_.assign(capacity, 0);
  }
  rot_change_.assign(capacity, 0.0f);
  torsion_.assign(capacity, 0.0f);
  pelvis_heading_.assign(capacity, 0.0f);
  upper_heading_.assign(capacity, 0.0f);
  has_prev_.assign(capacity, 0);
  prev_rot_valid_.assign(capacity, 0);
  drop_.assign(capacity, 0.0f);
  drop_rate_.assign(capacity, 0.0f);
  placed_xz_.assign(capacity, glm::vec2(0.0f));
  root_offset_.assign(capacity, glm::vec2(0.0f));
  support_reach_.assign(capacity, SupportReach{});
  locks_.lock.assign(capacity * 2, FootLock());
  locks_.anim_toe.assign(capacity * 2, glm::vec3(0.0f));
  locks_.drawn_toe.assign(capacity * 2, glm::vec3(0.0f));
  locks_.drawn_ankle.assign(capacity * 2, glm::vec3(0.0f));
  locks_.heel_pitch.assign(capacity * 2, 0.0f);
  locks_.heel_pitch_rate.assign(capacity * 2, 0.0f);
  locks_.lift_share.assign(capacity * 2, 0.0f);
  locks_.lift_lost.assign(capacity * 2, 0.0f);
  // Joints whose local translation is the same in every frame of every clip (a BVH's offsets:
  // every joint but the root in the built-in and CMU sets) are not sampled per agent: that value
  // is kept in each thread's local translations once, and only the others are sampled (when they
  // are few; a set with most joints translated samples them all four floats at a time).
  std::vector<glm::vec3> fixed_trans = skeleton_.rest_translations;
  fixed_trans.resize(J, glm::vec3(0.0f));
  bool clips_fit = !library.clips.empty();
  for (const LocomotionClip& lc : library.clips) {
    clips_fit = clips_fit && lc.clip.num_joints == num_joints_ && lc.clip.num_frames > 0;
  }
  if (clips_fit) {
    const Clip& first = library.clips.front().clip;
    for (size_t j = 0; j < J; ++j) {
      const glm::vec3 v = first.frame_translations(0)[j];
      bool same = true;
      for (const LocomotionClip& lc : library.clips) {
        for (int f = 0; same && f < lc.clip.num_frames; ++f) {
          same = lc.clip.frame_translations(f)[j] == v;
        }
      }
      if (same) {
        fixed_trans[j] = v;
      } else {
        translated_joints_.push_back(static_cast<int16_t>(j));
      }
    }
    if (2 * translated_joints_.size() > J) translated_joints_.clear();  // all, four-wide
    if (translated_joints_.empty()) fixed_trans.assign(J, glm::vec3(0.0f));
  }
  // Whole subtrees no clip moves (every frame's rotation and translation within kStill of the
  // first clip's first frame: export noise, as the mannequin's fingers carry) and of which the pose
  // stage reads nothing (no role joint, no spine joint) keep that pose: it is set in each thread's
  // scratch once and those joints are not sampled per agent. Only when they are many (a quarter
  // of the joints): a few would cost more in runs than they save.
  std::vector<glm::quat> fixed_rot(J, glm::quat(1, 0, 0, 0));
  if (clips_fit) {
    constexpr float kStill = 1e-5f;
    const Clip& first = library.clips.front().clip;
    std::vector<uint8_t> still(J, 1), read(J, 0);
    for (size_t j = 0; j < J; ++j) {
      const glm::quat q0 = first.frame_rotations(0)[j];
      const glm::vec3 v0 = first.frame_translations(0)[j];
      for (const LocomotionClip& lc : library.clips) {
        for (int f = 0; still[j] && f < lc.clip.num_frames; ++f) {
          glm::quat q = lc.clip.frame_rotations(f)[j];
          if (glm::dot(q, q0) < 0.0f) q = -q;
          const glm::vec4 dq(q.x - q0.x, q.y - q0.y, q.z - q0.z, q.w - q0.w);
          const glm::vec3 dv = lc.clip.frame_translations(f)[j] - v0;
          still[j] = glm::all(glm::lessThanEqual(glm::abs(dq), glm::vec4(kStill))) &&
                     glm::all(glm::lessThanEqual(glm::abs(dv), glm::vec3(kStill)));
        }
      }
    }
    for (int r = 0; r < kNumJointRoles; ++r) {
      const int j = skeleton_.role(static_cast<JointRole>(r));
      if (j >= 0 && j < num_joints_) read[j] = 1;
    }
    for (int16_t j : skeleton_.spine_chain) read[j] = 1;
    const auto ends = subtree_ends(skeleton_);
    std::vector<uint8_t> fixed(J, 0);
    size_t num_fixed = 0;
    for (int j = 1; j < num_joints_; ++j) {
      if (fixed[skeleton_.parents[j]]) {  // inside a fixed subtree
        fixed[j] = 1;
      } else {
        bool all = true;
        for (int k = j; all && k < ends[j]; ++k) all = still[k] && !read[k];
        fixed[j] = all;
      }
      num_fixed += fixed[j];
    }
    if (4 * num_fixed >= J) {
      fixed_rot_.assign(J, glm::quat(1, 0, 0, 0));
      fixed_trans_.assign(J, glm::vec3(0.0f));
      for (int j = 0; j < num_joints_; ++j) {
        std::vector<JointRun>& runs = fixed[j] ? fixed_runs_ : sampled_runs_;
        if (!runs.empty() && runs.back().to == j) {
          ++runs.back().to;
        } else {
          runs.push_back({j, j + 1});
        }
        if (!fixed[j]) continue;
        fixed_rot_[j] = fixed_rot[j] = glm::normalize(first.frame_rotations(0)[j]);
        fixed_trans_[j] = fixed_trans[j] = first.frame_translations(0)[j];
      }
    }
  }
  // The fixed joints' rotations are set in local_rot_ once (finish_pose writes the others).
  for (size_t slot = 0; slot < capacity; ++slot) {
    for (const JointRun& r : fixed_runs_) {
      std::copy(fixed_rot_.begin() + r.from, fixed_rot_.begin() + r.to,
                local_rot_.begin() + slot * J + r.from);
    }
  }
  // Per-thread sampling scratch, made once per worker thread on first use and kept.
  coarse_ = make_coarse_rig(library);
  const size_t K = static_cast<size_t>(coarse_.num_coarse);
  scratch_ = std::make_unique<tbb::enumerable_thread_specific<Scratch>>(
      [J, K, fixed_trans, fixed_rot] {
        Scratch s;
        s.rot.resize(2 * kMaxBlendLayers * J);
        s.trans.resize(2 * kMaxBlendLayers * J);
        s.local_trans = fixed_trans;  // the fixed ones stay; the others are sampled per agent
        s.coarse_rot.resize(K);
        s.coarse_trans.resize(K);
        s.world.resize(J);
        s.local_rot = fixed_rot;
        return s;
      });
  subtree_end_ = subtree_ends(skeleton_);
  for (Side side : {Side::kLeft, Side::kRight}) {
    const int hip = skeleton_.hip(side), knee = skeleton_.knee(side);
    JointRange& r = leg_range_[static_cast<int>(side)];
    r = subtree(hip);
    if (knee >= 0 && (knee < r.from || knee >= r.to)) {  // a knee outside its hip's subtree
      r = {std::max(0, std::min(hip, knee)), num_joints_};
    }
  }
  for (Side side : {Side::kLeft, Side::kRight}) {
    const int sd = static_cast<int>(side);
    const JointRange foot = subtree(skeleton_.ankle(side));
    leg_above_ankle_[sd] = leg_range_[sd];
    if (foot.from < foot.to && foot.from >= leg_range_[sd].from && foot.to == leg_range_[sd].to) {
      leg_above_ankle_[sd].to = foot.from;
    }
  }
  const std::vector<int16_t>& chain = skeleton_.spine_chain;
  const int hips = skeleton_.role(JointRole::kHips), chest = skeleton_.role(JointRole::kChest);
  can_twist_ = !chain.empty() && hips >= 0 && chest >= 0;  // as twist_spine requires
  if (can_twist_) {
    twist_range_ = subtree(chain.front());
    std::vector<uint8_t> read(J, 0);
    auto mark = [&](int j) {  // j and its ancestors inside the range
      for (; j >= twist_range_.from && j < twist_range_.to; j = skeleton_.parents[j]) read[j] = 1;
    };
    for (int16_t j : chain) mark(j);
    mark(hips);
    mark(chest);
    for (int j = twist_range_.from; j < twist_range_.to; ++j) {
      if (!read[j]) continue;
      if (!pre_twist_.empty() && pre_twist_.back().to == j) {
        ++pre_twist_.back().to;  // runs of joints in one pass (four at a time)
      } else {
        pre_twist_.push_back({j, j + 1});
      }
    }
  }
  if (can_twist_) {
    pre_twist_fk_ = range_list({0, twist_range_.from}, {});
    for (JointRange r : pre_twist_) {
      for (int j = r.from; j < r.to; ++j) pre_twist_fk_.push_back(static_cast<int16_t>(j));
    }
    for (int16_t j : range_list({twist_range_.to, num_joints_}, {})) pre_twist_fk_.push_back(j);
  }
  for (int sides = 1; sides < 4; ++sides) {
    auto pick = [&](int side, JointRange r) { return (sides >> side) & 1 ? r : JointRange{}; };
    leg_fk_[sides] = range_list(pick(0, leg_above_ankle_[0]), pick(1, leg_above_ankle_[1]));
    foot_fk_[sides] = range_list(pick(0, subtree(skeleton_.ankle(Side::kLeft))),
                                 pick(1, subtree(skeleton_.ankle(Side::kRight))));
  }
  // The pelvis is posed before the twist and the leg IK and neither moves it (outside their
  // ranges): its heading measured for the twist is the final one.
  if (can_twist_) {
    auto outside = [&](JointRange r) { return hips < r.from || hips >= r.to; };
    pelvis_stays_ = outside(twist_range_);
    for (Side side : {Side::kLeft, Side::kRight}) {
      pelvis_stays_ = pelvis_stays_ && outside(leg_above_ankle_[static_cast<int>(side)]) &&
                      outside(subtree(skeleton_.ankle(side)));
    }
  }
  affine_inverse_bind_ = is_affine(inverse_bind_);
  translation_inverse_bind_ = is_translation(inverse_bind_);
  // A crowd's palettes far larger than the caches are written past them (read only by the
  // upload, after the whole crowd is posed); a small crowd's stay cached for it.
  stream_palettes_ = palette_.size() * sizeof(glm::mat4) > (size_t{8} << 20);
  stream_world_ = world_.size() * sizeof(glm::mat4) > (size_t{8} << 20);
}

PoseSynthesizer::~PoseSynthesizer() = default;

void PoseSynthesizer::run(const AnimationPlans& pl, size_t n, const MediatorParams& P, float dt_s) {
  run(pl, n, P, dt_s, {});
}

void PoseSynthesizer::run(const AnimationPlans& pl, size_t n, const MediatorParams& P, float dt_s,
                          std::span<const uint8_t> detail) {
  tbb::enumerable_thread_specific<Scratch>& scratch = *scratch_;
  drop_step_ = spring_step(kDropHalflife, dt_s);
  heel_up_step_ = spring_step(kHeelUpHalflife, dt_s);
  heel_down_step_ = spring_step(kHeelHalflife, dt_s);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 32), [&](const tbb::blocked_range<size_t>& r) {
    Scratch& s = scratch.local();
    for (size_t i = r.begin(); i < r.end(); ++i) {
      const int slot = pl.slot_of_agent[i];
      const auto d = detail.empty() ? PoseDetail::kFull : static_cast<PoseDetail>(detail[slot]);
      // The next agent's pose arrays and clip frames are fetched while this one is posed (the
      // range's first, before it): its samples are written straight into its pose, which would
      // otherwise wait for those lines.
      if (i == r.begin()) prefetch_agent(pl, slot, detail);
      if (i + 1 < r.end()) prefetch_agent(pl, pl.slot_of_agent[i + 1], detail);
      if (d == PoseDetail::kHold && !pl.fresh[slot]) {
        hold_agent(pl, slot);
      } else {
        synthesize_agent(pl, P, slot, dt_s, s, d == PoseDetail::kHold ? PoseDetail::kLight : d);
      }
    }
    // The range's streamed world joints are ordered before the task's end tells anyone they are
    // done (one fence here, not one per agent: each waits for the stores before it to reach
    // memory).
    if (stream_world_) stream_fence();
  });
}

// Asks the caches for what posing `slot` reads and writes first (a hint; no effect on results):
// its pose arrays, foot locks and the frames of its clip layers; nothing for a held slot.
void PoseSynthesizer::prefetch_agent(const AnimationPlans& pl, int slot,
                                     std::span<const uint8_t> detail) const {
  const auto d = detail.empty() ? PoseDetail::kFull : static_cast<PoseDetail>(detail[slot]);
  if (d == PoseDetail::kHold && !pl.fresh[slot]) return;
  const bool coarse = d != PoseDetail::kFull && d != PoseDetail::kNoFootLocks && coarse_.useful();
  const size_t J = num_joints_;
  const size_t base = static_cast<size_t>(slot) * J;
  for (int k = 0; k < kMaxBlendLayers; ++k) {
    if (pl.layer_weight[slot * kMaxBlendLayers + k] <= 0.0f) continue;
    const int c = pl.layer_clip[slot * kMaxBlendLayers + k];
    const Clip& clip = coarse ? coarse_.clips[c] : library_.clips[c].playback();
    const float f = pl.layer_time_s[slot * kMaxBlendLayers + k] * clip.fps;
    if (!(f >= 0.0f && f < static_cast<float>(clip.num_frames))) continue;  // a wrap: not guessed
    const int i0 = static_cast<int>(f);
    const size_t rows = static_cast<size_t>(clip.num_joints) * (i0 + 1 < clip.num_frames ? 2 : 1);
    prefetch_bytes(clip.frame_rotations(i0), rows * sizeof(glm::quat));  // frames i0 and i0 + 1
    if (coarse || translated_joints_.empty()) {
      prefetch_bytes(clip.frame_translations(i0), rows * sizeof(glm::vec3));
    } else {  // only the sampled joints' translations (from the first to the last), both frames
      const size_t from = static_cast<size_t>(translated_joints_.front());
      const size_t count = translated_joints_.back() + 1 - from;
      prefetch_bytes(clip.frame_translations(i0) + from, count * sizeof(glm::vec3));
      if (i0 + 1 < clip.num_frames) {
        prefetch_bytes(clip.frame_translations(i0 + 1) + from, count * sizeof(glm::vec3));
      }
    }
  }
  if (!stream_world_) prefetch_bytes(world_.data() + base, J * sizeof(glm::mat4), true);
  if (coarse) return;
  prefetch_bytes(local_rot_.data() + base, J * sizeof(glm::quat), true);
  if (d != PoseDetail::kFull) return;
  prefetch_bytes(&locks_.lock[static_cast<size_t>(slot) * 2], 2 * sizeof(FootLock), true);
  prefetch_bytes(&locks_.anim_toe[static_cast<size_t>(slot) * 2], 2 * sizeof(glm::vec3), true);
  prefetch_bytes(&locks_.drawn_toe[static_cast<size_t>(slot) * 2], 2 * sizeof(glm::vec3), true);
}

// An agent not posed this frame: its world joints and palette stay where they were posed and are
// drawn root_offset further on (the root's ground walk since; the facing and the pose wait for the
// next update). Its toes as the foot locks know them move with it.
void PoseSynthesizer::hold_agent(const AnimationPlans& pl, int slot) {
  const glm::vec2 offset = pl.root_xz[slot] - placed_xz_[slot];
  const glm::vec2 delta = offset - root_offset_[slot];
  root_offset_[slot] = offset;
  support_reach_[slot] = SupportReach{};  // its feet were not looked at
  for (int side = 0; side < 2; ++side) {
    const size_t k = static_cast<size_t>(slot) * 2 + side;
    locks_.drawn_toe[k] += glm::vec3(delta.x, 0.0f, delta.y);
    locks_.drawn_ankle[k] += glm::vec3(delta.x, 0.0f, delta.y);
    locks_.anim_toe[k] += glm::vec3(delta.x, 0.0f, delta.y);
  }
}

// The slot's planned layers (the library's clips, or with `coarse` their coarse joints' tracks,
// mediator/coarse_pose.h) sampled and blended into out_rot / out_trans. A take's seam adds a
// second sample of its clip (take_seam). One sample is sampled straight into the output and two
// are blended as they are sampled (SampleBlendJob: the same numbers); more go through the scratch
// layers and BlendPosesJob.
void PoseSynthesizer::sample_layers(const AnimationPlans& pl, int slot, bool coarse, Scratch& s,
                                    glm::quat* out_rot_data, glm::vec3* out_trans_data, size_t n) {
  const std::span<glm::quat> out_rot(out_rot_data, n);
  const std::span<glm::vec3> out_trans(out_trans_data, n);
  // Kept field by field and read back as written: a whole Input read from fields just stored one
  // by one cannot be forwarded from the store buffer and waits for it to drain.
  const Clip* clip_of[2 * kMaxBlendLayers];
  float time_of[2 * kMaxBlendLayers], weight_of[2 * kMaxBlendLayers];
  int num_samples = 0;
  for (int k = 0; k < kMaxBlendLayers; ++k) {
    const float w = pl.layer_weight[slot * kMaxBlendLayers + k];
    if (w <= 0.0f) continue;
    const int c = pl.layer_clip[slot * kMaxBlendLayers + k];
    const float time = pl.layer_time_s[slot * kMaxBlendLayers + k];
    // A take (not a loop) replays one stride of itself: its last pose is not quite its first, so
    // over the stride's last fifth the pose one stride earlier is blended in, and the wrap to the
    // stride's start joins exactly.
    const LocomotionClip& lc = library_.clips[c];
    const Clip* clip = coarse ? &coarse_.clips[c] : &lc.playback();
    const float seam = take_seam(lc, time);
    clip_of[num_samples] = clip;
    time_of[num_samples] = time;
    weight_of[num_samples++] = w * (1.0f - seam);
    if (seam > 0.0f) {
      clip_of[num_samples] = clip;
      time_of[num_samples] = time - lc.cycle_s;
      weight_of[num_samples++] = w * seam;
    }
  }
  // BlendPosesJob skips the layers of weight 0 (a seam's full end): so do the fast paths.
  int num_weighted = 0, a = -1, b = -1;
  for (int i = 0; i < num_samples; ++i) {
    if (!(weight_of[i] > 0.0f)) continue;
    (a < 0 ? a : b) = i;
    ++num_weighted;
  }
  // The coarse clips have joints of their own: all sampled.
  const std::span<const int16_t> translated =
      coarse ? std::span<const int16_t>() : std::span<const int16_t>(translated_joints_);
  const std::span<const JointRun> runs =
      coarse ? std::span<const JointRun>() : std::span<const JointRun>(sampled_runs_);
  if (num_weighted == 1) {
    SampleClipJob{clip_of[a], time_of[a], out_rot, out_trans, translated, runs}.run();
    return;
  }
  if (num_weighted == 2) {
    SampleBlendJob job;
    job.a.clip = clip_of[a];
    job.a.time_s = time_of[a];
    job.a.weight = weight_of[a];
    job.b.clip = clip_of[b];
    job.b.time_s = time_of[b];
    job.b.weight = weight_of[b];
    job.out_rotations = out_rot;
    job.out_translations = out_trans;
    job.translated_joints = translated;
    job.sampled_runs = runs;
    job.run();
    return;
  }
  PoseLayer layers[2 * kMaxBlendLayers];
  for (int i = 0; i < num_samples; ++i) {
    std::span<glm::quat> r(s.rot.data() + i * n, n);
    std::span<glm::vec3> t(s.trans.data() + i * n, n);
    SampleClipJob{clip_of[i], time_of[i], r, t, translated}.run();
    layers[i] = {r, t, weight_of[i]};
  }
  BlendPosesJob{{layers, static_cast<size_t>(num_samples)}, out_rot, out_trans, translated}.run();
  if (coarse) return;
  for (const JointRun& r : fixed_runs_) {  // blended from every joint's samples: kept as they were
    std::copy(fixed_rot_.begin() + r.from, fixed_rot_.begin() + r.to, out_rot.begin() + r.from);
    std::copy(fixed_trans_.begin() + r.from, fixed_trans_.begin() + r.to,
              out_trans.begin() + r.from);
  }
}

void PoseSynthesizer::fk(glm::mat4* world, const glm::quat* rot, const glm::vec3* trans, int from,
                         int to, const glm::mat4& root) {
  const size_t J = num_joints_;
  LocalToModelJob job;
  job.skeleton = &skeleton_;
  job.rotations = {rot, J};
  job.translations = {trans, J};
  job.root_transform = root;
  job.out_model = {world, J};
  job.from = from;
  job.to = to;
  job.run();
}

// Where an agent's world joints are posed: a crowd's far larger than the caches in the thread's
// scratch (its lines stay in L1 for the whole agent), then streamed past the caches into world_
// (finish_pose), rather than read for ownership line by line; a small crowd's straight in world_,
// which stays cached.
glm::mat4* PoseSynthesizer::world_of(int slot, Scratch& s) {
  return stream_world_ ? s.world.data() : world_.data() + static_cast<size_t>(slot) * num_joints_;
}

PoseSynthesizer::JointRange PoseSynthesizer::subtree(int joint) const {
  if (joint < 0 || joint >= num_joints_) return {};
  return {joint, subtree_end_[joint]};
}

void PoseSynthesizer::fk_list(glm::mat4* world, const glm::quat* rot, const glm::vec3* trans,
                              const std::vector<int16_t>& joints, const glm::mat4& root) {
  const size_t J = num_joints_;
  LocalToModelListJob job;
  job.skeleton = &skeleton_;
  job.rotations = {rot, J};
  job.translations = {trans, J};
  job.root_transform = &root;
  job.out_model = {world, J};
  job.joints = joints;
  job.run();
}

std::vector<int16_t> PoseSynthesizer::range_list(JointRange a, JointRange b) const {
  if (a.from >= a.to || (b.from < b.to && b.from < a.from)) std::swap(a, b);
  if (b.from < b.to && b.from < a.to) {  // overlapping: one range
    a.to = std::max(a.to, b.to);
    b = {};
  }
  std::vector<int16_t> joints;
  for (JointRange r : {a, b}) {
    for (int j = r.from; j < r.to; ++j) joints.push_back(static_cast<int16_t>(j));
  }
  return joints;
}

void PoseSynthesizer::synthesize_agent(const AnimationPlans& pl, const MediatorParams& P, int slot,
                                       float dt, Scratch& s, PoseDetail detail) {
  const size_t J = num_joints_;
  if (pl.fresh[slot]) {
    has_prev_[slot] = 0;
    drop_[slot] = 0.0f;  // nothing of the slot's previous agent carries over
    drop_rate_[slot] = 0.0f;
  }
  if (detail == PoseDetail::kLight && coarse_.useful()) {
    pose_coarse(pl, P, slot, s);
    return;
  }
  // The pose is made in the thread's scratch and kept in world_ and local_rot_ once made
  // (finish_pose).
  glm::mat4* world = world_of(slot, s);
  glm::quat* rot = s.local_rot.data();

  // Sample and blend the planned layers.
  const glm::vec3* trans = s.local_trans.data();
  sample_layers(pl, slot, /*coarse=*/false, s, rot, s.local_trans.data(), J);

  const bool apm = P.mode == MediatorMode::kApm;
  const bool locking = apm && P.foot_locking && detail == PoseDetail::kFull;
  glm::mat4 root = root_placement(pl.root_xz[slot], pl.lower_yaw[slot]);
  placed_xz_[slot] = pl.root_xz[slot];
  root_offset_[slot] = glm::vec2(0.0f);
  support_reach_[slot] = SupportReach{};
  if (apm && P.foot_locking) root[3].y += library_.ground_lift_m;  // flat feet on the floor
  const bool twisting = apm && detail != PoseDetail::kLight;
  if (twisting && can_twist_) {
    // The twist poses its whole range again: before it, only the joints it reads there.
    fk_list(world, rot, trans, pre_twist_fk_, root);
  } else {
    fk(world, rot, trans, 0, num_joints_, root);
  }
  if (twisting) {
    twist_spine(slot, world, rot, trans, root, pl.upper_yaw[slot],
                glm::radians(P.torsion_limit_deg));
  }
  // Leaving full detail, the locks are let go through their releases (a reset would snap each
  // pinned foot to the clip's at once); once every foot is free the agent runs without them.
  const bool letting_go = apm && P.foot_locking && detail == PoseDetail::kNoFootLocks &&
                          !pl.fresh[slot] && locks_held(slot);
  if (locking || letting_go) lock_feet(pl, P, slot, world, rot, trans, root, dt, letting_go);
  // The twist measured the pelvis's heading, and nothing since moved the pelvis.
  finish_pose(slot, world, rot, detail, locking || letting_go,
              twisting && can_twist_ && pelvis_stays_);
}

// What every posed agent ends with: headings, the rotation change, the drawn toes, the foot locks
// reset when off, the skinning palette, and the local rotations and world joints kept (world_of).
void PoseSynthesizer::finish_pose(int slot, const glm::mat4* world, const glm::quat* rot,
                                  PoseDetail detail, bool locking, bool pelvis_known) {
  const size_t J = num_joints_;
  const size_t base = static_cast<size_t>(slot) * J;
  const bool track_rotation = detail != PoseDetail::kLight;
  // Torsion as measured (pelvis -> chest) and the per-frame rotation change for the pop metric.
  const int hips = skeleton_.role(JointRole::kHips), chest = skeleton_.role(JointRole::kChest);
  if (hips >= 0 && chest >= 0) {
    if (!pelvis_known) {
      pelvis_heading_[slot] = joint_heading(world[hips], rest_forward_[hips]);
    }
    upper_heading_[slot] = joint_heading(world[chest], rest_forward_[chest]);
    torsion_[slot] = wrap_pi(upper_heading_[slot] - pelvis_heading_[slot]);
  }
  float change = 0.0f;
  if (rot && track_rotation && prev_rot_valid_[slot] && has_prev_[slot] && J > 1) {
    // local_rot_ still holds the slot's last posed rotations. The largest angle is the acos of
    // the smallest |dot| (acos falls): one acos per agent. Joint 0 carries the root facing, not a
    // local bend. The new rotations replace the old as they are read.
    local_rot_[base] = rot[0];
    float d = 1.0f;
    if (fixed_runs_.empty()) {
      d = min_abs_dot_then_copy({rot + 1, J - 1}, {local_rot_.data() + base + 1, J - 1});
    } else {  // the fixed joints' rotations stay as they are in local_rot_ (set once)
      for (const JointRun& r : sampled_runs_) {
        const size_t from = static_cast<size_t>(std::max(r.from, 1)), to = r.to;
        if (from >= to) continue;
        d = std::min(d, min_abs_dot_then_copy({rot + from, to - from},
                                              {local_rot_.data() + base + from, to - from}));
      }
    }
    change = 2.0f * std::acos(d);
  } else if (rot && fixed_runs_.empty()) {
    std::copy_n(rot, J, local_rot_.begin() + base);
  } else if (rot) {
    for (const JointRun& r : sampled_runs_) {
      std::copy(rot + r.from, rot + r.to, local_rot_.begin() + base + r.from);
    }
  }
  rot_change_[slot] = change;
  // The toes (and ankles) as drawn, in every mode: foot locking starts from them (also after
  // being off).
  for (int side = 0; side < 2; ++side) {
    locks_.drawn_toe[static_cast<size_t>(slot) * 2 + side] =
        translation_of(world[skeleton_.toe(static_cast<Side>(side))]);
    locks_.drawn_ankle[static_cast<size_t>(slot) * 2 + side] =
        translation_of(world[skeleton_.ankle(static_cast<Side>(side))]);
  }
  if (!locking) {
    // Foot locks (and the pelvis drop and raised heels that serve them) start afresh from the
    // feet as drawn when they are next on.
    drop_[slot] = drop_rate_[slot] = 0.0f;
    for (int side = 0; side < 2; ++side) {
      const size_t k = static_cast<size_t>(slot) * 2 + side;
      // As a new agent's: drawn where it is, at rest (its last goal there, so the first goal
      // velocity taken when the locks are next on is the foot's own, not a jump from the origin).
      locks_.lock[k] = fresh_foot_lock(locks_.drawn_toe[k]);
      locks_.anim_toe[k] = locks_.drawn_toe[k];
      locks_.heel_pitch[k] = locks_.heel_pitch_rate[k] = 0.0f;
      locks_.lift_share[k] = locks_.lift_lost[k] = 0.0f;
    }
  }
  prev_rot_valid_[slot] = track_rotation;
  has_prev_[slot] = 1;
  if (stream_world_) copy_matrices({world, J}, {world_.data() + base, J}, /*stream=*/true);
  if (make_palettes_) palette_due_[slot] = 1;
}

void PoseSynthesizer::update_palettes() {
  if (!make_palettes_) return;
  const size_t J = static_cast<size_t>(num_joints_);
  auto make = [&](const tbb::blocked_range<size_t>& r) {
    bool streamed = false;
    for (size_t slot = r.begin(); slot < r.end(); ++slot) {
      if (!palette_due_[slot]) continue;
      palette_due_[slot] = 0;
      SkinningPaletteJob job;
      job.model = {world_.data() + slot * J, J};
      job.inverse_bind = inverse_bind_;
      job.out_palette = {palette_.data() + slot * J, J};
      job.affine_inverse_bind = affine_inverse_bind_;
      job.translation_inverse_bind = translation_inverse_bind_;
      job.stream_out = stream_palettes_;
      job.fence = false;  // once per range, below
      job.run();
      streamed = streamed || stream_palettes_;
    }
    // The range's streamed palettes are ordered before the task's end tells anyone they are done.
    if (streamed) stream_fence();
  };
  tbb::parallel_for(tbb::blocked_range<size_t>(0, palette_due_.size(), 64), make);
}

// A far agent's pose (PoseDetail::kLight) on the coarse joints only (mediator/coarse_pose.h): the
// detail joints follow their parents rigidly. No twist, no foot locks, as the full path at kLight.
void PoseSynthesizer::pose_coarse(const AnimationPlans& pl, const MediatorParams& P, int slot,
                                  Scratch& s) {
  const size_t K = static_cast<size_t>(coarse_.num_coarse);
  const std::span<glm::quat> rot(s.coarse_rot.data(), K);
  const std::span<glm::vec3> trans(s.coarse_trans.data(), K);
  sample_layers(pl, slot, /*coarse=*/true, s, rot.data(), trans.data(), K);
  glm::mat4 root = root_placement(pl.root_xz[slot], pl.lower_yaw[slot]);
  placed_xz_[slot] = pl.root_xz[slot];
  root_offset_[slot] = glm::vec2(0.0f);
  support_reach_[slot] = SupportReach{};  // no foot locks at this detail
  const bool apm = P.mode == MediatorMode::kApm;
  if (apm && P.foot_locking) root[3].y += library_.ground_lift_m;  // flat feet on the floor
  glm::mat4* world = world_of(slot, s);
  coarse_to_world(coarse_, skeleton_, rot, trans, root, {world, static_cast<size_t>(num_joints_)});
  finish_pose(slot, world, nullptr, PoseDetail::kLight, /*locking=*/false, /*pelvis_known=*/false);
}

void PoseSynthesizer::twist_spine(int slot, glm::mat4* world, glm::quat* rot,
                                  const glm::vec3* trans, const glm::mat4& root, float upper_yaw,
                                  float limit) {
  const std::vector<int16_t>& chain = skeleton_.spine_chain;
  const int hips = skeleton_.role(JointRole::kHips), chest = skeleton_.role(JointRole::kChest);
  if (chain.empty() || hips < 0 || chest < 0) return;
  const float pelvis = joint_heading(world[hips], rest_forward_[hips]);
  pelvis_heading_[slot] = pelvis;  // finish_pose's too when nothing moves the pelvis after
  const float chest_now = joint_heading(world[chest], rest_forward_[chest]);
  // The chest should face upper_yaw, but never further than the limit from the pelvis.
  // Unwrapped against last frame's torsion: theta passing behind the back must not flip the twist
  // from one limit to the other in a single frame.
  const float previous = has_prev_[slot] ? torsion_[slot] : 0.0f;
  const float asked = previous + wrap_pi(upper_yaw - pelvis - previous);
  const float wanted = std::clamp(asked, -limit, limit);
  const float twist = wanted - wrap_pi(chest_now - pelvis);
  const float per_joint = twist / static_cast<float>(chain.size());
  // A world-space rotation R at joint j becomes the local correction inv(Q_j) R Q_j; rotations
  // about the same (vertical) axis commute, so every correction uses the un-twisted Q_j. R turns
  // about world up, so inv(Q_j) R Q_j turns by the same angle about up seen from the joint:
  // inv(Q_j) * up, the world matrix's row y.
  const float c = std::cos(0.5f * per_joint), sn = std::sin(0.5f * per_joint);
  for (int16_t j : chain) {
    const glm::mat4& m = world[j];
    const glm::vec3 up = glm::normalize(glm::vec3(m[0].y, m[1].y, m[2].y));
    const glm::quat corr(c, sn * up.x, sn * up.y, sn * up.z);
    rot[j] = normalized_product(rot[j], corr);
  }
  const JointRange r = subtree(chain.front());  // the chain lies in its first joint's subtree
  fk(world, rot, trans, r.from, r.to, root);
}

bool PoseSynthesizer::locks_held(int slot) const {
  for (int side = 0; side < 2; ++side) {
    const FootLock& l = locks_.lock[static_cast<size_t>(slot) * 2 + side];
    if (l.state != FootLockState::kFree || glm::dot(l.offset, l.offset) > 1e-8f) return true;
  }
  return false;
}

void PoseSynthesizer::lock_feet(const AnimationPlans& pl, const MediatorParams& P, int slot,
                                glm::mat4* world, glm::quat* rot, const glm::vec3* trans,
                                const glm::mat4& root, float dt, bool letting_go) {
  const FootLockParams lp{0.5f * P.lock_release_s, P.idle_step_distance_m, P.idle_step_time_s,
                          library_.swing_height_m, library_.swing_speed_m_s, P.lock_release_s,
                          glide_halflife_s(P)};
  glm::vec3 goal[2], anim_toe[2], anim_vel[2];
  bool pinned[2] = {false, false};
  // While the standing clips vote the feet (the mediator's contacts pass), a pinned toe stands
  // where they have it, placed with the root and never below the floor (none known: the floor).
  const bool standing_votes = pl.standing_votes[slot] != 0;
  float stand_y[2];
  for (int s = 0; s < 2; ++s) {
    const float st = pl.stand_toe_y[s][slot];
    stand_y[s] = library_.planted_toe_m[s];
    if (st > std::numeric_limits<float>::lowest())
      stand_y[s] = std::max(stand_y[s], st + root[3].y);
  }
  if (pl.fresh[slot]) {
    // A new agent's feet start free: the first foot's rules read the other's state, which is
    // otherwise still the slot's previous agent's.
    locks_.lock[static_cast<size_t>(slot) * 2] = FootLock();
    locks_.lock[static_cast<size_t>(slot) * 2 + 1] = FootLock();
  }
  for (int side = 0; side < 2; ++side) {
    const size_t k = static_cast<size_t>(slot) * 2 + side;
    // The clip's toe, no lower than the gait clips alone have it: a walk blended with a standing
    // pose (a slow walk) takes shorter steps, but a foot that steps still clears the ground as
    // the walk does. While the other foot is pinned and carries the weight, the height the blend
    // takes away is given back in full once the gait clips step the feet (they vote the
    // contacts from kGaitVoteWeight), fading in below that. Otherwise (both feet free: a start,
    // a re-plant, a clip whose trailing toe leaves early) only as much as the blend walks, so the
    // body never hangs on two lifted feet. A foot pinned while the standing clips vote the feet
    // (a creeper; an agent about to set off) is given none: it stands on the floor
    // (FootLockInput::standing_votes), and given the walk's height then, its clips' toe was
    // centimetres up when the walk took the vote, and the released foot snapped up to it. The
    // share moves toward its goal over the lock's release time, so the toe never jumps.
    // Made whole in registers and stored once: a vector stored and then changed in memory is
    // read back (below) from two stores, which the load cannot take from the store buffer, and
    // it waits for every store before it (a streamed palette's too) to drain.
    const glm::vec3 drawn = translation_of(world[skeleton_.toe(static_cast<Side>(side))]);
    const float gw = pl.gait_weight[slot];
    // With no gait clip left in the blend (the agent has just stopped) there is no gait toe to
    // measure against: the height last taken away is kept, and the lift fades with its share.
    // Measured against nothing, the lift of a foot still in the air vanished in one frame, the
    // toe dropping onto the floor by centimetres.
    float& lost_kept = locks_.lift_lost[k];
    if (gw > 0.0f) {
      lost_kept = pl.gait_toe_y[side][slot] + root[3].y - drawn.y;
    } else if (pl.fresh[slot]) {
      lost_kept = 0.0f;
    }
    const float lost = lost_kept;
    const bool other_carries =
        !letting_go &&
        locks_.lock[static_cast<size_t>(slot) * 2 + (1 - side)].state == FootLockState::kLocked;
    const bool held_down =
        standing_votes && locks_.lock[k].state == FootLockState::kLocked && !pl.fresh[slot];
    const float share_goal =
        held_down ? 0.0f : smoothstep01(other_carries ? gw / kGaitVoteWeight : 2.0f * gw);
    float& share = locks_.lift_share[k];
    share = pl.fresh[slot] ? share_goal
                           : approach(share, share_goal, dt / std::max(P.lock_release_s, dt));
    const glm::vec3 toe(drawn.x, drawn.y + std::max(0.0f, lost) * share, drawn.z);
    anim_toe[side] = toe;
    FootLockInput in;
    in.anim_toe = toe;
    in.anim_toe_prev = locks_.anim_toe[k];
    in.drawn_toe_prev = locks_.drawn_toe[k];
    in.fresh = pl.fresh[slot] != 0;
    in.plant = !letting_go && pl.plant[side][slot] >= 0.5f;
    in.hold = pl.hold[side][slot] >= 0.5f;
    in.swing_progress = pl.swing_progress[side][slot];
    const FootLockState other = locks_.lock[static_cast<size_t>(slot) * 2 + (1 - side)].state;
    in.other_locked = !letting_go && other == FootLockState::kLocked;
    in.walking = pl.gait_weight[slot] >= kGaitVoteWeight;
    in.standing_votes = standing_votes;
    in.stand_toe_y = stand_y[side];
    // Running: clips with a flight phase, at a running speed. Below the walk-run speed a person
    // walks (GAIT.md), whatever the clips (a jog slowed for walkers, blended with the standing
    // pose, swings its feet low): the push-off is onto the other foot, and a pinned ball that
    // rose with the clips' stayed above the swinging foot, which then slid along the floor.
    in.flight = !letting_go && in.walking && pl.double_support[slot] < 0.5f &&
                pl.speed_m_s[slot] >= library_.walk_run_speed_m_s;
    const bool other_coming_down =
        pl.plant[1 - side][slot] >= 0.5f || pl.swing_progress[1 - side][slot] >= 0.5f;
    // The other foot is in the air and will come down: walking, coming down in the clips and not
    // pinned yet; or in a re-planting step (as when a standing agent sets off: the first step of
    // the clips waits until the re-planting foot is down, never both feet in the air).
    // A trailing foot keeps its weight until the leading one is flat: pinned on its heel, the
    // leading foot is still rolling onto its ball (the clips' toe-off may come first).
    // (Walking or not: a foot left behind by the standing clips does not step off either.)
    // The other foot as it was drawn (pinned, its heel on or off the floor), not as the clips
    // have it: a walk blended with the standing pose puts a planted toe above its heel, and a
    // foot held on such a "heel" kept this one pinned as its ball rose with the clips' swing
    // (up to 17 cm, for a third of a second).
    const size_t other_k = static_cast<size_t>(slot) * 2 + (1 - side);
    in.other_on_heel =
        other == FootLockState::kLocked && !pl.fresh[slot] &&
        on_heel(locks_.drawn_ankle[other_k], locks_.drawn_toe[other_k],
                library_.planted_ankle_m[1 - side], library_.planted_toe_m[1 - side]);
    in.other_landing =
        (in.other_on_heel && in.walking) || other == FootLockState::kStepping ||
        (pl.double_support[slot] >= 0.5f && other != FootLockState::kLocked && other_coming_down);
    in.floor_toe_m = library_.planted_toe_m[side];
    in.still_speed_m_s = still_speed_m_s(pl.speed_m_s[slot]);
    in.clip_speed_m_s = pl.clip_toe_speed[side][slot];
    goal[side] = advance_foot_lock(locks_.lock[k], in, lp, dt);
    anim_vel[side] = in.fresh ? glm::vec3(0.0f) : (in.anim_toe - in.anim_toe_prev) / dt;

    locks_.anim_toe[k] = anim_toe[side];
    const FootLockState st = locks_.lock[k].state;
    pinned[side] = st == FootLockState::kLocked || st == FootLockState::kStepping;
  }
  // A new agent's weight-bearing foot is placed as a walker's would be at this phase: it has been
  // pinned since it landed, the body has come over it, and the leg still reaches it when the
  // other foot comes down. The clips' own toe may be elsewhere: a blend of clips with different
  // stance lengths (a walk's push-off and a jog's early swing at the same phase) holds it above
  // the floor and further back than the legs reach, and pinned there it was let go at once and
  // floated until the other foot landed.
  if (pl.fresh[slot] && !letting_go) {
    for (int side = 0; side < 2; ++side) {
      FootLock& lock = locks_.lock[static_cast<size_t>(slot) * 2 + side];
      if (lock.state != FootLockState::kLocked) continue;
      const Side sd = static_cast<Side>(side);
      const bool alone = !pinned[1 - side];
      glm::vec3 g = goal[side];
      if (alone) g.y = library_.planted_toe_m[side];  // it carries the body: on the floor
      const glm::vec3 hip_p = translation_of(world[skeleton_.hip(sd)]);
      const float toward = ground_length(hip_p.x - g.x, hip_p.z - g.z);
      if (toward > 1e-4f) {
        // Moved toward the hip over the floor as far as the leg needs to reach it now, and, with
        // the heel as high as it rises (as a stance foot pushing off has it), from where the hip
        // will be when the other foot lands (the clips' landing time, the body at its speed in
        // its direction of travel); never past the hip.
        const glm::vec3 u((hip_p.x - g.x) / toward, 0.0f, (hip_p.z - g.z) / toward);
        const glm::vec3 d =
            translation_of(world[skeleton_.ankle(sd)]) - translation_of(world[skeleton_.toe(sd)]);
        const float reach = kIkSoften * kIkMaxExtension * library_.leg_length_m[side];
        float t = move_to_reach(g + d - hip_p, u, reach);
        const float landing_s = pl.landing_s[1 - side][slot];
        if (alone && landing_s >= 0.0f) {
          const float ahead = pl.speed_m_s[slot] * landing_s;
          const float yaw = pl.travel_yaw[slot];
          const glm::vec3 hip_then = hip_p + ahead * glm::vec3(std::sin(yaw), 0.0f, std::cos(yaw));
          t = std::max(t, move_to_reach(g + heel_pivot::fully_raised(d) - hip_then, u, reach));
        }
        g += std::min(t, toward) * u;
      }
      goal[side] = lock.target = lock.last_goal = g;
      lock.offset = lock.offset_vel = glm::vec3(0.0f);
    }
  }
  // Pelvis drop: a pinned foot the leg cannot reach pulls the whole body down (up to kMaxDrop)
  // rather than sliding; the body moves on a critically damped spring.
  float needed = 0.0f;
  for (int side = 0; side < 2; ++side) {
    if (!pinned[side]) continue;
    const Side sd = static_cast<Side>(side);
    const glm::vec3 ankle_goal = translation_of(world[skeleton_.ankle(sd)]) + goal[side] -
                                 translation_of(world[skeleton_.toe(sd)]);
    const glm::vec3 hip_p = translation_of(world[skeleton_.hip(sd)]);
    const float reach = kDropReach * library_.leg_length_m[side];
    const float dx = ground_length(ankle_goal.x - hip_p.x, ankle_goal.z - hip_p.z);
    const float dy = hip_p.y - ankle_goal.y;
    if (dx < reach && dy > 0.0f) needed = std::max(needed, dy - std::sqrt(reach * reach - dx * dx));
  }
  if (pl.fresh[slot]) drop_[slot] = drop_rate_[slot] = 0.0f;
  settle_spring(drop_[slot], drop_rate_[slot], std::min(needed, kMaxDrop), drop_step_);
  drop_[slot] = std::clamp(drop_[slot], 0.0f, kMaxDrop);
  const float drop = drop_[slot];
  glm::mat4 placed = root;
  placed[3].y -= drop;
  // Lowering the root lowers every joint by the same amount: no need for a second FK pass.
  if (drop != 0.0f) {
    for (int j = 0; j < num_joints_; ++j) world[j][3].y -= drop;
  }

  glm::quat ankle_world_rot[2];
  bool use_ik[2] = {false, false};
  bool repin[2] = {false, false};
  glm::vec3 toe_offset[2];
  for (int side = 0; side < 2; ++side) {
    const Side sd = static_cast<Side>(side);
    const int ankle = skeleton_.ankle(sd);
    // Pinned feet stay where they are pinned, and free ones keep the clips' height over the floor
    // (the swing leg bends more): a lowered body never drags a swinging foot over the ground.
    glm::vec3 g = goal[side];
    const glm::vec3 drawn_ankle = translation_of(world[ankle]);
    const glm::vec3 drawn_toe = translation_of(world[skeleton_.toe(sd)]);
    // Never below the floor the clips were authored on: a toe below it is raised onto it, and an
    // ankle below its own floor lifts the heel about the ball (below, with the heel-off pivot).
    g.y = std::max(g.y, library_.planted_toe_m[side]);
    toe_offset[side] = g - drawn_toe;
    use_ik[side] = glm::dot(toe_offset[side], toe_offset[side]) > 1e-10f ||
                   drawn_ankle.y + toe_offset[side].y < library_.planted_ankle_m[side] ||
                   locks_.heel_pitch[static_cast<size_t>(slot) * 2 + side] > 0.0f;
    if (use_ik[side]) ankle_world_rot[side] = rotation_of(world[ankle]);
  }
  if (!use_ik[0] && !use_ik[1]) return;
  TwoBoneIKLimb ik[2];
  glm::quat c_hip[2], c_knee[2];
  for (int side = 0; side < 2; ++side) {
    if (!use_ik[side]) continue;
    const Side sd = static_cast<Side>(side);
    const int hip = skeleton_.hip(sd), knee = skeleton_.knee(sd), ankle = skeleton_.ankle(sd);
    const size_t k = static_cast<size_t>(slot) * 2 + side;
    // IK: move the ankle by the toe's offset, keep the foot's world orientation.
    const glm::vec3 anim_ankle = translation_of(world[ankle]);
    glm::vec3 goal_ankle = anim_ankle + toe_offset[side];
    const glm::vec3 hip_p = translation_of(world[hip]);
    // The clip's own leg may be straighter than the limit (standing): only reaching further than
    // both counts.
    const float limit =
        std::max(P.max_leg_stretch * library_.leg_length_m[side], glm::length(anim_ankle - hip_p));
    // Heel-off: a leg that cannot reach its pinned foot raises the heel about the ball (the foot
    // pitches up about the toe) as far as that takes, as a stance foot does before toe-off. The
    // heel comes down again on a spring, so a released foot does not snap flat.
    float& pitch = locks_.heel_pitch[k];
    float& pitch_rate = locks_.heel_pitch_rate[k];
    if (pl.fresh[slot]) pitch = pitch_rate = 0.0f;
    const glm::vec3 toe_goal = translation_of(world[skeleton_.toe(sd)]) + toe_offset[side];
    float reach_pitch = 0.0f, floor_pitch = 0.0f;
    glm::vec3 pitch_axis(0.0f);
    const glm::vec3 d = goal_ankle - toe_goal;
    if (glm::length(glm::cross(d, glm::vec3(0, 1, 0))) > 1e-6f) {
      pitch_axis = glm::normalize(glm::cross(d, glm::vec3(0, 1, 0)));
      // The heel rises as soon as the leg would have to straighten into the soft end of its
      // reach, where IK no longer gets all the way: the pinned ball stays where it is.
      const float pivot_limit = std::max(kIkSoften * kIkMaxExtension * library_.leg_length_m[side],
                                         glm::length(anim_ankle - hip_p));
      if (glm::length(goal_ankle - hip_p) > std::min(limit, pivot_limit) &&
          locks_.lock[k].state == FootLockState::kLocked) {
        reach_pitch = heel_off_pivot(toe_goal, goal_ankle, hip_p, pivot_limit);
      }
      floor_pitch = heel_to_floor(toe_goal, d, library_.planted_ankle_m[side]);
    }
    // Up fast (a heel that must rise cannot wait long), down slowly; both on springs, so the
    // ankle never turns by more in a frame than a clip's joints do.
    settle_spring(pitch, pitch_rate, reach_pitch,
                  reach_pitch > pitch ? heel_up_step_ : heel_down_step_);
    // Above the floor it must be at once (a heel below the floor is seen).
    pitch = std::max(pitch, floor_pitch);
    if (pitch > 1e-5f && glm::length(pitch_axis) > 0.5f) {
      const glm::quat r = glm::angleAxis(pitch, pitch_axis);
      goal_ankle = toe_goal + r * d;
      ankle_world_rot[side] = r * ankle_world_rot[side];
    }
    if (!letting_go && locks_.lock[k].state == FootLockState::kLocked &&
        locks_.lock[static_cast<size_t>(slot) * 2 + (1 - side)].state != FootLockState::kLocked) {
      // This foot carries the body alone: the hip can go no further from it than the leg reaches
      // with the heel as high as it rises and the pelvis as low as it drops. Next frame the
      // mediator quickens the steps so the other foot lands before the body gets there
      // (rate_phase_pass), and with MediatorParams::support_hold holds the root within it.
      const glm::vec3 far_ankle = toe_goal + heel_pivot::fully_raised(d);
      const float dy = hip_p.y - (kMaxDrop - drop_[slot]) - far_ankle.y;
      const float r = limit > dy ? std::sqrt(limit * limit - dy * dy) : 0.0f;
      SupportReach& sr = support_reach_[slot];
      sr.centre =
          glm::vec2(far_ankle.x - (hip_p.x - placed[3].x), far_ankle.z - (hip_p.z - placed[3].z));
      sr.radius = r;
      // When the other foot comes down: a re-planting step when its time is up; a foot in the
      // clips' swing when the clips land it (AnimationPlans::landing_s).
      const FootLock& other = locks_.lock[static_cast<size_t>(slot) * 2 + (1 - side)];
      sr.replanting = other.state == FootLockState::kStepping;
      if (sr.replanting) {
        sr.landing_s = std::max(0.0f, lp.step_time_s - other.timer_s);
      } else {
        sr.landing_s = pl.landing_s[1 - side][slot];
      }
    }
    if (glm::length(goal_ankle - hip_p) > limit + 1e-3f &&
        locks_.lock[k].state == FootLockState::kLocked) {
      // Overstretched even with the pelvis down and the heel up: the foot steps to where the clip
      // has it while the clip keeps its weight on it (in contact, or a trailing ball pushing off),
      // and is let go when the clip lifts it. A step rises before it moves: let go low at push-off
      // instead, the trailing foot would catch up with the clip's along the floor.
      const glm::vec3 drawn = translation_of(world[skeleton_.toe(sd)]) + toe_offset[side];
      const FootLockState other_state =
          locks_.lock[static_cast<size_t>(slot) * 2 + (1 - side)].state;
      if (!letting_go && pl.hold[side][slot] >= 0.5f && other_state == FootLockState::kLocked) {
        locks_.lock[k] = start_foot_step(locks_.lock[k], drawn);
      } else if (other_state == FootLockState::kStepping) {
        // The other foot is in the air: this one keeps the weight and is re-pinned where the leg
        // reaches (after the IK below) rather than lifted as well.
        repin[side] = true;
      } else {
        // Both in the space of the lock's goals (the body before its drop): the offset is what
        // really separates the drawn toe from the clip's, not the drop as well. This frame is
        // drawn already: the clip's toe now is the one of the frame it was last drawn.
        locks_.lock[k] = release_foot_lock(locks_.lock[k], drawn, glm::vec3(0.0f), anim_toe[side],
                                           anim_vel[side]);
        support_reach_[slot] = SupportReach{};  // let go: it no longer holds the body
      }
    }
    // The knee bends toward the drawn knee's offset from the hip-ankle line and, by a few
    // centimetres more, the way the clips' knees bend (LocomotionLibrary::knee_bend_local, in
    // the thigh's frame): where the drawn leg is nearly straight, or a capture overextends it a
    // little, the offset alone may point backwards and the knee would fold back.
    const glm::vec3 knee_p = translation_of(world[knee]);
    const glm::vec3 axis = glm::normalize(anim_ankle - hip_p);
    // (World joints are rigid: the turned unit vector stays a unit one, or zero.)
    const glm::vec3 hinge = glm::mat3(world[hip]) * library_.knee_bend_local[side];
    glm::vec3 pole = (knee_p - hip_p) + kKneeBendBias * library_.leg_length_m[side] * hinge;
    pole -= axis * glm::dot(pole, axis);
    if (glm::length(pole) < 1e-4f) pole = glm::vec3(root[2]);
    // Both legs' IK in one pass (the legs' world joints stay as posed until fk_list below).
    TwoBoneIKLimb& job = ik[side];
    job.start_model = &world[hip];
    job.mid_model = &world[knee];
    job.end_model = &world[ankle];
    job.target = goal_ankle;
    job.pole = pole;
    job.soften = kIkSoften;
    job.max_extension = kIkMaxExtension;
    job.out_start_correction = &c_hip[side];
    job.out_mid_correction = &c_knee[side];
  }
  if (use_ik[0] && use_ik[1]) {
    two_bone_ik_pair(ik[0], ik[1]);
  } else {
    ik[use_ik[0] ? 0 : 1].job().run();
  }
  for (int side = 0; side < 2; ++side) {
    if (!use_ik[side]) continue;
    const Side sd = static_cast<Side>(side);
    const int hip = skeleton_.hip(sd), knee = skeleton_.knee(sd);
    rot[hip] = normalized_product(rot[hip], c_hip[side]);
    rot[knee] = normalized_product(rot[knee], c_knee[side]);
  }
  const int ik_sides = (use_ik[0] ? 1 : 0) | (use_ik[1] ? 2 : 0);
  fk_list(world, rot, trans, leg_fk_[ik_sides], placed);
  // Restore each ankle's world orientation under its new shin, then finish the feet. A leg
  // without IK keeps its shin, ankle and foot as posed.
  for (int side = 0; side < 2; ++side) {
    if (!use_ik[side]) continue;
    const Side sd = static_cast<Side>(side);
    const int ankle = skeleton_.ankle(sd);
    const int parent = skeleton_.parents[ankle];
    if (parent < 0) continue;
    const glm::quat parent_rot = rotation_of(world[parent]);
    rot[ankle] = normalized_inverse_product(parent_rot, ankle_world_rot[side]);
  }
  fk_list(world, rot, trans, foot_fk_[ik_sides], placed);
  for (int side = 0; side < 2; ++side) {
    if (!repin[side]) continue;
    const glm::vec3 toe = translation_of(world[skeleton_.toe(static_cast<Side>(side))]);
    FootLock& lock = locks_.lock[static_cast<size_t>(slot) * 2 + side];
    lock.target.x = toe.x;
    lock.target.z = toe.z;
  }
}

float heel_off_pitch(const glm::vec3& toe, const glm::vec3& ankle, const glm::vec3& hip,
                     float limit, bool closed_form) {
  return heel_off_pivot(toe, ankle, hip, limit, closed_form);
}

}  // namespace gk
