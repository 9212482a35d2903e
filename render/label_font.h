#pragma once
// Stamps short labels ("NAIVE", "APM", frame numbers) into an RGBA8 image with a built-in 5x7
// bitmap font, so captured frames and videos say what they show without a font library.
// Upper-case letters, digits, space and . : - / % are drawn; other characters leave a gap.

#include <cstdint>
#include <span>
#include <string_view>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

namespace gk {

// Draws `text` with its top-left corner at `origin_px` (image rows top first), each font pixel
// `scale` image pixels, on a dark translucent box. Clipped to the image.
void stamp_label(std::span<uint8_t> rgba, glm::ivec2 image_size, glm::ivec2 origin_px,
                 std::string_view text, int scale, glm::u8vec3 color = {255, 255, 255});

// Width in pixels of `text` at `scale` (without the box margin).
int label_width(std::string_view text, int scale);

}  // namespace gk
