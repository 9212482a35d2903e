#pragma once
// BVH writing: a skeleton and one clip as BVH text that load_bvh reads back to the same poses
// (rotations as Z Y X Euler angles in degrees, translations in the chosen unit). For exporting
// cut-out cycles and for tests that turn a clip into a file of another unit or channel layout.

#include <string>

#include "animation/clip.h"

namespace gk {

struct BvhWriteOptions {
  float units_per_m = 1.0f;  // file units per metre (100: centimetres) [Limit: > 0]
  // 6 channels on every joint, not only on the roots and the joints whose translation moves
  bool positions_on_every_joint = false;
};

// The text of a BVH file. A looping clip is written with its first frame repeated at the end (its
// root moved on by one loop), as loop files are, so that load_bvh finds it closed again.
std::string format_bvh(const Skeleton& skeleton, const Clip& clip,
                       const BvhWriteOptions& options = {});

}  // namespace gk
