// `gaitkeeper render --lesson NAME` offscreen through EGL: the lesson's scenario, split (that one
// idea off on the left, on on the right), follow camera and caption; a lesson that changes the
// simulation runs each half on its own crowd; an unknown name is refused with the list. Without
// EGL the tests skip with a message, except under CI=true.

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



TEST(RenderLesson, FootLockingSplitsLockingOffAndOnAndFollowsAnAgent) {
  const std::string dir = test::scratch_dir("render_lesson");
  GK_RUN_RENDER(r, "render --lesson foot-locking --size 480x270 --frames 60 --out " + dir +
                       "/locking.png --report " + dir + "/locking.json");
  const nlohmann::json j = read_json(dir + "/locking.json");
  EXPECT_EQ(j["lesson"].get<std::string>(), "foot-locking");
  EXPECT_TRUE(j["split"].get<bool>());
  EXPECT_EQ(j["agents"].size(), 12u) << "the lesson's crowd: crossing, 12 agents";
  EXPECT_FALSE(j["compare_params"]["foot_locking"].get<bool>()) << "left: locking off";
  EXPECT_TRUE(j["params"]["foot_locking"].get<bool>()) << "right: locking on";
  // Only that one idea differs: the mode and the other switches are the same on both sides.
  EXPECT_EQ(j["compare_params"]["mode"], j["params"]["mode"]);
  EXPECT_EQ(j["compare_params"]["feedback"], j["params"]["feedback"]);
  EXPECT_FALSE(j["compare_own_crowd"].get<bool>());
  // The followed agent sits at the centre of the right half.
  const int64_t id = j["follow_id"].get<int64_t>();
  ASSERT_GE(id, 0);
  bool found = false;
  for (const auto& a : j["agents"]) {
    if (a["id"].get<int64_t>() != id) continue;
    found = true;
    EXPECT_NEAR(a["px"].get<double>(), 120.0, 0.08 * 270);
    EXPECT_NEAR(a["py"].get<double>(), 135.0, 0.08 * 270);
  }
  EXPECT_TRUE(found);
  // The caption is stamped along the bottom edge in its amber (255, 220, 120).
  const test::Image img = test::read_png(dir + "/locking.png");
  ASSERT_EQ(img.width, 480);
  int amber = 0;
  for (int y = 240; y < 270; ++y) {
    for (int x = 0; x < 480; ++x) {
      const glm::u8vec4 c = img.at(x, y);
      amber += c.x > 230 && c.y > 195 && c.y < 245 && c.z > 90 && c.z < 150;
    }
  }
  EXPECT_GT(amber, 100) << "no caption at the bottom";
}

TEST(RenderLesson, FeedbackRunsEachHalfOnItsOwnCrowd) {
  const std::string dir = test::scratch_dir("render_lesson");
  GK_RUN_RENDER(r, "render --lesson feedback --size 320x180 --frames 20 --out " + dir +
                       "/feedback.png --report " + dir + "/feedback.json");
  const nlohmann::json j = read_json(dir + "/feedback.json");
  EXPECT_TRUE(j["compare_own_crowd"].get<bool>());
  EXPECT_FALSE(j["compare_params"]["feedback"].get<bool>());
  EXPECT_TRUE(j["params"]["feedback"].get<bool>());
}

// Without feedback the left half's runner is carried ahead of the right half's walker; one camera
// shows both halves, so it frames both places: after 5 s, metres apart, both bodies and the
// space over their heads (the speed labels) are inside the half view.
TEST(RenderLesson, FeedbackKeepsTheRingedAgentInViewInBothHalves) {
  const std::string dir = test::scratch_dir("render_lesson_feedback_frame");
  GK_RUN_RENDER(r, "render --lesson feedback --size 480x270 --frames 300 --out " + dir +
                       "/feedback.png --report " + dir + "/feedback.json");
  const nlohmann::json j = read_json(dir + "/feedback.json");
  ASSERT_TRUE(j.contains("followed_places")) << j.dump();
  const auto& places = j["followed_places"];
  ASSERT_EQ(places.size(), 2u);
  const double apart = std::hypot(places[0]["x"].get<double>() - places[1]["x"].get<double>(),
                                  places[0]["z"].get<double>() - places[1]["z"].get<double>());
  EXPECT_GT(apart, 2.0) << "the halves' runners should be apart: the check can fail";
  for (const auto& p : places) {
    EXPECT_TRUE(p["in_front"].get<bool>());
    for (const char* k : {"feet_px", "head_px"}) {
      EXPECT_GT(p[k].get<double>(), 0.0) << p;
      EXPECT_LT(p[k].get<double>(), 240.0) << p;
    }
    EXPECT_LT(p["feet_py"].get<double>(), 270.0) << p;
    EXPECT_GT(p["head_py"].get<double>(), 20.0) << "no room for the label over the head: " << p;
  }
}

TEST(RenderLesson, AnUnknownLessonIsRefusedWithTheList) {
  const test::CommandResult r =
      test::run_gaitkeeper("render --lesson skating --out /tmp/never_written.png");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("foot-sliding"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("torso-decoupling"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace gk
