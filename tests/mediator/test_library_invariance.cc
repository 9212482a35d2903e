// The library's in-place clips keep the hips on the travel line (the drawn root at p) wherever a
// take's root was and whatever joint is above the hips (tests/animation/clip_transforms.h).

#include <cmath>

#include <gtest/gtest.h>

#include "animation/pose_jobs.h"
#include "mediator/locomotion_library.h"
#include "tests/animation/clip_transforms.h"

namespace gk {
namespace {

using test::kDeg;
using test::Rig;

// Horizontal mean of the hips over a clip [m].
glm::vec2 mean_hips(const Clip& c, const Skeleton& sk) {
  std::vector<glm::mat4> model(sk.num_joints());
  glm::vec2 sum(0.0f);
  for (int f = 0; f < c.num_frames; ++f) {
    clip_frame_model(c, sk, f, model);
    const glm::vec3 h = translation_of(model[sk.role(JointRole::kHips)]);
    sum += glm::vec2(h.x, h.z);
  }
  return sum / static_cast<float>(c.num_frames);
}

// An in-place clip's hips stay on the travel line (the drawn root at p),
// wherever the take's root was and whatever is above the hips.
TEST(LibraryInvariance, InPlaceHipsStayOnTheTravelLine) {
  const char* file = "clips/bvh/more/cmu_16_15_walk_mrl30.bvh";
  GK_REQUIRE_DATA(file);
  const Rig r = test::load_rig(file);
  Rig side = r;
  test::move_take(&side.clip, *side.sk, glm::angleAxis(-120.0f * kDeg, glm::vec3(0, 1, 0)),
                  glm::vec3(0.5f, 0.0f, -0.7f));
  const Rig extra = test::with_parent_root(side, glm::vec3(0.3f, 0.0f, -0.4f),
                                           glm::angleAxis(-90.0f * kDeg, glm::vec3(1, 0, 0)));
  for (const Rig* rig : {&r, static_cast<const Rig*>(&side), &extra}) {
    ClipSet set;
    set.skeleton = rig->sk;
    set.clips.push_back(rig->clip);
    set.source = file;
    Result<LocomotionLibrary> lib = build_locomotion_library({set});
    ASSERT_TRUE(lib.ok()) << lib.message();
    int gait = 0;
    for (const LocomotionClip& lc : lib->clips) {
      if (!lc.gait) continue;
      ++gait;
      const glm::vec2 m = mean_hips(lc.clip, *lib->skeleton);
      EXPECT_LT(glm::length(m), 0.05f) << lc.clip.name << " hips at " << m.x << ", " << m.y;
      EXPECT_LT(std::abs(lc.direction_rad), 10.0f * kDeg) << lc.clip.name;
    }
    EXPECT_GE(gait, 1);
  }
}

}  // namespace
}  // namespace gk
