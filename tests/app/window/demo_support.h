#pragma once
// Shared by the window tests: the display requirement, one scripted demo run with its screenshot
// and report, and colour statistics of a screenshot.

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <glm/vec3.hpp>
#include <nlohmann/json.hpp>

#include "tests/app/cli_support.h"
#include "tests/test_data.h"

namespace gk {

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

inline Shot run_demo(const std::string& name, const std::string& args,
              const std::string& size = "1024x576") {
  const std::string dir = test::scratch_dir("demo");
  const std::string png = dir + "/" + name + ".png", json = dir + "/" + name + ".json";
  std::remove(png.c_str());
  std::remove(json.c_str());
  const test::CommandResult r = test::run_gaitkeeper("demo --size " + size + " " + args +
                                                     " --screenshot " + png + " --report " + json);
  EXPECT_EQ(r.code, 0) << r.out;
  Shot shot;
  shot.image = test::read_png(png);
  std::ifstream in(json);
  if (in) shot.report = nlohmann::json::parse(in);
  return shot;
}

// Mean colour of a rectangle.
inline glm::vec3 mean_color(const test::Image& img, int x0, int y0, int x1, int y1) {
  glm::dvec3 sum(0.0);
  for (int y = y0; y < y1; ++y) {
    for (int x = x0; x < x1; ++x) sum += glm::dvec3(glm::vec3(img.at(x, y)));
  }
  return glm::vec3(sum / static_cast<double>((x1 - x0) * (y1 - y0)));
}

}  // namespace gk
