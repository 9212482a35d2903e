// Offscreen rendering of small crowds with known placements and palettes, checked pixel by pixel
// against a frame of the same scene without agents.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <vector>

#include <stb_image.h>
#include <glm/gtc/matrix_transform.hpp>

#include "animation/pose_jobs.h"
#include "animation/procedural.h"
#include "tests/render/render_test_support.h"

namespace gk::test {
namespace {

constexpr float kPi = 3.14159265f;

// The crowd's body: the procedural mannequin in a walking pose, its palettes computed on the CPU
// exactly as the app will.
struct CrowdModel {
  SkinnedMesh mesh;
  int joints_per_agent = 2;
  float mid_height_m = 1.0f;  // a point inside the body to project
  float half_width_m = 0.5f;  // generous horizontal bound of the posed body and its shadow
  float height_m = 2.0f;
  ClipSet clip_set;
  const Clip* clip = nullptr;

  void palette(const glm::vec3& position, float heading_rad, float time_s,
               std::span<glm::mat4> out) const;
};

CrowdModel make_crowd_model() {
  CrowdModel model;
  model.clip_set = make_builtin_clip_set();
  const Skeleton& skeleton = *model.clip_set.skeleton;
  model.mesh = model.clip_set.mesh ? *model.clip_set.mesh : *make_mannequin_mesh(skeleton);
  model.joints_per_agent = skeleton.num_joints();
  for (const Clip& c : model.clip_set.clips) {
    if (c.name.find("walk") != std::string::npos) {
      model.clip = &c;
      break;
    }
  }
  if (model.clip == nullptr && !model.clip_set.clips.empty()) model.clip = &model.clip_set.clips[0];
  model.mid_height_m = 1.1f;  // chest height of a 1.75 m humanoid
  model.half_width_m = 1.0f;
  model.height_m = 2.0f;
  return model;
}

void CrowdModel::palette(const glm::vec3& position, float heading_rad, float time_s,
                         std::span<glm::mat4> out) const {
  const Skeleton& skeleton = *clip_set.skeleton;
  const int n = skeleton.num_joints();
  std::vector<glm::quat> rotations(skeleton.rest_rotations);
  std::vector<glm::vec3> translations(skeleton.rest_translations);
  if (clip != nullptr) {
    SampleClipJob sample{clip, time_s, rotations, translations};
    if (sample.validate()) sample.run();
    // Keep the agent where the test placed it: drop the clip's horizontal root motion.
    translations[0].x = 0.0f;
    translations[0].z = 0.0f;
  }
  std::vector<glm::mat4> model(n);
  LocalToModelJob fk;
  fk.skeleton = &skeleton;
  fk.rotations = rotations;
  fk.translations = translations;
  fk.root_transform = glm::rotate(glm::translate(glm::mat4(1.0f), position), heading_rad,
                                  glm::vec3(0.0f, 1.0f, 0.0f));
  fk.out_model = model;
  ASSERT_TRUE(fk.validate());
  fk.run();
  SkinningPaletteJob skin{model, mesh.inverse_bind, out.first(n)};
  ASSERT_TRUE(skin.validate());
  skin.run();
}

// Screen rectangle [min, max] covering an axis-aligned world box, or an empty one if any corner is
// behind the camera (the tests keep every agent in front).
void screen_bounds(const OrbitCamera& camera, glm::ivec2 viewport, const glm::vec3& lo,
                   const glm::vec3& hi, glm::vec2* out_min, glm::vec2* out_max) {
  *out_min = glm::vec2(1e9f);
  *out_max = glm::vec2(-1e9f);
  for (int i = 0; i < 8; ++i) {
    const glm::vec3 p((i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z);
    const ProjectedPoint q = camera.project(p, viewport);
    if (!q.in_front) continue;
    *out_min = glm::min(*out_min, q.pixel);
    *out_max = glm::max(*out_max, q.pixel);
  }
}

class RendererTest : public OffscreenRenderTest {
 protected:
  // The two-bone column added as a mesh (its id in *mesh), the camera on it from `distance_m`.
  void add_column_in_view(float distance_m, int* mesh) {
    Result<int> m = renderer_->add_mesh(make_two_bone_column());
    ASSERT_TRUE(m.ok()) << m.message();
    *mesh = *m;
    camera_.target = glm::vec3(0.0f, 1.0f, 0.0f);
    camera_.pitch_rad = 0.1f;
    camera_.distance_m = distance_m;
  }
};

TEST_F(RendererTest, CrowdIsDrawnWhereProjectedAndNowhereElse) {
  const CrowdModel model = make_crowd_model();
  Result<int> mesh = renderer_->add_mesh(model.mesh);
  ASSERT_TRUE(mesh.ok()) << mesh.message();
  // 20 agents on a 5 x 4 grid, 2 m apart, facing the camera-ish with varied headings.
  std::vector<AgentDraw> agents;
  std::vector<glm::mat4> palettes(20 * model.joints_per_agent);
  for (int i = 0; i < 20; ++i) {
    AgentDraw a;
    a.position = glm::vec3(-4.0f + 2.0f * (i % 5), 0.0f, -3.0f + 2.0f * (i / 5));
    a.tint = glm::vec3(0.5f + 0.5f * std::sin(i * 1.7f), 0.5f + 0.5f * std::sin(i * 2.3f + 1.0f),
                       0.5f + 0.5f * std::sin(i * 3.1f + 2.0f));
    a.mesh = *mesh;
    agents.push_back(a);
    ASSERT_NO_FATAL_FAILURE(model.palette(
        a.position, 0.3f * i, 0.1f * i,
        std::span(palettes).subspan(i * model.joints_per_agent, model.joints_per_agent)));
  }
  ASSERT_TRUE(renderer_->upload_palettes(palettes, model.joints_per_agent).ok());
  camera_.distance_m = 20.0f;  // the 30 deg default field of view: the grid fills half the image
  camera_.pitch_rad = 0.45f;
  camera_.target = glm::vec3(0.0f, 0.8f, 0.0f);

  FrameCapture empty, crowd;
  ASSERT_NO_FATAL_FAILURE(render({}, &empty));
  ASSERT_NO_FATAL_FAILURE(render(agents, &crowd));
  EXPECT_EQ(renderer_->stats().agents_visible, 20);
  const std::string dir = scratch_dir("render");
  ASSERT_TRUE(crowd.save_png(dir + "/crowd_640x360.png").ok());
  ASSERT_TRUE(empty.save_png(dir + "/empty_640x360.png").ok());

  for (const AgentDraw& a : agents) {
    const ProjectedPoint p =
        camera_.project(a.position + glm::vec3(0.0f, model.mid_height_m, 0.0f), viewport());
    ASSERT_TRUE(p.in_front);
    const int x = static_cast<int>(p.pixel.x), y = static_cast<int>(p.pixel.y);
    EXPECT_GT(pixel_difference(crowd.pixel(x, y), empty.pixel(x, y)), 30)
        << "no agent drawn at " << x << "," << y << " for agent at " << a.position.x << ","
        << a.position.z;
  }
  // Every pixel outside all agents' generous screen bounds must be exactly the empty scene.
  std::vector<glm::vec4> rects;
  for (const AgentDraw& a : agents) {
    glm::vec2 lo, hi;
    const glm::vec3 r(model.half_width_m, 0.0f, model.half_width_m);
    screen_bounds(camera_, viewport(), a.position - r,
                  a.position + r + glm::vec3(0.0f, model.height_m, 0.0f), &lo, &hi);
    rects.emplace_back(lo.x - 2.0f, lo.y - 2.0f, hi.x + 2.0f, hi.y + 2.0f);
  }
  int outside = 0, changed_outside = 0, changed_inside = 0;
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      const bool inside = std::any_of(rects.begin(), rects.end(), [&](const glm::vec4& r) {
        return x >= r.x && x <= r.z && y >= r.y && y <= r.w;
      });
      const bool changed = crowd.pixel(x, y) != empty.pixel(x, y);
      if (inside) {
        changed_inside += changed;
      } else {
        ++outside;
        changed_outside += changed;
      }
    }
  }
  EXPECT_GT(outside, kWidth * kHeight / 3);  // the check covers a good part of the image
  EXPECT_EQ(changed_outside, 0);
  EXPECT_GT(changed_inside, 20 * 200);  // each agent covers at least a few hundred pixels
}

TEST_F(RendererTest, MeshLodDrawsFarAgentsLighterAndKeepsTheCrowdsLook) {
  const CrowdModel model = make_crowd_model();
  Result<int> mesh = renderer_->add_mesh(model.mesh);
  ASSERT_TRUE(mesh.ok()) << mesh.message();
  ASSERT_EQ(renderer_->num_mesh_lods(*mesh), kMaxMeshLods);
  // Rows from 4 m in front of the eye to 140 m away: every level has its distance in this view.
  camera_.target = glm::vec3(0.0f, 0.8f, 0.0f);
  camera_.pitch_rad = 0.2f;
  camera_.distance_m = 12.0f;
  std::vector<AgentDraw> agents;
  for (float z = 8.0f; z >= -130.0f; z -= 3.0f) {
    for (float x = -6.0f; x <= 6.0f; x += 2.0f) {
      AgentDraw a;
      a.position = glm::vec3(x + 0.5f * std::sin(z), 0.0f, z);
      a.tint = glm::vec3(0.9f, 0.5f + 0.02f * z, 0.4f);
      a.mesh = *mesh;
      agents.push_back(a);
    }
  }
  const int n = static_cast<int>(agents.size());
  std::vector<glm::mat4> palettes(static_cast<size_t>(n) * model.joints_per_agent);
  for (int i = 0; i < n; ++i) {
    ASSERT_NO_FATAL_FAILURE(model.palette(
        agents[i].position, 0.4f * i, 0.05f * i,
        std::span(palettes).subspan(i * model.joints_per_agent, model.joints_per_agent)));
  }
  ASSERT_TRUE(renderer_->upload_palettes(palettes, model.joints_per_agent).ok());

  FrameCapture empty, full, lod;
  ASSERT_NO_FATAL_FAILURE(render({}, &empty));
  renderer_->settings().mesh_lod = false;
  ASSERT_NO_FATAL_FAILURE(render(agents, &full));
  const RenderStats full_stats = renderer_->stats();
  renderer_->settings().mesh_lod = true;
  ASSERT_NO_FATAL_FAILURE(render(agents, &lod));
  const RenderStats lod_stats = renderer_->stats();
  const std::string dir = scratch_dir("render");
  ASSERT_TRUE(lod.save_png(dir + "/mesh_lod_on.png").ok());
  ASSERT_TRUE(full.save_png(dir + "/mesh_lod_off.png").ok());

  // Without LOD every visible agent has the full mesh; with it the near rows keep it, the far
  // rows get the lightest level, and far fewer triangles are drawn.
  EXPECT_EQ(full_stats.agents_per_lod[0], full_stats.agents_visible);
  EXPECT_EQ(full_stats.agent_triangles,
            static_cast<int64_t>(full_stats.agents_visible) * model.mesh.num_triangles());
  EXPECT_EQ(lod_stats.agents_visible, full_stats.agents_visible);
  EXPECT_GT(lod_stats.agents_per_lod[0], 0);
  EXPECT_GT(lod_stats.agents_per_lod[kMaxMeshLods - 1], 0);
  int64_t expected_triangles = 0;
  for (int l = 0; l < kMaxMeshLods; ++l) {
    expected_triangles +=
        static_cast<int64_t>(lod_stats.agents_per_lod[l]) * renderer_->mesh_lod_triangles(*mesh, l);
  }
  EXPECT_EQ(lod_stats.agent_triangles, expected_triangles);
  EXPECT_LT(lod_stats.agent_triangles * 2, full_stats.agent_triangles);
  // Each levels' draw is one instanced call (plus ground, walls... none here, and shadows).
  int levels_used = 0;
  for (int count : lod_stats.agents_per_lod) levels_used += count > 0;
  EXPECT_EQ(lod_stats.skinned_draw_calls, levels_used);

  // The crowd is still there, agent by agent, and covers the same area of the image.
  for (const AgentDraw& a : agents) {
    const ProjectedPoint p =
        camera_.project(a.position + glm::vec3(0.0f, model.mid_height_m, 0.0f), viewport());
    const int x = static_cast<int>(p.pixel.x), y = static_cast<int>(p.pixel.y);
    if (!p.in_front || x < 0 || y < 0 || x >= kWidth || y >= kHeight) continue;
    EXPECT_GT(pixel_difference(lod.pixel(x, y), empty.pixel(x, y)), 30)
        << "no agent drawn at " << x << "," << y << " for agent at " << a.position.x << ","
        << a.position.z;
  }
  // Levels change edges by less than a pixel (and the lighter ones are pushed out to the full
  // mesh's volume): the crowd covers the same pixels within a few per cent.
  int covered_full = 0, covered_lod = 0;
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      covered_full += pixel_difference(full.pixel(x, y), empty.pixel(x, y)) > 8;
      covered_lod += pixel_difference(lod.pixel(x, y), empty.pixel(x, y)) > 8;
    }
  }
  EXPECT_GT(covered_full, 5000);
  EXPECT_NEAR(covered_lod, covered_full, 0.05 * covered_full);
}

