#pragma once
// Loading clips from user paths: files (.bvh, .gltf, .glb) or folders of them.

#include <string>
#include <vector>

#include "animation/bvh_loader.h"
#include "animation/clip.h"

namespace gk {

// Loads one file by extension.
Result<ClipSet> load_clip_file(const std::string& path, const LoadOptions& options = {});

// Expands folders (non-recursive, sorted by name) into the clip files they contain; a folder
// without any .bvh/.gltf/.glb file is an error (naming it), not an empty result.
Result<std::vector<std::string>> expand_clip_paths(const std::vector<std::string>& paths);

}  // namespace gk
