#pragma once
// Helpers shared by the BVH and glTF loaders (private to animation/).

#include <string>
#include <vector>

#include <glm/mat4x4.hpp>

#include "animation/clip.h"
#include "animation/skeleton.h"

namespace gk::internal {

// Model-space joint transforms of one local pose (same convention as LocalToModelJob); loaders use
// it so that they do not depend on the runtime jobs.
void local_to_model(const Skeleton& skeleton, const glm::quat* rotations,
                    const glm::vec3* translations, std::vector<glm::mat4>* out_model);

// Largest model-space difference [m] between the first and last frame of any joint position or
// of a point 0.1 m along any joint axis, with the root's horizontal translation removed so that
// travelling clips compare their poses only.
float loop_mismatch_m(const Clip& clip, const Skeleton& skeleton);

// Detects a closed loop (last frame repeats the first within tolerance_m) and then drops that
// duplicate frame and sets loops = true; otherwise loops = false. Clips of < 3 frames never loop.
void finalize_loop(Clip* clip, const Skeleton& skeleton, float tolerance_m);

// Loop tolerance for a skeleton: a fraction of the leg length (or 5 cm without leg roles), so that
// keyframed loops whose end differs by a few cm (UAL jog: 2.9 cm) still close, while mocap clips
// that travel and end mid-stride do not.
float loop_tolerance_m(const Skeleton& skeleton);

// Turns a take authored with another up axis (a Z-up or X-up tool) to stand along +y: every
// root's rest transform and per-frame transform are turned by the shortest rotation that takes
// the body's up axis to +y, so every joint keeps its place relative to the others. The body's up
// is the axis nearest the direction from the feet (ankles or toes) to the head (or neck, chest)
// in the rest pose, where that is within 37 degrees of an axis; a take whose motion stands along
// +y throughout is never turned (a rest pose authored lying down), nor one without those roles.
// Returns what was found and done ("+z: turned to stand along +y ..."), for ClipSet::up_reason.
std::string stand_up_along_y(Skeleton* skeleton, Clip* clip);

// File name without folders and extension ("walk" for "/a/walk.bvh").
std::string file_stem(const std::string& path);
// File name without folders ("walk.bvh").
std::string file_name(const std::string& path);

}  // namespace gk::internal