TEST_F(RendererTest, SkinningRotatesSecondJoint) {
  int mesh = 0;
  ASSERT_NO_FATAL_FAILURE(add_column_in_view(6.0f, &mesh));
  const AgentDraw agent{glm::vec3(0.0f), glm::vec3(1.0f), mesh};
  std::vector<glm::mat4> straight(2), bent(2);
  column_palette(agent.position, 0.0f, straight);
  column_palette(agent.position, kPi / 2.0f, bent);

  FrameCapture empty, straight_frame, bent_frame;
  ASSERT_TRUE(renderer_->upload_palettes(straight, 2).ok());
  ASSERT_NO_FATAL_FAILURE(render({}, &empty));
  ASSERT_NO_FATAL_FAILURE(render(std::span(&agent, 1), &straight_frame));
  ASSERT_TRUE(renderer_->upload_palettes(bent, 2).ok());
  ASSERT_NO_FATAL_FAILURE(render(std::span(&agent, 1), &bent_frame));
  ASSERT_TRUE(bent_frame.save_png(scratch_dir("render") + "/skinning_bent.png").ok());

  // Upper box: straight it is around (0, 1.7, 0); bent 90 deg about +z it lies along -x at y = 1.
  const ProjectedPoint up = camera_.project({0.0f, 1.7f, 0.0f}, viewport());
  const ProjectedPoint side = camera_.project({-0.7f, 1.0f, 0.0f}, viewport());
  const ProjectedPoint low = camera_.project({0.0f, 0.5f, 0.0f}, viewport());
  auto at = [](const FrameCapture& f, const ProjectedPoint& p) {
    return f.pixel(static_cast<int>(p.pixel.x), static_cast<int>(p.pixel.y));
  };
  EXPECT_GT(pixel_difference(at(straight_frame, up), at(empty, up)), 30);
  EXPECT_EQ(pixel_difference(at(straight_frame, side), at(empty, side)), 0);
  EXPECT_EQ(pixel_difference(at(bent_frame, up), at(empty, up)), 0);
  EXPECT_GT(pixel_difference(at(bent_frame, side), at(empty, side)), 30);
  // The lower box is on joint 0 and does not move.
  EXPECT_GT(pixel_difference(at(bent_frame, low), at(empty, low)), 30);
  EXPECT_EQ(at(bent_frame, low), at(straight_frame, low));
  // The upper box is orange, the lower one grey: the bent part must look orange.
  const glm::u8vec4 c = at(bent_frame, side);
  EXPECT_GT(c.x, c.z + 40) << int(c.x) << "," << int(c.y) << "," << int(c.z);
}

