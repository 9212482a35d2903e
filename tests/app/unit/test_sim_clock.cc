// The demo's fixed-step clock: steps per drawn frame at various frame rates and time scales, the
// backlog a slow machine cannot run is dropped, and the achieved rate says when it falls behind.
#include <gtest/gtest.h>

#include "app/crowd_setup.h"
#include "app/sim_clock.h"

namespace gk::app {
namespace {

// Runs `frames` frames of `frame_s` each, running at most `can_run` of the steps asked for (the
// caller's time budget); returns the steps run.
int run(SimClock* clock, int frames, double frame_s, double time_scale, int can_run = 1000) {
  int total = 0;
  for (int f = 0; f < frames; ++f) {
    const int asked = clock->begin_frame(frame_s, time_scale);
    const int ran = std::min(asked, can_run);
    clock->end_frame(ran);
    total += ran;
  }
  return total;
}

TEST(SimClock, OneStepPerFrameAtSixtyHertzAndTwoAtThirty) {
  SimClock clock;
  EXPECT_EQ(run(&clock, 120, kFrameTime_s, 1.0), 120);  // exactly one per frame, none skipped
  EXPECT_NEAR(clock.achieved_rate(), 1.0, 1e-9);
  EXPECT_FALSE(clock.behind());
  SimClock slow_display;
  for (int f = 0; f < 60; ++f) {
    ASSERT_EQ(slow_display.begin_frame(2.0 * kFrameTime_s, 1.0), 2) << "frame " << f;
    slow_display.end_frame(2);
  }
  EXPECT_NEAR(slow_display.achieved_rate(), 1.0, 1e-9);
  EXPECT_FALSE(slow_display.behind());
}

TEST(SimClock, DisplayJitterStillStepsOncePerFrame) {
  // A 60 Hz display whose frame times wobble by +-3%: no frame runs 0 or 2 steps.
  SimClock clock;
  for (int f = 0; f < 200; ++f) {
    const double dt = kFrameTime_s * (f % 2 ? 1.03 : 0.97);
    ASSERT_EQ(clock.begin_frame(dt, 1.0), 1) << "frame " << f;
    clock.end_frame(1);
  }
}

TEST(SimClock, SlowMotionTakesSmallerStepsAndFastForwardMoreOfThem) {
  EXPECT_DOUBLE_EQ(SimClock::step_s(0.25), kFrameTime_s * 0.25);
  EXPECT_DOUBLE_EQ(SimClock::step_s(2.0), kFrameTime_s);
  SimClock slow;
  EXPECT_EQ(run(&slow, 60, kFrameTime_s, 0.25), 60);  // still one (smaller) step per frame
  EXPECT_NEAR(slow.achieved_rate(), 0.25, 1e-9);
  EXPECT_FALSE(slow.behind()) << "slow motion asked for is not falling behind";
  SimClock fast;
  EXPECT_EQ(run(&fast, 60, kFrameTime_s, 2.0), 120);
  EXPECT_NEAR(fast.achieved_rate(), 2.0, 1e-9);
}

TEST(SimClock, AMachineThatCannotKeepUpIsBehindAndOwesNothing) {
  // Frames of 0.2 s would need 12 steps each; 8 run, the rest is dropped.
  SimClock capped;
  EXPECT_EQ(run(&capped, 10, 0.2, 1.0), 10 * SimClock::kMaxStepsPerFrame);
  EXPECT_NEAR(capped.achieved_rate(), 8.0 * kFrameTime_s / 0.2, 1e-6);
  EXPECT_TRUE(capped.behind());
  // Steps so slow that the caller's time budget runs out after one step per frame.
  SimClock budget;
  run(&budget, 30, 4.0 * kFrameTime_s, 1.0, /*can_run=*/1);
  EXPECT_NEAR(budget.achieved_rate(), 0.25, 1e-6);
  EXPECT_TRUE(budget.behind());
  // Once the machine is fast again nothing of the dropped backlog is run.
  EXPECT_EQ(budget.begin_frame(kFrameTime_s, 1.0), 1);
  budget.end_frame(1);
  EXPECT_EQ(run(&budget, 60, kFrameTime_s, 1.0), 60);
  EXPECT_FALSE(budget.behind());
  // A stall (a dragged window) counts as kMaxFrameTime_s at most.
  SimClock stall;
  EXPECT_EQ(stall.begin_frame(30.0, 1.0), SimClock::kMaxStepsPerFrame);
  // Paused: nothing is owed afterwards.
  stall.reset();
  EXPECT_EQ(stall.begin_frame(kFrameTime_s, 1.0), 1);
}

}  // namespace
}  // namespace gk::app
