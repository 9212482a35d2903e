#pragma once
// Pose synthesis over the whole crowd (ARCHITECTURE.md step 7 and the pose stage): per agent,
// sample and blend the planned clips, place the root, twist the spine toward the upper-body facing
// within the torsion limit, pin planted feet with two-bone IK, and produce world joint transforms
// and skinning palettes. Parallel over agents; all buffers sized at construction.

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <tbb/enumerable_thread_specific.h>
#include <glm/gtc/quaternion.hpp>
#include <glm/mat4x4.hpp>

#include "animation/pose_jobs.h"
#include "mediator/animation_plans.h"
#include "mediator/coarse_pose.h"
#include "mediator/foot_lock.h"
#include "mediator/locomotion_library.h"
#include "mediator/params.h"
#include "mediator/springs.h"

namespace gk {

// How much of an agent's pose run() works out this frame (level of detail, pipeline/lod.h).
enum class PoseDetail : uint8_t {
  kFull = 0,         // everything: spine twist, foot locks and leg IK
  kNoFootLocks = 1,  // spine twist, no foot locks (they start afresh from the drawn toes)
  kLight = 2,        // no spine twist, no foot locks, coarse joints only (mediator/coarse_pose.h)
  kHold = 3,         // not posed: the last pose is drawn where the root (root_xz) is now
};

// Per foot [slot * 2 + side].
struct FootLocks {
  std::vector<FootLock> lock;          // the lock state machine (mediator/foot_lock.h)
  std::vector<glm::vec3> anim_toe;     // the clip's (unlocked) toe position last frame [m]
  std::vector<glm::vec3> drawn_toe;    // the toe as drawn last frame (after IK) [m]
  std::vector<glm::vec3> drawn_ankle;  // the ankle as drawn last frame (after IK) [m]
  std::vector<float> heel_pitch;       // heel raised about the ball by the pivot [rad]
  std::vector<float> heel_pitch_rate;  // its rate [rad/s] (it settles back on a spring)
  // Share of the swing height a standing blend takes away that is given back to this foot, 0..1
  // (it moves toward its goal over MediatorParams::lock_release_s, so the toe never jumps).
  std::vector<float> lift_share;
  // The height [m] the standing blend takes from the toe against the gait clips' own (what the
  // share gives back), kept from the last frame with a gait clip in the blend.
  std::vector<float> lift_lost;
};

class PoseSynthesizer {
 public:
  PoseSynthesizer(const LocomotionLibrary& library, size_t capacity, bool make_palettes);
  ~PoseSynthesizer();

  // Synthesises the first num_agents agents of `plans` (the mediator's last plan: agent i in slot
  // plans.slot_of_agent[i]) with the parameters they were planned with.
  void run(const AnimationPlans& plans, size_t num_agents, const MediatorParams& params,
           float dt_s);
  // The same with a PoseDetail per slot (`detail_by_slot`, as uint8_t; capacity long, or empty:
  // every agent in full).
  void run(const AnimationPlans& plans, size_t num_agents, const MediatorParams& params,
           float dt_s, std::span<const uint8_t> detail_by_slot);