// An agent's offset moves its whole palette block: a pose made at one place and drawn with the
// offset to another looks as the same pose made there (a held pose of the crowd's level of detail).
TEST_F(RendererTest, OffsetDrawsThePaletteWhereTheAgentIsNow) {
  int mesh = 0;
  ASSERT_NO_FATAL_FAILURE(add_column_in_view(8.0f, &mesh));
  const glm::vec3 posed_at(-1.5f, 0.0f, 0.0f), now_at(1.5f, 0.0f, 0.5f);
  std::vector<glm::mat4> there(2), here(2);
  column_palette(posed_at, kPi / 4.0f, there);
  column_palette(now_at, kPi / 4.0f, here);

  FrameCapture empty, moved, made_here;
  ASSERT_NO_FATAL_FAILURE(render({}, &empty));
  AgentDraw agent{now_at, glm::vec3(1.0f), mesh};
  agent.offset = now_at - posed_at;
  ASSERT_TRUE(renderer_->upload_palettes(there, 2).ok());
  ASSERT_NO_FATAL_FAILURE(render(std::span(&agent, 1), &moved));
  agent.offset = glm::vec3(0.0f);
  ASSERT_TRUE(renderer_->upload_palettes(here, 2).ok());
  ASSERT_NO_FATAL_FAILURE(render(std::span(&agent, 1), &made_here));

  auto at = [&](const FrameCapture& f, const glm::vec3& p) {
    const ProjectedPoint q = camera_.project(p, viewport());
    return f.pixel(static_cast<int>(q.pixel.x), static_cast<int>(q.pixel.y));
  };
  // Nothing is left where the pose was made; the body stands where the agent is (the point is in
  // the bent, orange upper box).
  const glm::vec3 body(-0.35f, 1.35f, 0.0f);
  EXPECT_EQ(at(moved, posed_at + body), at(empty, posed_at + body));
  EXPECT_GT(pixel_difference(at(moved, now_at + body), at(empty, now_at + body)), 30);
  // And the two images agree but for rounding at a few edge pixels.
  int differing = 0;
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      differing += pixel_difference(moved.pixel(x, y), made_here.pixel(x, y)) > 30;
    }
  }
  EXPECT_LT(differing, kWidth * kHeight / 2000) << differing << " pixels differ";
}

