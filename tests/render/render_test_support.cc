#include "tests/render/render_test_support.h"

#include <array>

// Mesa keeps llvmpipe JIT and driver allocations past eglTerminate and then unloads the driver, so
// LeakSanitizer reports them from "unknown modules" that no suppression can name, and every GL
// test would fail under GK_SANITIZE. Leak checking is off for this binary only; ASan and UBSan
// still run. (The hook is only looked up in sanitizer builds.)
extern "C" int __lsan_is_turned_off() { return 1; }

namespace gk::test {
namespace {

void add_box(SkinnedMesh* mesh, glm::vec3 lo, glm::vec3 hi, int joint, glm::vec3 color) {
  // Six faces, each four vertices with the face normal, counter-clockwise seen from outside.
  const std::array<glm::vec3, 6> normals = {glm::vec3(1, 0, 0), glm::vec3(-1, 0, 0),
                                            glm::vec3(0, 1, 0), glm::vec3(0, -1, 0),
                                            glm::vec3(0, 0, 1), glm::vec3(0, 0, -1)};
  const glm::vec3 center = 0.5f * (lo + hi), half = 0.5f * (hi - lo);
  for (const glm::vec3& n : normals) {
    // Two axes spanning the face, ordered so that u x v = n.
    glm::vec3 u = std::abs(n.y) > 0.5f ? glm::vec3(0, 0, 1) : glm::vec3(0, 1, 0);
    glm::vec3 v = glm::cross(n, u);
    u = glm::cross(v, n);
    const uint32_t base = static_cast<uint32_t>(mesh->positions.size());
    const glm::vec2 corners[4] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
    for (const glm::vec2& c : corners) {
      mesh->positions.push_back(center + half * (n + c.x * u + c.y * v));
      mesh->normals.push_back(n);
      mesh->colors.push_back(color);
      mesh->joints.push_back(glm::u16vec4(joint, 0, 0, 0));
      mesh->weights.push_back(glm::vec4(1, 0, 0, 0));
    }
    for (uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) mesh->indices.push_back(base + i);
  }
}

}  // namespace

SkinnedMesh make_two_bone_column(float width) {
  SkinnedMesh mesh;
  const float h = 0.5f * width;
  add_box(&mesh, {-h, 0.0f, -h}, {h, 1.0f, h}, 0, glm::vec3(0.7f));
  add_box(&mesh, {-h, 1.0f, -h}, {h, 2.0f, h}, 1, glm::vec3(0.9f, 0.45f, 0.1f));
  mesh.inverse_bind = {glm::mat4(1.0f),
                       glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, -1.0f, 0.0f))};
  return mesh;
}

void column_palette(const glm::vec3& position, float bend_rad, std::span<glm::mat4> out) {
  const glm::mat4 root = glm::translate(glm::mat4(1.0f), position);
  const glm::mat4 joint1 = root * glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, 1.0f, 0.0f)) *
                           glm::rotate(glm::mat4(1.0f), bend_rad, glm::vec3(0.0f, 0.0f, 1.0f));
  out[0] = root;  // inverse bind of joint 0 is identity
  out[1] = joint1 * glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, -1.0f, 0.0f));
}

void OffscreenRenderTest::SetUp() {
  ContextOptions options;
  options.width = kWidth;
  options.height = kHeight;
  Result<std::unique_ptr<GlContext>> context = GlContext::create_offscreen(options);
  if (!context.ok()) {
    if (under_ci()) FAIL() << "offscreen GL required under CI: " << context.message();
    GTEST_SKIP() << "offscreen GL unavailable: " << context.message();
  }
  context_ = std::move(context).value();
  renderer_ = std::make_unique<CrowdRenderer>();
  const Status status = renderer_->init();
  ASSERT_TRUE(status.ok()) << status.message();
  camera_.target = glm::vec3(0.0f, 1.0f, 0.0f);
  camera_.yaw_rad = 0.0f;
  camera_.pitch_rad = 0.35f;
  camera_.distance_m = 9.0f;
}

void OffscreenRenderTest::render(std::span<const AgentDraw> agents, FrameCapture* out) {
  context_->begin_frame();
  const Status drawn = renderer_->draw(camera_, viewport(), agents);
  ASSERT_TRUE(drawn.ok()) << drawn.message();
  context_->finish_frame();
  const Status grabbed = out->grab(viewport());
  ASSERT_TRUE(grabbed.ok()) << grabbed.message();
}

}  // namespace gk::test
