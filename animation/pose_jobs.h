#pragma once
// Runtime jobs over one character's pose (ozz-animation style): inputs as spans of const data,
// outputs as spans the caller owns, validate() before run(), no allocation inside. The crowd-wide
// passes call them per agent in parallel.

#include <span>

#include <glm/gtc/quaternion.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "animation/clip.h"
#include "animation/skeleton.h"

namespace gk {

// Joints [from, to) of a skeleton.
struct JointRun {
  int from = 0, to = 0;
};

// Samples a clip at time_s with linear interpolation of translations and normalised lerp of
// rotations (shortest arc). Looping clips wrap time; others clamp it to [0, duration]. Between the
// last frame of a loop and its first, the root joint (joint 0) keeps its mean horizontal velocity
// instead of jumping back, so root motion stays continuous within one loop; callers that chain
// loops add one loop's displacement per wrap.
struct SampleClipJob {
  const Clip* clip = nullptr;
  float time_s = 0.0f;
  std::span<glm::quat> out_rotations;     // num_joints
  std::span<glm::vec3> out_translations;  // num_joints
  // Non-empty: only these joints' translations (ascending) are sampled and written; the others
  // are left as they are in out_translations. For joints whose translation is the same in every
  // frame of every clip (a BVH's offsets): the caller keeps that value there once, and a lerp or
  // blend of it per agent would only round it.
  std::span<const int16_t> translated_joints;
  // Non-empty: only the joints of these runs (ascending, apart, within the skeleton) are sampled
  // and written, rotations and translations (of those, with translated_joints, only the listed
  // ones' translations); the others are left as they are. For joints no clip moves (a rig's
  // fingers): the caller keeps their pose there once.
  std::span<const JointRun> sampled_runs;
  bool validate() const;
  void run() const;
};

// Two clips sampled and blended (weights normalised) straight into the output: the same numbers
// as SampleClipJob into two layers and BlendPosesJob over them (but for the sign of a zero, as
// BlendPosesJob's own four-wide loop), without the layers' buffers (each sample stays in registers
// until it is blended).
struct SampleBlendJob {
  struct Input {
    const Clip* clip = nullptr;
    float time_s = 0.0f;
    float weight = 0.0f;  // > 0
  };
  Input a, b;  // clips of the same skeleton
  std::span<glm::quat> out_rotations;     // num_joints
  std::span<glm::vec3> out_translations;  // num_joints
  // Non-empty: only these joints' translations (ascending) are sampled and written; the others
  // are left as they are in out_translations. For joints whose translation is the same in every
  // frame of every clip (a BVH's offsets): the caller keeps that value there once, and a lerp or
  // blend of it per agent would only round it.
  std::span<const int16_t> translated_joints;
  // Non-empty: only the joints of these runs (ascending, apart, within the skeleton) are sampled
  // and written, rotations and translations (of those, with translated_joints, only the listed
  // ones' translations); the others are left as they are. For joints no clip moves (a rig's
  // fingers): the caller keeps their pose there once.
  std::span<const JointRun> sampled_runs;
  bool validate() const;
  void run() const;
};

// One input of a blend: a local pose and its weight (weights need not sum to 1; they are
// normalised; layers with weight <= 0 are skipped).
struct PoseLayer {
  std::span<const glm::quat> rotations;
  std::span<const glm::vec3> translations;
  float weight = 0.0f;
};

// Weighted blend of N local poses: translations by weighted mean, rotations by weighted nlerp with
// every quaternion brought into the hemisphere of the first layer's. A single weighted layer is
// copied as it is (its rotations are taken to be unit quaternions, as a sampled clip's are).
struct BlendPosesJob {
  std::span<const PoseLayer> layers;
  std::span<glm::quat> out_rotations;
  std::span<glm::vec3> out_translations;
  // Non-empty: only these joints' translations (ascending) are blended and written; the others
  // are left as they are in out_translations. For joints whose translation is the same in every
  // frame of every layer: the caller keeps that value there once, and a lerp or
  // blend of it per agent would only round it.
  std::span<const int16_t> translated_joints;
  bool validate() const;
  void run() const;
};

// Local to model (forward kinematics): out_model[i] = out_model[parent] * T(t_i) * R(q_i), with
// root_transform applied to the roots (world placement of the character).
// By default every joint; [from, to) recomputes only those joints (ozz's from/to), for a partial
// update after some local transforms changed: out_model of every parent outside the range must be
// current. After joint j changed, [j, subtree_ends(skeleton)[j]) covers everything that moved.
struct LocalToModelJob {
  const Skeleton* skeleton = nullptr;
  std::span<const glm::quat> rotations;
  std::span<const glm::vec3> translations;
  glm::mat4 root_transform = glm::mat4(1.0f);
  std::span<glm::mat4> out_model;
  int from = 0;
  int to = -1;  // < 0: to the last joint
  bool validate() const;
  void run() const;
};

// Analytic two-bone IK (hip-knee-ankle). Given the model-space transforms of the start, mid and
// end joints, finds local rotation corrections so that the end joint reaches target (or gets as
// close as the limb allows), with the mid joint bending toward pole. Apply them as
//   local[start] = local[start] * out_start_correction; local[mid] = local[mid] *
//   out_mid_correction
// and recompute FK below the start joint.
struct TwoBoneIKJob {
  glm::mat4 start_model{1.0f};
  glm::mat4 mid_model{1.0f};
  glm::mat4 end_model{1.0f};
  glm::vec3 target{0.0f};
  glm::vec3 pole{0.0f, 0.0f, 1.0f};  // model-space direction the knee should point to
  float weight = 1.0f;               // [0, 1]: 0 leaves the pose unchanged
  // Fraction of the full limb length never exceeded, so the knee never snaps straight.
  float max_extension = 0.999f;
  // Soft IK: beyond this fraction of max_extension the chain reaches ever less of the remaining
  // distance (an exponential approach, continuous in value and slope), so a knee straightens
  // smoothly instead of snapping as the target crosses full reach (1 = off, a hard clamp). Reach
  // up to the pose's own hip-to-end distance is never softened.
  float soften = 1.0f;
  glm::quat* out_start_correction = nullptr;
  glm::quat* out_mid_correction = nullptr;
  bool* out_reached = nullptr;  // optional: target within reach
  bool validate() const;
  void run() const;
};

// Two limbs' TwoBoneIKJobs at once (a body's two legs), each job's operations in its order on SSE
// lanes: the same corrections, to the bit, as a.run() and b.run() (sqrt and division are
// correctly rounded in either form; exp is taken per lane by the same function). Rare cases (a
// limb straighter than 2 deg, degenerate lengths, a rotation near half a turn, a weight below 1,
// an out_reached asked for) run the jobs one by one. Without SSE2: a.run(); b.run().
void two_bone_ik_pair(const TwoBoneIKJob& a, const TwoBoneIKJob& b);

// A TwoBoneIKJob of weight 1 without out_reached, its matrices by pointer: two_bone_ik_pair's
// inputs without copying three matrices per limb (no member initialisers: nothing is written
// before the caller's fields).
struct TwoBoneIKLimb {
  const glm::mat4* start_model;
  const glm::mat4* mid_model;
  const glm::mat4* end_model;
  glm::vec3 target, pole;
  float max_extension, soften;
  glm::quat* out_start_correction;
  glm::quat* out_mid_correction;
  TwoBoneIKJob job() const;  // the same limb as a job
};
void two_bone_ik_pair(const TwoBoneIKLimb& a, const TwoBoneIKLimb& b);

// Skinning matrices: out[j] = model[j] * inverse_bind[j]. Affine inverse binds (bottom row
// 0 0 0 1, as every rig's) take the cheaper affine product; affine_inverse_bind tells which
// (is_affine(inverse_bind) once per rig; false always gives the full product).
struct SkinningPaletteJob {
  std::span<const glm::mat4> model;
  std::span<const glm::mat4> inverse_bind;
  std::span<glm::mat4> out_palette;
  bool affine_inverse_bind = false;
  // With affine_inverse_bind: write the palette past the caches (non-temporal stores), for a
  // crowd's palettes, far more than the caches hold and read only later by the upload.
  bool stream_out = false;
  // With stream_out: end with a store fence (streamed stores are ordered before whatever follows).
  // Off, the caller fences once after many palettes (stream_fence()): a fence per palette waits
  // for each one's stores to reach memory.
  bool fence = true;
  // Non-empty (model's size): the model matrices are also copied there, streamed as the palette
  // is read from them (copy_matrices with stream on, in the same pass).
  std::span<glm::mat4> out_model_copy;
  // With affine_inverse_bind: every inverse bind is a translation (its 3x3 exactly the identity,
  // as a rig whose rest rotations are all the identity has, a BVH's): the palette's first three
  // columns are the model matrix's own (the product's but for the sign of a zero: x * 1 + y * 0
  // + z * 0 is x), and only the last is computed. is_translation(inverse_bind) tells which.
  bool translation_inverse_bind = false;
  bool validate() const;
  void run() const;
};

// Copies matrices (`to` at least as long as `from`); with `stream`, past the caches (streaming
// stores when `to` is 16-byte aligned: a crowd's worth of them is read only after the crowd is
// posed; stream_fence() orders them before telling anyone).
void copy_matrices(std::span<const glm::mat4> from, std::span<glm::mat4> to, bool stream);

// Orders the streamed stores of SkinningPaletteJobs run with fence off before what follows.
void stream_fence();

// The smallest |dot(a[j], b[j])| over j (1 when empty): the largest angle between two poses'
// rotations is 2 acos of it. Four joints at a time, glm's dot to the bit.
float min_abs_dot(std::span<const glm::quat> a, std::span<const glm::quat> b);

// min_abs_dot(a, b), and then b = a (a pose's rotations kept as the next frame's previous ones):
// one pass over both.
float min_abs_dot_then_copy(std::span<const glm::quat> a, std::span<glm::quat> b);

// True when every matrix's bottom row is exactly 0 0 0 1.
bool is_affine(std::span<const glm::mat4> matrices);
// True when every matrix is affine and its 3x3 exactly the identity (a translation).
bool is_translation(std::span<const glm::mat4> matrices);

// Asks the caches for the lines of [p, p + bytes) ahead of use (a hint; no effect on results).
inline void prefetch_bytes(const void* p, size_t bytes, bool for_write = false) {
  const char* c = static_cast<const char*>(p);
  for (size_t off = 0; off < bytes; off += 64) {
    if (for_write) {
      __builtin_prefetch(c + off, 1);
    } else {
      __builtin_prefetch(c + off, 0);
    }
  }
  if (bytes > 0 && for_write) __builtin_prefetch(c + bytes - 1, 1);
  if (bytes > 0 && !for_write) __builtin_prefetch(c + bytes - 1, 0);
}

// Small helpers used by several jobs and by analysis.
inline glm::vec3 translation_of(const glm::mat4& m) { return glm::vec3(m[3]); }
// Model-space transforms of one frame of a clip (no placement): LocalToModelJob over its rows.
void clip_frame_model(const Clip& clip, const Skeleton& skeleton, int frame,
                      std::span<glm::mat4> out_model);
// Heading [rad] about +y of a horizontal direction (0 = +z, pi/2 = +x).
float heading_of(const glm::vec3& dir);
// Forward (+z) direction of a model matrix, projected on the ground and normalised (0 if vertical).
glm::vec3 horizontal_forward(const glm::mat4& m);

}  // namespace gk
