// `gaitkeeper render` with the teaching camera and overlays, offscreen through EGL: --follow keeps
// the agent at the image centre and --pull-out ends on the whole scene, the gallery's exhibits
// appear in their colour, and --overlay torso draws the fan, the limit arc and the twist label.
// Without EGL the tests skip with a message, except under CI=true.

#include <cmath>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/app/cli_support.h"
#include "tests/test_data.h"

namespace gk {
namespace {

using test::read_json;



const nlohmann::json* agent(const nlohmann::json& report, int64_t id) {
  for (const auto& a : report["agents"]) {
    if (a["id"].get<int64_t>() == id) return &a;
  }
  return nullptr;
}

bool teal(glm::u8vec4 c) { return c.z > c.x + 50 && c.y > c.x + 40; }

TEST(RenderFollow, TheCameraKeepsTheAgentAtTheCentreThenPullsOut) {
  const std::string dir = test::scratch_dir("render_follow");
  const std::string crowd = "render --scenario crossing --agents 20 --size 320x180 --frames 150 ";
  GK_RUN_RENDER(follow, crowd + "--follow 3 --out " + dir + "/follow.png --report " + dir +
                            "/follow.json");
  const nlohmann::json close = read_json(dir + "/follow.json");
  const nlohmann::json* a = agent(close, 3);
  ASSERT_NE(a, nullptr);
  // Agent 3 has walked 2.5 s: the camera kept its hips at the centre, from 8 m.
  EXPECT_NEAR((*a)["px"].get<double>(), 160.0, 0.04 * 180) << close.dump();
  EXPECT_NEAR((*a)["py"].get<double>(), 90.0, 0.04 * 180);
  EXPECT_NEAR(close["camera"]["distance_m"].get<double>(), 8.0, 0.01);
  // The same crowd without --follow: the agent is elsewhere in a far view (the check can fail).
  GK_RUN_RENDER(overview, crowd + "--out " + dir + "/overview.png --report " + dir +
                              "/overview.json");
  const nlohmann::json far = read_json(dir + "/overview.json");
  const nlohmann::json* b = agent(far, 3);
  ASSERT_NE(b, nullptr);
  EXPECT_GT(std::hypot((*b)["px"].get<double>() - 160.0, (*b)["py"].get<double>() - 90.0), 10.0);
  // Pulled out after 0.5 s: 4.5 s later the camera is where the plain render frames the scene.
  GK_RUN_RENDER(pulled, "render --scenario crossing --agents 20 --size 320x180 --frames 300 "
                        "--follow 3 --pull-out 0.5 --out " + dir + "/pulled.png --report " + dir +
                            "/pulled.json");
  const nlohmann::json out = read_json(dir + "/pulled.json");
  EXPECT_NEAR(out["camera"]["distance_m"].get<double>(), far["camera"]["distance_m"].get<double>(),
              0.05 * far["camera"]["distance_m"].get<double>());
}

TEST(RenderFollow, OptionsThatNeedAFollowedAgentSaySo) {
  const test::CommandResult pull =
      test::run_gaitkeeper("render --scenario crossing --frames 1 --pull-out 2 --out /tmp/x.png");
  EXPECT_EQ(pull.code, 2);
  EXPECT_NE(pull.out.find("--pull-out"), std::string::npos) << pull.out;
  EXPECT_NE(pull.out.find("--follow"), std::string::npos) << pull.out;
  const test::CommandResult torso = test::run_gaitkeeper(
      "render --scenario crossing --frames 1 --overlay torso --out /tmp/x.png");
  EXPECT_EQ(torso.code, 2);
  EXPECT_NE(torso.out.find("--follow"), std::string::npos) << torso.out;
  const test::CommandResult bad = test::run_gaitkeeper(
      "render --scenario crossing --frames 1 --follow 0 --pull-out soon --out /tmp/x.png");
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.out.find("--pull-out"), std::string::npos) << bad.out;
}

TEST(RenderShots, ExhibitsAppearInTheirColour) {
  const std::string dir = test::scratch_dir("render_follow");
  GK_RUN_RENDER(r, "render --scenario gallery --agents 0 --frames 1 --size 640x360 --out " + dir +
                       "/exhibits.png --report " + dir + "/exhibits.json");
  const test::Image img = test::read_png(dir + "/exhibits.png");
  const nlohmann::json report = read_json(dir + "/exhibits.json");
  ASSERT_EQ(report["exhibits"].size(), 4u);  // the gallery's four attention targets
  int shown = 0;
  for (const auto& e : report["exhibits"]) {
    const int x = static_cast<int>(e["px"].get<double>()), y = static_cast<int>(e["py"].get<double>());
    if (!e["in_front"].get<bool>() || x < 2 || y < 2 || x >= img.width - 2 || y >= img.height - 2) {
      continue;
    }
    int teal_px = 0;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) teal_px += teal(img.at(x + dx, y + dy));
    }
    shown += teal_px >= 5;
  }
  // The 3/4 view looks at the faces of the exhibits on the far wall (the near ones show the
  // backs of their boards).
  EXPECT_GE(shown, 2);
  // A scenario without attention targets has no exhibits, and no teal anywhere.
  GK_RUN_RENDER(none, "render --scenario crossing --agents 0 --frames 1 --size 640x360 --out " +
                          dir + "/no_exhibits.png --report " + dir + "/no_exhibits.json");
  EXPECT_EQ(read_json(dir + "/no_exhibits.json")["exhibits"].size(), 0u);
  const test::Image plain = test::read_png(dir + "/no_exhibits.png");
  int teal_anywhere = 0;
  for (int y = 0; y < plain.height; ++y) {
    for (int x = 0; x < plain.width; ++x) teal_anywhere += teal(plain.at(x, y));
  }
  EXPECT_EQ(teal_anywhere, 0);
}