  int num_joints() const { return num_joints_; }
  // World transforms of one slot's joints where they were last posed. A slot held this frame
  // (PoseDetail::kHold) is drawn root_offset(slot) further on: add it to the translations (or use
  // joint_position), as the renderer does per instance.
  std::span<const glm::mat4> world(int slot) const {
    return {world_.data() + static_cast<size_t>(slot) * num_joints_,
            static_cast<size_t>(num_joints_)};
  }
  // Ground displacement (x, z) [m] from where a slot's world joints and palette were posed to where
  // it is drawn now: (0, 0) for a slot posed this frame; for a held one, its root's walk since its
  // last pose. A held agent costs O(1) this way, not a move of every joint's matrix.
  glm::vec2 root_offset(int slot) const { return root_offset_[slot]; }
  std::span<const glm::vec2> root_offsets() const { return root_offset_; }
  // Per slot, where a foot that carries the body alone (pinned, the other foot not) lets the root
  // go, and when the other foot comes down (SupportReach): the mediator quickens the steps so the
  // other foot lands before the body leaves that reach, and with support_hold holds the root
  // within it until then (and feeds the held position back), so the support foot stays pinned.
  std::span<const SupportReach> support_reach() const { return support_reach_; }
  // One joint's world position as drawn this frame (world(slot)'s translation + root_offset).
  glm::vec3 joint_position(int slot, int joint) const {
    const glm::vec4& t = world_[static_cast<size_t>(slot) * num_joints_ + joint][3];
    const glm::vec2 o = root_offset_[slot];
    return {t.x + o.x, t.y, t.z + o.y};
  }
  // Makes the skinning palettes (world * inverse bind) of the slots posed since the last call:
  // the renderer's work, done only where palettes are drawn or read (before an upload), not in
  // run(). Nothing without make_palettes.
  void update_palettes();
  // Every slot's skinning palette as of the last update_palettes(), slot after slot (empty without
  // make_palettes); drawn with root_offset added to their translations, like world().
  std::span<const glm::mat4> palettes() const { return palette_; }
  std::span<const glm::mat4> palette(int slot) const {
    return {palette_.data() + static_cast<size_t>(slot) * num_joints_,
            static_cast<size_t>(num_joints_)};
  }
  std::span<const glm::quat> local_rotations(int slot) const {
    return {local_rot_.data() + static_cast<size_t>(slot) * num_joints_,
            static_cast<size_t>(num_joints_)};
  }
  // Largest change of any joint's local rotation since the slot's previous frame [rad] (0 on an
  // agent's first frame, and on a frame posed PoseDetail::kLight or right after one).
  float max_rotation_change(int slot) const { return rot_change_[slot]; }
  const FootLocks& foot_locks() const { return locks_; }
  // Final torsion pelvis -> chest [rad], signed, per slot.
  float torsion(int slot) const { return torsion_[slot]; }
  // Ground headings [rad] of the pelvis and the upper chest (rest-pose relative), per slot.
  float pelvis_heading(int slot) const { return pelvis_heading_[slot]; }
  float upper_heading(int slot) const { return upper_heading_[slot]; }
  const std::vector<glm::mat4>& inverse_bind() const { return inverse_bind_; }

 private:
  struct Scratch;
  void synthesize_agent(const AnimationPlans& pl, const MediatorParams& P, int slot, float dt,
                        Scratch& s, PoseDetail detail = PoseDetail::kFull);
  void hold_agent(const AnimationPlans& pl, int slot);
  void prefetch_agent(const AnimationPlans& pl, int slot, std::span<const uint8_t> detail) const;
  glm::mat4* world_of(int slot, Scratch& s);
  void pose_coarse(const AnimationPlans& pl, const MediatorParams& P, int slot, Scratch& s);
  // Pointers, not spans: a span passed on the stack is read back whole, which the store buffer
  // cannot forward from its two halves (the load then waits for the buffer to drain).
  void sample_layers(const AnimationPlans& pl, int slot, bool coarse, Scratch& s,
                     glm::quat* out_rot, glm::vec3* out_trans, size_t n);
  // pelvis_known: pelvis_heading_[slot] is already this pose's (twist_spine measured it).
  // `rot`: the pose's local rotations (null for a coarse pose, which keeps none).
  void finish_pose(int slot, const glm::mat4* world, const glm::quat* rot, PoseDetail detail,
                   bool locking, bool pelvis_known);
  // Forward kinematics of joints [from, to) of an agent (their parents outside it are current):
  // its world joints, local rotations and translations, all in the posing thread's scratch.
  void fk(glm::mat4* world, const glm::quat* rot, const glm::vec3* trans, int from, int to,
          const glm::mat4& root);
  // Joints [from, to) to recompute after some local transforms changed (empty: from == to).
  struct JointRange {
    int from = 0, to = 0;
  };
  JointRange subtree(int joint) const;
  // Forward kinematics of an agent's joints in `joints`' order (LocalToModelListJob: runs of a
  // few joints each go four at a time across the runs, in one call).
  void fk_list(glm::mat4* world, const glm::quat* rot, const glm::vec3* trans,
               const std::vector<int16_t>& joints, const glm::mat4& root);
  // The joints of range a and then b (overlapping ranges as one), in order.
  std::vector<int16_t> range_list(JointRange a, JointRange b) const;
  void twist_spine(int slot, glm::mat4* world, glm::quat* rot, const glm::vec3* trans,
                   const glm::mat4& root, float upper_yaw, float limit_rad);
  // Foot locks and leg IK. letting_go: the agent has left full detail, so no foot is pinned anew
  // (nor re-planted by a step); the locks it still has are let go as the clips lift each foot,
  // through the usual release, so nothing snaps.
  void lock_feet(const AnimationPlans& pl, const MediatorParams& P, int slot, glm::mat4* world,
                 glm::quat* rot, const glm::vec3* trans, const glm::mat4& root, float dt,
                 bool letting_go = false);
  // Any foot of the slot still pinned, stepping or shedding a release offset.
  bool locks_held(int slot) const;

