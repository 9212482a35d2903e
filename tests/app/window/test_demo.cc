// The demo window under a display (CTest runs this binary through xvfb-run): it opens, draws the
// crowd where the camera projects the agents and the panel beside it, the compare view shows two
// different halves; keys (Space, H, R, Esc), clicks and the wheel arrive through Dear ImGui as a
// user's would (`--input`) and do what the help says; the follow camera keeps the selected agent
// at the centre; the showcase opens close on the door. Without DISPLAY the tests skip with a
// message, except under CI=true.

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "render/camera.h"
#include "tests/app/cli_support.h"
#include "tests/app/window/demo_support.h"
#include "tests/ik_rig_fixture.h"
#include "tests/test_data.h"

namespace gk {
namespace {

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
  const Shot shot = run_demo("compare", "--scenario gallery --agents 30 --frames 30 --compare");
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
  const std::string crowd = "--scenario gallery --agents 12 --frames 20 --threads 1";
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

// Small and few: these runs check state, not looks.
constexpr const char* kSmall = "640x360";
constexpr double kStep_s = 1.0 / 60.0;  // one simulation step per scripted frame
const std::string kFew = "--scenario gallery --agents 6 --threads 1 ";

TEST(DemoKeys, SpacePausesAndResumesSimulatedTime) {
  GK_REQUIRE_DISPLAY();
  const Shot paused = run_demo("space", kFew + "--frames 20 --input 8:key:space", kSmall);
  ASSERT_TRUE(paused.report.contains("time_s"));
  // Frames 0..7 stepped; the press arrives at frame 8, before its step.
  EXPECT_NEAR(paused.report["time_s"].get<double>(), 8 * kStep_s, 1e-4);
  EXPECT_TRUE(paused.report["paused"].get<bool>());
  const Shot resumed =
      run_demo("space2", kFew + "--frames 20 --input 8:key:space --input 14:key:space", kSmall);
  EXPECT_NEAR(resumed.report["time_s"].get<double>(), 14 * kStep_s, 1e-4);
  EXPECT_FALSE(resumed.report["paused"].get<bool>());
  // The screenshots: paused, the scene (above the status text along the bottom) stands still
  // from frame 12 to frame 20; running, the crowd has moved on by frame 20.
  const Shot paused_early = run_demo("space_early", kFew + "--frames 12 --input 8:key:space", kSmall);
  const Shot running = run_demo("space_running", kFew + "--frames 20", kSmall);
  const int w = paused.report["scene_width"].get<int>();
  auto changed = [&](const test::Image& a, const test::Image& b) {
    int n = 0;
    for (int y = 40; y < 300; ++y) {
      for (int x = 0; x < w; ++x) n += test::pixel_difference(a.at(x, y), b.at(x, y)) > 30;
    }
    return n;
  };
  const int while_paused = changed(paused.image, paused_early.image);
  const int while_running = changed(running.image, paused_early.image);
  EXPECT_LT(while_paused, 10) << "the scene moved while paused";
  EXPECT_GT(while_running, 80) << "the crowd should move in 8 frames: the check can fail";
}

TEST(DemoKeys, HShowsTheHelpOverTheSceneAndEscQuits) {
  GK_REQUIRE_DISPLAY();
  const Shot help = run_demo("help", kFew + "--frames 8 --input 3:key:h", kSmall);
  const Shot plain = run_demo("no_help", kFew + "--frames 8", kSmall);
  ASSERT_TRUE(help.report["help"].get<bool>());
  EXPECT_FALSE(plain.report["help"].get<bool>());
  const auto& r = help.report["help_rect"];
  const int x0 = static_cast<int>(r[0].get<double>()), y0 = static_cast<int>(r[1].get<double>());
  const int x1 = x0 + static_cast<int>(r[2].get<double>()),
            y1 = y0 + static_cast<int>(r[3].get<double>());
  ASSERT_GT(x1 - x0, 200);
  ASSERT_GT(y1 - y0, 100);
  // The help is a dark window with light text where the scene shows the light ground.
  const glm::vec3 over = mean_color(help.image, x0, y0, x1, y1);
  const glm::vec3 under = mean_color(plain.image, x0, y0, x1, y1);
  EXPECT_LT(over.x + 60.0f, under.x) << over.x << " vs " << under.x;
  // H again closes it.
  const Shot twice = run_demo("help2", kFew + "--frames 8 --input 3:key:h --input 5:key:h", kSmall);
  EXPECT_FALSE(twice.report["help"].get<bool>());
  // Esc quits at once (exit code 0, checked by run_demo), not after the 100 frames asked for.
  const Shot quit = run_demo("escape", kFew + "--frames 100 --input 6:key:escape", kSmall);
  EXPECT_EQ(quit.report["frames"].get<int>(), 6);
}

TEST(DemoKeys, RRestartsTheCrowdAndAPausedRestartShowsAHint) {
  GK_REQUIRE_DISPLAY();
  const Shot restarted = run_demo("restart", kFew + "--frames 20 --input 12:key:r", kSmall);
  EXPECT_NEAR(restarted.report["time_s"].get<double>(), 8 * kStep_s, 1e-4);
  EXPECT_EQ(restarted.report["hint"].get<std::string>(), "");
  // Paused, then a new crowd: not an empty room without a word.
  const Shot hint = run_demo("restart_paused",
                             kFew + "--frames 12 --input 4:key:space --input 8:key:r", kSmall);
  EXPECT_NEAR(hint.report["time_s"].get<double>(), 0.0, 1e-9);
  EXPECT_NE(hint.report["hint"].get<std::string>().find("Space"), std::string::npos)
      << hint.report["hint"];
}

TEST(DemoMouse, AClickSelectsAnAgentAndTheCameraBringsItToTheCentre) {
  GK_REQUIRE_DISPLAY();
  // Same seed, one thread: the click at frame 20 sees the first run's last frame.
  const std::string crowd = "--scenario gallery --agents 12 --threads 1 ";
  const std::string size = "800x450";
  const Shot first = run_demo("click_before", crowd + "--frames 20", size);
  const int scene_w = first.report["scene_width"].get<int>();
  const double cx = scene_w / 2.0, cy = 225.0;
  int64_t target = -1;
  double tx = 0, ty = 0;
  for (const auto& a : first.report["agents"]) {
    const double x = a["px"].get<double>(), y = a["py"].get<double>();
    if (!a["in_front"].get<bool>() || x < 30 || y < 30 || x > scene_w - 30 || y > 420) continue;
    double nearest = 1e9;
    for (const auto& b : first.report["agents"]) {
      if (b["id"] == a["id"]) continue;
      nearest = std::min(nearest, std::hypot(b["px"].get<double>() - x, b["py"].get<double>() - y));
    }
    // Isolated, and far from the centre of the view before the click.
    if (nearest > 25.0 && std::hypot(x - cx, y - cy) > 40.0) {
      target = a["id"].get<int64_t>(), tx = x, ty = y;
      break;
    }
  }
  ASSERT_GE(target, 0) << "no isolated agent away from the centre";
  const double before_m = first.report["camera"]["distance_m"].get<double>();
  const Shot after = run_demo("click_follow",
                              crowd + "--frames 80 --input 20:click:" + std::to_string(tx) + "," +
                                  std::to_string(ty),
                              size);
  ASSERT_EQ(after.report["selected"].get<int64_t>(), target);
  EXPECT_TRUE(after.report["following"].get<bool>());
  bool found = false;
  for (const auto& a : after.report["agents"]) {
    if (a["id"].get<int64_t>() != target) continue;
    found = true;
    EXPECT_NEAR(a["px"].get<double>(), cx, 0.05 * 450) << after.report.dump();
    EXPECT_NEAR(a["py"].get<double>(), cy, 0.05 * 450);
  }
  EXPECT_TRUE(found);
  // Closing in on it (one second into a move from the overview to 8 m).
  EXPECT_LT(after.report["camera"]["distance_m"].get<double>(), 0.6 * before_m);
  // The screenshot: the selection ring (magenta) at the clicked agent's feet, now at the centre
  // of the view; before the click there is no ring anywhere in the scene.
  auto ring_pixels = [](const test::Image& img, int x0, int y0, int x1, int y1) {
    int n = 0;
    for (int y = std::max(0, y0); y < std::min(img.height, y1); ++y) {
      for (int x = std::max(0, x0); x < x1; ++x) {
        const glm::u8vec4 c = img.at(x, y);
        n += c.x > 200 && c.y < 110 && c.z > 170;
      }
    }
    return n;
  };
  const int ring_after = ring_pixels(after.image, static_cast<int>(cx) - 100,
                                     static_cast<int>(cy) - 20, static_cast<int>(cx) + 100,
                                     static_cast<int>(cy) + 140);
  const int ring_before = ring_pixels(first.image, 0, 0, scene_w, 450);
  EXPECT_GT(ring_after, 40) << "no selection ring under the clicked agent";
  EXPECT_LT(ring_before, 5) << "a ring before anything was selected";
}

OrbitCamera camera_of(const nlohmann::json& report) {
  OrbitCamera c;
  const auto& j = report["camera"];
  c.target = {j["target"][0].get<float>(), j["target"][1].get<float>(), j["target"][2].get<float>()};
  c.distance_m = j["distance_m"].get<float>();
  c.pitch_rad = j["pitch_rad"].get<float>();
  c.yaw_rad = j["yaw_rad"].get<float>();
  return c;
}

TEST(DemoMouse, TheWheelZoomsTowardTheCursor) {
  GK_REQUIRE_DISPLAY();
  const std::string still = kFew + "--frames 6 --input 0:key:space ";  // nothing moves
  const Shot before = run_demo("wheel_before", still, kSmall);
  const Shot after = run_demo("wheel_after", still + "--input 4:wheel:120,90,3", kSmall);
  const OrbitCamera a = camera_of(before.report), b = camera_of(after.report);
  const glm::ivec2 view(before.report["scene_width"].get<int>(), 360);
  EXPECT_NEAR(b.distance_m, a.distance_m * std::pow(0.88f, 3.0f), 1e-3f * a.distance_m);
  const std::optional<glm::vec3> ground = intersect_ground(a.pick_ray({120.0f, 90.0f}, view));
  ASSERT_TRUE(ground.has_value());
  const ProjectedPoint p = b.project(*ground, view);
  EXPECT_NEAR(p.pixel.x, 120.0f, 1.0f);
  EXPECT_NEAR(p.pixel.y, 90.0f, 1.0f);
  // Zooming toward the orbit target instead would have moved that point by tens of pixels.
  OrbitCamera centred = a;
  centred.zoom(std::pow(0.88f, 3.0f));
  EXPECT_GT(glm::length(centred.project(*ground, view).pixel - glm::vec2(120.0f, 90.0f)), 20.0f);
}

TEST(DemoShots, FollowKeepsTheSelectedAgentAtTheCentreThenPullsOut) {
  GK_REQUIRE_DISPLAY();
  const Shot follow = run_demo("follow", "--scenario crossing --agents 20 --select 3 --frames 30",
                               kSmall);
  const double cx = follow.report["scene_width"].get<int>() / 2.0;
  bool found = false;
  for (const auto& a : follow.report["agents"]) {
    if (a["id"].get<int64_t>() != 3) continue;
    found = true;
    EXPECT_NEAR(a["px"].get<double>(), cx, 0.04 * 360);
    EXPECT_NEAR(a["py"].get<double>(), 180.0, 0.04 * 360);
  }
  EXPECT_TRUE(found);
  EXPECT_NEAR(follow.report["camera"]["distance_m"].get<double>(), 8.0, 0.01);
  const Shot pulled = run_demo(
      "pull_out", "--scenario crossing --agents 20 --select 3 --pull-out 0.1 --frames 90", kSmall);
  EXPECT_FALSE(pulled.report["following"].get<bool>());
  EXPECT_GT(pulled.report["camera"]["distance_m"].get<double>(), 40.0);
  EXPECT_EQ(pulled.report["selected"].get<int64_t>(), 3) << "still selected, no longer followed";
}

TEST(DemoShots, ShowcaseOpensCloseOnAnAgentAtTheDoorInTheSplit) {
  GK_REQUIRE_DISPLAY();
  const Shot s = run_demo("showcase", "--frames 3", kSmall);
  EXPECT_EQ(s.report["scenario"].get<std::string>(), "bottleneck");
  EXPECT_EQ(s.report["agent_count"].get<int>(), 80) << "the scenario's own count";
  EXPECT_TRUE(s.report["compare"].get<bool>());
  EXPECT_TRUE(s.report["following"].get<bool>());
  EXPECT_NEAR(s.report["camera"]["distance_m"].get<double>(), 8.0, 0.01);
  const int64_t id = s.report["selected"].get<int64_t>();
  const double half = s.report["scene_width"].get<int>() / 2.0;
  for (const auto& a : s.report["agents"]) {
    if (a["id"].get<int64_t>() != id) continue;
    // The report gives the right (apm) half's pixels: the agent is at its centre.
    EXPECT_NEAR(a["px"].get<double>(), 1.5 * half, 0.05 * 360);
  }
}

TEST(DemoShots, ExhibitsAppearInTheirColour) {
  GK_REQUIRE_DISPLAY();
  const Shot shot = run_demo("exhibits", "--scenario gallery --agents 0 --frames 2");
  ASSERT_EQ(shot.report["exhibits"].size(), 4u);
  int shown = 0;
  for (const auto& e : shot.report["exhibits"]) {
    const int x = static_cast<int>(e["px"].get<double>()), y = static_cast<int>(e["py"].get<double>());
    const glm::u8vec4 c = shot.image.at(x, y);
    shown += e["in_front"].get<bool>() && c.z > c.x + 50 && c.y > c.x + 40;
  }
  EXPECT_GE(shown, 2) << "the far wall's exhibits face the camera in teal";
}

// The panel driven by clicks at the pixels of its widgets in a 1280x720 window (the layout of
// app/demo_panel.cc: if it changes, these positions must follow).
TEST(DemoPanel, ANewScenarioComesWithItsOwnAgentCountAndAPausedOneSaysSo) {
  GK_REQUIRE_DISPLAY();
  // Gallery with 6 agents, paused; the scenario combo opened, "circle" chosen from its list.
  const Shot s = run_demo("scenario_change",
                          "--scenario gallery --agents 6 --frames 10 --input 1:key:space "
                          "--input 3:click:1160,119 --input 6:click:1100,161",
                          "1280x720");
  EXPECT_EQ(s.report["scenario"].get<std::string>(), "circle") << s.report["status"];
  EXPECT_EQ(s.report["agent_count"].get<int>(), 24) << "circle.json's default_agents, not 6";
  EXPECT_NEAR(s.report["time_s"].get<double>(), 0.0, 1e-9);
  EXPECT_NE(s.report["hint"].get<std::string>().find("Space"), std::string::npos);
}

TEST(DemoPanel, TheFolderBrowserLoadsAFolderOfClips) {
  GK_REQUIRE_DISPLAY();
  GK_REQUIRE_DATA("clips/bvh/ual_walk_loop.bvh");
  const std::string data = test::data_dir();
  // A data folder whose clips/ holds two of the shared BVH clips: the browser opens there.
  const std::string root = test::scratch_dir("demo_browser");
  std::filesystem::remove_all(root + "/clips");
  std::filesystem::create_directories(root + "/clips");
  for (const char* name : {"ual_walk_loop.bvh", "ual_jog_fwd_loop.bvh"}) {
    std::filesystem::copy_file(data + "/clips/bvh/" + name, root + "/clips/" + name);
  }
  // Untick "built-in", press "browse...", then "this folder".
  const std::string dir = test::scratch_dir("demo");
  const test::CommandResult r = test::run_gaitkeeper(
      "demo --size 1280x720 --scenario gallery --agents 6 --frames 12 --input 2:click:1082,165 "
      "--input 5:click:940,211 --input 9:click:794,525 --report " + dir + "/browser.json",
      "GAITKEEPER_DATA=" + root + " ");
  ASSERT_EQ(r.code, 0) << r.out;
  std::ifstream in(dir + "/browser.json");
  const nlohmann::json report = nlohmann::json::parse(in);
  EXPECT_EQ(report["status"].get<std::string>(), "");
  std::string names;
  for (const auto& c : report["clips"]) names += c["name"].get<std::string>() + " ";
  EXPECT_NE(names.find("ual_walk_loop"), std::string::npos) << names;
  EXPECT_NE(names.find("ual_jog_fwd_loop"), std::string::npos) << names;
  EXPECT_EQ(names.find("walk_slow"), std::string::npos) << "the built-in set is gone: " << names;
}

// An IK-style rig with meaningless joint names (tests/ik_rig_fixture.h): loaded from the panel
// it is refused with the way out; with a role manifest chosen under it ("roles...", the same
// browser) it loads, and the panel shows the manifest in use.
// Pixels of the widgets in a 1280x720 window (app/demo_panel.cc, app/file_browser.cc).
const std::string kRolesButton = "940,257";  // "roles..." under the clip path
const std::string kFirstEntry = "420,214";   // the browser's first listed file
const std::string kOpenButton = "728,525";   // the browser's "open"

TEST(DemoPanel, ARoleManifestIsChosenInThePanel) {
  GK_REQUIRE_DISPLAY();
  const std::string root = test::scratch_dir("demo_roles");
  std::filesystem::remove_all(root + "/clips");
  std::filesystem::create_directories(root + "/clips");
  test::IkRigOptions o;
  o.known_names = false;
  const test::IkRig rig = test::make_ik_rig(o);
  ASSERT_TRUE(test::write_file(root + "/clips/ik_rig.glb", rig.glb));
  ASSERT_TRUE(test::write_file(root + "/clips/ik_rig_roles.json", rig.roles_json));
  const std::string dir = test::scratch_dir("demo");
  const std::string env = "GAITKEEPER_DATA=" + root + " ";
  const std::string demo = "demo --size 1280x720 --scenario gallery --agents 6 ";
  // Untick "built-in", press "browse...", then "this folder": refused, saying how.
  const std::string load_folder =
      "--input 2:click:1082,165 --input 5:click:940,211 --input 9:click:794,525 ";
  const test::CommandResult refused = test::run_gaitkeeper(
      demo + "--frames 12 " + load_folder + "--report " + dir + "/roles_refused.json", env);
  ASSERT_EQ(refused.code, 0) << refused.out;
  const nlohmann::json r1 = test::read_json(dir + "/roles_refused.json");
  EXPECT_NE(r1["status"].get<std::string>().find("--roles FILE.json"), std::string::npos)
      << r1["status"];
  EXPECT_EQ(r1["roles"].get<std::string>(), "");
  // Untick "built-in", press "roles...", pick the manifest and "open", then load the folder.
  const test::CommandResult loaded = test::run_gaitkeeper(
      demo + "--frames 24 --input 2:click:1082,165 --input 5:click:" + kRolesButton +
          " --input 8:click:" + kFirstEntry + " --input 11:click:" + kOpenButton +
          " --input 14:click:940,211 --input 18:click:794,525 --report " + dir +
          "/roles_loaded.json",
      env);
  ASSERT_EQ(loaded.code, 0) << loaded.out;
  const nlohmann::json r2 = test::read_json(dir + "/roles_loaded.json");
  EXPECT_EQ(r2["status"].get<std::string>(), "");
  EXPECT_EQ(r2["roles"].get<std::string>(), root + "/clips/ik_rig_roles.json");
  std::string names;
  for (const auto& c : r2["clips"]) names += c["name"].get<std::string>() + " ";
  EXPECT_NE(names.find("walk_fast"), std::string::npos) << names;
  EXPECT_TRUE(r2["clips_left_out"].empty()) << r2["clips_left_out"].dump();
}

}  // namespace
}  // namespace gk
