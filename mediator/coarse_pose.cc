#include "mediator/coarse_pose.h"

#include <algorithm>

#include <glm/geometric.hpp>

#include "animation/pose_jobs.h"
#include "mediator/locomotion_library.h"

namespace gk {

namespace {

// p * [r t; 0 1] with the products by the local matrix's zeros left out (as LocalToModelJob).
void place(const glm::mat4& p, const glm::mat3& r, const glm::vec3& t, glm::mat4& m) {
  m[0] = p[0] * r[0][0] + p[1] * r[0][1] + p[2] * r[0][2];
  m[1] = p[0] * r[1][0] + p[1] * r[1][1] + p[2] * r[1][2];
  m[2] = p[0] * r[2][0] + p[1] * r[2][1] + p[2] * r[2][2];
  m[3] = p[0] * t.x + p[1] * t.y + p[2] * t.z + p[3];
}

}  // namespace

std::vector<uint8_t> detail_joints(const Skeleton& skeleton, float leg_length_m) {
  const int J = skeleton.num_joints();
  std::vector<uint8_t> detail(J, 0);
  if (J == 0 || !(leg_length_m > 0.0f)) return detail;
  std::vector<glm::mat4> rest(J);
  LocalToModelJob{&skeleton, skeleton.rest_rotations, skeleton.rest_translations, glm::mat4(1.0f),
                  rest}
      .run();
  // span[a]: the farthest any joint (or bone tip) of a's subtree lies from a in the rest pose.
  std::vector<float> span(J, 0.0f);
  auto reach = [&](int from, const glm::vec3& p) {
    for (int a = from; a >= 0; a = skeleton.parents[a]) {
      span[a] = std::max(span[a], glm::length(p - translation_of(rest[a])));
    }
  };
  for (int j = 0; j < J; ++j) {
    reach(j, translation_of(rest[j]));
    if (static_cast<size_t>(j) < skeleton.end_sites.size()) {
      reach(j, glm::vec3(rest[j] * glm::vec4(skeleton.end_sites[j], 1.0f)));
    }
  }
  // The joints with a role (where the character looks, its legs and shoulders) and their
  // ancestors are always posed; toes only serve foot locking, which far agents do not do.
  std::vector<uint8_t> kept(J, 0);
  for (int role = 0; role < kNumJointRoles; ++role) {
    if (role == static_cast<int>(JointRole::kLeftToe) ||
        role == static_cast<int>(JointRole::kRightToe)) {
      continue;
    }
    for (int a = skeleton.roles[role]; a >= 0 && a < J; a = skeleton.parents[a]) kept[a] = 1;
  }
  const float small = kDetailSpanOfLeg * leg_length_m;
  for (int j = 0; j < J; ++j) {  // parents come first
    const int p = skeleton.parents[j];
    detail[j] = !kept[j] && p >= 0 && (detail[p] || span[p] < small);
  }
  return detail;
}

CoarseRig make_coarse_rig(const LocomotionLibrary& library) {
  const Skeleton& sk = *library.skeleton;
  const int J = sk.num_joints();
  CoarseRig rig;
  rig.index.assign(J, -1);
  rig.rigid_rotation.assign(J, glm::mat3(1.0f));
  rig.rigid_translation.assign(J, glm::vec3(0.0f));
  const float leg = 0.5f * (library.leg_length_m[0] + library.leg_length_m[1]);
  const std::vector<uint8_t> detail = detail_joints(sk, leg);
  std::vector<int> coarse;
  for (int j = 0; j < J; ++j) {
    if (detail[j]) continue;
    rig.index[j] = static_cast<int16_t>(coarse.size());
    coarse.push_back(j);
  }
  rig.num_coarse = static_cast<int>(coarse.size());
  if (!rig.useful()) return rig;
  // The reference pose of the detail joints: relaxed hands and feet as the clips stand.
  const Clip* reference = nullptr;
  if (library.idle >= 0) reference = &library.clips[library.idle].clip;
  if (!reference && !library.clips.empty()) reference = &library.clips.front().clip;
  for (int j = 0; j < J; ++j) {
    if (!detail[j]) continue;
    const bool from_clip = reference && reference->num_frames > 0 && reference->num_joints == J;
    const glm::quat q = from_clip ? reference->frame_rotations(0)[j] : sk.rest_rotations[j];
    rig.rigid_rotation[j] = glm::mat3_cast(glm::normalize(q));
    rig.rigid_translation[j] =
        from_clip ? reference->frame_translations(0)[j] : sk.rest_translations[j];
  }
  rig.clips.reserve(library.clips.size());
  const size_t K = coarse.size();
  for (const LocomotionClip& lc : library.clips) {
    const Clip& c = lc.playback();
    Clip out;
    out.name = c.name;
    out.source = c.source;
    out.fps = c.fps;
    out.loops = c.loops;
    out.num_frames = c.num_frames;
    out.num_joints = static_cast<int>(K);
    out.rotations.resize(static_cast<size_t>(c.num_frames) * K);
    out.translations.resize(static_cast<size_t>(c.num_frames) * K);
    for (int f = 0; f < c.num_frames; ++f) {
      for (size_t k = 0; k < K; ++k) {
        out.rotations[f * K + k] = c.frame_rotations(f)[coarse[k]];
        out.translations[f * K + k] = c.frame_translations(f)[coarse[k]];
      }
    }
    rig.clips.push_back(std::move(out));
  }
  return rig;
}

void coarse_to_world(const CoarseRig& rig, const Skeleton& skeleton,
                     std::span<const glm::quat> rotations, std::span<const glm::vec3> translations,
                     const glm::mat4& root, std::span<glm::mat4> out_world) {
  const int J = skeleton.num_joints();
  for (int j = 0; j < J; ++j) {
    const int parent = skeleton.parents[j];
    const glm::mat4& p = parent < 0 ? root : out_world[parent];
    const int k = rig.index[j];
    if (k >= 0) {
      place(p, glm::mat3_cast(rotations[k]), translations[k], out_world[j]);
    } else {
      place(p, rig.rigid_rotation[j], rig.rigid_translation[j], out_world[j]);
    }
  }
}

}  // namespace gk
