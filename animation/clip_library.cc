// Clip files by extension, and folders expanded into the clip files they hold.

#include "animation/clip_library.h"

#include <algorithm>
#include <filesystem>
#include <system_error>

#include "animation/gltf_loader.h"
#include "common/ascii.h"

namespace gk {
namespace {

std::string lower_extension(const std::string& path) {
  return lower_ascii(std::filesystem::path(path).extension().string());
}

bool is_clip_extension(const std::string& ext) {
  return ext == ".bvh" || ext == ".gltf" || ext == ".glb";
}

}  // namespace

Result<ClipSet> load_clip_file(const std::string& path, const LoadOptions& options) {
  const std::string ext = lower_extension(path);
  if (ext == ".bvh") return load_bvh(path, options);
  if (ext == ".gltf" || ext == ".glb") return load_gltf(path, options);
  return Status::Error(path + ": unknown clip file type '" + ext +
                       "' (expected .bvh, .gltf or .glb)");
}

Result<std::vector<std::string>> expand_clip_paths(const std::vector<std::string>& paths) {
  std::vector<std::string> out;
  for (const std::string& path : paths) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) {
      std::vector<std::string> found;
      for (const auto& entry : std::filesystem::directory_iterator(path, ec)) {
        std::error_code file_ec;
        if (entry.is_regular_file(file_ec) && is_clip_extension(lower_extension(entry.path()))) {
          found.push_back(entry.path().string());
        }
      }
      if (ec) return Status::Error(path + ": cannot list folder: " + ec.message());
      if (found.empty()) {
        return Status::Error(path +
                             ": the folder holds no clips (expected .bvh, .gltf or .glb files)");
      }
      std::sort(found.begin(), found.end());
      out.insert(out.end(), found.begin(), found.end());
    } else if (std::filesystem::exists(path, ec)) {
      out.push_back(path);
    } else {
      return Status::Error(path + ": no such file or folder");
    }
  }
  return out;
}

}  // namespace gk
