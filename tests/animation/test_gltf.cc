// glTF loading: the hand-written two-bone fixture (reordered skin, intermediate node, armature
// transform, LINEAR/STEP keys, skinned triangle), the bad fixtures, and the real mannequin glb
// against PROVENANCE.md and against the UAL BVH files converted from it.

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <glm/gtc/quaternion.hpp>

#include "animation/bvh_loader.h"
#include "animation/clip_library.h"
#include "animation/gltf_loader.h"
#include "animation/mesh.h"
#include "animation/pose_jobs.h"
#include "tests/test_data.h"
#include "tests/animation/model_pose.h"

namespace gk {
namespace {

constexpr const char* kGlb = "clips/gltf/ual_mannequin_quaternius.glb";

std::string fixture(const std::string& rel) { return test::source_path("tests/data/" + rel); }

using test::model_pose;

glm::vec3 joint_at(const ClipSet& set, const Clip& clip, int frame, int joint) {
  return glm::vec3(model_pose(*set.skeleton, clip.frame_rotations(frame),
                              clip.frame_translations(frame))[joint][3]);
}

TEST(GltfFixture, TwoBoneSkinReorderedWithIntermediateNode) {
  Result<ClipSet> set = load_clip_file(fixture("good/two_bone_skin.gltf"));
  ASSERT_TRUE(set.ok()) << set.message();
  const Skeleton& s = *set->skeleton;
  // Skin lists Tip before Base; Helper sits between them without being a skin joint.
  ASSERT_EQ(s.names, (std::vector<std::string>{"Base", "Helper", "Tip"}));
  EXPECT_EQ(s.parents, (std::vector<int16_t>{-1, 0, 1}));
  // The Armature node above the skin is folded into the top joint.
  EXPECT_NEAR(glm::distance(s.rest_translations[0], glm::vec3(0, 0, 1)), 0.0f, 1e-6f);

  ASSERT_EQ(set->clips.size(), 1u);
  const Clip& clip = set->clips[0];
  EXPECT_EQ(clip.name, "Bend");
  EXPECT_FLOAT_EQ(clip.fps, 2.0f);  // keys 0.5 s apart
  EXPECT_EQ(clip.num_frames, 3);
  EXPECT_FALSE(clip.loops);
  const float r = std::sqrt(2.0f);
  // t = 0.5: Base at (1,0,1) turned 45 deg about Z (LINEAR rotation halfway), Tip's STEP
  // translation still (0,1,0): Tip = Base + Rz(45)*(0,2,0).
  EXPECT_NEAR(glm::distance(joint_at(*set, clip, 1, 0), glm::vec3(1, 0, 1)), 0.0f, 1e-5f);
  EXPECT_NEAR(glm::distance(joint_at(*set, clip, 1, 2), glm::vec3(1 - r, r, 1)), 0.0f, 1e-5f);
  // t = 1: Base (2,0,1) turned 90 deg, Tip's translation now (0,3,0): Tip = (2,0,1) + (-4,0,0).
  EXPECT_NEAR(glm::distance(joint_at(*set, clip, 2, 1), glm::vec3(1, 0, 1)), 0.0f, 1e-5f);
  EXPECT_NEAR(glm::distance(joint_at(*set, clip, 2, 2), glm::vec3(-2, 0, 1)), 0.0f, 1e-5f);

  ASSERT_TRUE(set->mesh);
  const SkinnedMesh& m = *set->mesh;
  ASSERT_EQ(m.num_vertices(), 3);
  EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2}));
  // Skin joint 0 is Tip (skeleton joint 2), skin joint 1 is Base (skeleton joint 0).
  EXPECT_EQ(m.joints[0], glm::u16vec4(2, 2, 2, 2));
  EXPECT_EQ(m.joints[1], glm::u16vec4(0, 2, 2, 2));
  EXPECT_EQ(m.weights[0], glm::vec4(1, 0, 0, 0));  // (2,0,0,0) normalised
  EXPECT_EQ(m.weights[1], glm::vec4(0.5f, 0.5f, 0, 0));
  EXPECT_EQ(m.weights[2], glm::vec4(0, 0, 0, 1));
  for (const glm::vec3& c : m.colors) {
    EXPECT_NEAR(glm::distance(c, glm::vec3(0.2f, 0.4f, 0.6f)), 0.0f, 1e-6f);
  }
  ASSERT_EQ(m.inverse_bind.size(), 3u);  // no inverseBindMatrices in the file: identity
  EXPECT_EQ(m.inverse_bind[1], glm::mat4(1.0f));
}

