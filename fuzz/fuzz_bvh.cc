// libFuzzer harness: BVH text through parse_bvh (hierarchy, channels, motion, unit detection, role
// detection, loop detection). Any input must give a clip set or an error, never a crash.

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "animation/bvh_loader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  gk::Result<gk::ClipSet> set = gk::parse_bvh(text, "fuzz.bvh");
  if (set.ok()) (void)gk::validate_skeleton(*set->skeleton, "fuzz.bvh");
  return 0;
}
