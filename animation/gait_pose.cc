#include "animation/gait_pose.h"

#include <algorithm>
#include <cassert>
#include <cmath>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>

namespace gk {

std::vector<glm::vec3> gait::rest_positions(const Skeleton& skeleton) {
  const int n = skeleton.num_joints();
  std::vector<glm::vec3> pos(n);
  std::vector<glm::quat> rot(n);
  for (int j = 0; j < n; ++j) {
    const int p = skeleton.parents[j];
    if (p < 0) {
      pos[j] = skeleton.rest_translations[j];
      rot[j] = skeleton.rest_rotations[j];
    } else {
      pos[j] = pos[p] + rot[p] * skeleton.rest_translations[j];
      rot[j] = rot[p] * skeleton.rest_rotations[j];
    }
  }
  return pos;
}

float estimate_stature(const Skeleton& skeleton) {
  const std::vector<glm::vec3> pos = gait::rest_positions(skeleton);
  float leg = 0.0f;
  int legs = 0;
  for (Side side : {Side::kLeft, Side::kRight}) {
    const int hip = skeleton.hip(side), knee = skeleton.knee(side), ankle = skeleton.ankle(side);
    if (hip < 0 || knee < 0 || ankle < 0) continue;
    leg += glm::distance(pos[hip], pos[knee]) + glm::distance(pos[knee], pos[ankle]);
    ++legs;
  }
  // Hip joint to ankle is 0.491 of stature (0.245 thigh + 0.246 shank, Drillis and Contini).
  if (legs > 0 && leg > 0.0f) return leg / legs / 0.491f;
  float lo = 0.0f, hi = 0.0f;
  for (const glm::vec3& p : pos) {
    lo = std::min(lo, p.y);
    hi = std::max(hi, p.y);
  }
  // Joints span roughly ankle to head top: about 0.9 of stature.
  return hi - lo > 1e-3f ? (hi - lo) / 0.9f : 1.75f;
}

FootShape estimate_foot_shape(const Skeleton& skeleton, Side side) {
  const float h = estimate_stature(skeleton);
  FootShape shape;
  shape.ankle_height_m = 0.039f * h;
  shape.ball_forward_m = 0.083f * h;
  shape.ball_height_m = 0.014f * h;
  shape.width_m = 0.055f * h;
  const int ankle = skeleton.ankle(side), toe = skeleton.toe(side);
  if (ankle >= 0 && toe >= 0) {
    const std::vector<glm::vec3> pos = gait::rest_positions(skeleton);
    const glm::vec3 d = pos[toe] - pos[ankle];
    const float forward = std::sqrt(d.x * d.x + d.z * d.z);
    if (forward > 0.02f * h) shape.ball_forward_m = forward;
    // The ball joint sits above the sole; if the skeleton's ankle is lower than the norm relative
    // to its toe joint, raise the sole estimate rather than bury the ball.
    const float drop = -d.y;
    shape.ball_height_m = std::max(shape.ankle_height_m - drop, 0.008f * h);
    shape.ankle_height_m = drop + shape.ball_height_m;
  }
  // Heel 0.029 h and toe tip 0.040 h against the 0.083 h ankle-to-ball distance.
  shape.heel_back_m = 0.35f * shape.ball_forward_m;
  shape.toe_length_m = 0.48f * shape.ball_forward_m;
  return shape;
}

namespace gait {
namespace {

int first_child(const Skeleton& skeleton, int joint) {
  if (joint < 0) return -1;
  for (int j = joint + 1; j < skeleton.num_joints(); ++j) {
    if (skeleton.parents[j] == joint) return j;
  }
  return -1;
}

// Rotation taking the rest frame (bone direction a0, reference f0) onto (a1, f1); the references
// fix the twist about the bone.
glm::quat frame_rotation(glm::vec3 a0, glm::vec3 f0, glm::vec3 a1, glm::vec3 f1) {
  auto frame = [](glm::vec3 a, glm::vec3 f) {
    a = glm::normalize(a);
    f = f - a * glm::dot(a, f);
    if (glm::dot(f, f) < 1e-10f) f = std::abs(a.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
    f = glm::normalize(f - a * glm::dot(a, f));
    return glm::mat3(a, f, glm::cross(a, f));
  };
  return glm::normalize(glm::quat_cast(frame(a1, f1) * glm::transpose(frame(a0, f0))));
}

glm::quat yaw_q(float a) { return glm::angleAxis(a, glm::vec3(0, 1, 0)); }
glm::quat roll_q(float a) { return glm::angleAxis(a, glm::vec3(0, 0, 1)); }
glm::quat pitch_q(float a) { return glm::angleAxis(a, glm::vec3(1, 0, 0)); }

}  // namespace

GaitRig::GaitRig(const Skeleton& skeleton) {
  const std::vector<glm::vec3> pos = rest_positions(skeleton);
  root = std::max(skeleton.role(JointRole::kHips), 0);
  neck = skeleton.role(JointRole::kNeck);
  head = skeleton.role(JointRole::kHead);
  spine.assign(skeleton.spine_chain.begin(), skeleton.spine_chain.end());
  for (int s = 0; s < 2; ++s) {
    const Side side = s == 0 ? Side::kLeft : Side::kRight;
    hip[s] = skeleton.hip(side);
    knee[s] = skeleton.knee(side);
    ankle[s] = skeleton.ankle(side);
    toe[s] = skeleton.toe(side);
    assert(hip[s] >= 0 && knee[s] >= 0 && ankle[s] >= 0 && toe[s] >= 0);
    hip_offset[s] = pos[hip[s]] - pos[root];
    ball_offset[s] = pos[toe[s]] - pos[ankle[s]];
    thigh_m[s] = glm::distance(pos[hip[s]], pos[knee[s]]);
    shank_m[s] = glm::distance(pos[knee[s]], pos[ankle[s]]);
    thigh_dir[s] = glm::normalize(pos[knee[s]] - pos[hip[s]]);
    shank_dir[s] = glm::normalize(pos[ankle[s]] - pos[knee[s]]);
    foot[s] = estimate_foot_shape(skeleton, side);
    upper_arm[s] = skeleton.role(s == 0 ? JointRole::kLeftShoulder : JointRole::kRightShoulder);
    forearm[s] = first_child(skeleton, upper_arm[s]);
    hand[s] = first_child(skeleton, forearm[s]);
    if (hand[s] >= 0) {
      upper_arm_dir[s] = glm::normalize(pos[forearm[s]] - pos[upper_arm[s]]);
      forearm_dir[s] = glm::normalize(pos[hand[s]] - pos[forearm[s]]);
    } else {
      upper_arm[s] = forearm[s] = hand[s] = -1;
    }
  }
}

// Left/right mirror across the x = 0 plane: positions negate x, rotations keep their x axis
// component and negate y and z, and each joint takes its mirror partner's motion.
void mirror_clip(const Skeleton& skeleton, Clip* clip) {
  std::vector<int> partner(skeleton.num_joints());
  for (int j = 0; j < skeleton.num_joints(); ++j) {
    std::string name = skeleton.names[j];
    if (name.rfind("Left", 0) == 0)
      name = "Right" + name.substr(4);
    else if (name.rfind("Right", 0) == 0)
      name = "Left" + name.substr(5);
    const int other = skeleton.find(name);
    partner[j] = other >= 0 ? other : j;
  }
  const Clip source = *clip;
  for (int f = 0; f < clip->num_frames; ++f) {
    for (int j = 0; j < clip->num_joints; ++j) {
      const size_t dst = size_t(f) * clip->num_joints + j;
      const size_t src = size_t(f) * clip->num_joints + partner[j];
      const glm::quat q = source.rotations[src];
      clip->rotations[dst] = glm::quat(q.w, q.x, -q.y, -q.z);
      const glm::vec3 t = source.translations[src];
      clip->translations[dst] = glm::vec3(-t.x, t.y, t.z);
    }
  }
}

glm::quat pelvis_rotation(float yaw, float roll) { return yaw_q(yaw) * roll_q(roll); }

void build_local_pose(const Skeleton& skeleton, const GaitRig& rig, const PoseTargets& t,
                      glm::quat* out_rot, glm::vec3* out_trans) {
  const int n = skeleton.num_joints();
  std::vector<glm::quat> world(n, glm::quat(1, 0, 0, 0));
  std::vector<bool> set(n, false);
  auto put = [&](int j, glm::quat q) {
    if (j < 0) return;
    world[j] = q;
    set[j] = true;
  };
  const glm::quat pelvis = pelvis_rotation(t.pelvis_yaw, t.pelvis_roll);
  put(rig.root, pelvis);

  // Spine: the twist and the obliquity fade out from the pelvis to the counter-rotated chest.
  const int num_spine = static_cast<int>(rig.spine.size());
  for (int i = 0; i < num_spine; ++i) {
    const float f = float(i + 1) / num_spine;
    const float yaw = t.pelvis_yaw + (t.thorax_yaw - t.pelvis_yaw) * f;
    const float roll = t.pelvis_roll * (1.0f - 1.3f * f);
    put(rig.spine[i], yaw_q(yaw) * roll_q(roll) * pitch_q(t.lean * f));
  }
  const glm::quat chest = num_spine > 0 ? world[rig.spine.back()] : pelvis;
  // The head keeps looking ahead: it undoes most of the chest's twist and lean.
  put(rig.neck, yaw_q(0.5f * (t.thorax_yaw + t.head_yaw)) * pitch_q(0.6f * t.lean));
  put(rig.head, yaw_q(t.head_yaw) * pitch_q(0.3f * t.lean));

  for (int s = 0; s < 2; ++s) {
    if (rig.upper_arm[s] < 0) continue;
    const float sign = s == 0 ? 1.0f : -1.0f;
    auto hanging = [sign](float abduction) {
      return glm::vec3(sign * std::sin(abduction), -std::cos(abduction), 0.0f);
    };
    const glm::vec3 fwd(0, 0, 1);
    // Hanging, then swung about the lateral axis in the chest's frame (negative pitch = forward).
    put(rig.upper_arm[s],
        chest * pitch_q(-t.arm_forward[s]) *
            frame_rotation(rig.upper_arm_dir[s], fwd, hanging(t.arm_abduction), fwd));
    put(rig.forearm[s],
        chest * pitch_q(-(t.arm_forward[s] + t.elbow[s])) *
            frame_rotation(rig.forearm_dir[s], fwd, hanging(t.forearm_abduction), fwd));
    put(rig.hand[s], world[rig.forearm[s]]);
  }

  // Legs: analytic two-bone IK in the plane of hip, ankle and a forward knee pole.
  for (int s = 0; s < 2; ++s) {
    const glm::vec3 hip = t.root_position + pelvis * rig.hip_offset[s];
    const float l1 = rig.thigh_m[s], l2 = rig.shank_m[s];
    glm::vec3 to_ankle = t.ankle[s] - hip;
    float dist = glm::length(to_ankle);
    const glm::vec3 u = to_ankle / std::max(dist, 1e-6f);
    // A swing foot out of reach is pulled in smoothly (tanh) instead of snapping the knee straight.
    const float soft = (l1 + l2) * 0.997f, hard = (l1 + l2) * 0.9999f;
    if (!t.planted[s] && dist > soft)
      dist = soft + (hard - soft) * std::tanh((dist - soft) / (hard - soft));
    dist = std::clamp(dist, std::abs(l1 - l2) + 1e-4f, (l1 + l2) * 0.99999f);
    const float cos_a = std::clamp((l1 * l1 + dist * dist - l2 * l2) / (2 * l1 * dist), -1.f, 1.f);
    const glm::vec3 pole(0, 0, 1);
    glm::vec3 w = pole - u * glm::dot(pole, u);
    w = glm::dot(w, w) > 1e-10f ? glm::normalize(w) : glm::vec3(0, 0, 1);
    const glm::vec3 knee = hip + l1 * (cos_a * u + std::sqrt(1 - cos_a * cos_a) * w);
    const glm::vec3 ankle = hip + u * dist;
    // Each bone's "forward" is taken in the leg plane (normal n) rather than as the fixed pole, so
    // a shank swung back to horizontal (running) never becomes parallel to its reference.
    const glm::vec3 n = glm::normalize(glm::cross(u, w));
    const glm::vec3 thigh = glm::normalize(knee - hip), shank = glm::normalize(ankle - knee);
    put(rig.hip[s], frame_rotation(rig.thigh_dir[s], pole, thigh, glm::cross(n, thigh)));
    put(rig.knee[s], frame_rotation(rig.shank_dir[s], pole, shank, glm::cross(n, shank)));
    put(rig.ankle[s], pitch_q(-t.foot[s].pitch));
    put(rig.toe[s], pitch_q(-t.foot[s].toe_pitch));
  }

  for (int j = 0; j < n; ++j) {
    const int p = skeleton.parents[j];
    if (!set[j]) world[j] = p >= 0 ? world[p] : glm::quat(1, 0, 0, 0);
    out_rot[j] = p >= 0 ? glm::normalize(glm::inverse(world[p]) * world[j]) : world[j];
    out_trans[j] = skeleton.rest_translations[j];
  }
  out_trans[rig.root] = t.root_position;
}

}  // namespace gait
}  // namespace gk