TEST_F(RendererTest, OneInstancedDrawPerMeshAndPerAgentTint) {
  Result<int> a = renderer_->add_mesh(make_two_bone_column(0.4f));
  Result<int> b = renderer_->add_mesh(make_two_bone_column(0.6f));
  ASSERT_TRUE(a.ok() && b.ok());
  std::vector<AgentDraw> agents;
  std::vector<glm::mat4> palettes(30 * 2);
  for (int i = 0; i < 30; ++i) {
    const glm::vec3 p(-5.0f + (i % 10) * 1.1f, 0.0f, -2.0f * (i / 10));
    const glm::vec3 tint = i == 0 ? glm::vec3(1.0f, 0.1f, 0.1f) : glm::vec3(0.1f, 0.3f, 1.0f);
    agents.push_back({p, tint, i % 2 == 0 ? *a : *b});
    column_palette(p, 0.0f, std::span(palettes).subspan(i * 2, 2));
  }
  ASSERT_TRUE(renderer_->upload_palettes(palettes, 2).ok());
  camera_.distance_m = 13.0f;
  FrameCapture frame;
  ASSERT_NO_FATAL_FAILURE(render(agents, &frame));
  EXPECT_EQ(renderer_->stats().agents_visible, 30);
  EXPECT_EQ(renderer_->stats().skinned_draw_calls, 2);
  EXPECT_EQ(renderer_->stats().draw_calls, 4);  // ground + 2 meshes + all shadows
  // Agent 0 is tinted red, agent 1 blue: check their lower boxes.
  auto body = [&](int i) {
    const ProjectedPoint p =
        camera_.project(agents[i].position + glm::vec3(0, 0.5f, 0), viewport());
    return frame.pixel(static_cast<int>(p.pixel.x), static_cast<int>(p.pixel.y));
  };
  EXPECT_GT(body(0).x, body(0).z + 60);
  EXPECT_GT(body(1).z, body(1).x + 60);

  // Only mesh a in use: one skinned draw.
  for (AgentDraw& agent : agents) agent.mesh = *a;
  ASSERT_NO_FATAL_FAILURE(render(agents, &frame));
  EXPECT_EQ(renderer_->stats().skinned_draw_calls, 1);
}

