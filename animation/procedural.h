#pragma once
// The built-in default that needs no files: a procedural humanoid skeleton, a procedurally generated
// locomotion set on it (idle, walks from slow to fast, jog, run, strafe left/right, walk backward),
// cyclic, with root motion, and a mannequin mesh generated and skinned for any skeleton.

#include <memory>

#include "animation/clip.h"
#include "animation/mesh.h"

namespace gk {

struct HumanoidParams {
  float height_m = 1.75f;
};

std::shared_ptr<const Skeleton> make_humanoid_skeleton(const HumanoidParams& params = {});

// The locomotion set on the humanoid skeleton, plus its mannequin.
ClipSet make_builtin_clip_set(const HumanoidParams& params = {});

// A mannequin (capsule-like limbs and torso, head, feet) generated from any skeleton's rest pose
// with smooth skin weights; requires only parents and rest transforms, uses roles when present.
std::shared_ptr<const SkinnedMesh> make_mannequin_mesh(const Skeleton& skeleton);

// Half-width of the body seen from above [skeleton units], from the rest pose: half the distance
// between the shoulder joints plus the mannequin's upper-arm radius, or half the distance between
// the hip joints plus its pelvis radius, whichever is wider (0.25 m for the built-in 1.75 m
// humanoid). A crowd simulator that keeps agents two such radii apart keeps the drawn bodies from
// overlapping side by side. Skeletons without those roles: 0.14 of the estimated stature.
float body_radius(const Skeleton& skeleton);

}  // namespace gk
