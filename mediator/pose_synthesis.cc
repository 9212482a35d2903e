#include "mediator/pose_synthesis.h"

#include <algorithm>
#include <cmath>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "animation/pose_jobs.h"
#include "mediator/springs.h"

namespace gk {

struct PoseSynthesizer::Scratch {
  std::vector<glm::quat> rot;    // kMaxBlendLayers * joints
  std::vector<glm::vec3> trans;  // kMaxBlendLayers * joints
};

namespace {

glm::mat4 root_placement(const glm::vec2& xz, float yaw) {
  glm::mat4 m = glm::mat4_cast(glm::angleAxis(yaw, glm::vec3(0, 1, 0)));
  m[3] = glm::vec4(xz.x, 0.0f, xz.y, 1.0f);
  return m;
}

glm::quat rotation_of(const glm::mat4& m) { return glm::normalize(glm::quat_cast(glm::mat3(m))); }

// Highest lift [m] of a released foot on its way back to the clip's foot.
constexpr float kReleaseLiftMax = 0.05f;
// A foot plants when its toe is within kPlantToe and its ankle within kPlantAnkle of the ground
// (METRICS.md counts 2.5 cm and 5 cm as contact) and it moves slower than kPlantSpeed over it.
constexpr float kPlantToe = 0.03f;
constexpr float kPlantAnkle = 0.06f;
constexpr float kPlantSpeed = 0.5f;  // [m/s]
// A planted foot is held until its toe or ankle clearly lifts (heel-off pivots on the ball).
constexpr float kHoldToe = 0.045f;
constexpr float kHoldAnkle = 0.09f;
// A foot that is not pinned and moves faster than kLiftSpeed low over the ground is lifted to
// kClearance so it swings instead of dragging; fully from kClearSpeed on. METRICS.md counts a toe
// within 2.5 cm of its lowest height as in contact, and 30 cm/s as skating.
constexpr float kClearance = 0.045f;
constexpr float kLiftSpeed = 0.2f;     // [m/s]
constexpr float kClearSpeed = 0.3f;    // [m/s]
constexpr float kMaxLiftSpeed = 1.5f;  // [m/s] fastest change of that lift
constexpr float kMaxStepSpeed = 1.5f;  // [m/s] a released foot travels back no faster on average
// The pelvis is lowered so pinned feet stay within kDropReach of the leg length, by at most
// kMaxDrop, and comes back up at kDropRecovery.
constexpr float kDropReach = 0.99f;
constexpr float kMaxDrop = 0.04f;       // [m]
constexpr float kDropRecovery = 0.25f;  // [m/s]

float smoothstep01(float x) {
  x = std::clamp(x, 0.0f, 1.0f);
  return x * x * (3.0f - 2.0f * x);
}

}  // namespace

float joint_heading(const glm::mat4& world, const glm::quat& rest_model_rot_inv) {
  const glm::vec3 f = rotation_of(world) * (rest_model_rot_inv * glm::vec3(0, 0, 1));
  return std::atan2(f.x, f.z);
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
  rest_model_rot_inv_.resize(J);
  for (size_t j = 0; j < J; ++j) rest_model_rot_inv_[j] = glm::inverse(rotation_of(rest[j]));
  if (library.mesh && library.mesh->inverse_bind.size() == J) {
    inverse_bind_ = library.mesh->inverse_bind;
  } else {
    inverse_bind_.resize(J);
    for (size_t j = 0; j < J; ++j) inverse_bind_[j] = glm::inverse(rest[j]);
  }
  local_rot_.assign(capacity * J, glm::quat(1, 0, 0, 0));
  local_trans_.assign(capacity * J, glm::vec3(0.0f));
  prev_local_rot_.assign(capacity * J, glm::quat(1, 0, 0, 0));
  world_.assign(capacity * J, glm::mat4(1.0f));
  if (make_palettes_) palette_.assign(capacity * J, glm::mat4(1.0f));
  rot_change_.assign(capacity, 0.0f);
  torsion_.assign(capacity, 0.0f);
  pelvis_heading_.assign(capacity, 0.0f);
  upper_heading_.assign(capacity, 0.0f);
  has_prev_.assign(capacity, 0);
  drop_.assign(capacity, 0.0f);
  locks_.state.assign(capacity * 2, static_cast<uint8_t>(FootLockState::kFree));
  locks_.target.assign(capacity * 2, glm::vec3(0.0f));
  locks_.from.assign(capacity * 2, glm::vec3(0.0f));
  locks_.weight.assign(capacity * 2, 0.0f);
  locks_.timer.assign(capacity * 2, 0.0f);
  locks_.anim_toe.assign(capacity * 2, glm::vec3(0.0f));
  locks_.lift.assign(capacity * 2, 0.0f);
  locks_.drawn_toe.assign(capacity * 2, glm::vec3(0.0f));
  // Per-thread sampling scratch, made once per worker thread on first use and kept.
  scratch_ = std::make_unique<tbb::enumerable_thread_specific<Scratch>>([J] {
    Scratch s;
    s.rot.resize(kMaxBlendLayers * J);
    s.trans.resize(kMaxBlendLayers * J);
    return s;
  });
  first_leg_joint_ = std::min(skeleton_.hip(Side::kLeft), skeleton_.hip(Side::kRight));
  first_spine_joint_ = skeleton_.spine_chain.empty() ? num_joints_ : skeleton_.spine_chain.front();
}

PoseSynthesizer::~PoseSynthesizer() = default;

void PoseSynthesizer::run(const Mediator& m, float dt_s) {
  const AnimationPlans& pl = m.plans();
  const size_t n = m.num_agents();
  tbb::enumerable_thread_specific<Scratch>& scratch = *scratch_;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 32), [&](const tbb::blocked_range<size_t>& r) {
    Scratch& s = scratch.local();
    for (size_t i = r.begin(); i < r.end(); ++i) synthesize_agent(m, pl.slot_of_agent[i], dt_s, s);
  });
}