// Agent 2 of the gallery looks at an exhibit about 47 deg to its right after 10 s; with the
// torsion limit at 30 deg its chest stops there.
TEST(RenderShots, TorsoFanLimitArcAndTwistLabelAreDrawn) {
  const std::string dir = test::scratch_dir("render_follow");
  const std::string run = "render --scenario gallery --follow 2 --frames 600 --size 640x360 "
                          "--set torsion_limit_deg=30 --report " + dir + "/fan.json --out ";
  GK_RUN_RENDER(with, run + dir + "/fan.png --overlay torso");
  GK_RUN_RENDER(without, run + dir + "/no_fan.png");
  const nlohmann::json report = read_json(dir + "/fan.json");
  ASSERT_TRUE(report.contains("followed")) << report.dump();
  const auto& f = report["followed"];
  EXPECT_GT(std::abs(f["theta_deg"].get<double>()), 35.0) << "the agent should look far aside";
  EXPECT_NEAR(std::abs(f["twist_deg"].get<double>()), 30.0, 1.5) << "the chest stops at the limit";
  const test::Image fan = test::read_png(dir + "/fan.png");
  const test::Image plain = test::read_png(dir + "/no_fan.png");
  ASSERT_EQ(fan.width, 640);
  ASSERT_EQ(plain.width, 640);
  // Around the agent (the fan reaches 1 m, ~60 px here): orange fan and chest ray, white arc.
  const nlohmann::json* a = agent(report, 2);
  ASSERT_NE(a, nullptr);
  const int cx = static_cast<int>((*a)["px"].get<double>()), cy = static_cast<int>((*a)["py"].get<double>());
  int orange = 0, white = 0, orange_before = 0, white_before = 0;
  auto is_orange = [](glm::u8vec4 c) { return c.x > 200 && c.y > 90 && c.y < 190 && c.z < 110; };
  auto is_white = [](glm::u8vec4 c) { return c.x > 235 && c.y > 235 && c.z > 235; };
  for (int y = cy - 120; y < cy + 80; ++y) {
    for (int x = cx - 140; x < cx + 140; ++x) {
      orange += is_orange(fan.at(x, y));
      orange_before += is_orange(plain.at(x, y));
      white += is_white(fan.at(x, y));
      white_before += is_white(plain.at(x, y));
    }
  }
  EXPECT_GT(orange - orange_before, 150) << orange << " vs " << orange_before;
  EXPECT_GT(white - white_before, 60) << white << " vs " << white_before;
  // The label above the head: white letters on a dark box.
  const int hx = static_cast<int>(f["head_px"].get<double>()), hy = static_cast<int>(f["head_py"].get<double>());
  int letters = 0, letters_before = 0;
  for (int y = hy - 30; y < hy; ++y) {
    for (int x = hx - 110; x < hx + 110; ++x) {
      letters += is_white(fan.at(x, y));
      letters_before += is_white(plain.at(x, y));
    }
  }
  EXPECT_GT(letters - letters_before, 100) << letters << " vs " << letters_before;
}

}  // namespace
}  // namespace gk