TEST(GltfFixture, EachBadFileHasItsSpecificError) {
  const std::pair<const char*, const char*> cases[] = {
      {"gltf_sampler_index.gltf",
       "gltf_sampler_index.gltf: animations[0].channels[1].sampler: index 9 out of range (3 "
       "samplers)"},
      {"gltf_accessor_overflow.gltf",
       "gltf_accessor_overflow.gltf: accessors[5]: 1000000 elements of 12 bytes do not fit in "
       "bufferView 5 (36 bytes)"},
      {"gltf_no_skin.gltf", "gltf_no_skin.gltf: skins: no skin"},
      {"gltf_skin_joint_range.gltf",
       "gltf_skin_joint_range.gltf: skins[0].joints[1]: node 42 out of range (5 nodes)"},
      {"gltf_vertex_joint.gltf",
       "gltf_vertex_joint.gltf: meshes[0].primitives[0].attributes.JOINTS_0: vertex 1 uses joint "
       "7 (skin has 2)"},
      {"gltf_truncated.gltf", "gltf_truncated.gltf"},
  };
  for (const auto& [file, expected] : cases) {
    Result<ClipSet> set = load_gltf(fixture(std::string("bad/") + file));
    ASSERT_FALSE(set.ok()) << file;
    EXPECT_NE(set.message().find(expected), std::string::npos)
        << "expected '" << expected << "' in '" << set.message() << "'";
  }
  EXPECT_FALSE(load_gltf(fixture("bad/does_not_exist.glb")).ok());
}

