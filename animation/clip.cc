// Clip validation and the loaders' shared helpers (FK for loop detection, file names).

#include "animation/clip.h"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtx/quaternion.hpp>

#include "animation/loader_internal.h"

namespace gk {

Status validate_clip(const Clip& clip, const Skeleton& skeleton) {
  const std::string where =
      clip.source.empty() ? "clip '" + clip.name + "'" : clip.source + ": clip '" + clip.name + "'";
  auto fail = [&](const std::string& what) { return Status::Error(where + ": " + what); };
  if (!(clip.fps > 0.0f) || !std::isfinite(clip.fps)) return fail("fps must be > 0");
  if (clip.num_frames < 1) return fail("has no frames");
  if (clip.num_joints != skeleton.num_joints()) {
    return fail("has " + std::to_string(clip.num_joints) + " joints, the skeleton has " +
                std::to_string(skeleton.num_joints()));
  }
  const size_t n = static_cast<size_t>(clip.num_frames) * static_cast<size_t>(clip.num_joints);
  if (clip.rotations.size() != n || clip.translations.size() != n) {
    return fail("expected " + std::to_string(n) + " rotations and translations, found " +
                std::to_string(clip.rotations.size()) + " and " +
                std::to_string(clip.translations.size()));
  }
  for (size_t i = 0; i < n; ++i) {
    const glm::quat& q = clip.rotations[i];
    const glm::vec3& t = clip.translations[i];
    const float len = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
    const bool finite_t = std::isfinite(t.x) && std::isfinite(t.y) && std::isfinite(t.z);
    if (!finite_t || !std::isfinite(len) || std::abs(len - 1.0f) > 1e-3f) {
      return fail("frame " + std::to_string(i / clip.num_joints) + ", joint " +
                  std::to_string(i % clip.num_joints) +
                  ": non-finite translation or non-unit rotation");
    }
  }
  return Status::Ok();
}

namespace internal {

void local_to_model(const Skeleton& skeleton, const glm::quat* rotations,
                    const glm::vec3* translations, std::vector<glm::mat4>* out_model) {
  const int n = skeleton.num_joints();
  out_model->resize(n);
  for (int j = 0; j < n; ++j) {
    const glm::mat4 local = glm::translate(glm::mat4(1.0f), translations[j]) *
                            glm::toMat4(glm::normalize(rotations[j]));
    const int p = skeleton.parents[j];
    (*out_model)[j] = p >= 0 ? (*out_model)[p] * local : local;
  }
}

float loop_mismatch_m(const Clip& clip, const Skeleton& skeleton) {
  if (clip.num_frames < 2) return 0.0f;
  const int n = clip.num_joints;
  std::vector<glm::mat4> a, b;
  auto pose = [&](int frame, std::vector<glm::mat4>* out) {
    std::vector<glm::vec3> t(clip.frame_translations(frame), clip.frame_translations(frame) + n);
    for (int j = 0; j < n; ++j) {
      if (skeleton.parents[j] < 0) t[j].x = t[j].z = 0.0f;
    }
    local_to_model(skeleton, clip.frame_rotations(frame), t.data(), out);
  };
  pose(0, &a);
  pose(clip.num_frames - 1, &b);
  // Positions alone miss leaf joints turning in place (a head, a toe), so each joint's axes are
  // compared too, as points kLever from the joint.
  constexpr float kLever = 0.1f;
  float worst = 0.0f;
  for (int j = 0; j < n; ++j) {
    worst = std::max(worst, glm::length(glm::vec3(a[j][3] - b[j][3])));
    for (int axis = 0; axis < 3; ++axis) {
      worst = std::max(worst, kLever * glm::length(glm::vec3(a[j][axis] - b[j][axis])));
    }
  }
  return worst;
}

void finalize_loop(Clip* clip, const Skeleton& skeleton, float tolerance_m) {
  clip->loops = false;
  if (clip->num_frames < 3 || loop_mismatch_m(*clip, skeleton) > tolerance_m) return;
  clip->loops = true;
  clip->num_frames -= 1;
  const size_t keep = static_cast<size_t>(clip->num_frames) * clip->num_joints;
  clip->rotations.resize(keep);
  clip->translations.resize(keep);
}

float loop_tolerance_m(const Skeleton& skeleton) {
  std::vector<glm::mat4> model;
  local_to_model(skeleton, skeleton.rest_rotations.data(), skeleton.rest_translations.data(),
                 &model);
  float leg = 0.0f;
  int sides = 0;
  for (Side s : {Side::kLeft, Side::kRight}) {
    if (skeleton.hip(s) < 0 || skeleton.ankle(s) < 0) continue;
    leg += glm::length(glm::vec3(model[skeleton.hip(s)][3] - model[skeleton.ankle(s)][3]));
    ++sides;
  }
  if (sides == 0 || !(leg > 0.0f)) return 0.05f;
  return 0.06f * leg / sides;
}

std::string file_name(const std::string& path) {
  const size_t slash = path.find_last_of("/\\");
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

std::string file_stem(const std::string& path) {
  std::string name = file_name(path);
  const size_t dot = name.find_last_of('.');
  return dot == std::string::npos || dot == 0 ? name : name.substr(0, dot);
}

}  // namespace internal
}  // namespace gk
