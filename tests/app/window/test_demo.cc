// The demo window under a display (CTest runs this binary through xvfb-run): it opens, draws the
// crowd where the camera projects the agents and the panel beside it, and the compare view shows
// two different halves. Without DISPLAY the tests skip with a message, except under CI=true.

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/app/cli_support.h"
#include "tests/test_data.h"

namespace gk {
namespace {

// A macro: GTEST_SKIP and FAIL return from the test itself only when written in its body.
#define GK_REQUIRE_DISPLAY()                                                                 \
  do {                                                                                       \
    const char* gk_display_ = std::getenv("DISPLAY");                                        \
    if (!gk_display_ || !*gk_display_) {                                                     \
      if (test::under_ci()) FAIL() << "the window tests need a display under CI (xvfb-run)"; \
      GTEST_SKIP() << "DISPLAY is not set; CTest runs these through xvfb-run";               \
    }                                                                                        \
  } while (0)

struct Shot {
  test::Image image;
  nlohmann::json report;
};

Shot run_demo(const std::string& name, const std::string& args) {
  const std::string dir = test::scratch_dir("demo");
  const std::string png = dir + "/" + name + ".png", json = dir + "/" + name + ".json";
  std::remove(png.c_str());
  const test::CommandResult r = test::run_gaitkeeper("demo --size 1024x576 " + args +
                                                     " --screenshot " + png + " --report " + json);
  EXPECT_EQ(r.code, 0) << r.out;
  Shot shot;
  shot.image = test::read_png(png);
  std::ifstream in(json);
  if (in) shot.report = nlohmann::json::parse(in);
  return shot;
}

// Mean colour of a rectangle.
glm::vec3 mean_color(const test::Image& img, int x0, int y0, int x1, int y1) {
  glm::dvec3 sum(0.0);
  for (int y = y0; y < y1; ++y) {
    for (int x = x0; x < x1; ++x) sum += glm::dvec3(glm::vec3(img.at(x, y)));
  }
  return glm::vec3(sum / static_cast<double>((x1 - x0) * (y1 - y0)));
}

TEST(Demo, WindowShowsCrowdAndPanel) {
  GK_REQUIRE_DISPLAY();
  const Shot empty = run_demo("empty", "--scenario gallery --agents 0 --frames 10");
  const Shot crowd = run_demo("crowd", "--scenario gallery --agents 12 --frames 40");
  ASSERT_EQ(crowd.image.width, 1024);
  ASSERT_EQ(crowd.image.height, 576);
  ASSERT_EQ(empty.image.width, 1024);
  // The panel is docked at the right edge and looks nothing like the 3D view beside it.
  const auto& panel = crowd.report["panel"];
  const int px = static_cast<int>(panel[0].get<double>());
  const int scene_w = crowd.report["scene_width"].get<int>();
  EXPECT_EQ(px, scene_w);
  EXPECT_GT(static_cast<int>(panel[2].get<double>()), 200);
  const glm::vec3 panel_mean = mean_color(crowd.image, px + 10, 100, 1014, 560);
  const glm::vec3 scene_mean = mean_color(crowd.image, 10, 100, scene_w - 10, 560);
  EXPECT_GT(glm::length(panel_mean - scene_mean), 40.0f)
      << "panel " << panel_mean.x << " vs scene " << scene_mean.x;
  // Agents are drawn where the camera projects them: there the crowd's frame differs from the
  // empty scene's (same camera: the view frames the walls, which do not depend on the crowd here).
  int inside = 0, hits = 0;
  for (const auto& a : crowd.report["agents"]) {
    const int x = static_cast<int>(a["px"].get<double>()),
              y = static_cast<int>(a["py"].get<double>());
    if (!a["in_front"].get<bool>() || x < 3 || y < 3 || x >= scene_w - 3 || y >= 573) continue;
    ++inside;
    int best = 0;
    for (int dy = -2; dy <= 2; ++dy) {
      for (int dx = -2; dx <= 2; ++dx) {
        best = std::max(best, test::pixel_difference(crowd.image.at(x + dx, y + dy),
                                                     empty.image.at(x + dx, y + dy)));
      }
    }
    if (best > 30) ++hits;
  }
  EXPECT_GE(inside, 10);
  EXPECT_GE(hits, inside - 1);
}

TEST(Demo, CompareShowsTwoDifferentHalves) {
  GK_REQUIRE_DISPLAY();
  const Shot shot = run_demo("compare", "--scenario gallery --agents 30 --frames 60 --compare");
  ASSERT_EQ(shot.image.width, 1024);
  ASSERT_TRUE(shot.report["compare"].get<bool>());
  const int half = shot.report["scene_width"].get<int>() / 2;
  int differing = 0, total = 0;
  for (int y = 0; y < shot.image.height; ++y) {
    for (int x = 0; x < half - 1; ++x) {
      ++total;
      if (test::pixel_difference(shot.image.at(x, y), shot.image.at(x + half, y)) > 30) ++differing;
    }
  }
  EXPECT_GT(differing, 50) << "naive and apm halves look the same";
  EXPECT_LT(differing, total / 10) << "the halves should show the same scene";
}

TEST(Demo, ClickingAnAgentSelectsIt) {
  GK_REQUIRE_DISPLAY();
  // Same seed, one thread: the second run's last frame is the first run's.
  const std::string crowd = "--scenario gallery --agents 12 --frames 40 --threads 1";
  const Shot first = run_demo("pick_before", crowd);
  const int scene_w = first.report["scene_width"].get<int>();
  // An agent well inside the view whose neighbours on screen are not too close.
  int64_t target = -1;
  double tx = 0, ty = 0;
  for (const auto& a : first.report["agents"]) {
    const double x = a["px"].get<double>(), y = a["py"].get<double>();
    if (!a["in_front"].get<bool>() || x < 20 || y < 20 || x > scene_w - 20 || y > 556) continue;
    double nearest = 1e9;
    for (const auto& b : first.report["agents"]) {
      if (b["id"] == a["id"]) continue;
      nearest = std::min(nearest, std::hypot(b["px"].get<double>() - x, b["py"].get<double>() - y));
    }
    if (nearest > 30.0) {
      target = a["id"].get<int64_t>(), tx = x, ty = y;
      break;
    }
  }
  ASSERT_GE(target, 0) << "no isolated agent in view";
  const Shot hit =
      run_demo("pick_hit", crowd + " --click " + std::to_string(tx) + "," + std::to_string(ty));
  EXPECT_EQ(hit.report["selected"].get<int64_t>(), target);
  // A click on the empty ground in a corner of the view selects nobody.
  const Shot miss = run_demo("pick_miss", crowd + " --click 5,570");
  EXPECT_EQ(miss.report["selected"].get<int64_t>(), -1);
}

}  // namespace
}  // namespace gk
