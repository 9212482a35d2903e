// An IK-style rig (feet parented to the root; tests/ik_rig_fixture.h) through the executable:
// known joint names work with no manifest, meaningless ones are refused saying how to give
// --roles and then work with it.

#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/app/cli_support.h"
#include "tests/ik_rig_fixture.h"
#include "tests/test_data.h"

namespace gk {
namespace {

using test::CommandResult;
using test::read_json;

TEST(CliIkRig, KnownNamesWorkWithoutAManifest) {
  const std::string dir = test::scratch_dir("cli_ik_rig");
  const std::string glb = dir + "/ik_rig_cm.glb";
  ASSERT_TRUE(test::write_file(glb, test::make_ik_rig().glb));
  const CommandResult a = test::run_gaitkeeper("analyze-clip " + glb);
  ASSERT_EQ(a.code, 0) << a.out;
  EXPECT_NE(a.out.find("rig: IK-style feet attached to the legs: foot_l under calf_l"),
            std::string::npos)
      << a.out;
  EXPECT_NE(a.out.find("centimetres"), std::string::npos) << a.out;
  // Each clip holds two strides: analysis finds alternating contacts and a cycle of one.
  const CommandResult j = test::run_gaitkeeper("analyze-clip --json " + glb);
  ASSERT_EQ(j.code, 0) << j.out;
  for (const nlohmann::json& c : nlohmann::json::parse(j.out)) {
    if (c["name"] == "idle") continue;
    const double cycle = c["cycle"]["end_s"].get<double>() - c["cycle"]["start_s"].get<double>();
    EXPECT_NEAR(cycle, 0.5 * c["duration_s"].get<double>(), 0.02) << c["name"];
    EXPECT_EQ(c["contacts"]["left"].size(), 2u) << c["name"];
    EXPECT_EQ(c["contacts"]["right"].size(), 2u) << c["name"];
  }
  const std::string common =
      "bench --scenario crossing --agents 12 --frames 300 --clips " + glb + " --json ";
  const CommandResult apm = test::run_gaitkeeper(common + dir + "/apm.json");
  ASSERT_EQ(apm.code, 0) << apm.out;
  const CommandResult naive = test::run_gaitkeeper(common + dir + "/naive.json --mode naive");
  ASSERT_EQ(naive.code, 0) << naive.out;
  const nlohmann::json ra = read_json(dir + "/apm.json"), rn = read_json(dir + "/naive.json");
  ASSERT_TRUE(ra["metrics"].is_object() && rn["metrics"].is_object());
  EXPECT_TRUE(ra["left_out"].empty()) << ra["left_out"].dump();
  const double slide_apm = ra["metrics"]["foot_slide_cm_s"].get<double>();
  const double slide_naive = rn["metrics"]["foot_slide_cm_s"].get<double>();
  EXPECT_LT(slide_apm, 2.0);
  EXPECT_GT(slide_naive, 5.0 * slide_apm) << slide_naive << " vs " << slide_apm;
}

TEST(CliIkRig, MeaninglessNamesAreRefusedThenWorkWithRoles) {
  const std::string dir = test::scratch_dir("cli_ik_rig");
  const test::IkRig rig = test::make_ik_rig(test::meaningless_inch_rig());
  const std::string glb = dir + "/ik_rig_in.glb", roles = dir + "/ik_rig_in_roles.json";
  ASSERT_TRUE(test::write_file(glb, rig.glb));
  ASSERT_TRUE(test::write_file(roles, rig.roles_json));
  const std::string bench = "bench --scenario corridor --agents 6 --frames 60 --clips " + glb;
  const CommandResult refused = test::run_gaitkeeper(bench);
  EXPECT_EQ(refused.code, 2) << refused.out;
  EXPECT_NE(refused.out.find("ik_rig_in.glb: skeleton lacks the hips/leg joints"),
            std::string::npos)
      << refused.out;
  EXPECT_NE(refused.out.find("give a role manifest with --roles FILE.json"), std::string::npos)
      << refused.out;
  const CommandResult analysed = test::run_gaitkeeper("analyze-clip " + glb);
  EXPECT_NE(analysed.code, 0);
  EXPECT_NE(analysed.out.find("--roles FILE.json"), std::string::npos) << analysed.out;
  const CommandResult ok = test::run_gaitkeeper(bench + " --roles " + roles);
  EXPECT_EQ(ok.code, 0) << ok.out;
  const CommandResult ok_analysed =
      test::run_gaitkeeper("analyze-clip --roles " + roles + " " + glb);
  EXPECT_EQ(ok_analysed.code, 0) << ok_analysed.out;
  EXPECT_NE(ok_analysed.out.find("inches"), std::string::npos) << ok_analysed.out;
}

// The renderer does not care about the hierarchy: the IK-style rig and the same character with
// its feet under the shins, rendered close up on the same crowd, give the same picture.
TEST(CliIkRig, RendersAsTheSameCharacterWithItsFeetUnderTheShins) {
  const std::string dir = test::scratch_dir("cli_ik_rig");
  test::IkRigOptions chain;
  chain.feet_under_root = false;
  ASSERT_TRUE(test::write_file(dir + "/ik.glb", test::make_ik_rig().glb));
  ASSERT_TRUE(test::write_file(dir + "/chain.glb", test::make_ik_rig(chain).glb));
  const std::string common =
      "render --scenario crossing --agents 6 --frames 60 --follow 2 --size 320x180 --clips ";
  GK_RUN_RENDER(ik, common + dir + "/ik.glb --out " + dir + "/ik.png");
  GK_RUN_RENDER(ch, common + dir + "/chain.glb --out " + dir + "/chain.png");
  // Another crowd (seed) with the same rig: a picture that really shows the crowd differs.
  GK_RUN_RENDER(other, common + dir + "/ik.glb --seed 2 --out " + dir + "/ik_seed2.png");
  const test::Image a = test::read_png(dir + "/ik.png"), b = test::read_png(dir + "/chain.png");
  const test::Image c = test::read_png(dir + "/ik_seed2.png");
  ASSERT_EQ(a.width, 320);
  ASSERT_EQ(b.width, 320);
  ASSERT_EQ(c.width, 320);
  int same_crowd = 0, other_crowd = 0;
  for (int y = 0; y < 180; ++y) {
    for (int x = 0; x < 320; ++x) {
      same_crowd += test::pixel_difference(a.at(x, y), b.at(x, y)) > 30;
      other_crowd += test::pixel_difference(a.at(x, y), c.at(x, y)) > 30;
    }
  }
  EXPECT_GT(other_crowd, 320 * 180 / 50) << other_crowd << " pixels differ with another seed";
  EXPECT_LT(same_crowd, 320 * 180 / 400) << same_crowd << " pixels differ";
}

}  // namespace
}  // namespace gk
