#pragma once
// glTF 2.0 / GLB loading through tinygltf: the skeleton from the (first) skin, every animation as a
// clip resampled at the keys' rate, and the skinned mesh (positions, normals, joints, weights,
// inverse bind matrices) for the renderer. Errors name the file and the glTF field.

#include <string>
#include <string_view>

#include "animation/bvh_loader.h"  // LoadOptions
#include "animation/clip.h"

namespace gk {

Result<ClipSet> load_gltf(const std::string& path, const LoadOptions& options = {});
// Same, from the bytes of a .glb (starting with the "glTF" magic) or .gltf file in memory;
// source_name labels the errors, and external buffer URIs resolve against its folder.
Result<ClipSet> parse_gltf(std::string_view bytes, const std::string& source_name,
                           const LoadOptions& options = {});

}  // namespace gk
