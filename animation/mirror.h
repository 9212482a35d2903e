#pragma once
// Mirror images of motion: the left side's joints play what the right side's did and vice versa,
// reflected in a vertical plane. A take with only one good step (a stop, a sudden stop) has no
// steady stride to loop; that step and its mirror image make one.

#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "animation/clip.h"
#include "animation/skeleton.h"

namespace gk {

// Per joint, the joint on the other side of the body that mirrors it (itself for a joint on the
// body's middle, or one without a counterpart). Pairs come from the leg roles, then from names that
// differ only in their side (Left/Right, L/R, l/r, .L/.R, _l/_r: "LeftUpLeg", "lfemur", "thigh.L",
// "LHipJoint"), confirmed by the rest pose (the two lie mirrored across the hips' middle plane);
// a joint whose name finds none is paired by the rest pose alone: the joint at the same depth of
// the tree whose rest position is the mirror image of its own, within a few percent of the leg.
std::vector<int16_t> mirror_joint_map(const Skeleton& skeleton);

// The clip's motion mirrored: every frame reflected in the vertical plane through `point` with the
// horizontal unit normal `normal` (in the clip's own space, where its root moves), each joint's
// motion given to its mirror joint (`map`, from mirror_joint_map). A joint's rotation away from
// its rest pose is what is reflected, so rigs whose left and right joints have differently
// oriented local axes mirror as well as symmetric ones. Each joint keeps its own bone (its offset
// from its parent); a joint whose offset the clip animates (the root's travel, position channels)
// is placed where the reflection puts it. The result keeps the clip's frame rate, length and
// looping.
Clip mirror_clip(const Clip& clip, const Skeleton& skeleton, const std::vector<int16_t>& map,
                 const glm::vec3& point, const glm::vec3& normal);

}  // namespace gk