  const LocomotionLibrary& library_;
  const Skeleton& skeleton_;
  int num_joints_;
  bool make_palettes_;
  std::vector<glm::vec3> rest_forward_;  // per joint, +z of the rest pose in the joint's frame
  std::vector<glm::mat4> inverse_bind_;
  std::vector<glm::quat> local_rot_;  // the last posed rotations (max_rotation_change's reference)
  std::vector<glm::mat4> world_;
  std::vector<glm::mat4> palette_;
  std::vector<uint8_t> palette_due_;  // per slot: posed since its palette was last made
  std::vector<float> rot_change_;
  std::vector<float> torsion_;
  std::vector<float> pelvis_heading_;
  std::vector<float> upper_heading_;
  std::vector<uint8_t> has_prev_;
  std::vector<uint8_t> prev_rot_valid_;  // local_rot_ holds a pose to measure the change against
  std::vector<float> drop_;       // pelvis drop per slot [m]
  std::vector<float> drop_rate_;  // its rate [m/s] (critically damped spring)
  // The pelvis drop's and the heels' springs over this run's dt (every agent steps by it): their
  // exps once per frame, set by run().
  SpringStep drop_step_, heel_up_step_, heel_down_step_;
  std::vector<glm::vec2> placed_xz_;  // root (x, z) [m] the slot's world joints are placed at
  std::vector<glm::vec2> root_offset_;    // root_offset(slot)
  std::vector<SupportReach> support_reach_;  // support_reach()
  FootLocks locks_;
  std::unique_ptr<tbb::enumerable_thread_specific<Scratch>> scratch_;
  std::vector<int> subtree_end_;  // subtree_ends(skeleton_)
  JointRange leg_range_[2];       // per side, what moves when leg IK turns the hip and the knee
  // leg_range_ without its ankle's subtree when that is the range's tail (the feet are posed again
  // once the ankles are restored), else leg_range_.
  JointRange leg_above_ankle_[2];
  // The spine twist's range (the spine chain's first joint's subtree) and the joints in it that
  // the twist reads before it changes them (the chain, the chest and their ancestors in it): the
  // rest of the range is posed once, after the twist.
  bool can_twist_ = false;
  bool pelvis_stays_ = false;  // the pelvis is outside the twist's and the leg IK's ranges
  JointRange twist_range_;
  std::vector<JointRange> pre_twist_;  // those joints, as runs of consecutive ones
  std::vector<int16_t> pre_twist_fk_;  // all joints posed before the twist, in order
  // The joints leg IK poses again (leg_above_ankle_) and then the feet (the ankles' subtrees), by
  // the sides it turns (bit 0 left, bit 1 right).
  std::vector<int16_t> leg_fk_[4], foot_fk_[4];
  CoarseRig coarse_;  // the joints a kLight pose samples (mediator/coarse_pose.h)
  // The joints whose translations are sampled per agent (ascending), or empty: all of them. The
  // others' are the same in every frame of every clip and kept in each Scratch's local_trans.
  std::vector<int16_t> translated_joints_;
  // Joints no clip moves (whole subtrees the pose stage reads nothing of: the mannequin's
  // fingers) are not sampled per agent: their pose (fixed_rot_, fixed_trans_) stays in each
  // Scratch. sampled_runs_ are the other joints, or empty: all of them.
  std::vector<JointRun> sampled_runs_, fixed_runs_;
  std::vector<glm::quat> fixed_rot_;
  std::vector<glm::vec3> fixed_trans_;
  bool affine_inverse_bind_ = false;
  bool translation_inverse_bind_ = false;  // is_translation(inverse_bind_): the cheaper palette
  bool stream_palettes_ = false;
  bool stream_world_ = false;  // world_ is written with streaming stores (copy_matrices)
};

// The heel-off pivot of leg IK (for tests): the foot's pitch about its toe [rad] that brings the
// ankle within `limit` [m] of the hip: the heel rises about the ball, as far as the foot may pitch
// up (at most to about 57 deg of the toe -> ankle line; all of that when even it is not enough).
// Found by 12 bisection steps over that range (the distance shrinks as the heel rises toward the
// hip), most of them decided by the distance's closed form; with `closed_form` off, every step
// measures the distance (the reference).
float heel_off_pitch(const glm::vec3& toe, const glm::vec3& ankle, const glm::vec3& hip,
                     float limit, bool closed_form = true);

// Forward direction on the ground of a joint, relative to its rest orientation (the rest pose faces
// +z; rest_forward is that +z in the joint's own frame): heading [rad], by fast_atan2
// (animation/fast_atan2.h: within 3e-7 rad).
float joint_heading(const glm::mat4& world, const glm::vec3& rest_forward);

}  // namespace gk
