// Mannequin mesh for any skeleton: well-formed skin data, bind-pose skinning reproduces the mesh,
// the built-in one stands on the ground at the stature, and it works without roles and for the
// real mocap skeletons.

#include <algorithm>
#include <filesystem>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/quaternion.hpp>

#include "animation/bvh_loader.h"
#include "animation/gait_generator.h"
#include "animation/pose_jobs.h"
#include "animation/procedural.h"
#include "tests/test_data.h"

namespace gk {
namespace {

constexpr float kHeight = 1.75f;  // HumanoidParams default stature [m]

glm::vec3 pos(const glm::mat4& m) { return glm::vec3(m[3]); }

std::vector<glm::mat4> rest_model(const Skeleton& s) {
  std::vector<glm::mat4> out(s.num_joints());
  LocalToModelJob job;
  job.skeleton = &s;
  job.rotations = s.rest_rotations;
  job.translations = s.rest_translations;
  job.out_model = out;
  EXPECT_TRUE(job.validate());
  job.run();
  return out;
}

void expect_valid_mannequin(const Skeleton& s, const SkinnedMesh& mesh, const char* what) {
  const size_t nv = mesh.positions.size();
  ASSERT_GT(nv, 0u) << what;
  ASSERT_EQ(mesh.normals.size(), nv);
  ASSERT_EQ(mesh.colors.size(), nv);
  ASSERT_EQ(mesh.joints.size(), nv);
  ASSERT_EQ(mesh.weights.size(), nv);
  ASSERT_EQ(mesh.indices.size() % 3, 0u);
  ASSERT_EQ(mesh.inverse_bind.size(), size_t(s.num_joints()));
  for (uint32_t i : mesh.indices) ASSERT_LT(i, nv) << what;
  for (size_t v = 0; v < nv; ++v) {
    const glm::vec4 w = mesh.weights[v];
    EXPECT_NEAR(w.x + w.y + w.z + w.w, 1.0f, 1e-5f) << what;
    for (int k = 0; k < 4; ++k) {
      EXPECT_GE(w[k], 0.0f);
      EXPECT_LT(mesh.joints[v][k], s.num_joints()) << what;
    }
    EXPECT_NEAR(glm::length(mesh.normals[v]), 1.0f, 1e-4f);
  }
  // Bind pose: FK of the rest pose times inverse_bind is the identity, so skinning reproduces the
  // mesh exactly.
  const auto model = rest_model(s);
  std::vector<glm::mat4> palette(s.num_joints());
  SkinningPaletteJob job{model, mesh.inverse_bind, palette};
  ASSERT_TRUE(job.validate());
  job.run();
  float worst = 0.0f;
  for (size_t v = 0; v < nv; ++v) {
    glm::vec4 p(0.0f);
    for (int k = 0; k < 4; ++k)
      p += mesh.weights[v][k] * (palette[mesh.joints[v][k]] * glm::vec4(mesh.positions[v], 1));
    worst = std::max(worst, glm::distance(glm::vec3(p), mesh.positions[v]));
  }
  EXPECT_LT(worst, 1e-4f) << what;
}

TEST(Mannequin, BuiltinMeshIsValidStandsOnTheGroundAndHasTheStature) {
  const auto skel = make_humanoid_skeleton();
  const auto mesh = make_mannequin_mesh(*skel);
  expect_valid_mannequin(*skel, *mesh, "builtin");
  EXPECT_GE(mesh->num_triangles(), 2000);
  EXPECT_LE(mesh->num_triangles(), 6000);
  float lo = 1e9f, hi = -1e9f;
  for (const glm::vec3& p : mesh->positions) {
    lo = std::min(lo, p.y);
    hi = std::max(hi, p.y);
  }
  EXPECT_NEAR(lo, 0.0f, 0.005f) << "the sole is on the ground";
  EXPECT_NEAR(hi, kHeight, 0.05f * kHeight) << "top of the head at the stature";
  // Each vertex is driven mostly by a joint whose bone it lies on (not by a far-away joint).
  const auto model = rest_model(*skel);
  for (size_t v = 0; v < mesh->positions.size(); ++v) {
    const int j = mesh->joints[v][0];  // the largest weight comes first
    float nearest = glm::distance(mesh->positions[v], pos(model[j]));
    for (int c = 0; c < skel->num_joints(); ++c) {
      if (skel->parents[c] != j) continue;
      const glm::vec3 a = pos(model[j]), b = pos(model[c]);
      const float t =
          std::clamp(glm::dot(mesh->positions[v] - a, b - a) / glm::dot(b - a, b - a), 0.f, 1.f);
      nearest = std::min(nearest, glm::distance(mesh->positions[v], a + t * (b - a)));
    }
    EXPECT_LT(nearest, 0.2f * kHeight) << "vertex " << v;
  }
}

// One colour per agent: the renderer multiplies the mesh colours by the agent's tint, so the mesh
// must be greys only, and one grey for the whole body (the shoes may be darker). Two differently
// shaded halves or bands would read as two agents' limbs.
TEST(Mannequin, BuiltinMeshIsOneGreyWithDarkerShoes) {
  const auto skel = make_humanoid_skeleton();
  const auto mesh = make_mannequin_mesh(*skel);
  std::vector<glm::vec3> distinct;
  for (const glm::vec3& c : mesh->colors) {
    EXPECT_FLOAT_EQ(c.x, c.y);
    EXPECT_FLOAT_EQ(c.y, c.z);
    if (std::find(distinct.begin(), distinct.end(), c) == distinct.end()) distinct.push_back(c);
  }
  EXPECT_LE(distinct.size(), 2u) << "body and shoes";
  // Everything above the ankles is the body's colour.
  glm::vec3 body(-1.0f);
  for (size_t v = 0; v < mesh->positions.size(); ++v) {
    if (mesh->positions[v].y < 0.1f * kHeight) continue;
    if (body.x < 0.0f) body = mesh->colors[v];
    EXPECT_EQ(mesh->colors[v], body) << "vertex " << v;
  }
}

// body_radius is the half-width of the body that is drawn: the skinned mannequin, walking with the
// built-in clips, reaches that far to each side of its pelvis and not much farther or less far.
TEST(Mannequin, BodyRadiusIsTheDrawnHalfWidth) {
  const ClipSet set = make_builtin_clip_set();
  const Skeleton& s = *set.skeleton;
  const float radius = body_radius(s);
  EXPECT_NEAR(radius, 0.25f, 0.05f) << "a 1.75 m adult is about 0.5 m across the shoulders";
  const int hips = s.role(JointRole::kHips);
  std::vector<glm::mat4> model(s.num_joints()), palette(s.num_joints());
  float widest = 0.0f;
  for (const Clip& c : set.clips) {
    if (c.name.rfind("walk", 0) != 0) continue;
    for (int f = 0; f < c.num_frames; ++f) {
      LocalToModelJob fk;
      fk.skeleton = &s;
      fk.rotations = {c.frame_rotations(f), size_t(s.num_joints())};
      fk.translations = {c.frame_translations(f), size_t(s.num_joints())};
      fk.out_model = model;
      ASSERT_TRUE(fk.validate());
      fk.run();
      SkinningPaletteJob skin{model, set.mesh->inverse_bind, palette};
      ASSERT_TRUE(skin.validate());
      skin.run();
      const glm::mat4 to_pelvis = glm::inverse(model[hips]);
      for (size_t v = 0; v < set.mesh->positions.size(); ++v) {
        glm::vec4 p(0.0f);
        for (int k = 0; k < 4; ++k) {
          p += set.mesh->weights[v][k] *
               (palette[set.mesh->joints[v][k]] * glm::vec4(set.mesh->positions[v], 1.0f));
        }
        widest = std::max(widest, std::abs((to_pelvis * p).x));
      }
    }
  }
  EXPECT_NEAR(widest, radius, 0.1f * radius) << "widest point of the walking mannequin";
}

TEST(Mannequin, WorksForASkeletonWithoutRoles) {
  Skeleton s;
  auto add = [&](const char* name, int parent, glm::vec3 offset) {
    s.names.push_back(name);
    s.parents.push_back(int16_t(parent));
    s.rest_translations.push_back(offset);
    s.rest_rotations.push_back(glm::angleAxis(0.3f * parent, glm::normalize(glm::vec3(1, 2, 3))));
  };
  add("root", -1, {0, 1, 0});
  add("a", 0, {0, 0.4f, 0});
  add("b", 1, {0.3f, 0.1f, 0});
  add("c", 1, {-0.3f, 0.1f, 0});
  add("d", 0, {0, -0.5f, 0.1f});
  add("e", 4, {0, -0.4f, 0});
  add("zero", 5, {0, 0, 0});
  const auto mesh = make_mannequin_mesh(s);
  expect_valid_mannequin(s, *mesh, "no roles");
  EXPECT_GT(mesh->num_triangles(), 100);
}

TEST(Mannequin, WorksForTheMocapSkeletons) {
  GK_REQUIRE_DATA("clips/bvh/cmu_07_01_walk.bvh");
  for (const char* file : {"clips/bvh/cmu_07_01_walk.bvh", "clips/bvh/ual_walk_loop.bvh"}) {
    if (!std::filesystem::exists(test::data_path(file))) continue;
    const auto loaded = load_bvh(test::data_path(file));
    ASSERT_TRUE(loaded.ok()) << loaded.message();
    const Skeleton& s = *loaded->skeleton;
    const auto mesh = make_mannequin_mesh(s);
    expect_valid_mannequin(s, *mesh, file);
    // The mocap skeletons are in centimetres or inches: the radius scales with the stature.
    const float h = estimate_stature(s);
    EXPECT_GT(body_radius(s), 0.1f * h) << file;
    EXPECT_LT(body_radius(s), 0.2f * h) << file;
    EXPECT_GE(mesh->num_triangles(), 1500) << file;
    EXPECT_LE(mesh->num_triangles(), 7000) << file;
  }
}

}  // namespace
}  // namespace gk