TEST_F(RendererTest, CullsAgentsOutsideTheFrustum) {
  Result<int> mesh = renderer_->add_mesh(make_two_bone_column());
  ASSERT_TRUE(mesh.ok());
  // Camera on +z looking toward -z: 10 agents in front, 5 behind the eye, 3 far off to the side.
  std::vector<AgentDraw> agents;
  for (int i = 0; i < 10; ++i)
    agents.push_back({{-3.0f + i * 0.7f, 0, -1.0f}, glm::vec3(1), *mesh});
  for (int i = 0; i < 5; ++i) agents.push_back({{-2.0f + i, 0, 15.0f}, glm::vec3(1), *mesh});
  for (int i = 0; i < 3; ++i) agents.push_back({{60.0f + i, 0, 0.0f}, glm::vec3(1), *mesh});
  std::vector<glm::mat4> palettes(agents.size() * 2);
  for (size_t i = 0; i < agents.size(); ++i) {
    column_palette(agents[i].position, 0.0f, std::span(palettes).subspan(i * 2, 2));
  }
  ASSERT_TRUE(renderer_->upload_palettes(palettes, 2).ok());
  ASSERT_GT(camera_.eye().z, 5.0f);
  ASSERT_LT(camera_.eye().z, 15.0f);
  FrameCapture culled, unculled;
  ASSERT_NO_FATAL_FAILURE(render(agents, &culled));
  EXPECT_EQ(renderer_->stats().agents_submitted, 18);
  EXPECT_EQ(renderer_->stats().agents_visible, 10);
  EXPECT_EQ(renderer_->stats().agents_culled, 8);
  EXPECT_EQ(renderer_->stats().skinned_draw_calls, 1);
  // Culling must not change the picture.
  renderer_->settings().cull_agents = false;
  ASSERT_NO_FATAL_FAILURE(render(agents, &unculled));
  EXPECT_EQ(renderer_->stats().agents_visible, 18);
  EXPECT_TRUE(std::equal(culled.rgba().begin(), culled.rgba().end(), unculled.rgba().begin()));
}

