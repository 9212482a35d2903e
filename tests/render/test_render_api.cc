// Camera maths (no GL), error reporting, debug lines, walls and the GLFW window path.
#include <cmath>
#include <cstdlib>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "render/camera.h"
#include "render/shader_program.h"
#include "tests/render/render_test_support.h"

namespace gk::test {
namespace {

TEST(Camera, ProjectAndPickRayAreInverse) {
  OrbitCamera camera;
  camera.target = {1.0f, 0.5f, -2.0f};
  camera.yaw_rad = 0.7f;
  camera.pitch_rad = 0.5f;
  camera.distance_m = 10.0f;
  const glm::ivec2 viewport(800, 600);
  // The target projects to the viewport centre.
  const ProjectedPoint centre = camera.project(camera.target, viewport);
  ASSERT_TRUE(centre.in_front);
  EXPECT_NEAR(centre.pixel.x, 400.0f, 1e-3f);
  EXPECT_NEAR(centre.pixel.y, 300.0f, 1e-3f);
  // A point above the target appears higher on screen (smaller y).
  EXPECT_LT(camera.project(camera.target + glm::vec3(0, 1, 0), viewport).pixel.y, 300.0f);
  // A ground point -> pixel -> ray -> ground gives the point back.
  const glm::vec3 ground(3.0f, 0.0f, 1.5f);
  const ProjectedPoint p = camera.project(ground, viewport);
  ASSERT_TRUE(p.in_front);
  const Ray ray = camera.pick_ray(p.pixel, viewport);
  EXPECT_NEAR(glm::length(ray.origin - camera.eye()), 0.0f, 1e-4f);
  const std::optional<glm::vec3> hit = intersect_ground(ray);
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(glm::length(*hit - ground), 0.0f, 1e-3f);
  // Behind the eye.
  const glm::vec3 behind = camera.eye() + (camera.eye() - camera.target);
  EXPECT_FALSE(camera.project(behind, viewport).in_front);
}

TEST(Camera, OrbitPanZoomStayInLimits) {
  OrbitCamera camera;
  camera.orbit(0.0f, 10.0f);
  EXPECT_LE(camera.pitch_rad, OrbitCamera::kMaxPitchRad);
  camera.zoom(1e-9f);
  EXPECT_GE(camera.distance_m, camera.near_m);
  camera.zoom(std::nanf(""));
  EXPECT_TRUE(std::isfinite(camera.distance_m));
  // Panning right by the full viewport height moves the target by the visible height at its depth.
  camera = OrbitCamera();
  camera.pitch_rad = 0.0f;
  const glm::vec3 before = camera.target;
  camera.pan({0.0f, 600.0f}, {800, 600});
  const float visible = 2.0f * camera.distance_m * std::tan(glm::radians(camera.fov_y_deg) / 2.0f);
  EXPECT_NEAR(camera.target.y - before.y, visible, 1e-3f);
}

TEST(Camera, ZoomAboutKeepsTheGroundPointUnderTheCursor) {
  OrbitCamera camera;
  camera.target = {2.0f, 0.9f, -1.0f};
  camera.yaw_rad = 0.6f;
  camera.pitch_rad = 0.5f;
  camera.distance_m = 20.0f;
  const glm::ivec2 viewport(800, 450);
  const glm::vec2 cursor(620.0f, 330.0f);  // off centre: a plain zoom would move this point
  const std::optional<glm::vec3> before = intersect_ground(camera.pick_ray(cursor, viewport));
  ASSERT_TRUE(before.has_value());
  OrbitCamera plain = camera;
  plain.zoom(0.5f);
  camera.zoom_about(cursor, viewport, 0.5f);
  EXPECT_NEAR(camera.distance_m, 10.0f, 1e-4f);
  const glm::vec2 moved = camera.project(*before, viewport).pixel;
  EXPECT_NEAR(moved.x, cursor.x, 0.05f);
  EXPECT_NEAR(moved.y, cursor.y, 0.05f);
  // The plain zoom (toward the target) does move it: the test can tell the two apart.
  EXPECT_GT(glm::length(plain.project(*before, viewport).pixel - cursor), 50.0f);
  // Clamped at the near limit, the cursor point still stays put.
  camera.zoom_about(cursor, viewport, 1e-6f);
  EXPECT_GE(camera.distance_m, camera.near_m);
  const glm::vec2 clamped = camera.project(*before, viewport).pixel;
  EXPECT_NEAR(glm::length(clamped - cursor), 0.0f, 0.5f);
  // Above the horizon there is no ground point: a plain zoom.
  OrbitCamera level;
  level.pitch_rad = 0.0f;
  level.zoom_about({400.0f, 10.0f}, viewport, 0.5f);
  EXPECT_NEAR(level.distance_m, OrbitCamera().distance_m * 0.5f, 1e-4f);
  EXPECT_EQ(level.target, OrbitCamera().target);
}

TEST(Camera, FrustumKeepsVisibleAndRejectsHiddenSpheres) {
  OrbitCamera camera;
  const Frustum frustum(camera.view_projection({640, 360}));
  EXPECT_TRUE(frustum.intersects_sphere(camera.target, 0.5f));
  EXPECT_FALSE(frustum.intersects_sphere(camera.eye() + (camera.eye() - camera.target), 0.5f));
  EXPECT_FALSE(frustum.intersects_sphere({1000.0f, 0.0f, 0.0f}, 1.0f));
  EXPECT_TRUE(frustum.intersects_sphere({1000.0f, 0.0f, 0.0f}, 2000.0f));
}

TEST(Context, BadSizesAreErrors) {
  ContextOptions options;
  options.width = 0;
  const auto offscreen = GlContext::create_offscreen(options);
  ASSERT_FALSE(offscreen.ok());
  EXPECT_NE(offscreen.message().find("bad size"), std::string::npos) << offscreen.message();
  const auto window = GlContext::create_window(options);
  EXPECT_FALSE(window.ok());
}

TEST(Context, WindowWithoutDisplayIsAnError) {
  const char* display = std::getenv("DISPLAY");
  const char* wayland = std::getenv("WAYLAND_DISPLAY");
  if ((display && *display) || (wayland && *wayland)) GTEST_SKIP() << "a display is available";
  ContextOptions options;
  options.width = 64;
  options.height = 64;
  const auto window = GlContext::create_window(options);
  ASSERT_FALSE(window.ok());
  EXPECT_NE(window.message().find("display"), std::string::npos) << window.message();
}

TEST(Context, WindowRendersWhenADisplayIsSet) {
  const char* display = std::getenv("DISPLAY");
  if (display == nullptr || *display == '\0') GTEST_SKIP() << "DISPLAY not set (try xvfb-run)";
  ContextOptions options;
  options.width = 320;
  options.height = 240;
  options.visible = false;
  auto window = GlContext::create_window(options);
  ASSERT_TRUE(window.ok()) << window.message();
  GlContext& context = **window;
  CrowdRenderer renderer;
  ASSERT_TRUE(renderer.init().ok());
  Result<int> mesh = renderer.add_mesh(make_two_bone_column());
  ASSERT_TRUE(mesh.ok());
  std::vector<glm::mat4> palette(2);
  column_palette(glm::vec3(0.0f), 0.0f, palette);
  ASSERT_TRUE(renderer.upload_palettes(palette, 2).ok());
  const AgentDraw agent{glm::vec3(0.0f), glm::vec3(1.0f), *mesh};
  OrbitCamera camera;
  camera.distance_m = 5.0f;
  context.begin_frame();
  const glm::ivec2 size = context.framebuffer_size();
  ASSERT_TRUE(renderer.draw(camera, size, std::span(&agent, 1)).ok());
  context.finish_frame();
  FrameCapture frame;
  ASSERT_TRUE(frame.grab(size).ok());
  context.present();
  const ProjectedPoint p = camera.project({0.0f, 1.0f, 0.0f}, size);
  const glm::u8vec4 body = frame.pixel(static_cast<int>(p.pixel.x), static_cast<int>(p.pixel.y));
  EXPECT_GT(pixel_difference(body, frame.pixel(2, 2)), 30);
  EXPECT_FALSE(context.description().empty());
}

TEST(Context, MultisampledOffscreenFrameIsResolvedForCapture) {
  ContextOptions options;
  options.width = 160;
  options.height = 90;
  options.samples = 4;
  auto context = GlContext::create_offscreen(options);
  if (!context.ok()) {
    if (under_ci()) FAIL() << "offscreen GL required under CI: " << context.message();
    GTEST_SKIP() << "offscreen GL unavailable: " << context.message();
  }
  CrowdRenderer renderer;
  ASSERT_TRUE(renderer.init().ok());
  renderer.add_line({-10.0f, 1.0f, 0.0f}, {10.0f, 1.0f, 0.0f}, {1.0f, 0.0f, 0.0f});
  OrbitCamera camera;
  camera.pitch_rad = 0.0f;
  (*context)->begin_frame();
  ASSERT_TRUE(renderer.draw(camera, {160, 90}, {}).ok());
  (*context)->finish_frame();
  FrameCapture frame;
  ASSERT_TRUE(frame.grab({160, 90}).ok());
  // glReadPixels from a multisampled FBO is a GL error, so a successful grab that shows the line
  // through the image centre proves finish_frame() resolved the samples.
  const glm::u8vec4 centre = frame.pixel(80, 44), below = frame.pixel(80, 45);
  EXPECT_TRUE(centre.x > 150 || below.x > 150) << int(centre.x) << " / " << int(below.x);
  options.samples = 1000;
  EXPECT_FALSE(GlContext::create_offscreen(options).ok());
}

class RenderApiTest : public OffscreenRenderTest {};

TEST_F(RenderApiTest, ShaderErrorsNameTheFileAndCarryTheLog) {
  const auto broken = ShaderProgram::build_from_source(
      "ok.vert", "void main() { gl_Position = vec4(0.0); }", "broken.frag",
      "out vec4 c;\nvoid main() { c = vec4(undeclared_thing); }");
  ASSERT_FALSE(broken.ok());
  EXPECT_NE(broken.message().find("broken.frag"), std::string::npos) << broken.message();
  EXPECT_NE(broken.message().find("undeclared_thing"), std::string::npos) << broken.message();
  EXPECT_FALSE(ShaderProgram::build("missing.vert", "lit.frag").ok());
  EXPECT_FALSE(embedded_shader("skinned.vert").empty());
}

TEST_F(RenderApiTest, BadInputIsReportedNotDrawn) {
  SkinnedMesh mesh = make_two_bone_column();
  mesh.indices.push_back(100000);
  mesh.indices.push_back(0);
  mesh.indices.push_back(1);
  EXPECT_FALSE(renderer_->add_mesh(mesh).ok());
  mesh = make_two_bone_column();
  mesh.weights.pop_back();
  EXPECT_FALSE(renderer_->add_mesh(mesh).ok());
  EXPECT_FALSE(renderer_->add_mesh(SkinnedMesh{}).ok());

  Result<int> id = renderer_->add_mesh(make_two_bone_column());
  ASSERT_TRUE(id.ok());
  std::vector<glm::mat4> palettes(5);
  EXPECT_FALSE(renderer_->upload_palettes(palettes, 2).ok());  // 5 is not 2 per agent
  EXPECT_FALSE(renderer_->upload_palettes(palettes, 0).ok());
  palettes.resize(4);
  ASSERT_TRUE(renderer_->upload_palettes(palettes, 2).ok());
  std::vector<AgentDraw> agents(3);
  Status s = renderer_->draw(camera_, viewport(), agents);  // 3 agents, palettes for 2
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("palettes for 2"), std::string::npos) << s.message();
  agents.resize(2);
  agents[1].mesh = 7;
  EXPECT_FALSE(renderer_->draw(camera_, viewport(), agents).ok());
  agents[1].mesh = *id;
  EXPECT_FALSE(renderer_->draw(camera_, {0, 10}, agents).ok());
  // A mesh with more joints than the palettes carry.
  ASSERT_TRUE(renderer_->upload_palettes(std::span(palettes).first(2), 1).ok());
  EXPECT_FALSE(renderer_->draw(camera_, viewport(), std::span(agents).first(1)).ok());
  // Non-finite agent positions are skipped, not drawn.
  ASSERT_TRUE(renderer_->upload_palettes(palettes, 2).ok());
  agents[0].position.x = std::nanf("");
  ASSERT_TRUE(renderer_->draw(camera_, viewport(), agents).ok());
  EXPECT_EQ(renderer_->stats().agents_visible, 1);
  const glm::vec4 bad_wall(0.0f, std::nanf(""), 1.0f, 1.0f);
  EXPECT_FALSE(renderer_->set_walls(std::span(&bad_wall, 1)).ok());
}

TEST_F(RenderApiTest, DebugLinesAndWallsAreDrawn) {
  FrameCapture empty, scene;
  ASSERT_NO_FATAL_FAILURE(render({}, &empty));
  // A red line across the view at head height and a wall 3 m in front of the target.
  renderer_->add_line({-3.0f, 1.0f, 0.0f}, {3.0f, 1.0f, 0.0f}, {1.0f, 0.0f, 0.0f});
  const glm::vec4 wall(-2.0f, -3.0f, 2.0f, -3.0f);
  ASSERT_TRUE(renderer_->set_walls(std::span(&wall, 1)).ok());
  ASSERT_NO_FATAL_FAILURE(render({}, &scene));
  EXPECT_EQ(renderer_->stats().lines_drawn, 1);
  EXPECT_EQ(renderer_->stats().draw_calls, 3);  // ground, walls, lines
  ASSERT_TRUE(scene.save_png(scratch_dir("render") + "/lines_walls.png").ok());
  const ProjectedPoint on_line = camera_.project({1.0f, 1.0f, 0.0f}, viewport());
  const glm::u8vec4 c =
      scene.pixel(static_cast<int>(on_line.pixel.x), static_cast<int>(on_line.pixel.y));
  EXPECT_GT(c.x, 200);
  EXPECT_LT(c.y, 60);
  const ProjectedPoint on_wall = camera_.project({0.5f, 0.5f, -3.0f}, viewport());
  const int wx = static_cast<int>(on_wall.pixel.x), wy = static_cast<int>(on_wall.pixel.y);
  EXPECT_GT(pixel_difference(scene.pixel(wx, wy), empty.pixel(wx, wy)), 20);
  // Lines last one frame.
  ASSERT_NO_FATAL_FAILURE(render({}, &scene));
  EXPECT_EQ(renderer_->stats().lines_drawn, 0);
}

TEST_F(RenderApiTest, PropsAndTranslucentTrianglesAreDrawn) {
  FrameCapture empty, scene;
  ASSERT_NO_FATAL_FAILURE(render({}, &empty));
  // A teal panel standing 3 m behind the target, turned 30 deg, and a half-transparent red
  // triangle on the ground in front of it.
  PropBox panel;
  panel.center = {0.0f, 1.0f, -3.0f};
  panel.half_size = {1.0f, 0.8f, 0.05f};
  panel.yaw_rad = 0.5f;
  panel.color = {0.02f, 0.45f, 0.5f};
  ASSERT_TRUE(renderer_->set_props(std::span(&panel, 1)).ok());
  renderer_->add_triangle({1.0f, 0.02f, 0.5f}, {3.0f, 0.02f, 0.5f}, {2.0f, 0.02f, 2.0f},
                          {1.0f, 0.0f, 0.0f, 0.5f});
  ASSERT_NO_FATAL_FAILURE(render({}, &scene));
  EXPECT_EQ(renderer_->stats().triangles_drawn, 1);
  ASSERT_TRUE(scene.save_png(scratch_dir("render") + "/props_triangles.png").ok());
  const ProjectedPoint on_panel = camera_.project(panel.center, viewport());
  const glm::u8vec4 p =
      scene.pixel(static_cast<int>(on_panel.pixel.x), static_cast<int>(on_panel.pixel.y));
  EXPECT_GT(p.z, p.x + 40) << "teal expected: " << int(p.x) << "," << int(p.y) << "," << int(p.z);
  EXPECT_GT(p.y, p.x + 40);
  // Half red over the grey ground: redder than the ground, yet not pure red.
  const ProjectedPoint on_tri = camera_.project({2.0f, 0.02f, 1.0f}, viewport());
  const int tx = static_cast<int>(on_tri.pixel.x), ty = static_cast<int>(on_tri.pixel.y);
  const glm::u8vec4 t = scene.pixel(tx, ty), ground = empty.pixel(tx, ty);
  EXPECT_GT(t.x, ground.x + 30);
  EXPECT_LT(t.y, ground.y - 30);
  EXPECT_GT(t.y, 20) << "the triangle should let the ground show through";
  EXPECT_EQ(t.w, 255) << "captured frames stay opaque";
  // Triangles last one frame; bad boxes are refused.
  ASSERT_NO_FATAL_FAILURE(render({}, &scene));
  EXPECT_EQ(renderer_->stats().triangles_drawn, 0);
  panel.half_size.y = 0.0f;
  EXPECT_FALSE(renderer_->set_props(std::span(&panel, 1)).ok());
  panel.half_size.y = 1.0f;
  panel.center.x = std::nanf("");
  EXPECT_FALSE(renderer_->set_props(std::span(&panel, 1)).ok());
}

TEST_F(RenderApiTest, DebugLinesBeyondCapacityAreDroppedAndCounted) {
  CrowdRenderer small;
  RendererConfig config;
  config.max_debug_lines = 2;
  ASSERT_TRUE(small.init(config).ok());
  for (int i = 0; i < 5; ++i) small.add_line(glm::vec3(0.0f), glm::vec3(1.0f), glm::vec3(1.0f));
  ASSERT_TRUE(small.draw(camera_, viewport(), {}).ok());
  EXPECT_EQ(small.stats().lines_drawn, 2);
  EXPECT_EQ(small.stats().lines_dropped, 3);
}

TEST_F(RenderApiTest, ContactShadowDarkensTheGroundBesideTheFeet) {
  Result<int> mesh = renderer_->add_mesh(make_two_bone_column());
  ASSERT_TRUE(mesh.ok());
  std::vector<glm::mat4> palette(2);
  column_palette(glm::vec3(0.0f), 0.0f, palette);
  ASSERT_TRUE(renderer_->upload_palettes(palette, 2).ok());
  const AgentDraw agent{glm::vec3(0.0f), glm::vec3(1.0f), *mesh};
  camera_.target = glm::vec3(0.0f);
  camera_.pitch_rad = 1.5f;  // nearly top-down so the ground around the feet is visible
  camera_.distance_m = 10.0f;
  FrameCapture empty, frame;
  ASSERT_NO_FATAL_FAILURE(render({}, &empty));
  ASSERT_NO_FATAL_FAILURE(render(std::span(&agent, 1), &frame));
  ASSERT_TRUE(frame.save_png(scratch_dir("render") + "/shadow_top.png").ok());
  // Just outside the 0.4 m wide column (half width 0.2 m; its top, 2 m closer to the eye, looks
  // 25 % wider), well inside the 0.45 m shadow.
  const ProjectedPoint p = camera_.project({0.33f, 0.0f, 0.0f}, viewport());
  const glm::u8vec4 lit = empty.pixel(static_cast<int>(p.pixel.x), static_cast<int>(p.pixel.y));
  const glm::u8vec4 shaded = frame.pixel(static_cast<int>(p.pixel.x), static_cast<int>(p.pixel.y));
  EXPECT_LT(shaded.y + 8, lit.y) << int(shaded.y) << " vs " << int(lit.y);
  // Far from the agent the ground is untouched.
  const ProjectedPoint far = camera_.project({1.5f, 0.0f, 0.0f}, viewport());
  EXPECT_EQ(frame.pixel(static_cast<int>(far.pixel.x), static_cast<int>(far.pixel.y)),
            empty.pixel(static_cast<int>(far.pixel.x), static_cast<int>(far.pixel.y)));
}

}  // namespace
}  // namespace gk::test
