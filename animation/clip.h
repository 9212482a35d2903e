#pragma once
// Clip: sampled local joint transforms at a fixed frame rate, frame-major (all joints of frame 0,
// then frame 1, ...) so that sampling one time touches two contiguous blocks. The root joint's
// translation carries the root motion in metres (zero horizontal motion for in-place clips).
// Immutable once built.

#include <memory>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>
#include <glm/vec3.hpp>

#include "animation/skeleton.h"

namespace gk {

struct Clip {
  std::string name;
  std::string source;  // file it came from, or "builtin"
  float fps = 30.0f;
  int num_frames = 0;
  int num_joints = 0;
  // [frame * num_joints + joint]
  std::vector<glm::quat> rotations;
  std::vector<glm::vec3> translations;
  // Loop clips are sampled with wrap-around: frame num_frames-1 is followed by frame 0 (loaders
  // drop a final frame that duplicates the first).
  bool loops = true;
  // The frames sample a continuous motion (a capture: BVH), not keys meant to be joined by
  // straight segments (glTF's LINEAR interpolation): played below 60 fps, it is upsampled on a
  // monotone cubic (upsample_clip).
  bool sampled_capture = false;

  float duration_s() const {
    return loops ? num_frames / fps : (num_frames > 1 ? (num_frames - 1) / fps : 0.0f);
  }
  const glm::quat* frame_rotations(int frame) const {
    return rotations.data() + static_cast<size_t>(frame) * num_joints;
  }
  const glm::vec3* frame_translations(int frame) const {
    return translations.data() + static_cast<size_t>(frame) * num_joints;
  }
};

Status validate_clip(const Clip& clip, const Skeleton& skeleton);

// The clip at `factor` times its frame rate, the new frames on a monotone cubic through the
// source frames (per channel, Fritsch-Butland slopes: smooth, and never beyond the samples either
// side; rotations on one hemisphere, normalised): a 24 or 30 fps capture played at 60 Hz then
// moves smoothly between its samples instead of in straight segments whose velocity jumps at
// every source frame. Every source frame is kept exactly; the duration is the same. Beyond a
// take's ends the curve continues the end's own velocity; a loop wraps, a root moved on by the
// loop's ground travel. factor <= 1 (or a clip that does not match the skeleton) returns the clip
// unchanged.
Clip upsample_clip(const Clip& clip, int factor, const Skeleton& skeleton);

// A loaded or generated set: one skeleton, its clips, and optionally a skinned mesh.
struct SkinnedMesh;
struct ClipSet {
  std::shared_ptr<const Skeleton> skeleton;
  std::vector<Clip> clips;
  std::shared_ptr<const SkinnedMesh> mesh;  // null when the source has none (BVH)
  float scale_m_per_unit = 1.0f;            // the unit scale applied while loading
  std::string scale_reason;                 // how it was chosen ("detected: centimetres", ...)
  // IK-style feet re-parented under their shins at load (attach_ik_feet), or empty.
  std::string rig_reason;
  // Which way the source's body stands and whether it was turned to stand along +y (BVH from a
  // Z-up or X-up tool: internal::stand_up_along_y); empty where the format fixes it (glTF).
  std::string up_reason;
  std::string source;
};

}  // namespace gk
