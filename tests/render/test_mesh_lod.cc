// Mesh level of detail without GL: the simplified index buffers of the mannequin (valid, lighter
// level by level, the same body in the bind pose) and the choice of a level from the size on
// screen, with its hysteresis.
#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "animation/procedural.h"
#include "render/mesh_lod.h"

namespace gk::test {
namespace {

struct Bounds {
  glm::vec3 lo{1e30f}, hi{-1e30f};
  glm::vec3 size() const { return hi - lo; }
};

Bounds bounds_of(const SkinnedMesh& mesh, const std::vector<uint32_t>& indices) {
  Bounds b;
  for (uint32_t i : indices) {
    b.lo = glm::min(b.lo, mesh.positions[i]);
    b.hi = glm::max(b.hi, mesh.positions[i]);
  }
  return b;
}

SkinnedMesh mannequin() {
  const ClipSet set = make_builtin_clip_set();
  return set.mesh ? *set.mesh : *make_mannequin_mesh(*set.skeleton);
}

TEST(MeshLod, MannequinChainIsValidLighterAndKeepsTheBody) {
  const SkinnedMesh mesh = mannequin();
  Result<MeshLodChain> chain = build_mesh_lods(mesh, mesh.indices);
  ASSERT_TRUE(chain.ok()) << chain.message();
  // The mannequin is thousands of triangles: the default shares must give all four levels.
  ASSERT_EQ(chain->num_levels(), kMaxMeshLods);
  EXPECT_EQ(chain->levels[0].indices.size(), mesh.indices.size());
  EXPECT_EQ(chain->levels[0].error_m, 0.0f);
  const Bounds full = bounds_of(mesh, mesh.indices);
  const float extent = std::max({full.size().x, full.size().y, full.size().z});
  for (int l = 0; l < chain->num_levels(); ++l) {
    const MeshLodLevel& level = chain->levels[l];
    SCOPED_TRACE("level " + std::to_string(l));
    ASSERT_FALSE(level.indices.empty());
    ASSERT_EQ(level.indices.size() % 3, 0u);
    for (uint32_t i : level.indices) ASSERT_LT(i, mesh.positions.size());
    if (l > 0) {
      const MeshLodLevel& previous = chain->levels[l - 1];
      EXPECT_LT(level.indices.size(), previous.indices.size());
      EXPECT_GE(level.error_m, previous.error_m);
      // Within the cap of MeshLodOptions::max_relative_error (5 % of the extent).
      EXPECT_LE(level.error_m, 0.05f * extent * 1.001f);
    }
    // The same body: the bind-pose box of what is drawn moves by at most 3 % of the extent on
    // every side (hands, feet and head stay).
    const Bounds b = bounds_of(mesh, level.indices);
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(b.lo[k], full.lo[k], 0.03f * extent) << "axis " << k;
      EXPECT_NEAR(b.hi[k], full.hi[k], 0.03f * extent) << "axis " << k;
    }
  }
  // The lightest level is a real saving: at most a tenth of the full mesh's triangles.
  EXPECT_LE(chain->levels.back().indices.size() * 10, mesh.indices.size());
}

// Whether the triangle at `t` winds counter-clockwise seen from where its vertex normals point.
float facing(const SkinnedMesh& mesh, const uint32_t* tri) {
  const glm::vec3 face = glm::cross(mesh.positions[tri[1]] - mesh.positions[tri[0]],
                                    mesh.positions[tri[2]] - mesh.positions[tri[0]]);
  return glm::dot(face, mesh.normals[tri[0]] + mesh.normals[tri[1]] + mesh.normals[tri[2]]);
}

TEST(MeshLod, LevelsKeepTheWindingOfTheFullMesh) {
  // The renderer winds the full mesh to its normals and culls back faces at every level: the
  // simplified triangles must still face where their normals point.
  const SkinnedMesh mesh = mannequin();
  std::vector<uint32_t> wound = mesh.indices;
  for (size_t t = 0; t < wound.size(); t += 3) {
    if (facing(mesh, &wound[t]) < 0.0f) std::swap(wound[t + 1], wound[t + 2]);
  }
  Result<MeshLodChain> chain = build_mesh_lods(mesh, wound);
  ASSERT_TRUE(chain.ok()) << chain.message();
  ASSERT_GT(chain->num_levels(), 1);
  // A closed surface wound outward encloses a positive volume; a triangle turned inside out
  // subtracts. A surface that stays within error_m of the full one changes the volume by at most
  // error_m times the area, so the level's volume and reported error must agree.
  const auto volume = [&](const std::vector<uint32_t>& idx) {
    double v = 0.0;
    for (size_t t = 0; t < idx.size(); t += 3) {
      v += glm::dot(mesh.positions[idx[t]],
                    glm::cross(mesh.positions[idx[t + 1]], mesh.positions[idx[t + 2]])) /
           6.0;
    }
    return v;
  };
  double area = 0.0;
  for (size_t t = 0; t < wound.size(); t += 3) {
    area += 0.5 * glm::length(glm::cross(mesh.positions[wound[t + 1]] - mesh.positions[wound[t]],
                                         mesh.positions[wound[t + 2]] - mesh.positions[wound[t]]));
  }
  const double full = volume(wound);
  ASSERT_GT(full, 0.0);
  for (int l = 1; l < chain->num_levels(); ++l) {
    const double v = volume(chain->levels[l].indices);
    EXPECT_GT(v, 0.0) << "level " << l;
    EXPECT_LE(full - v, chain->levels[l].error_m * area) << "level " << l;
    EXPECT_LE(v - full, chain->levels[l].error_m * area) << "level " << l;
  }
}

// One triangle with every attribute filled in.
SkinnedMesh one_triangle() {
  SkinnedMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.normals.assign(3, glm::vec3(0, 0, 1));
  m.joints.assign(3, glm::u16vec4(0));
  m.weights.assign(3, glm::vec4(1, 0, 0, 0));
  m.indices = {0, 1, 2};
  return m;
}

TEST(MeshLod, BadInputIsAnErrorNamingWhatIsWrong) {
  const SkinnedMesh m = one_triangle();
  Result<MeshLodChain> a = build_mesh_lods(m, std::vector<uint32_t>{0, 1, 3});
  ASSERT_FALSE(a.ok());
  EXPECT_NE(a.message().find("index 2 = 3"), std::string::npos) << a.message();
  Result<MeshLodChain> b = build_mesh_lods(m, std::vector<uint32_t>{0, 1});
  ASSERT_FALSE(b.ok());
  EXPECT_NE(b.message().find("multiple of 3"), std::string::npos) << b.message();
  SkinnedMesh nan = m;
  nan.positions[1].x = NAN;
  Result<MeshLodChain> c = build_mesh_lods(nan, nan.indices);
  ASSERT_FALSE(c.ok());
  EXPECT_NE(c.message().find("vertex 1"), std::string::npos) << c.message();
  SkinnedMesh short_weights = m;
  short_weights.weights.pop_back();
  Result<MeshLodChain> d = build_mesh_lods(short_weights, m.indices);
  ASSERT_FALSE(d.ok());
  EXPECT_NE(d.message().find("one entry per vertex"), std::string::npos) << d.message();
  MeshLodOptions rising;
  rising.triangle_share = {0.3f, 0.5f, 0.1f};
  EXPECT_FALSE(build_mesh_lods(m, m.indices, rising).ok());
}

TEST(MeshLod, ATinyMeshKeepsOnlyItsFullLevel) {
  // One triangle cannot be simplified: the chain is the full mesh alone, never an empty level.
  const SkinnedMesh m = one_triangle();
  Result<MeshLodChain> chain = build_mesh_lods(m, m.indices);
  ASSERT_TRUE(chain.ok()) << chain.message();
  EXPECT_EQ(chain->num_levels(), 1);
}

TEST(MeshLod, PixelsPerMetreFollowTheProjection) {
  // 30 deg vertical field of view, 720 px: at 10 m one metre covers 720 / (2 tan 15 deg) / 10.
  const float y_scale = 1.0f / std::tan(glm::radians(15.0f));
  EXPECT_NEAR(pixels_per_metre(y_scale, 720, 10.0f), 720.0f / (2.0f * 0.267949f) / 10.0f, 0.05f);
  EXPECT_NEAR(pixels_per_metre(y_scale, 720, 20.0f), 0.5f * pixels_per_metre(y_scale, 720, 10.0f),
              1e-3f);
  EXPECT_TRUE(std::isinf(pixels_per_metre(y_scale, 720, 0.0f)));
  EXPECT_TRUE(std::isinf(pixels_per_metre(y_scale, 720, -3.0f)));
}

TEST(MeshLod, AFarAgentGetsALighterLevel) {
  const std::vector<float> errors = {0.0f, 0.005f, 0.02f, 0.06f};  // [m]
  MeshLodSelection s;
  s.max_error_px = 1.0f;
  s.hysteresis = 0.25f;
  EXPECT_EQ(choose_mesh_lod(errors, 500.0f, s, -1), 0);  // close: 5 mm is 2.5 px
  EXPECT_EQ(choose_mesh_lod(errors, 100.0f, s, -1), 1);  // 0.5 px; level 2 would be 2 px
  EXPECT_EQ(choose_mesh_lod(errors, 40.0f, s, -1), 2);
  EXPECT_EQ(choose_mesh_lod(errors, 10.0f, s, -1), 3);  // 0.6 px
  // Monotone in distance: never a heavier level farther away.
  int last = 0;
  for (float ppm = 1000.0f; ppm > 1.0f; ppm *= 0.9f) {
    const int l = choose_mesh_lod(errors, ppm, s, -1);
    EXPECT_GE(l, last) << ppm;
    EXPECT_LE(errors[l] * ppm, s.max_error_px) << ppm;
    last = l;
  }
  EXPECT_EQ(last, 3);
  // Level 0 wherever the size is unknown or the limit is 0.
  EXPECT_EQ(choose_mesh_lod(errors, INFINITY, s, 3), 0);
  EXPECT_EQ(choose_mesh_lod(errors, NAN, s, 2), 0);
  s.max_error_px = 0.0f;
  EXPECT_EQ(choose_mesh_lod(errors, 1.0f, s, 3), 0);
  EXPECT_EQ(choose_mesh_lod(std::vector<float>{0.0f}, 1.0f, MeshLodSelection{}, 0), 0);
}

TEST(MeshLod, HysteresisHoldsALevelNearItsThreshold) {
  const std::vector<float> errors = {0.0f, 0.01f, 0.04f};
  MeshLodSelection s;
  s.max_error_px = 1.0f;
  s.hysteresis = 0.25f;
  // Level 1 turns acceptable at 100 px/m (1 px). Walking away from the camera (ppm falling), the
  // agent drawn with level 0 keeps it until level 1's error is under 0.75 px.
  EXPECT_EQ(choose_mesh_lod(errors, 95.0f, s, 0), 0);
  EXPECT_EQ(choose_mesh_lod(errors, 76.0f, s, 0), 0);
  EXPECT_EQ(choose_mesh_lod(errors, 74.0f, s, 0), 1);
  // Coming back (ppm rising) it keeps level 1 up to the threshold itself, then goes heavier.
  EXPECT_EQ(choose_mesh_lod(errors, 80.0f, s, 1), 1);
  EXPECT_EQ(choose_mesh_lod(errors, 99.0f, s, 1), 1);
  EXPECT_EQ(choose_mesh_lod(errors, 101.0f, s, 1), 0);
  // So a jitter of +-9 % around the threshold changes the level once, then never again.
  int level = choose_mesh_lod(errors, 100.0f, s, -1);
  EXPECT_EQ(level, 1);  // exactly at 1 px: acceptable
  int changes = 0;
  for (int f = 0; f < 40; ++f) {
    const int next = choose_mesh_lod(errors, f % 2 ? 91.0f : 109.0f, s, level);
    changes += next != level;
    level = next;
  }
  EXPECT_EQ(changes, 1);
  EXPECT_EQ(level, 0);
  // Without hysteresis the same jitter flips the level every frame.
  s.hysteresis = 0.0f;
  EXPECT_EQ(choose_mesh_lod(errors, 91.0f, s, 0), 1);
  EXPECT_EQ(choose_mesh_lod(errors, 109.0f, s, 1), 0);
  // A jump across two levels goes straight there.
  s.hysteresis = 0.25f;
  EXPECT_EQ(choose_mesh_lod(errors, 10.0f, s, 0), 2);
  EXPECT_EQ(choose_mesh_lod(errors, 500.0f, s, 2), 0);
}

}  // namespace
}  // namespace gk::test
