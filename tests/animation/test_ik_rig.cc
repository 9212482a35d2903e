// IK-style rigs (feet parented to the root): the generated fixture (tests/ik_rig_fixture.h) in
// centimetres with Unreal-style names, and in inches with meaningless names and a role manifest.
// What is asserted comes from the built-in clips the fixture was written from, not from the
// loader: every joint's model-space position on every frame, and the skinned vertices.

#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/quaternion.hpp>

#include "animation/bvh_loader.h"
#include "animation/gltf_loader.h"
#include "animation/ik_rig.h"
#include "animation/mesh.h"
#include "animation/pose_jobs.h"
#include "tests/ik_rig_fixture.h"
#include "tests/test_data.h"
#include "tests/animation/model_pose.h"

namespace gk {
namespace {

using test::model_pose;

std::string role_joint(const Skeleton& s, JointRole r) {
  return s.has(r) ? s.names[s.role(r)] : "-";
}

// Largest distance [m] over every clip, frame and joint between the loaded set's forward
// kinematics and the positions the fixture was written from.
float worst_joint_error(const ClipSet& set, const test::IkRig& rig) {
  const Skeleton& s = *set.skeleton;
  EXPECT_EQ(set.clips.size(), rig.authored.clips.size());
  float worst = 0.0f;
  for (size_t c = 0; c < set.clips.size() && c < rig.positions.size(); ++c) {
    const Clip& clip = set.clips[c];
    EXPECT_EQ(clip.name, rig.authored.clips[c].name);
    EXPECT_EQ(clip.num_frames, static_cast<int>(rig.positions[c].size())) << clip.name;
    EXPECT_TRUE(clip.loops) << clip.name;
    for (int f = 0; f < clip.num_frames && f < static_cast<int>(rig.positions[c].size()); ++f) {
      const auto model = model_pose(s, clip.frame_rotations(f), clip.frame_translations(f));
      for (size_t j = 0; j < rig.names.size(); ++j) {
        const int k = s.find(rig.names[j]);
        EXPECT_GE(k, 0) << rig.names[j];
        if (k < 0) return 1e9f;
        worst = std::max(worst, glm::distance(glm::vec3(model[k][3]), rig.positions[c][f][j]));
      }
    }
  }
  return worst;
}

// Vertices skinned with the loaded skeleton, clip and mesh (model x inverse bind) against the
// built-in mesh skinned with the built-in skeleton's own pose [m], at `frame` of clip `c`.
float worst_vertex_error(const ClipSet& set, const test::IkRig& rig, size_t c, int frame) {
  const SkinnedMesh& loaded = *set.mesh;
  const SkinnedMesh& ref = *rig.authored.mesh;
  EXPECT_EQ(loaded.num_vertices(), ref.num_vertices());
  const Skeleton& s = *set.skeleton;
  const Skeleton& hs = *rig.authored.skeleton;
  const Clip& clip = set.clips[c];
  const Clip& src = rig.authored.clips[c];
  const int n = src.num_frames;
  // The authored pose: built-in frame (frame mod n), moved on by whole strides as the fixture is.
  std::vector<glm::vec3> t(src.frame_translations(frame % n),
                           src.frame_translations(frame % n) + hs.num_joints());
  const auto at = [&](int f) {
    return glm::vec3(model_pose(hs, src.frame_rotations(f),
                                src.frame_translations(f))[hs.role(JointRole::kHips)][3]);
  };
  glm::vec3 stride = 2.0f * at(n - 1) - at(n - 2) - at(0);
  stride.y = 0.0f;
  t[hs.role(JointRole::kHips)] += stride * static_cast<float>(frame / n);
  const auto ref_model = model_pose(hs, src.frame_rotations(frame % n), t.data());
  const auto ref_rest = model_pose(hs, hs.rest_rotations.data(), hs.rest_translations.data());
  const auto model = model_pose(s, clip.frame_rotations(frame), clip.frame_translations(frame));
  float worst = 0.0f;
  for (int v = 0; v < ref.num_vertices() && v < loaded.num_vertices(); ++v) {
    glm::vec3 a(0.0f), b(0.0f);
    for (int k = 0; k < 4; ++k) {
      const int jl = loaded.joints[v][k], jr = ref.joints[v][k];
      a += loaded.weights[v][k] *
           glm::vec3(model[jl] * loaded.inverse_bind[jl] * glm::vec4(loaded.positions[v], 1.0f));
      b += ref.weights[v][k] * glm::vec3(ref_model[jr] * glm::inverse(ref_rest[jr]) *
                                         glm::vec4(ref.positions[v], 1.0f));
    }
    worst = std::max(worst, glm::distance(a, b));
  }
  return worst;
}

// Unreal-style names, centimetres, feet under the root: works with no manifest.
TEST(IkRig, KnownNamesInCentimetresLoadAsLegChains) {
  const test::IkRig rig = test::make_ik_rig();
  Result<ClipSet> set = parse_gltf(rig.glb, "ik_rig_cm.glb");
  ASSERT_TRUE(set.ok()) << set.message();
  EXPECT_FLOAT_EQ(set->scale_m_per_unit, 0.01f) << set->scale_reason;
  const Skeleton& s = *set->skeleton;
  ASSERT_TRUE(s.has_locomotion_roles()) << missing_locomotion_roles(s);
  EXPECT_EQ(role_joint(s, JointRole::kHips), "pelvis");
  EXPECT_EQ(role_joint(s, JointRole::kChest), "spine_03");
  EXPECT_EQ(role_joint(s, JointRole::kLeftKnee), "calf_l");
  EXPECT_EQ(role_joint(s, JointRole::kLeftAnkle), "foot_l");
  EXPECT_EQ(role_joint(s, JointRole::kLeftToe), "ball_l");
  EXPECT_EQ(role_joint(s, JointRole::kRightAnkle), "foot_r");
  EXPECT_EQ(role_joint(s, JointRole::kRightToe), "ball_r");
  // The feet now hang from the shins, and the load says so.
  for (Side side : {Side::kLeft, Side::kRight}) {
    EXPECT_EQ(s.parents[s.ankle(side)], s.knee(side));
    EXPECT_EQ(s.parents[s.toe(side)], s.ankle(side));
  }
  EXPECT_NE(set->rig_reason.find("foot_l under calf_l (was under root)"), std::string::npos)
      << set->rig_reason;
  EXPECT_NE(set->rig_reason.find("foot_r under calf_r (was under root)"), std::string::npos)
      << set->rig_reason;
  EXPECT_EQ(set->rig_reason.find("ball_"), std::string::npos) << "toes were under the feet";
  EXPECT_TRUE(validate_skeleton(s, "ik").ok());
  EXPECT_LT(worst_joint_error(*set, rig), 1e-3f);
  ASSERT_TRUE(set->mesh);
  for (size_t c = 0; c < set->clips.size(); ++c) {
    for (int f : {0, 7, set->clips[c].num_frames - 1}) {
      EXPECT_LT(worst_vertex_error(*set, rig, c, f), 1e-3f) << set->clips[c].name << " " << f;
    }
  }
}

// Meaningless names in inches, feet and toes under the root: the roles cannot be found (and
// nothing is guessed), the manifest gives them, and the legs then load as chains.
TEST(IkRig, MeaninglessNamesInInchesNeedTheManifest) {
  const test::IkRig rig = test::make_ik_rig(test::meaningless_inch_rig());
  Result<ClipSet> bare = parse_gltf(rig.glb, "ik_rig_in.glb");
  ASSERT_TRUE(bare.ok()) << bare.message();
  EXPECT_FALSE(bare->skeleton->has_locomotion_roles());
  EXPECT_EQ(missing_locomotion_roles(*bare->skeleton),
            "hips, chest, left_hip, left_knee, left_ankle, left_toe, right_hip, right_knee, "
            "right_ankle, right_toe");
  EXPECT_TRUE(bare->rig_reason.empty()) << bare->rig_reason;

  const std::string dir = test::scratch_dir("ik_rig");
  ASSERT_TRUE(test::write_file(dir + "/roles_in.json", rig.roles_json));
  LoadOptions load;
  load.role_manifest = dir + "/roles_in.json";
  Result<ClipSet> set = parse_gltf(rig.glb, "ik_rig_in.glb", load);
  ASSERT_TRUE(set.ok()) << set.message();
  EXPECT_FLOAT_EQ(set->scale_m_per_unit, 0.0254f) << set->scale_reason;
  const Skeleton& s = *set->skeleton;
  ASSERT_TRUE(s.has_locomotion_roles());
  for (Side side : {Side::kLeft, Side::kRight}) {
    EXPECT_EQ(s.parents[s.ankle(side)], s.knee(side));
    EXPECT_EQ(s.parents[s.toe(side)], s.ankle(side));
  }
  EXPECT_FALSE(s.spine_chain.empty());
  EXPECT_LT(worst_joint_error(*set, rig), 1e-3f);
  for (size_t c = 0; c < set->clips.size(); ++c) {
    EXPECT_LT(worst_vertex_error(*set, rig, c, 11), 1e-3f) << set->clips[c].name;
  }
}

// A BVH whose feet hang from the hips (listed before the legs, so the joints must be reordered),
// in centimetres. In the second frame the left thigh swings 30 deg forward: the file's foot does
// not follow it (it is its own joint under the hips), and re-parented under the shin it still
// must not, while the whole body moves 5 cm forward.
TEST(IkRig, BvhFeetUnderTheHipsKeepTheirPlaceOnEveryFrame) {
  std::string text =
      "HIERARCHY\nROOT Hips\n{\nOFFSET 0 95 0\n"
      "CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n";
  for (const char* side : {"Left", "Right"}) {
    const std::string x = side[0] == 'L' ? "10" : "-10";
    text += std::string("JOINT ") + side + "Foot\n{\nOFFSET " + x +
            " -89 0\nCHANNELS 3 Zrotation Xrotation Yrotation\nJOINT " + side +
            "ToeBase\n{\nOFFSET 0 -4 12\nCHANNELS 3 Zrotation Xrotation Yrotation\n"
            "End Site\n{\nOFFSET 0 0 5\n}\n}\n}\n";
  }
  text +=
      "JOINT Spine\n{\nOFFSET 0 10 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n"
      "JOINT Neck\n{\nOFFSET 0 40 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n"
      "JOINT Head\n{\nOFFSET 0 10 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n"
      "End Site\n{\nOFFSET 0 10 0\n}\n}\n}\n}\n";
  for (const char* side : {"Left", "Right"}) {
    const std::string x = side[0] == 'L' ? "10" : "-10";
    text += std::string("JOINT ") + side + "UpLeg\n{\nOFFSET " + x +
            " -5 0\nCHANNELS 3 Zrotation Xrotation Yrotation\nJOINT " + side +
            "Leg\n{\nOFFSET 0 -42 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n"
            "End Site\n{\nOFFSET 0 -42 0\n}\n}\n}\n";
  }
  // Channels in file order: hips (6), feet and toes (12), spine, neck, head (9), legs (12).
  std::string frame0 = "0 95 0 0 0 0", frame1 = "0 95 5 0 0 0";
  for (int k = 0; k < 33; ++k) {
    frame0 += " 0";
    frame1 += k == 22 ? " -30" : " 0";  // LeftUpLeg's Xrotation
  }
  text += "}\nMOTION\nFrames: 2\nFrame Time: 0.0333333\n" + frame0 + "\n" + frame1 + "\n";
  Result<ClipSet> set = parse_bvh(text, "ik_feet.bvh");
  ASSERT_TRUE(set.ok()) << set.message();
  EXPECT_FLOAT_EQ(set->scale_m_per_unit, 0.01f) << set->scale_reason;
  const Skeleton& s = *set->skeleton;
  ASSERT_TRUE(s.has_locomotion_roles()) << missing_locomotion_roles(s);
  EXPECT_EQ(role_joint(s, JointRole::kLeftAnkle), "LeftFoot");
  EXPECT_EQ(s.parents[s.ankle(Side::kLeft)], s.knee(Side::kLeft));
  EXPECT_EQ(s.parents[s.toe(Side::kLeft)], s.ankle(Side::kLeft));
  EXPECT_GT(s.ankle(Side::kLeft), s.knee(Side::kLeft));
  EXPECT_NE(set->rig_reason.find("LeftFoot under LeftLeg (was under Hips)"), std::string::npos)
      << set->rig_reason;
  // End sites travel with their joints.
  EXPECT_NEAR(glm::distance(s.end_sites[s.toe(Side::kLeft)], glm::vec3(0, 0, 0.05f)), 0.0f, 1e-6f);
  const Clip& c = set->clips[0];
  ASSERT_EQ(c.num_frames, 2);
  for (int f = 0; f < 2; ++f) {
    const auto m = model_pose(s, c.frame_rotations(f), c.frame_translations(f));
    const glm::vec3 hips(0.0f, 0.95f, 0.05f * f);
    EXPECT_LT(
        glm::distance(glm::vec3(m[s.ankle(Side::kLeft)][3]), hips + glm::vec3(0.1f, -0.89f, 0)),
        1e-5f)
        << f;
    EXPECT_LT(
        glm::distance(glm::vec3(m[s.toe(Side::kLeft)][3]), hips + glm::vec3(0.1f, -0.93f, 0.12f)),
        1e-5f)
        << f;
    // The knee does swing: forward and up by the thigh's 30 deg.
    const glm::vec3 knee = glm::vec3(m[s.knee(Side::kLeft)][3]) - hips;
    const float a = f == 0 ? 0.0f : glm::radians(30.0f);
    EXPECT_LT(
        glm::distance(knee, glm::vec3(0.1f, -0.05f - 0.42f * std::cos(a), 0.42f * std::sin(a))),
        1e-5f)
        << f;
  }
}

// attach_ik_feet leaves an ordinary chain alone.
TEST(IkRig, ChainsAreLeftAsTheyAre) {
  const test::IkRig rig = test::make_ik_rig();
  ClipSet copy = rig.authored;
  const auto before = copy.skeleton;
  EXPECT_EQ(attach_ik_feet(&copy), "");
  EXPECT_EQ(copy.skeleton, before);
}

}  // namespace
}  // namespace gk
