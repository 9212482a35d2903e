#pragma once
// Shared pieces of the render tests: an offscreen GL fixture that skips (or fails under CI=true)
// without EGL, hand-built skinned meshes with known geometry, and image comparison helpers.

#include <cstdlib>
#include <memory>
#include <span>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "animation/mesh.h"
#include "render/crowd_renderer.h"
#include "render/frame_capture.h"
#include "render/gl_context.h"
#include "tests/test_data.h"

namespace gk::test {

// Two stacked boxes, `width` wide: box 0 spans y in [0, 1] on joint 0 (at the origin), box 1 spans
// y in [1, 2] on joint 1 (at y = 1). Colours: joint 0 light grey, joint 1 orange.
SkinnedMesh make_two_bone_column(float width = 0.4f);

// Palette of the column placed at `position` with heading 0; joint 1 rotated by `bend_rad` about
// +z at its pivot (pi/2 swings box 1 over to -x).
void column_palette(const glm::vec3& position, float bend_rad, std::span<glm::mat4> out);

// Sum of absolute RGB differences between two pixels.
inline int pixel_difference(glm::u8vec4 a, glm::u8vec4 b) {
  return std::abs(a.x - b.x) + std::abs(a.y - b.y) + std::abs(a.z - b.z);
}

class OffscreenRenderTest : public ::testing::Test {
 protected:
  static constexpr int kWidth = 640;
  static constexpr int kHeight = 360;

  void SetUp() override;
  // Draws agents (palettes already uploaded) and reads the frame back into `out`.
  void render(std::span<const AgentDraw> agents, FrameCapture* out);
  glm::ivec2 viewport() const { return {kWidth, kHeight}; }

  std::unique_ptr<GlContext> context_;
  std::unique_ptr<CrowdRenderer> renderer_;
  OrbitCamera camera_;
};

}  // namespace gk::test
