#include "animation/bvh_writer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <glm/gtc/quaternion.hpp>
#include <glm/mat3x3.hpp>

namespace gk {
namespace {

// Angles [deg] (z, y, x) with q = Rz(z) * Ry(y) * Rx(x), the product load_bvh builds for the
// channel order "Zrotation Yrotation Xrotation".
glm::vec3 zyx_degrees(const glm::quat& q) {
  const glm::mat3 m = glm::mat3_cast(glm::normalize(q));  // m[column][row]
  const float sy = std::clamp(-m[0][2], -1.0f, 1.0f);
  const float y = std::asin(sy);
  float x, z;
  if (std::abs(sy) < 0.99999f) {
    x = std::atan2(m[1][2], m[2][2]);
    z = std::atan2(m[0][1], m[0][0]);
  } else {  // gimbal lock: z and x turn about the same axis; put it all in z
    x = 0.0f;
    z = std::atan2(-m[1][0], m[1][1]);
  }
  return glm::degrees(glm::vec3(z, y, x));
}

void append(std::string* out, const char* fmt, double a, double b, double c) {
  char buf[128];
  std::snprintf(buf, sizeof buf, fmt, a, b, c);
  *out += buf;
}

}  // namespace

std::string format_bvh(const Skeleton& sk, const Clip& clip, const BvhWriteOptions& options) {
  const int nj = sk.num_joints();
  const float u = options.units_per_m;
  std::vector<int> children_left(nj, 0);
  for (int j = 0; j < nj; ++j) {
    if (sk.parents[j] >= 0) ++children_left[sk.parents[j]];
  }
  // Position channels where the pose needs them: the roots, and any joint whose translation leaves
  // its rest offset on some frame (a glTF clip may animate any joint's translation).
  std::vector<uint8_t> moves(nj, 0);
  for (int f = 0; f < clip.num_frames; ++f) {
    for (int j = 0; j < nj; ++j) {
      const glm::vec3 d = clip.frame_translations(f)[j] - sk.rest_translations[j];
      if (glm::dot(d, d) > 1e-12f) moves[j] = 1;
    }
  }
  auto has_positions = [&](int j) {
    return sk.parents[j] < 0 || options.positions_on_every_joint || moves[j];
  };
  std::string out = "HIERARCHY\n";
  // Depth-first in joint order: a skeleton's joints are topological, and a joint's subtree
  // closes before the next joint that is not below it.
  std::vector<int> open;  // joints whose braces are open
  // Closes the innermost open joint (with its End Site when it is a leaf that has one).
  auto close_joint = [&] {
    const int k = open.back();
    open.pop_back();
    const std::string pad(open.size() * 2, ' ');
    if (children_left[k] == 0 && k < static_cast<int>(sk.end_sites.size())) {
      const glm::vec3 e = sk.end_sites[k] * u;
      out += pad + "  End Site\n" + pad + "  {\n" + pad;
      append(&out, "    OFFSET %.9g %.9g %.9g\n", e.x, e.y, e.z);
      out += pad + "  }\n";
    }
    out += pad + "}\n";
  };
  for (int j = 0; j < nj; ++j) {
    while (!open.empty() && open.back() != sk.parents[j]) close_joint();
    const std::string pad(open.size() * 2, ' ');
    out += pad + (sk.parents[j] < 0 ? "ROOT " : "JOINT ") + sk.names[j] + "\n" + pad + "{\n";
    const glm::vec3 o = sk.rest_translations[j] * u;
    append(&out, (pad + "  OFFSET %.9g %.9g %.9g\n").c_str(), o.x, o.y, o.z);
    out += pad +
           (has_positions(j) ? "  CHANNELS 6 Xposition Yposition Zposition " : "  CHANNELS 3 ") +
           "Zrotation Yrotation Xrotation\n";
    open.push_back(j);
  }
  while (!open.empty()) close_joint();
  const int n = clip.num_frames;
  const bool close_loop = clip.loops && n >= 2;
  char buf[96];
  std::snprintf(buf, sizeof buf, "MOTION\nFrames: %d\nFrame Time: %.9g\n", n + (close_loop ? 1 : 0),
                1.0 / clip.fps);
  out += buf;
  glm::vec3 per_loop(0.0f);
  if (close_loop) {
    per_loop = (clip.frame_translations(n - 1)[0] - clip.frame_translations(0)[0]) *
               (static_cast<float>(n) / (n - 1));
    per_loop.y = 0.0f;
  }
  for (int k = 0; k < n + (close_loop ? 1 : 0); ++k) {
    const int f = k % n;
    const glm::quat* r = clip.frame_rotations(f);
    const glm::vec3* t = clip.frame_translations(f);
    for (int j = 0; j < nj; ++j) {
      if (has_positions(j)) {
        glm::vec3 p = t[j];
        if (k == n && sk.parents[j] < 0) p += per_loop;
        p *= u;
        append(&out, "%.9g %.9g %.9g ", p.x, p.y, p.z);
      }
      const glm::vec3 e = zyx_degrees(r[j]);
      append(&out, j + 1 < nj ? "%.9g %.9g %.9g " : "%.9g %.9g %.9g", e.x, e.y, e.z);
    }
    out += "\n";
  }
  return out;
}

}  // namespace gk
