// Skeleton utilities: role detection for each naming convention (synthetic name lists and the real
// files), topology checks, the JSON role manifest and structural validation.

#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "animation/bvh_loader.h"
#include "animation/gltf_loader.h"
#include "animation/skeleton.h"
#include "tests/test_data.h"

namespace gk {
namespace {

// A skeleton from (name, parent name) pairs in topological order; rest offsets point down the
// chain.
Skeleton make_skeleton(const std::vector<std::pair<std::string, std::string>>& joints) {
  Skeleton s;
  for (const auto& [name, parent] : joints) {
    s.names.push_back(name);
    s.parents.push_back(static_cast<int16_t>(parent.empty() ? -1 : s.find(parent)));
    s.rest_translations.push_back(glm::vec3(0.0f, 0.1f, 0.0f));
    s.rest_rotations.push_back(glm::quat(1.0f, 0.0f, 0.0f, 0.0f));
  }
  return s;
}

std::string role_joint(const Skeleton& s, JointRole r) {
  return s.has(r) ? s.names[s.role(r)] : "-";
}

// Expected joint names for hips, spine, chest, neck, head, left hip/knee/ankle/toe, right
// hip/knee/ankle/toe, left/right shoulder (in JointRole order).
using Expected = std::array<const char*, kNumJointRoles>;

void expect_roles(const Skeleton& s, const Expected& expected) {
  for (int r = 0; r < kNumJointRoles; ++r) {
    EXPECT_EQ(role_joint(s, static_cast<JointRole>(r)), expected[r])
        << joint_role_name(static_cast<JointRole>(r));
  }
}

std::vector<std::string> chain_names(const Skeleton& s) {
  std::vector<std::string> out;
  for (int16_t j : s.spine_chain) out.push_back(s.names[j]);
  return out;
}

// A biped from a naming scheme: {hips, spines..., neck, head} and per side {thigh, shin, foot, toe,
// clavicle, arm} with "%" replaced by the side word.
Skeleton biped(const std::string& hips, const std::vector<std::string>& spine,
               const std::string& neck, const std::string& head,
               const std::vector<std::string>& leg, const std::vector<std::string>& arm,
               const std::string& left, const std::string& right) {
  std::vector<std::pair<std::string, std::string>> j = {{hips, ""}};
  std::string parent = hips;
  for (const std::string& s : spine) j.push_back({s, std::exchange(parent, s)});
  const std::string chest = parent;
  j.push_back({neck, chest});
  j.push_back({head, neck});
  for (const std::string& side : {left, right}) {
    auto named = [&](std::string pattern) { return pattern.replace(pattern.find('%'), 1, side); };
    std::string p = hips;
    for (const std::string& l : leg) j.push_back({named(l), std::exchange(p, named(l))});
    p = chest;
    for (const std::string& a : arm) j.push_back({named(a), std::exchange(p, named(a))});
  }
  return make_skeleton(j);
}

TEST(SkeletonSubtrees, DepthFirstRangesAreExactOthersRunToTheEnd) {
  const Skeleton dfs = make_skeleton({{"hips", ""},
                                      {"spine", "hips"},
                                      {"chest", "spine"},
                                      {"l_hip", "hips"},
                                      {"l_knee", "l_hip"},
                                      {"r_hip", "hips"},
                                      {"r_knee", "r_hip"}});
  EXPECT_EQ(subtree_ends(dfs), (std::vector<int>{7, 3, 3, 5, 5, 7, 7}));
  // Breadth first: spine, l_hip and r_hip have a joint of another branch between them and their
  // children, so their ranges run to the last joint; the leaves' ranges are themselves.
  const Skeleton bfs = make_skeleton({{"hips", ""},
                                      {"spine", "hips"},
                                      {"l_hip", "hips"},
                                      {"r_hip", "hips"},
                                      {"chest", "spine"},
                                      {"l_knee", "l_hip"},
                                      {"r_knee", "r_hip"}});
  EXPECT_EQ(subtree_ends(bfs), (std::vector<int>{7, 7, 7, 7, 5, 6, 7}));
  // Two roots: each one's range stops at the other.
  const Skeleton two = make_skeleton({{"a", ""}, {"a1", "a"}, {"b", ""}, {"b1", "b"}});
  EXPECT_EQ(subtree_ends(two), (std::vector<int>{2, 2, 4, 4}));
}

TEST(SkeletonRoles, RoleNamesRoundTrip) {
  for (int r = 0; r < kNumJointRoles; ++r) {
    JointRole back;
    ASSERT_TRUE(joint_role_from_name(joint_role_name(static_cast<JointRole>(r)), &back));
    EXPECT_EQ(static_cast<int>(back), r);
  }
  EXPECT_EQ(joint_role_name(JointRole::kLeftKnee), "left_knee");
  JointRole unused;
  EXPECT_FALSE(joint_role_from_name("left_kneee", &unused));
}

TEST(SkeletonRoles, CmuUpLegForm) {
  Skeleton s = biped("Hips", {"LowerBack", "Spine", "Spine1"}, "Neck", "Head",
                     {"%UpLeg", "%Leg", "%Foot", "%ToeBase"}, {"%Shoulder", "%Arm", "%ForeArm"},
                     "Left", "Right");
  detect_joint_roles(&s);
  expect_roles(s, {"Hips", "LowerBack", "Spine1", "Neck", "Head", "LeftUpLeg", "LeftLeg",
                   "LeftFoot", "LeftToeBase", "RightUpLeg", "RightLeg", "RightFoot", "RightToeBase",
                   "LeftArm", "RightArm"});
  EXPECT_EQ(chain_names(s), (std::vector<std::string>{"LowerBack", "Spine", "Spine1"}));
  EXPECT_TRUE(s.has_locomotion_roles());
}

TEST(SkeletonRoles, CmuHipKneeFormUppercase) {
  Skeleton s =
      biped("HIPS", {"CHEST", "CHEST2"}, "NECK", "HEAD", {"%HIP", "%KNEE", "%ANKLE", "%TOE"},
            {"%COLLAR", "%SHOULDER", "%ELBOW"}, "LEFT", "RIGHT");
  detect_joint_roles(&s);
  expect_roles(
      s, {"HIPS", "CHEST", "CHEST2", "NECK", "HEAD", "LEFTHIP", "LEFTKNEE", "LEFTANKLE", "LEFTTOE",
          "RIGHTHIP", "RIGHTKNEE", "RIGHTANKLE", "RIGHTTOE", "LEFTSHOULDER", "RIGHTSHOULDER"});
}

TEST(SkeletonRoles, Rigify) {
  Skeleton s = biped("DEF-hips", {"DEF-spine.001", "DEF-spine.002", "DEF-spine.003"}, "DEF-neck",
                     "DEF-head", {"DEF-thigh.%", "DEF-shin.%", "DEF-foot.%", "DEF-toe.%"},
                     {"DEF-shoulder.%", "DEF-upper_arm.%"}, "L", "R");
  detect_joint_roles(&s);
  expect_roles(s, {"DEF-hips", "DEF-spine.001", "DEF-spine.003", "DEF-neck", "DEF-head",
                   "DEF-thigh.L", "DEF-shin.L", "DEF-foot.L", "DEF-toe.L", "DEF-thigh.R",
                   "DEF-shin.R", "DEF-foot.R", "DEF-toe.R", "DEF-upper_arm.L", "DEF-upper_arm.R"});
}

TEST(SkeletonRoles, Mixamo) {
  Skeleton s =
      biped("mixamorig:Hips", {"mixamorig:Spine", "mixamorig:Spine1", "mixamorig:Spine2"},
            "mixamorig:Neck", "mixamorig:Head",
            {"mixamorig:%UpLeg", "mixamorig:%Leg", "mixamorig:%Foot", "mixamorig:%ToeBase"},
            {"mixamorig:%Shoulder", "mixamorig:%Arm"}, "Left", "Right");
  detect_joint_roles(&s);
  expect_roles(s, {"mixamorig:Hips", "mixamorig:Spine", "mixamorig:Spine2", "mixamorig:Neck",
                   "mixamorig:Head", "mixamorig:LeftUpLeg", "mixamorig:LeftLeg",
                   "mixamorig:LeftFoot", "mixamorig:LeftToeBase", "mixamorig:RightUpLeg",
                   "mixamorig:RightLeg", "mixamorig:RightFoot", "mixamorig:RightToeBase",
                   "mixamorig:LeftArm", "mixamorig:RightArm"});
}

TEST(SkeletonRoles, PlainPrefixAndSuffixNames) {
  Skeleton pre =
      biped("pelvis", {"spine_01", "spine_02"}, "neck", "head",
            {"%_hip", "%_knee", "%_ankle", "%_toe"}, {"%_clavicle", "%_upperarm"}, "l", "r");
  detect_joint_roles(&pre);
  expect_roles(pre, {"pelvis", "spine_01", "spine_02", "neck", "head", "l_hip", "l_knee", "l_ankle",
                     "l_toe", "r_hip", "r_knee", "r_ankle", "r_toe", "l_upperarm", "r_upperarm"});
  Skeleton post = biped("root_hips", {"spine"}, "neck", "head",
                        {"hip_%", "knee_%", "foot_%", "ball_%"}, {"shoulder_%"}, "l", "r");
  detect_joint_roles(&post);
  // "root_hips" is not a hips name: the pelvis is then where the two legs meet.
  expect_roles(post, {"root_hips", "spine", "spine", "neck", "head", "hip_l", "knee_l", "foot_l",
                      "ball_l", "hip_r", "knee_r", "foot_r", "ball_r", "shoulder_l", "shoulder_r"});
  Skeleton words = biped("hips", {"spine"}, "neck", "head",
                         {"%_thigh", "%_knee", "%_foot", "%_toes"}, {"%_arm"}, "left", "right");
  detect_joint_roles(&words);
  EXPECT_EQ(role_joint(words, JointRole::kLeftKnee), "left_knee");
  EXPECT_EQ(role_joint(words, JointRole::kRightToe), "right_toes");
  // A toe no name rule knows (a foot word in it, an "_End" suffix): the ankle's child joint.
  for (const char* toe : {"%FootToe", "%Toe_End", "%Digits"}) {
    Skeleton odd = biped("Hips", {"Spine"}, "Neck", "Head", {"%UpLeg", "%Leg", "%Foot", toe},
                         {"%Arm"}, "Left", "Right");
    detect_joint_roles(&odd);
    std::string want = toe;
    EXPECT_EQ(role_joint(odd, JointRole::kLeftToe), "Left" + want.substr(1)) << toe;
    EXPECT_EQ(role_joint(odd, JointRole::kRightToe), "Right" + want.substr(1)) << toe;
    EXPECT_EQ(role_joint(odd, JointRole::kLeftAnkle), "LeftFoot") << toe;
  }
}

// A knee that is not below its hip is not a knee of that leg.
TEST(SkeletonRoles, TopologyRejectsMisplacedJoints) {
  Skeleton s = make_skeleton({{"Hips", ""},
                              {"LeftUpLeg", "Hips"},
                              {"Spine", "Hips"},
                              {"LeftLeg", "Spine"},  // wrongly attached: not below LeftUpLeg
                              {"LeftFoot", "LeftLeg"},
                              {"RightUpLeg", "Hips"},
                              {"RightLeg", "RightUpLeg"},
                              {"LeftKnee", "LeftUpLeg"},  // the real knee of the left leg
                              {"LeftAnkle", "LeftKnee"}});
  detect_joint_roles(&s);
  EXPECT_EQ(role_joint(s, JointRole::kLeftHip), "LeftUpLeg");
  EXPECT_EQ(role_joint(s, JointRole::kLeftKnee), "LeftKnee");
  EXPECT_EQ(role_joint(s, JointRole::kLeftAnkle), "LeftAnkle");
  EXPECT_EQ(role_joint(s, JointRole::kRightAnkle), "-");  // no foot below RightLeg
  EXPECT_FALSE(s.has_locomotion_roles());
}

// A skeleton from (name, parent name, rest offset [m]) in topological order.
struct PlacedJoint {
  std::string name, parent;
  glm::vec3 offset;
};
Skeleton placed_skeleton(const std::vector<PlacedJoint>& joints) {
  Skeleton s;
  for (const PlacedJoint& j : joints) {
    s.names.push_back(j.name);
    s.parents.push_back(static_cast<int16_t>(j.parent.empty() ? -1 : s.find(j.parent)));
    s.rest_translations.push_back(j.offset);
    s.rest_rotations.push_back(glm::quat(1.0f, 0.0f, 0.0f, 0.0f));
  }
  return s;
}

// A robot whose feet hang from the root (an IK-style rig): each foot is the same-side foot joint
// a shin length below its knee, not the IK helper at hip height nor the other side's foot.
TEST(SkeletonRoles, IkStyleFeetAreMatchedToTheKneeAboveThem) {
  std::vector<PlacedJoint> j = {{"root", "", {0, 0, 0}},
                                {"pelvis", "root", {0, 0.95f, 0}},
                                {"spine_01", "pelvis", {0, 0.1f, 0}},
                                {"spine_02", "spine_01", {0, 0.2f, 0}},
                                {"neck_01", "spine_02", {0, 0.2f, 0}},
                                {"head", "neck_01", {0, 0.1f, 0}}};
  for (const char* side : {"l", "r"}) {
    const float x = side[0] == 'l' ? 0.1f : -0.1f;
    const std::string s = side;
    j.push_back({s + "_foot", "root", {x, 0.9f, 0.2f}});  // an IK target at hip height
    j.push_back({"thigh_" + s, "pelvis", {x, -0.05f, 0}});
    j.push_back({"calf_" + s, "thigh_" + s, {0, -0.42f, 0.01f}});
    j.push_back({"foot_" + s, "root", {x, 0.08f, 0}});
    j.push_back({"ball_" + s, "root", {x, 0.02f, 0.13f}});
  }
  Skeleton s = placed_skeleton(j);
  detect_joint_roles(&s);
  EXPECT_EQ(role_joint(s, JointRole::kLeftKnee), "calf_l");
  EXPECT_EQ(role_joint(s, JointRole::kLeftAnkle), "foot_l");
  EXPECT_EQ(role_joint(s, JointRole::kLeftToe), "ball_l");
  EXPECT_EQ(role_joint(s, JointRole::kRightAnkle), "foot_r");
  EXPECT_EQ(role_joint(s, JointRole::kRightToe), "ball_r");
  EXPECT_TRUE(s.has_locomotion_roles()) << missing_locomotion_roles(s);
  // Without the rest pose to go by (every joint at the root), no foot is guessed.
  for (glm::vec3& t : s.rest_translations) t = glm::vec3(0.0f, 0.1f, 0.0f);
  detect_joint_roles(&s);
  EXPECT_EQ(role_joint(s, JointRole::kLeftAnkle), "-");
  EXPECT_EQ(missing_locomotion_roles(s), "left_ankle, left_toe, right_ankle, right_toe");
}

// RobotExpressive-style names (UpperLegL, a capital side letter at the end), and leg words with
// no side at all (Blender's duplicates "Foot", "Foot.001"), sided by where they stand.
TEST(SkeletonRoles, CapitalSideLetterAndUnsidedLegWords) {
  std::vector<PlacedJoint> robot = {{"Hips", "", {0, 1, 0}},
                                    {"Abdomen", "Hips", {0, 0.1f, 0}},
                                    {"Torso", "Abdomen", {0, 0.2f, 0}},
                                    {"Neck", "Torso", {0, 0.2f, 0}},
                                    {"Head", "Neck", {0, 0.1f, 0}}};
  std::vector<PlacedJoint> blender = robot;
  for (const char* side : {"L", "R"}) {
    const std::string s = side;
    const float x = s == "L" ? 0.1f : -0.1f;
    robot.push_back({"UpperLeg" + s, "Hips", {x, -0.05f, 0}});
    robot.push_back({"LowerLeg" + s, "UpperLeg" + s, {0, -0.45f, 0}});
    robot.push_back({"Foot" + s, "LowerLeg" + s, {0, -0.42f, 0}});
    robot.push_back({"Ball" + s, "Foot" + s, {0, -0.05f, 0.12f}});
    const std::string dup = s == "L" ? "" : ".001";
    blender.push_back({"Thigh" + dup, "Hips", {x, -0.05f, 0}});
    blender.push_back({"Shin" + dup, "Thigh" + dup, {0, -0.45f, 0}});
    blender.push_back({"Foot" + dup, "Shin" + dup, {0, -0.42f, 0}});
    blender.push_back({"Toe" + dup, "Foot" + dup, {0, -0.05f, 0.12f}});
  }
  Skeleton r = placed_skeleton(robot);
  detect_joint_roles(&r);
  EXPECT_EQ(role_joint(r, JointRole::kLeftHip), "UpperLegL");
  EXPECT_EQ(role_joint(r, JointRole::kLeftKnee), "LowerLegL");
  EXPECT_EQ(role_joint(r, JointRole::kRightAnkle), "FootR");
  EXPECT_EQ(role_joint(r, JointRole::kRightToe), "BallR");
  EXPECT_EQ(role_joint(r, JointRole::kChest), "Torso");
  Skeleton b = placed_skeleton(blender);
  detect_joint_roles(&b);
  EXPECT_EQ(role_joint(b, JointRole::kLeftHip), "Thigh");  // at +x: the left side
  EXPECT_EQ(role_joint(b, JointRole::kLeftToe), "Toe");
  EXPECT_EQ(role_joint(b, JointRole::kRightKnee), "Shin.001");
  EXPECT_EQ(role_joint(b, JointRole::kRightAnkle), "Foot.001");
  EXPECT_TRUE(b.has_locomotion_roles()) << missing_locomotion_roles(b);
}

// Every shared BVH file and the glb resolve every role (PROVENANCE.md names the joints).
TEST(SkeletonRoles, RealFilesResolveEveryRole) {
  const Expected cmu = {"Hips",      "LowerBack", "Spine1",       "Neck",        "Head",
                        "LeftUpLeg", "LeftLeg",   "LeftFoot",     "LeftToeBase", "RightUpLeg",
                        "RightLeg",  "RightFoot", "RightToeBase", "LeftArm",     "RightArm"};
  const Expected ual = {"DEF-hips",  "DEF-spine.001",   "DEF-spine.003",  "DEF-neck",
                        "DEF-head",  "DEF-thigh.L",     "DEF-shin.L",     "DEF-foot.L",
                        "DEF-toe.L", "DEF-thigh.R",     "DEF-shin.R",     "DEF-foot.R",
                        "DEF-toe.R", "DEF-upper_arm.L", "DEF-upper_arm.R"};
  const std::pair<const char*, const Expected*> files[] = {
      {"clips/bvh/cmu_07_01_walk.bvh", &cmu},
      {"clips/bvh/cmu_09_11_run.bvh", &cmu},
      {"clips/bvh/ual_idle_loop.bvh", &ual},
      {"clips/bvh/ual_walk_loop.bvh", &ual},
      {"clips/bvh/ual_walk_formal_loop.bvh", &ual},
      {"clips/bvh/ual_jog_fwd_loop.bvh", &ual},
      {"clips/bvh/ual_sprint_loop.bvh", &ual},
      {"clips/bvh/ual_crouch_fwd_loop.bvh", &ual},
      {"clips/gltf/ual_mannequin_quaternius.glb", &ual}};
  for (const auto& [rel, expected] : files) {
    GK_REQUIRE_DATA(rel);
    SCOPED_TRACE(rel);
    const std::string path = test::data_path(rel);
    Result<ClipSet> set = path.ends_with(".glb") ? load_gltf(path) : load_bvh(path);
    ASSERT_TRUE(set.ok()) << set.message();
    expect_roles(*set->skeleton, *expected);
    EXPECT_TRUE(set->skeleton->has_locomotion_roles());
    EXPECT_EQ(set->skeleton->spine_chain.size(), 3u);
  }
}

TEST(SkeletonManifest, OverridesRemovesAndRebuildsSpineChain) {
  Skeleton s =
      biped("Hips", {"LowerBack", "Spine", "Spine1"}, "Neck", "Head",
            {"%UpLeg", "%Leg", "%Foot", "%ToeBase"}, {"%Shoulder", "%Arm"}, "Left", "Right");
  detect_joint_roles(&s);
  Status st = apply_role_manifest_text(
      R"({"roles": {"chest": "Spine", "left_toe": "LeftFoot", "right_shoulder": null}})", "m.json",
      &s);
  ASSERT_TRUE(st.ok()) << st.message();
  EXPECT_EQ(role_joint(s, JointRole::kChest), "Spine");
  EXPECT_EQ(role_joint(s, JointRole::kLeftToe), "LeftFoot");
  EXPECT_EQ(role_joint(s, JointRole::kRightShoulder), "-");
  EXPECT_EQ(chain_names(s), (std::vector<std::string>{"LowerBack", "Spine"}));
}

TEST(SkeletonManifest, ErrorsNameFileAndField) {
  Skeleton s = biped("Hips", {"Spine"}, "Neck", "Head", {"%UpLeg", "%Leg", "%Foot", "%ToeBase"},
                     {"%Arm"}, "Left", "Right");
  detect_joint_roles(&s);
  const Skeleton before = s;
  const std::pair<const char*, const char*> cases[] = {
      {R"({"roles": {"left_knee": "Knee_L"}})", "m.json: roles.left_knee: no joint named 'Knee_L'"},
      {R"({"roles": {"left_kneee": "LeftLeg"}})", "m.json: roles.left_kneee: unknown role"},
      {R"({"roles": {"left_knee": 3}})", "m.json: roles.left_knee: expected a joint name"},
      {R"({"roles": ["left_knee"]})", "m.json: roles: expected an object"},
      {R"({"joints": {}})", "m.json: roles: missing"},
      {R"({"roles": {"left_knee": )", "m.json: invalid JSON: parse error"},
  };
  for (const auto& [text, expected] : cases) {
    Status st = apply_role_manifest_text(text, "m.json", &s);
    ASSERT_FALSE(st.ok()) << text;
    EXPECT_NE(st.message().find(expected), std::string::npos) << st.message();
    EXPECT_EQ(s.roles, before.roles);  // a failed manifest changes nothing
  }
  Status missing = apply_role_manifest("/nonexistent/roles.json", &s);
  EXPECT_NE(missing.message().find("/nonexistent/roles.json"), std::string::npos);
}

TEST(SkeletonManifest, LoaderAppliesManifestFromOptions) {
  const std::string path = test::scratch_dir("manifest") + "/roles.json";
  std::ofstream(path) << R"({"roles": {"hips": "Tip"}})";
  LoadOptions options;
  options.role_manifest = path;
  options.scale_m_per_unit = 1.0f;
  Result<ClipSet> set =
      load_bvh(test::source_path("tests/data/good/two_joint_crlf_tabs.bvh"), options);
  ASSERT_TRUE(set.ok()) << set.message();
  EXPECT_EQ(role_joint(*set->skeleton, JointRole::kHips), "Tip");
  std::ofstream(path) << R"({"roles": {"hips": "Nope"}})";
  Result<ClipSet> bad =
      load_bvh(test::source_path("tests/data/good/two_joint_crlf_tabs.bvh"), options);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.message().find(path + ": roles.hips: no joint named 'Nope'"), std::string::npos)
      << bad.message();
}

TEST(SkeletonValidate, RejectsBrokenStructure) {
  Skeleton s = make_skeleton({{"a", ""}, {"b", "a"}});
  EXPECT_TRUE(validate_skeleton(s, "s").ok());
  Skeleton order = s;
  order.parents[0] = 1;  // parent after child
  EXPECT_NE(validate_skeleton(order, "s").message().find("joint 0 'a': parent 1"),
            std::string::npos);
  Skeleton quat = s;
  quat.rest_rotations[1] = glm::quat(2.0f, 0.0f, 0.0f, 0.0f);
  EXPECT_NE(validate_skeleton(quat, "s").message().find("not a unit quaternion"),
            std::string::npos);
  Skeleton sizes = s;
  sizes.names.pop_back();
  EXPECT_FALSE(validate_skeleton(sizes, "s").ok());
  Skeleton nan = s;
  nan.rest_translations[0].x = std::nanf("");
  EXPECT_FALSE(validate_skeleton(nan, "s").ok());
  EXPECT_FALSE(validate_skeleton(Skeleton(), "s").ok());
}

TEST(ClipValidate, RejectsWrongSizesAndValues) {
  Skeleton s = make_skeleton({{"a", ""}, {"b", "a"}});
  Clip c;
  c.name = "c";
  c.num_frames = 2;
  c.num_joints = 2;
  c.rotations.assign(4, glm::quat(1.0f, 0.0f, 0.0f, 0.0f));
  c.translations.assign(4, glm::vec3(0.0f));
  EXPECT_TRUE(validate_clip(c, s).ok());
  Clip short_clip = c;
  short_clip.rotations.pop_back();
  EXPECT_NE(validate_clip(short_clip, s).message().find("expected 4 rotations"), std::string::npos);
  Clip joints = c;
  joints.num_joints = 3;
  EXPECT_FALSE(validate_clip(joints, s).ok());
  Clip fps = c;
  fps.fps = 0.0f;
  EXPECT_FALSE(validate_clip(fps, s).ok());
  Clip bad_q = c;
  bad_q.rotations[3] = glm::quat(0.0f, 0.0f, 0.0f, 0.0f);
  EXPECT_NE(validate_clip(bad_q, s).message().find("frame 1, joint 1"), std::string::npos);
}

}  // namespace
}  // namespace gk
