// libFuzzer harness: a clip-role manifest ({"roles": {"left_knee": "Knee_L", ...}}) applied through
// apply_role_manifest_text to the built-in humanoid skeleton, then validated.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string_view>

#include "animation/procedural.h"
#include "animation/skeleton.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::shared_ptr<const gk::Skeleton> humanoid = gk::make_humanoid_skeleton();
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  gk::Skeleton skeleton = *humanoid;
  if (gk::apply_role_manifest_text(text, "fuzz_roles.json", &skeleton).ok()) {
    (void)gk::validate_skeleton(skeleton, "fuzz_roles.json");
  }
  return 0;
}
