#pragma once
// Reads the finished frame back from the GPU (GlContext::finish_frame binds it for reading) into
// RGBA8 rows ordered top to bottom, the way images and camera pixels are, and saves it as PNG or
// streams raw RGB24 frames (e.g. into `ffmpeg -f rawvideo -pix_fmt rgb24 -s WxH -i -`).

#include <cstdint>
#include <cstdio>
#include <span>
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec4.hpp>

#include "common/status.h"

namespace gk {

class FrameCapture {
 public:
  // Reads size_px pixels from the bound read framebuffer. The buffer grows only when a frame is
  // larger than any before, so capturing video does not allocate per frame.
  Status grab(glm::ivec2 size_px);

  glm::ivec2 size() const { return size_; }
  std::span<const uint8_t> rgba() const {
    return {pixels_.data(), static_cast<size_t>(size_.x) * size_.y * 4};
  }
  // Writable view of the same pixels, e.g. to stamp labels before saving or streaming.
  std::span<uint8_t> mutable_rgba() {
    return {pixels_.data(), static_cast<size_t>(size_.x) * size_.y * 4};
  }
  // Pixel at (x, y), top-left origin; (0, 0, 0, 0) outside the image.
  glm::u8vec4 pixel(int x, int y) const;

  Status save_png(const std::string& path) const;
  // Writes width * height * 3 bytes (RGB24, top row first) to out.
  Status write_rgb(std::FILE* out);

 private:
  glm::ivec2 size_{0, 0};
  std::vector<uint8_t> pixels_;
  std::vector<uint8_t> row_scratch_;  // one row, for the vertical flip
  std::vector<uint8_t> rgb_scratch_;  // one frame of RGB24
};

// Saves any RGBA8 image (rows top first) as PNG. Errors name the path.
Status write_png_rgba(const std::string& path, glm::ivec2 size_px, std::span<const uint8_t> rgba);

}  // namespace gk
