// Split-screen drawing (draw_region clears and draws only its rectangle) and the label stamp.

#include <algorithm>
#include <vector>

#include <gtest/gtest.h>

#include "render/label_font.h"
#include "tests/render/render_test_support.h"

namespace gk::test {
namespace {

using SplitTest = OffscreenRenderTest;

TEST_F(SplitTest, EachRegionKeepsItsOwnPicture) {
  Result<int> mesh = renderer_->add_mesh(make_two_bone_column());
  ASSERT_TRUE(mesh.ok());
  const std::vector<AgentDraw> agents = {{{0.0f, 0.0f, 0.0f}, glm::vec3(1), *mesh}};
  std::vector<glm::mat4> palette(2);
  column_palette(agents[0].position, 0.0f, palette);
  ASSERT_TRUE(renderer_->upload_palettes(palette, 2).ok());
  const glm::ivec2 half(kWidth / 2, kHeight);
  context_->begin_frame();
  // Left: the column; right: an empty scene drawn afterwards must not wipe the left half.
  ASSERT_TRUE(renderer_->draw_region(camera_, {0, 0}, half, agents).ok());
  ASSERT_TRUE(renderer_->draw_region(camera_, {half.x, 0}, half, {}).ok());
  context_->finish_frame();
  FrameCapture frame;
  ASSERT_TRUE(frame.grab(viewport()).ok());
  // The column stands at the centre of each half's view: present on the left only.
  const ProjectedPoint p = camera_.project({0.0f, 1.5f, 0.0f}, half);
  ASSERT_TRUE(p.in_front);
  const int x = static_cast<int>(p.pixel.x), y = static_cast<int>(p.pixel.y);
  const glm::u8vec4 left = frame.pixel(x, y), right = frame.pixel(x + half.x, y);
  EXPECT_GT(pixel_difference(left, right), 60)
      << "left " << int(left.x) << "," << int(left.y) << " right " << int(right.x);
  // Away from the column both halves show the same ground.
  EXPECT_LE(pixel_difference(frame.pixel(20, kHeight - 20), frame.pixel(20 + half.x, kHeight - 20)),
            6);
}

TEST(LabelFont, StampsTextInsideItsBoxOnly) {
  const glm::ivec2 size(64, 24);
  std::vector<uint8_t> rgba(size.x * size.y * 4, 100);
  stamp_label(rgba, size, {6, 6}, "APM", 1);
  int white = 0;
  for (size_t i = 0; i < rgba.size(); i += 4) white += rgba[i] == 255;
  // A, P and M are drawn from 5x7 glyphs: dozens of lit pixels.
  EXPECT_GT(white, 30);
  EXPECT_LT(white, 3 * 35);
  EXPECT_EQ(label_width("APM", 1), 17);
  // Far right of the image is outside the label's box and keeps its value.
  EXPECT_EQ(rgba[(10 * size.x + 60) * 4], 100);
  // Clipped, never written out of bounds (ASan checks) for labels past the edges.
  stamp_label(rgba, size, {-20, -5}, "NAIVE", 3);
  stamp_label(rgba, size, {60, 20}, "NAIVE", 3);
}

}  // namespace
}  // namespace gk::test