void PoseSynthesizer::fk_from(int slot, int first, const glm::mat4& root) {
  const size_t base = static_cast<size_t>(slot) * num_joints_;
  for (int j = std::max(first, 0); j < num_joints_; ++j) {
    glm::mat4 local = glm::mat4_cast(local_rot_[base + j]);
    local[3] = glm::vec4(local_trans_[base + j], 1.0f);
    const int parent = skeleton_.parents[j];
    world_[base + j] = (parent < 0 ? root : world_[base + parent]) * local;
  }
}

void PoseSynthesizer::synthesize_agent(const Mediator& m, int slot, float dt, Scratch& s) {
  const AnimationPlans& pl = m.plans();
  const MediatorParams& P = m.params();
  const size_t J = num_joints_;
  const size_t base = static_cast<size_t>(slot) * J;
  if (pl.fresh[slot]) {
    has_prev_[slot] = 0;
    drop_[slot] = 0.0f;  // nothing of the slot's previous agent carries over
  }

  // Sample and blend the planned layers.
  PoseLayer layers[kMaxBlendLayers];
  int num_layers = 0;
  for (int k = 0; k < kMaxBlendLayers; ++k) {
    const float w = pl.layer_weight[slot * kMaxBlendLayers + k];
    if (w <= 0.0f) continue;
    const Clip& clip = library_.clips[pl.layer_clip[slot * kMaxBlendLayers + k]].clip;
    std::span<glm::quat> r(s.rot.data() + num_layers * J, J);
    std::span<glm::vec3> t(s.trans.data() + num_layers * J, J);
    SampleClipJob{&clip, pl.layer_time_s[slot * kMaxBlendLayers + k], r, t}.run();
    layers[num_layers++] = {r, t, w};
  }
  std::span<glm::quat> out_r(local_rot_.data() + base, J);
  std::span<glm::vec3> out_t(local_trans_.data() + base, J);
  BlendPosesJob{{layers, static_cast<size_t>(num_layers)}, out_r, out_t}.run();

  const glm::mat4 root = root_placement(pl.root_xz[slot], pl.lower_yaw[slot]);
  fk_from(slot, 0, root);
  const bool apm = P.mode == MediatorMode::kApm;
  if (apm) twist_spine(slot, root, pl.upper_yaw[slot], glm::radians(P.torsion_limit_deg));
  if (apm && P.foot_locking) lock_feet(m, slot, root, dt);

  // Torsion as measured (pelvis -> chest) and the per-frame rotation change for the pop metric.
  const int hips = skeleton_.role(JointRole::kHips), chest = skeleton_.role(JointRole::kChest);
  if (hips >= 0 && chest >= 0) {
    pelvis_heading_[slot] = joint_heading(world_[base + hips], rest_model_rot_inv_[hips]);
    upper_heading_[slot] = joint_heading(world_[base + chest], rest_model_rot_inv_[chest]);
    torsion_[slot] = wrap_pi(upper_heading_[slot] - pelvis_heading_[slot]);
  }
  float change = 0.0f;
  if (has_prev_[slot]) {
    for (size_t j = 1; j < J; ++j) {  // joint 0 carries the root facing, not a local bend
      const float d = std::abs(glm::dot(local_rot_[base + j], prev_local_rot_[base + j]));
      change = std::max(change, 2.0f * std::acos(std::min(1.0f, d)));
    }
  }
  rot_change_[slot] = change;
  // The toes as drawn, in every mode: foot locking starts from them (also after being off).
  for (int side = 0; side < 2; ++side) {
    locks_.drawn_toe[static_cast<size_t>(slot) * 2 + side] =
        translation_of(world_[base + skeleton_.toe(static_cast<Side>(side))]);
  }
  std::copy_n(local_rot_.begin() + base, J, prev_local_rot_.begin() + base);
  has_prev_[slot] = 1;
  if (make_palettes_) {
    SkinningPaletteJob{{world_.data() + base, J}, inverse_bind_, {palette_.data() + base, J}}.run();
  }
}

