#include "render/frame_capture.h"

#include <algorithm>
#include <cerrno>
#include <cstring>

#include <stb_image_write.h>

#include "render/gl_api.h"

namespace gk {

Status FrameCapture::grab(glm::ivec2 size_px) {
  if (size_px.x < 1 || size_px.y < 1 || size_px.x > 16384 || size_px.y > 16384) {
    return Status::Error("capture: bad size " + std::to_string(size_px.x) + "x" +
                         std::to_string(size_px.y));
  }
  const size_t row_bytes = static_cast<size_t>(size_px.x) * 4;
  const size_t bytes = row_bytes * size_px.y;
  if (pixels_.size() < bytes) pixels_.resize(bytes);
  if (row_scratch_.size() < row_bytes) row_scratch_.resize(row_bytes);
  size_ = size_px;
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, size_px.x, size_px.y, GL_RGBA, GL_UNSIGNED_BYTE, pixels_.data());
  if (const GLenum error = glGetError(); error != GL_NO_ERROR) {
    return Status::Error("capture: glReadPixels failed with GL error " + std::to_string(error));
  }
  // GL's first row is the bottom one.
  for (int y = 0; y < size_px.y / 2; ++y) {
    uint8_t* top = pixels_.data() + row_bytes * y;
    uint8_t* bottom = pixels_.data() + row_bytes * (size_px.y - 1 - y);
    std::memcpy(row_scratch_.data(), top, row_bytes);
    std::memcpy(top, bottom, row_bytes);
    std::memcpy(bottom, row_scratch_.data(), row_bytes);
  }
  return Status::Ok();
}

glm::u8vec4 FrameCapture::pixel(int x, int y) const {
  if (x < 0 || y < 0 || x >= size_.x || y >= size_.y) return glm::u8vec4(0);
  const uint8_t* p = pixels_.data() + (static_cast<size_t>(y) * size_.x + x) * 4;
  return {p[0], p[1], p[2], p[3]};
}

Status FrameCapture::save_png(const std::string& path) const {
  if (size_.x == 0) return Status::Error(path + ": nothing captured yet");
  return write_png_rgba(path, size_, rgba());
}

Status FrameCapture::write_rgb(std::FILE* out) {
  if (out == nullptr) return Status::Error("capture: write_rgb to a null FILE*");
  if (size_.x == 0) return Status::Error("capture: nothing captured yet");
  const size_t num_pixels = static_cast<size_t>(size_.x) * size_.y;
  if (rgb_scratch_.size() < num_pixels * 3) rgb_scratch_.resize(num_pixels * 3);
  for (size_t i = 0; i < num_pixels; ++i) {
    std::memcpy(&rgb_scratch_[i * 3], &pixels_[i * 4], 3);
  }
  if (std::fwrite(rgb_scratch_.data(), 1, num_pixels * 3, out) != num_pixels * 3) {
    return Status::Error(std::string("capture: writing a raw frame failed: ") +
                         std::strerror(errno));
  }
  return Status::Ok();
}

Status write_png_rgba(const std::string& path, glm::ivec2 size_px, std::span<const uint8_t> rgba) {
  if (size_px.x < 1 || size_px.y < 1 ||
      rgba.size() < static_cast<size_t>(size_px.x) * size_px.y * 4) {
    return Status::Error(path + ": image buffer does not hold " + std::to_string(size_px.x) + "x" +
                         std::to_string(size_px.y) + " RGBA pixels");
  }
  if (stbi_write_png(path.c_str(), size_px.x, size_px.y, 4, rgba.data(), size_px.x * 4) == 0) {
    return Status::Error(path + ": cannot write PNG (" + std::strerror(errno) + ")");
  }
  return Status::Ok();
}

}  // namespace gk
