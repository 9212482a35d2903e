// The follow camera: springs that track a moving goal without lag, a walking and turning agent
// kept at the image centre, the pull-out to the overview, and a user who takes the camera.
#include <cmath>

#include <gtest/gtest.h>
#include <glm/gtc/constants.hpp>

#include "app/camera_director.h"

namespace gk::app {
namespace {

constexpr float kDt = 1.0f / 60.0f;

TEST(Spring, TracksAGoalMovingAtConstantVelocityWithoutLag) {
  float x = 0.0f, v = 0.0f;
  for (int f = 0; f < 600; ++f) {
    const float goal = 5.0f + 1.5f * f * kDt;
    spring_step(&x, &v, goal, 1.5f, 0.2f, kDt);
  }
  EXPECT_NEAR(x, 5.0f + 1.5f * 600 * kDt, 1e-3f);  // the step lands on the goal of its end
  EXPECT_NEAR(v, 1.5f, 1e-3f);
  // A still goal: about half the gap is left after one half-life (critical damping overshoots
  // the plain exponential a little), and no overshoot past the goal.
  x = 1.0f, v = 0.0f;
  float lowest = 1.0f;
  for (int f = 0; f < 12; ++f) spring_step(&x, &v, 0.0f, 0.0f, 0.2f, kDt);
  EXPECT_GT(x, 0.4f);
  EXPECT_LT(x, 0.75f);
  for (int f = 0; f < 600; ++f) {
    spring_step(&x, &v, 0.0f, 0.0f, 0.2f, kDt);
    lowest = std::min(lowest, x);
  }
  EXPECT_GE(lowest, -1e-6f);
  // Exact, not an integration: one step of 0.1 s equals six of 1/60 s.
  float a = 1.0f, va = 0.3f, b = 1.0f, vb = 0.3f;
  spring_step(&a, &va, 2.0f, 0.5f, 0.3f, 0.1f);
  for (int k = 0; k < 6; ++k) spring_step(&b, &vb, 2.0f + 0.5f * k * (0.1f / 6), 0.5f, 0.3f, 0.1f / 6);
  EXPECT_NEAR(a, b, 1e-4f);
}

// An agent walking at 1.4 m/s that turns through 90 degrees over 2 s, followed from 8 m.
TEST(CameraDirector, KeepsAWalkingAndTurningAgentAtTheImageCentre) {
  OrbitCamera camera;
  camera.yaw_rad = 0.6f;
  camera.distance_m = 40.0f;  // starts far out: the camera closes in
  CameraDirector director;
  director.set_overview(camera);
  director.follow(7);
  const glm::ivec2 view(640, 720);
  glm::vec3 p(0.0f);
  float heading = 0.0f, worst_px = 0.0f;
  for (int f = 0; f < 600; ++f) {
    const float t = f * kDt;
    if (t > 4.0f && t < 6.0f) heading += glm::half_pi<float>() / 2.0f * kDt;
    const glm::vec2 v = 1.4f * glm::vec2(std::sin(heading), std::cos(heading));
    p += glm::vec3(v.x, 0.0f, v.y) * kDt;
    director.update(t, kDt, FollowedAgent{p, v}, &camera);
    const ProjectedPoint hips = camera.project(p + glm::vec3(0.0f, kFollowHeight_m, 0.0f), view);
    ASSERT_TRUE(hips.in_front);
    if (t > 3.0f) worst_px = std::max(worst_px, glm::length(hips.pixel - glm::vec2(320, 360)));
  }
  EXPECT_NEAR(camera.distance_m, kFollowDistance_m, 0.05f);
  EXPECT_NEAR(camera.pitch_rad, kFollowPitch_rad, 1e-2f);
  EXPECT_NEAR(camera.yaw_rad, 0.6f, 1e-6f) << "following does not turn the view";
  // Within 3% of the image height of the centre, turning included (a camera trailing by a
  // quarter second would be ~60 px off).
  EXPECT_LT(worst_px, 0.03f * 720) << worst_px;
}

TEST(CameraDirector, PullsOutToTheOverviewAtItsTimeAndWhenTheAgentLeaves) {
  OrbitCamera overview;
  overview.target = {3.0f, 0.0f, -2.0f};
  overview.distance_m = 45.0f;
  overview.pitch_rad = 0.7f;
  overview.yaw_rad = 2.5f;
  OrbitCamera camera = overview;
  CameraDirector director;
  director.set_overview(overview);
  director.follow(1);
  director.snap();
  director.pull_out_at(2.0);
  const FollowedAgent still{glm::vec3(-4.0f, 0.0f, 1.0f), glm::vec2(0.0f)};
  director.update(0.0, kDt, still, &camera);
  EXPECT_FLOAT_EQ(camera.distance_m, kFollowDistance_m);  // snapped onto the agent
  for (int f = 1; f < 110; ++f) director.update(f * kDt, kDt, still, &camera);
  EXPECT_NEAR(camera.distance_m, kFollowDistance_m, 1e-3f) << "no pull-out before 2 s";
  EXPECT_TRUE(director.following());
  for (int f = 110; f < 600; ++f) director.update(f * kDt, kDt, still, &camera);
  EXPECT_FALSE(director.following());
  EXPECT_NEAR(camera.distance_m, overview.distance_m, 0.5f);
  EXPECT_NEAR(glm::length(camera.target - overview.target), 0.0f, 0.1f);
  EXPECT_NEAR(std::remainder(camera.yaw_rad - overview.yaw_rad, 6.2831853f), 0.0f, 0.02f);

  // The agent leaves the scene: nothing to follow, the camera pulls out.
  CameraDirector leaving;
  leaving.set_overview(overview);
  leaving.follow(2);
  leaving.snap();
  camera = overview;
  leaving.update(0.0, kDt, still, &camera);
  for (int f = 1; f < 400; ++f) leaving.update(f * kDt, kDt, std::nullopt, &camera);
  EXPECT_FALSE(leaving.following());
  EXPECT_NEAR(camera.distance_m, overview.distance_m, 0.5f);

  // A replayed pedestrian that has not appeared yet is waited for.
  CameraDirector waiting;
  waiting.follow(3);
  camera = overview;
  for (int f = 0; f < 60; ++f) waiting.update(f * kDt, kDt, std::nullopt, &camera);
  EXPECT_TRUE(waiting.following());
  EXPECT_EQ(camera.target, overview.target);
}

TEST(CameraDirector, AUserWhoTakesTheCameraCancelsThePullOut) {
  OrbitCamera overview;
  overview.distance_m = 45.0f;
  OrbitCamera camera = overview;
  CameraDirector director;
  director.set_overview(overview);
  director.follow(1);
  director.snap();
  director.pull_out_at(1.0);
  const FollowedAgent still{glm::vec3(0.0f), glm::vec2(0.0f)};
  director.update(0.0, kDt, still, &camera);
  camera.zoom(0.5f);  // the user zooms in to 4 m
  director.user_took_camera();
  for (int f = 1; f < 300; ++f) director.update(f * kDt, kDt, still, &camera);
  EXPECT_TRUE(director.following());
  EXPECT_NEAR(camera.distance_m, 0.5f * kFollowDistance_m, 1e-4f);
}

// The feedback lesson: the same agent in two halves under one camera, the left one carried 1.2 m/s
// faster than the right one, seen from behind. Followed alone, the one running ahead leaves the
// top of the image within seconds; with the twin both stay in view, feet and label, while the
// camera backs away; a user who zooms keeps the distance they chose.
TEST(CameraDirector, KeepsBothPlacesOfATwinInView) {
  const glm::ivec2 view(480, 540);
  auto run = [&](bool twin, bool zoom, float* worst_top, float* distance) {
    OrbitCamera camera;
    camera.yaw_rad = -glm::half_pi<float>();  // behind agents walking along +x
    CameraDirector director;
    director.set_view(view);
    director.set_overview(camera);
    director.follow(3, 7.0f, kFollowPitch_rad);
    director.snap();
    *worst_top = 1e9f;
    for (int f = 0; f < 600; ++f) {
      const float t = f * kDt;
      const glm::vec3 slow(1.8f * t, 0.0f, 0.0f), fast(3.0f * t, 0.0f, 0.0f);
      FollowedAgent a{slow, {1.8f, 0.0f}};
      if (twin) a.twin = fast;
      if (zoom && f == 300) {
        director.user_took_camera();
        camera.distance_m = 6.0f;
      }
      director.update(t, kDt, a, &camera);
      if (f >= 300 || zoom) continue;
      for (const glm::vec3& p : {slow, fast}) {
        const ProjectedPoint head = camera.project(p + glm::vec3(0.0f, 2.2f, 0.0f), view);
        const ProjectedPoint feet = camera.project(p, view);
        ASSERT_TRUE(head.in_front && feet.in_front);
        *worst_top = std::min(*worst_top, head.pixel.y);
        if (twin) {
          EXPECT_LT(feet.pixel.y, view.y) << "frame " << f;
          EXPECT_GT(head.pixel.x, 0.0f);
          EXPECT_LT(head.pixel.x, view.x);
        }
      }
    }
    *distance = camera.distance_m;
  };
  float top_alone = 0.0f, top_twin = 0.0f, d_alone = 0.0f, d_twin = 0.0f, d_zoom = 0.0f, unused;
  run(false, false, &top_alone, &d_alone);
  run(true, false, &top_twin, &d_twin);
  run(true, true, &unused, &d_zoom);
  EXPECT_LT(top_alone, 0.0f) << "alone, the runner ahead leaves the image: the check can fail";
  EXPECT_GT(top_twin, 0.0f);
  EXPECT_NEAR(d_alone, 7.0f, 1e-3f);
  EXPECT_GT(d_twin, 9.0f) << "10 s apart at 1.2 m/s: the camera backed away";
  EXPECT_NEAR(d_zoom, 6.0f, 1e-3f) << "the user's zoom is kept";
}

}  // namespace
}  // namespace gk::app
