// The demo's Lessons menu and timeline under a display (CTest runs this through xvfb-run): a click
// on the menu and on a lesson sets that lesson's scenario, split, overlays and speed and shows its
// text over the scene; Page Up scrubs back 5 s and the window then draws the crowd as it was 5 s
// earlier. Without DISPLAY the tests skip with a message, except under CI=true.

#include <cmath>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/app/cli_support.h"
#include "tests/app/window/demo_support.h"

namespace gk {
namespace {

const nlohmann::json* agent(const nlohmann::json& report, int64_t id) {
  for (const auto& a : report["agents"]) {
    if (a["id"].get<int64_t>() == id) return &a;
  }
  return nullptr;
}

std::string centre(const nlohmann::json& rect) {
  return std::to_string(rect[0].get<double>() + 0.5 * rect[2].get<double>()) + "," +
         std::to_string(rect[1].get<double>() + 0.5 * rect[3].get<double>());
}

// Bright text pixels and the mean brightness in a rectangle.
void text_box_stats(const test::Image& img, int x0, int y0, int x1, int y1, int* bright,
                    float* mean) {
  double sum = 0.0;
  *bright = 0;
  for (int y = y0; y < y1; ++y) {
    for (int x = x0; x < x1; ++x) {
      const glm::u8vec4 c = img.at(x, y);
      const int l = (c.x + c.y + c.z) / 3;
      sum += l;
      *bright += l > 200;
    }
  }
  *mean = static_cast<float>(sum / ((x1 - x0) * (y1 - y0)));
}

TEST(DemoLessons, TheMenuSwitchesToALessonAndItsSplit) {
  GK_REQUIRE_DISPLAY();
  const std::string crowd = "--scenario gallery --agents 6 --threads 1 ";
  // Where the menu is, and (opened by a click) where its items are.
  const Shot closed = run_demo("lesson_menu", crowd + "--frames 2", "1280x720");
  const std::string menu = centre(closed.report["lessons_menu"]);
  const Shot open = run_demo("lesson_open", crowd + "--frames 4 --input 2:click:" + menu, "1280x720");
  ASSERT_EQ(open.report["lesson_items"].size(), 5u) << open.report.dump();
  const std::string item = centre(open.report["lesson_items"][2]);  // Foot locking
  const Shot s = run_demo("lesson_switch",
                          crowd + "--frames 40 --input 2:click:" + menu + " --input 5:click:" + item,
                          "1280x720");
  EXPECT_EQ(s.report["lesson"].get<std::string>(), "foot-locking") << s.report["status"];
  EXPECT_EQ(s.report["scenario"].get<std::string>(), "crossing");
  EXPECT_EQ(s.report["agent_count"].get<int>(), 12);
  EXPECT_TRUE(s.report["compare"].get<bool>());
  EXPECT_FALSE(s.report["compare_params"]["foot_locking"].get<bool>());
  EXPECT_TRUE(s.report["params"]["foot_locking"].get<bool>());
  EXPECT_EQ(s.report["compare_params"]["mode"], s.report["params"]["mode"]);
  EXPECT_TRUE(s.report["overlays"]["planted"].get<bool>());
  EXPECT_TRUE(s.report["overlays"]["trails"].get<bool>());
  EXPECT_NEAR(s.report["time_scale"].get<double>(), 0.5, 1e-6);
  EXPECT_TRUE(s.report["following"].get<bool>());
  // The lesson's text sits in a dark box along the bottom of the scene; before the switch the
  // same place showed the gallery.
  const auto& box = s.report["lesson_text"];
  const int x0 = static_cast<int>(box[0].get<double>()), y0 = static_cast<int>(box[1].get<double>());
  const int x1 = x0 + static_cast<int>(box[2].get<double>());
  const int y1 = y0 + static_cast<int>(box[3].get<double>());
  ASSERT_GT(x1 - x0, 300) << box;
  ASSERT_GT(y1 - y0, 40) << box;
  EXPECT_LE(x1, s.report["scene_width"].get<int>());
  int bright = 0, bright_before = 0;
  float mean = 0.0f, mean_before = 0.0f;
  text_box_stats(s.image, x0, y0, x1, y1, &bright, &mean);
  text_box_stats(closed.image, x0, y0, x1, y1, &bright_before, &mean_before);
  EXPECT_GT(bright, 300) << "no text over the scene";
  EXPECT_LT(mean, 90.0f) << "no dark box behind the text";
  EXPECT_GT(mean_before, mean + 40.0f);
}

TEST(DemoTimeline, PageUpScrubsBack5sToTheCrowdAsItWas) {
  GK_REQUIRE_DISPLAY();
  // Planted feet (a few crosses) rather than the torso fan: the overlays are drawn live only.
  const std::string crowd = "--scenario crossing --agents 10 --threads 1 --select 3 "
                            "--overlay planted ";
  const Shot scrubbed =
      run_demo("scrub", crowd + "--frames 482 --input 480:key:pageup", "640x360");
  const Shot live = run_demo("scrub_live", crowd + "--frames 480", "640x360");
  const auto& t = scrubbed.report["timeline"];
  ASSERT_TRUE(t["scrubbing"].get<bool>()) << scrubbed.report.dump();
  const double shown = t["shown_time_s"].get<double>();
  EXPECT_NEAR(shown, live.report["time_s"].get<double>() - 5.0, 0.06);
  EXPECT_GE(t["posed_capacity"].get<int>(), 10) << "10 agents fit the pose budget";
  // The same crowd run to the recorded moment: the drawn agents stand where it had them.
  const int frames = static_cast<int>(std::lround(shown * 60.0));
  const Shot then = run_demo("scrub_then", crowd + "--frames " + std::to_string(frames), "640x360");
  EXPECT_NEAR(then.report["time_s"].get<double>(), shown, 1e-6);
  int matched = 0;
  for (const auto& a : then.report["agents"]) {
    const nlohmann::json* b = agent(scrubbed.report, a["id"].get<int64_t>());
    ASSERT_NE(b, nullptr) << "agent " << a["id"] << " is not drawn in the scrubbed frame";
    EXPECT_NEAR((*b)["x"].get<double>(), a["x"].get<double>(), 1e-4);
    EXPECT_NEAR((*b)["z"].get<double>(), a["z"].get<double>(), 1e-4);
    ++matched;
  }
  EXPECT_EQ(matched, 10);
  const nlohmann::json* followed_then = agent(then.report, 3);
  const nlohmann::json* followed_live = agent(live.report, 3);
  ASSERT_TRUE(followed_then && followed_live);
  EXPECT_GT(std::hypot((*followed_live)["x"].get<double>() - (*followed_then)["x"].get<double>(),
                       (*followed_live)["z"].get<double>() - (*followed_then)["z"].get<double>()),
            2.0)
      << "agent 3 walked on in those 5 s: the check can fail";
  // The picture too: the scrubbed scene looks like the crowd 5 s earlier, not like the live one.
  const int w = scrubbed.report["scene_width"].get<int>();
  auto difference = [&](const test::Image& a, const test::Image& b) {
    double sum = 0.0;
    for (int y = 40; y < 300; ++y) {
      for (int x = 0; x < w; ++x) sum += test::pixel_difference(a.at(x, y), b.at(x, y));
    }
    return sum / (260.0 * w);
  };
  EXPECT_LT(difference(scrubbed.image, then.image), 0.5 * difference(scrubbed.image, live.image));
}

}  // namespace
}  // namespace gk