void PoseSynthesizer::twist_spine(int slot, const glm::mat4& root, float upper_yaw, float limit) {
  const std::vector<int16_t>& chain = skeleton_.spine_chain;
  const int hips = skeleton_.role(JointRole::kHips), chest = skeleton_.role(JointRole::kChest);
  if (chain.empty() || hips < 0 || chest < 0) return;
  const size_t base = static_cast<size_t>(slot) * num_joints_;
  const float pelvis = joint_heading(world_[base + hips], rest_model_rot_inv_[hips]);
  const float chest_now = joint_heading(world_[base + chest], rest_model_rot_inv_[chest]);
  // The chest should face upper_yaw, but never further than the limit from the pelvis.
  // Unwrapped against last frame's torsion: theta passing behind the back must not flip the twist
  // from one limit to the other in a single frame.
  const float previous = has_prev_[slot] ? torsion_[slot] : 0.0f;
  const float asked = previous + wrap_pi(upper_yaw - pelvis - previous);
  const float wanted = std::clamp(asked, -limit, limit);
  const float twist = wanted - wrap_pi(chest_now - pelvis);
  const float per_joint = twist / static_cast<float>(chain.size());
  // A world-space rotation R at joint j becomes the local correction inv(Q_j) R Q_j; rotations
  // about the same (vertical) axis commute, so every correction uses the un-twisted Q_j.
  const glm::quat r = glm::angleAxis(per_joint, glm::vec3(0, 1, 0));
  for (int16_t j : chain) {
    const glm::quat q = rotation_of(world_[base + j]);
    local_rot_[base + j] = glm::normalize(local_rot_[base + j] * (glm::inverse(q) * r * q));
  }
  fk_from(slot, first_spine_joint_, root);
}