TEST_F(RendererTest, WindingFollowsTheNormalsSoCullingNeverHidesFaces) {
  SkinnedMesh ccw = make_two_bone_column();
  SkinnedMesh cw = ccw;  // every triangle clockwise
  for (size_t t = 0; t < cw.indices.size(); t += 3) std::swap(cw.indices[t + 1], cw.indices[t + 2]);
  SkinnedMesh mixed = ccw;  // every other triangle clockwise
  for (size_t t = 0; t < mixed.indices.size(); t += 6) {
    std::swap(mixed.indices[t + 1], mixed.indices[t + 2]);
  }
  Result<int> a = renderer_->add_mesh(ccw), b = renderer_->add_mesh(cw),
              c = renderer_->add_mesh(mixed);
  ASSERT_TRUE(a.ok() && b.ok() && c.ok());
  std::vector<glm::mat4> palette(2);
  column_palette(glm::vec3(0.0f), 0.3f, palette);
  ASSERT_TRUE(renderer_->upload_palettes(palette, 2).ok());
  FrameCapture unculled, frame;
  AgentDraw agent{glm::vec3(0.0f), glm::vec3(1.0f), *a};
  renderer_->settings().cull_back_faces = false;
  ASSERT_NO_FATAL_FAILURE(render(std::span(&agent, 1), &unculled));
  renderer_->settings().cull_back_faces = true;
  for (int id : {*a, *b, *c}) {
    agent.mesh = id;
    ASSERT_NO_FATAL_FAILURE(render(std::span(&agent, 1), &frame));
    EXPECT_TRUE(std::equal(unculled.rgba().begin(), unculled.rgba().end(), frame.rgba().begin()))
        << "mesh " << id << " drawn with back-face culling differs from the unculled original";
  }
}

TEST_F(RendererTest, PngAndRawFramesAreWritten) {
  FrameCapture frame;
  ASSERT_NO_FATAL_FAILURE(render({}, &frame));
  const std::string path = scratch_dir("render") + "/capture_check.png";
  std::remove(path.c_str());
  ASSERT_TRUE(frame.save_png(path).ok());
  std::ifstream in(path, std::ios::binary);
  std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)), {});
  ASSERT_GT(bytes.size(), 33u);
  const unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  EXPECT_TRUE(std::equal(signature, signature + 8, bytes.begin()));
  auto be32 = [&](size_t o) {
    return (bytes[o] << 24) | (bytes[o + 1] << 16) | (bytes[o + 2] << 8) | bytes[o + 3];
  };
  EXPECT_EQ(be32(16), kWidth);  // IHDR width and height
  EXPECT_EQ(be32(20), kHeight);
  int w = 0, h = 0, channels = 0;
  unsigned char* decoded = stbi_load(path.c_str(), &w, &h, &channels, 4);
  ASSERT_NE(decoded, nullptr);
  EXPECT_EQ(w, kWidth);
  EXPECT_EQ(h, kHeight);
  EXPECT_TRUE(std::equal(frame.rgba().begin(), frame.rgba().end(), decoded));
  stbi_image_free(decoded);

  std::FILE* raw = std::tmpfile();
  ASSERT_NE(raw, nullptr);
  ASSERT_TRUE(frame.write_rgb(raw).ok());
  ASSERT_TRUE(frame.write_rgb(raw).ok());  // frames stream back to back
  EXPECT_EQ(std::ftell(raw), 2L * kWidth * kHeight * 3);
  std::rewind(raw);
  unsigned char first[3];
  ASSERT_EQ(std::fread(first, 1, 3, raw), 3u);
  EXPECT_EQ(first[0], frame.pixel(0, 0).x);
  EXPECT_EQ(first[2], frame.pixel(0, 0).z);
  std::fclose(raw);
  EXPECT_FALSE(frame.save_png("/nonexistent-dir/x.png").ok());
}

}  // namespace
}  // namespace gk::test
