// Mirror images of motion: which joint mirrors which on every rig of the shared data (checked
// against the rigs' own naming, decoded here independently), the reflection against geometry
// (mirrored twice is the clip itself; a mirrored joint lies where the reflection puts the original),
// and the built-in walk, which the generator makes left-right symmetric half a cycle apart: its
// mirror image is the same walk half a cycle on.

#include <cctype>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "animation/clip_library.h"
#include "animation/mirror.h"
#include "animation/pose_jobs.h"
#include "animation/procedural.h"
#include "tests/animation/joint_positions.h"
#include "tests/test_data.h"

namespace gk {
namespace {

// The partner a rig's naming gives a joint, decoded without the library's rules: a "Left"/"Right"
// word, a ".L"/".R" or "_l"/"_r" suffix, or a one-letter side prefix before the body part
// ("LHipJoint", "lfemur"); empty when the name has no side.
std::string named_partner(const std::string& n, const Skeleton& sk) {
  auto swap_word = [&](const std::string& a, const std::string& b) -> std::string {
    const size_t at = n.find(a);
    if (at == std::string::npos) return "";
    std::string s = n;
    s.replace(at, a.size(), b);
    return s;
  };
  for (const auto& [a, b] : {std::pair{"Left", "Right"}, std::pair{"Right", "Left"}}) {
    if (std::string s = swap_word(a, b); !s.empty()) return s;
  }
  const size_t len = n.size();
  if (len > 2 && (n[len - 2] == '.' || n[len - 2] == '_')) {
    const char c = n[len - 1];
    const char o = c == 'L' ? 'R' : c == 'R' ? 'L' : c == 'l' ? 'r' : c == 'r' ? 'l' : 0;
    if (o != 0) return n.substr(0, len - 1) + o;
  }
  if (len > 1) {
    const char c = n[0];
    const char o = c == 'L' ? 'R' : c == 'R' ? 'L' : c == 'l' ? 'r' : c == 'r' ? 'l' : 0;
    // Upper-case side letter before an upper-case part ("LThumb"); lower-case side letter where
    // the rest of the name exists with the other letter too ("lfemur"/"rfemur").
    const bool upper = (c == 'L' || c == 'R') && std::isupper(static_cast<unsigned char>(n[1]));
    if (o != 0 && (upper || (std::islower(static_cast<unsigned char>(c)) &&
                             sk.find(std::string(1, o) + n.substr(1)) >= 0))) {
      return std::string(1, o) + n.substr(1);
    }
  }
  return "";
}

void expect_map_follows_names(const Skeleton& sk, const std::string& what) {
  const std::vector<int16_t> map = mirror_joint_map(sk);
  ASSERT_EQ(static_cast<int>(map.size()), sk.num_joints()) << what;
  int paired = 0;
  for (int j = 0; j < sk.num_joints(); ++j) {
    ASSERT_GE(map[j], 0) << what;
    EXPECT_EQ(map[map[j]], j) << what << ": " << sk.names[j];  // an involution
    const std::string partner = named_partner(sk.names[j], sk);
    if (!partner.empty() && sk.find(partner) >= 0) {
      EXPECT_EQ(sk.names[map[j]], partner) << what << ": " << sk.names[j];
      ++paired;
    } else {
      EXPECT_EQ(map[j], j) << what << ": " << sk.names[j] << " has no side, mirrored to "
                           << sk.names[map[j]];
    }
  }
  // Both legs at least (hip, knee, ankle, toe on each side).
  EXPECT_GE(paired, 8) << what;
}

TEST(Mirror, JointsPairAsTheRigsNameThem) {
  expect_map_follows_names(*make_humanoid_skeleton(), "built-in");
  const char* rigs[] = {"clips/bvh/cmu_07_01_walk.bvh", "clips/bvh/ual_walk_loop.bvh",
                        "clips/bvh/more/cmu_16_15_walk_mrl30.bvh",
                        "clips/gltf/ual_mannequin_quaternius.glb"};
  for (const char* rel : rigs) GK_REQUIRE_DATA(rel);
  for (const char* rel : rigs) {
    auto set = load_clip_file(test::data_path(rel));
    ASSERT_TRUE(set.ok()) << set.message();
    expect_map_follows_names(*set->skeleton, rel);
  }
}

// Without usable names (every joint renamed to a number), the rest pose alone pairs the legs and
// arms of the built-in rig as its names did.
TEST(Mirror, TheRestPosePairsJointsWithoutNames) {
  const std::shared_ptr<const Skeleton> rig = make_humanoid_skeleton();
  const Skeleton& named = *rig;
  Skeleton anonymous = named;
  for (int j = 0; j < anonymous.num_joints(); ++j) anonymous.names[j] = "joint" + std::to_string(j);
  EXPECT_EQ(mirror_joint_map(anonymous), mirror_joint_map(named));
}

// Reflected twice in the same plane, a clip is itself; once, every joint of the mirror image lies
// where the reflection puts its partner, and the root travels mirrored.
TEST(Mirror, ReflectsPositionsExactlyAndTwiceIsIdentity) {
  const ClipSet set = make_builtin_clip_set();
  const Skeleton& sk = *set.skeleton;
  const std::vector<int16_t> map = mirror_joint_map(sk);
  const glm::vec3 point(0.3f, 0.0f, -0.2f);
  const glm::vec3 normal = glm::normalize(glm::vec3(1.0f, 0.0f, 0.4f));
  for (const Clip& c : set.clips) {
    const Clip once = mirror_clip(c, sk, map, point, normal);
    const Clip twice = mirror_clip(once, sk, map, point, normal);
    ASSERT_EQ(once.num_frames, c.num_frames);
    for (int f = 0; f < c.num_frames; f += 5) {
      const std::vector<glm::vec3> p = test::joint_positions(c, sk, f);
      const std::vector<glm::vec3> m = test::joint_positions(once, sk, f);
      const std::vector<glm::vec3> back = test::joint_positions(twice, sk, f);
      for (int j = 0; j < sk.num_joints(); ++j) {
        const glm::vec3 want = p[j] - 2.0f * glm::dot(p[j] - point, normal) * normal;
        EXPECT_LT(glm::length(m[map[j]] - want), 1e-4f) << c.name << " frame " << f << " "
                                                         << sk.names[j];
        EXPECT_LT(glm::length(back[j] - p[j]), 1e-4f) << c.name << " frame " << f << " "
                                                      << sk.names[j];
      }
    }
  }
}

// The built-in forward walk is generated left-right symmetric, the right side half a cycle behind
// the left: mirrored in its middle plane it is the same walk half a cycle on (positions relative to
// the hips' travel; the rotations too, as every joint's orientation decides the skinned mesh).
TEST(Mirror, TheBuiltInWalkMirroredIsItselfHalfACycleOn) {
  const ClipSet set = make_builtin_clip_set();
  const Skeleton& sk = *set.skeleton;
  const std::vector<int16_t> map = mirror_joint_map(sk);
  int checked = 0;
  for (const Clip& c : set.clips) {
    if (c.name.find("walk") == std::string::npos || c.num_frames % 2 != 0) continue;
    const Clip m = mirror_clip(c, sk, map, glm::vec3(0.0f), glm::vec3(1.0f, 0.0f, 0.0f));
    const int half = c.num_frames / 2;
    const int hips = sk.role(JointRole::kHips);
    for (int f = 0; f < c.num_frames; ++f) {
      const int g = (f + half) % c.num_frames;
      const std::vector<glm::vec3> a = test::joint_positions(m, sk, f);
      const std::vector<glm::vec3> b = test::joint_positions(c, sk, g);
      for (int j = 0; j < sk.num_joints(); ++j) {
        const glm::vec3 pa = a[j] - glm::vec3(0.0f, 0.0f, a[hips].z);
        const glm::vec3 pb = b[j] - glm::vec3(0.0f, 0.0f, b[hips].z);
        EXPECT_LT(glm::length(pa - pb), 2e-3f) << c.name << " frame " << f << " " << sk.names[j];
      }
    }
    ++checked;
  }
  EXPECT_GE(checked, 1);
}

}  // namespace
}  // namespace gk
