// The procedural humanoid: joint offsets from stature with anthropometric segment fractions
// (Drillis and Contini / Winter), identity rest rotations, offsets in rest world axes (T-pose),
// CMU/Mixamo joint names so that name-based role detection recognises it.

#include <cassert>

#include "animation/procedural.h"

namespace gk {
namespace {

struct JointSpec {
  const char* name;
  int parent;
  glm::vec3 offset_h;  // offset from the parent as a fraction of stature (x left, y up, z forward)
};

// Fractions of stature h. Hip joint centre 0.530 h = ankle 0.039 + shank 0.246 + thigh 0.245;
// shoulder 0.81 h; upper arm 0.186 h, forearm 0.146 h; foot 0.152 h long with the heel 0.029 h
// behind the ankle and the ball (metatarsophalangeal joint) 0.083 h ahead, 0.014 h above the sole.
constexpr float kHipsHeight = 0.550f;
constexpr float kHipLateral = 0.052f;
constexpr float kAnkleHeight = 0.039f;
constexpr float kBallHeight = 0.014f;
constexpr float kBallForward = 0.083f;

const JointSpec kJoints[] = {
    {"Hips", -1, {0.0f, kHipsHeight, 0.0f}},
    {"Spine", 0, {0.0f, 0.045f, -0.005f}},
    {"Spine1", 1, {0.0f, 0.070f, 0.0f}},
    {"Spine2", 2, {0.0f, 0.070f, 0.0f}},
    {"Neck", 3, {0.0f, 0.090f, -0.005f}},
    {"Head", 4, {0.0f, 0.060f, 0.010f}},
    {"HeadTop_End", 5, {0.0f, 0.110f, 0.0f}},
    {"LeftShoulder", 3, {0.025f, 0.070f, 0.0f}},
    {"LeftArm", 7, {0.085f, 0.005f, 0.0f}},
    {"LeftForeArm", 8, {0.186f, 0.0f, 0.0f}},
    {"LeftHand", 9, {0.146f, 0.0f, 0.0f}},
    {"LeftHandMiddle1", 10, {0.055f, 0.0f, 0.0f}},
    {"RightShoulder", 3, {-0.025f, 0.070f, 0.0f}},
    {"RightArm", 12, {-0.085f, 0.005f, 0.0f}},
    {"RightForeArm", 13, {-0.186f, 0.0f, 0.0f}},
    {"RightHand", 14, {-0.146f, 0.0f, 0.0f}},
    {"RightHandMiddle1", 15, {-0.055f, 0.0f, 0.0f}},
    {"LeftUpLeg", 0, {kHipLateral, 0.530f - kHipsHeight, 0.0f}},
    {"LeftLeg", 17, {0.0f, -0.245f, 0.0f}},
    {"LeftFoot", 18, {0.0f, -0.246f, 0.0f}},
    {"LeftToeBase", 19, {0.0f, kBallHeight - kAnkleHeight, kBallForward}},
    {"RightUpLeg", 0, {-kHipLateral, 0.530f - kHipsHeight, 0.0f}},
    {"RightLeg", 21, {0.0f, -0.245f, 0.0f}},
    {"RightFoot", 22, {0.0f, -0.246f, 0.0f}},
    {"RightToeBase", 23, {0.0f, kBallHeight - kAnkleHeight, kBallForward}},
};

}  // namespace

std::shared_ptr<const Skeleton> make_humanoid_skeleton(const HumanoidParams& params) {
  const float h = params.height_m > 0.5f ? params.height_m : 1.75f;
  auto skeleton = std::make_shared<Skeleton>();
  for (const JointSpec& spec : kJoints) {
    skeleton->names.emplace_back(spec.name);
    skeleton->parents.push_back(static_cast<int16_t>(spec.parent));
    skeleton->rest_translations.push_back(spec.offset_h * h);
    skeleton->rest_rotations.emplace_back(1.0f, 0.0f, 0.0f, 0.0f);
  }
  // Roles are filled here from the table so that the built-in set never depends on detection.
  auto set = [&](JointRole role, const char* name) {
    const int index = skeleton->find(name);
    assert(index >= 0);
    skeleton->roles[static_cast<int>(role)] = static_cast<int16_t>(index);
  };
  set(JointRole::kHips, "Hips");
  set(JointRole::kSpine, "Spine");
  set(JointRole::kChest, "Spine2");
  set(JointRole::kNeck, "Neck");
  set(JointRole::kHead, "Head");
  set(JointRole::kLeftHip, "LeftUpLeg");
  set(JointRole::kLeftKnee, "LeftLeg");
  set(JointRole::kLeftAnkle, "LeftFoot");
  set(JointRole::kLeftToe, "LeftToeBase");
  set(JointRole::kRightHip, "RightUpLeg");
  set(JointRole::kRightKnee, "RightLeg");
  set(JointRole::kRightAnkle, "RightFoot");
  set(JointRole::kRightToe, "RightToeBase");
  set(JointRole::kLeftShoulder, "LeftArm");
  set(JointRole::kRightShoulder, "RightArm");
  for (const char* name : {"Spine", "Spine1", "Spine2"}) {
    skeleton->spine_chain.push_back(static_cast<int16_t>(skeleton->find(name)));
  }
  return skeleton;
}

}  // namespace gk