void PoseSynthesizer::lock_feet(const Mediator& m, int slot, const glm::mat4& root, float dt) {
  const AnimationPlans& pl = m.plans();
  const MediatorParams& P = m.params();
  const size_t base = static_cast<size_t>(slot) * num_joints_;
  glm::quat ankle_world_rot[2];
  glm::vec3 toe_offset[2] = {glm::vec3(0.0f), glm::vec3(0.0f)};
  bool use_ik[2] = {false, false}, pinned[2] = {false, false};
  for (int side = 0; side < 2; ++side) {
    const Side sd = static_cast<Side>(side);
    const int ankle = skeleton_.ankle(sd), toe = skeleton_.toe(sd);
    const size_t k = static_cast<size_t>(slot) * 2 + side;
    const glm::vec3 anim_toe = translation_of(world_[base + toe]);
    const glm::vec3 anim_ankle = translation_of(world_[base + ankle]);
    // Contact from the animated foot itself (after blending, placing and twisting), not from the
    // clips' labels: a blend of a standing and a walking clip has feet of its own.
    // Heights as drawn: the body is still lowered by last frame's pelvis drop.
    const float toe_h = anim_toe.y - drop_[slot] - library_.toe_floor_m[side];
    const float ankle_h = anim_ankle.y - drop_[slot] - library_.ankle_floor_m[side];
    const glm::vec3 prev = locks_.anim_toe[k];
    locks_.anim_toe[k] = anim_toe;
    const float ground_speed =
        pl.fresh[slot] ? 0.0f : std::hypot(anim_toe.x - prev.x, anim_toe.z - prev.z) / dt;
    const bool planted = toe_h <= kPlantToe && ankle_h <= kPlantAnkle && ground_speed < kPlantSpeed;
    const bool held = toe_h <= kHoldToe && ankle_h <= kHoldAnkle;
    auto& state = reinterpret_cast<FootLockState&>(locks_.state[k]);
    float& weight = locks_.weight[k];
    glm::vec3& target = locks_.target[k];
    if (pl.fresh[slot]) {
      state = FootLockState::kFree;
      weight = 0.0f;
      locks_.lift[k] = 0.0f;
      locks_.drawn_toe[k] = anim_toe;
    }
    const glm::vec3 drawn_before = locks_.drawn_toe[k];
    switch (state) {
      case FootLockState::kFree:
        if (planted) {
          // Pinned where it was drawn last frame: the foot stops on the frame it plants instead
          // of taking one more step of the clip's (still slowing) foot.
          state = FootLockState::kLocked;
          target = glm::vec3(drawn_before.x, anim_toe.y, drawn_before.z);
          weight = 1.0f;
        }
        break;
      case FootLockState::kLocked: {
        if (!held) {
          state = FootLockState::kReleasing;
          locks_.from[k] = target;
          locks_.timer[k] = 0.0f;
          break;
        }
        // The pinned toe follows the clip's toe down (a heel strike rolls onto the ball), never up.
        target.y = std::min(target.y, anim_toe.y);
        // Standing: a foot left behind by a turn or a drift is re-planted with a short step,
        // one foot at a time.
        const glm::vec3 d = target - anim_toe;
        const float drift = std::hypot(d.x, d.z);
        const size_t other = static_cast<size_t>(slot) * 2 + (1 - side);
        if (drift > P.idle_step_distance_m) {
          if (!pl.standing[slot]) {  // walking slowly with feet that hardly lift: step anyway
            state = FootLockState::kReleasing;
            locks_.from[k] = target;
            locks_.timer[k] = 0.0f;
          } else if (locks_.state[other] == static_cast<uint8_t>(FootLockState::kLocked)) {
            state = FootLockState::kStepping;
            locks_.from[k] = target;
            locks_.timer[k] = 0.0f;
          }
        }
        break;
      }
      case FootLockState::kReleasing: {
        // The foot is carried from where it was pinned to where the clip has it: lifted first,
        // then moved, so a released foot steps instead of sliding over the ground.
        // timer holds the progress 0..1; a long way back takes longer (at most kMaxStepSpeed).
        const glm::vec3 from = locks_.from[k];
        const float gap = std::hypot(anim_toe.x - from.x, anim_toe.z - from.z);
        locks_.timer[k] += dt / std::max(P.lock_release_s, gap / kMaxStepSpeed);
        const float u = std::min(1.0f, locks_.timer[k]);
        const float lift = std::min(kReleaseLiftMax, 5.0f * gap) *
                           std::sqrt(std::max(0.0f, std::sin(3.14159265f * u)));
        target = glm::mix(from, anim_toe, smoothstep01(u)) + glm::vec3(0.0f, lift, 0.0f);
        weight = 1.0f;
        if (u >= 1.0f) {
          state = FootLockState::kFree;
          weight = 0.0f;
        }
        break;
      }
      case FootLockState::kStepping: {
        locks_.timer[k] += dt;
        const float u = locks_.timer[k] / P.idle_step_time_s;
        const glm::vec3 from = locks_.from[k];
        target = glm::mix(from, anim_toe, smoothstep01(u));
        target.y = glm::mix(from.y, anim_toe.y, smoothstep01(u)) +
                   0.05f * std::sin(3.14159265f * std::min(u, 1.0f));
        weight = 1.0f;
        if (u >= 1.0f) {
          state = FootLockState::kLocked;
          target = anim_toe;
        }
        break;
      }
    }
    // A free or released foot skimming the ground fast is lifted clear (continuous in height and
    // speed). The speed is that of the foot as it will be drawn, from where it was drawn.
    float lift = 0.0f;
    if ((state == FootLockState::kFree || state == FootLockState::kReleasing) &&
        ankle_h <= kHoldAnkle) {
      const glm::vec3 goal = glm::mix(anim_toe, target, weight);
      const float speed =
          pl.fresh[slot] ? 0.0f : std::hypot(goal.x - drawn_before.x, goal.z - drawn_before.z) / dt;
      const float fast = smoothstep01((speed - kLiftSpeed) / (kClearSpeed - kLiftSpeed));
      const float h = goal.y - drop_[slot] - library_.toe_floor_m[side];
      lift = std::max(0.0f, kClearance - h) * fast;
    }
    // Rate-limited so the knee never snaps (a pop) when the foot speeds up through the band.
    const float max_change = kMaxLiftSpeed * dt;
    lift = std::clamp(lift, locks_.lift[k] - max_change, locks_.lift[k] + max_change);
    locks_.lift[k] = lift;
    use_ik[side] = weight > 0.0f || lift > 0.0f;
    // Where the toe must go, relative to the animated foot (the ankle moves by the same offset).
    toe_offset[side] = glm::mix(anim_toe, target, weight) + glm::vec3(0.0f, lift, 0.0f) - anim_toe;
    pinned[side] = weight > 0.0f;
  }
  if (!use_ik[0] && !use_ik[1]) {
    drop_[slot] = 0.0f;
    return;
  }
  // Pelvis drop: a pinned foot the leg cannot reach pulls the whole body down (up to kMaxDrop)
  // rather than sliding; the drop eases back at kDropRecovery.
  float needed = 0.0f;
  for (int side = 0; side < 2; ++side) {
    if (!pinned[side]) continue;
    const Side sd = static_cast<Side>(side);
    const glm::vec3 goal = translation_of(world_[base + skeleton_.ankle(sd)]) + toe_offset[side];
    const glm::vec3 hip_p = translation_of(world_[base + skeleton_.hip(sd)]);
    const float reach = kDropReach * library_.leg_length_m[side];
    const float dx = std::hypot(goal.x - hip_p.x, goal.z - hip_p.z), dy = hip_p.y - goal.y;
    if (dx < reach && dy > 0.0f) needed = std::max(needed, dy - std::sqrt(reach * reach - dx * dx));
  }
  float drop = std::max(needed, drop_[slot] - kDropRecovery * dt);
  drop = std::clamp(drop, 0.0f, kMaxDrop);
  drop_[slot] = drop;
  glm::mat4 placed = root;
  if (drop > 0.0f) {
    placed[3].y -= drop;
    // Lowering the root lowers every joint by the same amount: no need for a second FK pass.
    for (int j = 0; j < num_joints_; ++j) world_[base + j][3].y -= drop;
    // Free feet go down with the body; pinned ones stay where they are pinned.
    for (int side = 0; side < 2; ++side) {
      if (pinned[side]) toe_offset[side].y += drop;
    }
  }
  for (int side = 0; side < 2; ++side) {
    const Side sd = static_cast<Side>(side);
    const int hip = skeleton_.hip(sd), knee = skeleton_.knee(sd), ankle = skeleton_.ankle(sd);
    const size_t k = static_cast<size_t>(slot) * 2 + side;
    ankle_world_rot[side] = rotation_of(world_[base + ankle]);
    if (!use_ik[side]) continue;
    // IK: move the ankle by the toe's offset, keep the foot's world orientation.
    const glm::vec3 anim_ankle = translation_of(world_[base + ankle]);
    const glm::vec3 goal_ankle = anim_ankle + toe_offset[side];
    const glm::vec3 hip_p = translation_of(world_[base + hip]);
    const float reach = glm::length(goal_ankle - hip_p);
    if (reach > P.max_leg_stretch * library_.leg_length_m[side] &&
        locks_.state[k] == static_cast<uint8_t>(FootLockState::kLocked)) {
      // Overstretched even with the pelvis down: let the foot go, smoothly.
      locks_.state[k] = static_cast<uint8_t>(FootLockState::kReleasing);
      locks_.from[k] = locks_.target[k];
      locks_.timer[k] = 0.0f;
    }
    const glm::vec3 knee_p = translation_of(world_[base + knee]);
    const glm::vec3 axis = glm::normalize(anim_ankle - hip_p);
    glm::vec3 pole = (knee_p - hip_p) - axis * glm::dot(knee_p - hip_p, axis);
    if (glm::length(pole) < 1e-4f) pole = glm::vec3(root[2]);
    glm::quat c_hip, c_knee;
    TwoBoneIKJob ik;
    ik.start_model = world_[base + hip];
    ik.mid_model = world_[base + knee];
    ik.end_model = world_[base + ankle];
    ik.target = goal_ankle;
    ik.pole = pole;
    ik.out_start_correction = &c_hip;
    ik.out_mid_correction = &c_knee;
    ik.run();
    local_rot_[base + hip] = glm::normalize(local_rot_[base + hip] * c_hip);
    local_rot_[base + knee] = glm::normalize(local_rot_[base + knee] * c_knee);
  }
  fk_from(slot, first_leg_joint_, placed);
  // Restore each ankle's world orientation under its new shin, then finish the feet.
  for (int side = 0; side < 2; ++side) {
    const Side sd = static_cast<Side>(side);
    const int ankle = skeleton_.ankle(sd);
    const int parent = skeleton_.parents[ankle];
    if (parent < 0) continue;
    const glm::quat parent_rot = rotation_of(world_[base + parent]);
    local_rot_[base + ankle] = glm::normalize(glm::inverse(parent_rot) * ankle_world_rot[side]);
  }
  fk_from(slot, std::min(skeleton_.ankle(Side::kLeft), skeleton_.ankle(Side::kRight)), placed);
}

}  // namespace gk
