#pragma once
// BVH (Biovision hierarchy) loading: any channel order and count per joint, End Sites, CRLF or LF,
// tabs or spaces. Translations are converted to metres with a unit scale that is detected from the
// leg length (metres, centimetres, inches, or the CMU/cgspeed unit of 0.056444 m) unless given.
// Never trusts the file: every count is checked against the bytes left before allocating, and every
// error names the file, the line and what was expected.

#include <string>
#include <string_view>

#include "animation/clip.h"

namespace gk {

struct LoadOptions {
  float scale_m_per_unit = 0.0f;  // > 0 forces the unit scale; 0 detects it
  std::string role_manifest;      // optional JSON overriding detected joint roles
  int max_joints = 1024;          // deeper/larger hierarchies are rejected as not sane
  int max_depth = 64;
};

// One clip (named after the file stem) on its skeleton; clip.loops is set when the last frame
// repeats the first (that frame is then dropped).
Result<ClipSet> load_bvh(const std::string& path, const LoadOptions& options = {});
// Same, from text in memory; source_name is used in messages.
Result<ClipSet> parse_bvh(std::string_view text, const std::string& source_name,
                          const LoadOptions& options = {});

// Detects the unit scale [m per file unit] from the rest-pose leg length (hip to ankle, or hips
// height). Fills reason with what was chosen and why.
float detect_unit_scale(const Skeleton& skeleton_in_file_units, std::string* reason);

}  // namespace gk