// parse_gltf (bytes in memory, used by the fuzzer) gives the file loader's result and errors.
TEST(GltfFixture, ParseFromMemoryMatchesTheFileLoader) {
  auto read = [](const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  const std::string good = fixture("good/two_bone_skin.gltf");
  Result<ClipSet> from_file = load_gltf(good);
  Result<ClipSet> from_memory = parse_gltf(read(good), good);
  ASSERT_TRUE(from_file.ok()) << from_file.message();
  ASSERT_TRUE(from_memory.ok()) << from_memory.message();
  EXPECT_EQ(from_memory->skeleton->names, from_file->skeleton->names);
  ASSERT_EQ(from_memory->clips.size(), from_file->clips.size());
  EXPECT_EQ(from_memory->clips[0].rotations, from_file->clips[0].rotations);
  ASSERT_TRUE(from_memory->mesh);
  EXPECT_EQ(from_memory->mesh->num_vertices(), 3);

  const std::string bad = fixture("bad/gltf_sampler_index.gltf");
  Result<ClipSet> bad_set = parse_gltf(read(bad), "memory.gltf");
  ASSERT_FALSE(bad_set.ok());
  EXPECT_EQ(bad_set.message().rfind("memory.gltf: animations[0].channels[1].sampler", 0), 0u)
      << bad_set.message();
  // The same JSON in a GLB container (a JSON chunk only: the buffers are data: URIs).
  std::string json = read(good);
  json.resize((json.size() + 3) / 4 * 4, ' ');
  auto le32 = [](uint32_t v) {
    return std::string{char(v & 255), char(v >> 8 & 255), char(v >> 16 & 255), char(v >> 24)};
  };
  const auto json_size = static_cast<uint32_t>(json.size());
  const std::string glb = "glTF" + le32(2) + le32(20 + json_size) + le32(json_size) + "JSON" + json;
  Result<ClipSet> from_glb = parse_gltf(glb, "memory.glb");
  ASSERT_TRUE(from_glb.ok()) << from_glb.message();
  EXPECT_EQ(from_glb->skeleton->names, from_file->skeleton->names);
  EXPECT_FALSE(parse_gltf("glTF\x02", "short.glb").ok());
  EXPECT_FALSE(parse_gltf("", "empty.gltf").ok());
}

// The mannequin is loaded once for the tests below (about 0.1 s).
const ClipSet* mannequin() {
  static Result<ClipSet> set = load_gltf(test::data_path(kGlb));
  return set.ok() ? &set.value() : nullptr;
}

const Clip* find_clip(const ClipSet& set, const std::string& name) {
  for (const Clip& c : set.clips) {
    if (c.name == name) return &c;
  }
  return nullptr;
}

// PROVENANCE.md: 53 skin joints starting with the static `root` (-90 deg about X), 44 animations
// keyed at 24 fps, hips 0.92 m and head 1.57 m in the rest pose.
TEST(GltfMannequin, SkeletonAndClipsMatchProvenance) {
  GK_REQUIRE_DATA(kGlb);
  const ClipSet* set = mannequin();
  ASSERT_TRUE(set) << load_gltf(test::data_path(kGlb)).message();
  const Skeleton& s = *set->skeleton;
  ASSERT_EQ(s.num_joints(), 53);
  EXPECT_EQ(s.names[0], "root");
  EXPECT_EQ(std::count(s.parents.begin(), s.parents.end(), -1), 1);
  const glm::quat minus_90_x = glm::angleAxis(glm::radians(-90.0f), glm::vec3(1, 0, 0));
  EXPECT_NEAR(std::abs(glm::dot(s.rest_rotations[0], minus_90_x)), 1.0f, 1e-6f);

  const auto rest = model_pose(s, s.rest_rotations.data(), s.rest_translations.data());
  EXPECT_NEAR(rest[s.find("DEF-hips")][3].y, 0.92f, 0.01f);
  EXPECT_NEAR(rest[s.find("DEF-head")][3].y, 1.57f, 0.01f);

  ASSERT_EQ(set->clips.size(), 44u);
  for (const Clip& c : set->clips) {
    EXPECT_TRUE(validate_clip(c, s).ok()) << validate_clip(c, s).message();
    EXPECT_FLOAT_EQ(c.fps, 24.0f) << c.name;
    // root is constant in every clip.
    for (int f = 0; f < c.num_frames; ++f) {
      ASSERT_NEAR(std::abs(glm::dot(c.frame_rotations(f)[0], minus_90_x)), 1.0f, 1e-5f) << c.name;
    }
  }
  // Locomotion loops: PROVENANCE frame counts minus the duplicated last frame.
  const std::pair<const char*, int> loops[] = {{"Idle_Loop", 60},        {"Walk_Loop", 32},
                                               {"Walk_Formal_Loop", 32}, {"Jog_Fwd_Loop", 22},
                                               {"Sprint_Loop", 16},      {"Crouch_Fwd_Loop", 48}};
  for (const auto& [name, frames] : loops) {
    const Clip* c = find_clip(*set, name);
    ASSERT_TRUE(c) << name;
    EXPECT_TRUE(c->loops) << name;
    EXPECT_EQ(c->num_frames, frames) << name;
  }
}

// PROVENANCE.md: one skinned mesh of 8,691 vertices and 3 plain-colour materials.
TEST(GltfMannequin, SkinnedMeshIsConsistentWithTheSkeleton) {
  GK_REQUIRE_DATA(kGlb);
  const ClipSet* set = mannequin();
  ASSERT_TRUE(set && set->mesh);
  const SkinnedMesh& m = *set->mesh;
  const Skeleton& s = *set->skeleton;
  ASSERT_EQ(m.num_vertices(), 8691);
  ASSERT_EQ(m.normals.size(), m.positions.size());
  ASSERT_EQ(m.weights.size(), m.positions.size());
  ASSERT_EQ(m.joints.size(), m.positions.size());
  ASSERT_EQ(m.colors.size(), m.positions.size());
  EXPECT_GT(m.num_triangles(), 0);
  EXPECT_EQ(m.indices.size() % 3, 0u);
  for (uint32_t i : m.indices) ASSERT_LT(i, 8691u);
  std::set<std::tuple<float, float, float>> colors;
  for (int v = 0; v < m.num_vertices(); ++v) {
    const glm::vec4 w = m.weights[v];
    ASSERT_NEAR(w.x + w.y + w.z + w.w, 1.0f, 1e-5f) << v;
    ASSERT_GE(std::min({w.x, w.y, w.z, w.w}), 0.0f);
    for (int c = 0; c < 4; ++c) ASSERT_LT(m.joints[v][c], 53);
    ASSERT_NEAR(glm::length(m.normals[v]), 1.0f, 1e-3f);
    colors.insert({m.colors[v].x, m.colors[v].y, m.colors[v].z});
  }
  EXPECT_EQ(colors.size(), 3u);
  // The bind pose is the rest pose: inverse bind x rest world = identity for every joint.
  ASSERT_EQ(m.inverse_bind.size(), 53u);
  const auto rest = model_pose(s, s.rest_rotations.data(), s.rest_translations.data());
  for (int j = 0; j < 53; ++j) {
    const glm::mat4 p = m.inverse_bind[j] * rest[j];
    for (int c = 0; c < 4; ++c) {
      for (int r = 0; r < 4; ++r) {
        ASSERT_NEAR(p[c][r], c == r ? 1.0f : 0.0f, 2e-4f) << s.names[j];
      }
    }
  }
  // The mesh stands on the ground at human height.
  float lo = 1e9f, hi = -1e9f;
  for (const glm::vec3& p : m.positions) {
    lo = std::min(lo, p.y);
    hi = std::max(hi, p.y);
  }
  EXPECT_NEAR(lo, 0.0f, 0.05f);
  EXPECT_GT(hi, 1.5f);
  EXPECT_LT(hi, 2.0f);
}

// The ual_*.bvh files were sampled from these animations (PROVENANCE.md): with both loaders,
// every BVH joint must sit where the glb joint of the same name is, on every frame (the glb adds
// the static root, which the BVH folds into DEF-hips). Both drop the duplicated last key.
TEST(GltfMannequin, AgreesWithTheConvertedBvhClips) {
  GK_REQUIRE_DATA(kGlb);
  const ClipSet* glb = mannequin();
  ASSERT_TRUE(glb);
  const std::pair<const char*, const char*> pairs[] = {
      {"ual_idle_loop.bvh", "Idle_Loop"},
      {"ual_walk_loop.bvh", "Walk_Loop"},
      {"ual_walk_formal_loop.bvh", "Walk_Formal_Loop"},
      {"ual_jog_fwd_loop.bvh", "Jog_Fwd_Loop"},
      {"ual_sprint_loop.bvh", "Sprint_Loop"},
      {"ual_crouch_fwd_loop.bvh", "Crouch_Fwd_Loop"}};
  for (const auto& [file, name] : pairs) {
    const std::string rel = std::string("clips/bvh/") + file;
    GK_REQUIRE_DATA(rel);
    Result<ClipSet> bvh = load_bvh(test::data_path(rel));
    ASSERT_TRUE(bvh.ok()) << bvh.message();
    const Clip& a = bvh->clips[0];
    const Clip* b = find_clip(*glb, name);
    ASSERT_TRUE(b) << name;
    ASSERT_EQ(a.num_frames, b->num_frames) << name;
    EXPECT_EQ(a.loops, b->loops) << name;
    const Skeleton& sa = *bvh->skeleton;
    const Skeleton& sb = *glb->skeleton;
    std::vector<int> map(sa.num_joints());
    for (int j = 0; j < sa.num_joints(); ++j) {
      map[j] = sb.find(sa.names[j]);
      ASSERT_GE(map[j], 0) << sa.names[j];
    }
    float worst = 0.0f;
    for (int f = 0; f < a.num_frames; ++f) {
      const auto pa = model_pose(sa, a.frame_rotations(f), a.frame_translations(f));
      const auto pb = model_pose(sb, b->frame_rotations(f), b->frame_translations(f));
      for (int j = 0; j < sa.num_joints(); ++j) {
        worst = std::max(worst, glm::distance(glm::vec3(pa[j][3]), glm::vec3(pb[map[j]][3])));
      }
    }
    EXPECT_LT(worst, 1e-3f) << name;
  }
}

// glTF is metres by specification, but a file exported in centimetres is recognised by its size
// (as BVH files are): the fixture with every node translation times 100 loads at 0.01 m per unit,
// with the same rest pose in metres as the original.
TEST(GltfFixture, CentimetreFileIsDetectedFromItsSize) {
  const std::string good = fixture("good/two_bone_skin.gltf");
  std::ifstream in(good);
  nlohmann::json doc = nlohmann::json::parse(in);
  for (auto& node : doc["nodes"]) {
    if (!node.contains("translation")) continue;
    for (auto& x : node["translation"]) x = x.get<double>() * 100.0;
  }
  Result<ClipSet> metres = load_gltf(good);
  Result<ClipSet> cm = parse_gltf(doc.dump(), "cm.gltf");
  ASSERT_TRUE(metres.ok()) << metres.message();
  ASSERT_TRUE(cm.ok()) << cm.message();
  EXPECT_FLOAT_EQ(metres->scale_m_per_unit, 1.0f) << metres->scale_reason;
  EXPECT_FLOAT_EQ(cm->scale_m_per_unit, 0.01f) << cm->scale_reason;
  EXPECT_NE(cm->scale_reason.find("centimetres"), std::string::npos) << cm->scale_reason;
  ASSERT_EQ(cm->skeleton->num_joints(), metres->skeleton->num_joints());
  for (int j = 0; j < cm->skeleton->num_joints(); ++j) {
    const glm::vec3 d = cm->skeleton->rest_translations[j] - metres->skeleton->rest_translations[j];
    EXPECT_LT(glm::length(d), 1e-5f) << cm->skeleton->names[j];
  }
}

}  // namespace
}  // namespace gk
