// libFuzzer harness: .gltf JSON or .glb bytes through parse_gltf (tinygltf's parse, then every
// node, skin, accessor, animation and mesh index checked by our loader).

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "animation/gltf_loader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  // No folder in the name: a relative buffer URI resolves against the working directory, where
  // scripts/fuzz.sh runs the target (build-fuzz/), so it cannot reach the source tree.
  (void)gk::parse_gltf(bytes, "fuzz.glb");
  return 0;
}
