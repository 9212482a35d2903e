#pragma once
// The demo window's simulation clock: a fixed simulation step decoupled from the draw rate. Each
// drawn frame adds its wall-clock time (times the time scale) to an accumulator and runs as many
// whole steps as it holds, at most kMaxStepsPerFrame; what a slow machine cannot run is dropped,
// and the rate actually achieved is measured so the window can say when it falls behind
// ("simulation at 0.4x real time").

namespace gk::app {

class SimClock {
 public:
  static constexpr int kMaxStepsPerFrame = 8;
  static constexpr double kMaxFrameTime_s = 0.25;  // a stall (window drag) counts as this much
  static constexpr double kMeasureWindow_s = 0.5;  // wall time over which the rate is measured

  // Simulated seconds per step: 1/60 s, smaller in slow motion (time scale < 1) so the crowd
  // still moves at every drawn frame of a 60 Hz display.
  static double step_s(double time_scale);

  // Steps to run for a frame that took `real_dt_s` of wall time at `time_scale` (> 0).
  int begin_frame(double real_dt_s, double time_scale);
  // After the frame's steps: `steps_run` of the `begin_frame` steps ran (fewer when the caller's
  // time budget ran out). The rest is dropped, not carried: a machine that cannot keep up
  // shows slow motion rather than a growing backlog.
  void end_frame(int steps_run);
  // Paused, or a new crowd: nothing is owed, and the measurement starts over.
  void reset();

  // Simulated seconds per wall-clock second over the last measured window (includes the time
  // scale: 0.5 in half-speed slow motion); 0 before a window was measured.
  double achieved_rate() const { return achieved_rate_; }
  // True when the achieved rate is under 90% of the time scale asked for.
  bool behind() const { return measured_ && achieved_rate_ < 0.9 * time_scale_; }

 private:
  double accumulator_steps_ = 0.0;  // owed simulation time, in steps
  int pending_steps_ = 0;
  double step_s_ = 0.0;
  double time_scale_ = 1.0;
  double window_real_s_ = 0.0, window_sim_s_ = 0.0;
  double achieved_rate_ = 0.0;
  bool measured_ = false;
};

}  // namespace gk::app
