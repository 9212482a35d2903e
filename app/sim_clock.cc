#include "app/sim_clock.h"

#include <algorithm>
#include <cmath>

#include "app/crowd_setup.h"

namespace gk::app {
namespace {

// A frame a little short of a whole step still runs it (and owes the difference): a 60 Hz
// display's frame times jitter around one step, which would otherwise run 0, 2, 1, ... steps.
constexpr double kJitter = 0.1;

}  // namespace

double SimClock::step_s(double time_scale) { return kFrameTime_s * std::min(time_scale, 1.0); }

int SimClock::begin_frame(double real_dt_s, double time_scale) {
  real_dt_s = std::clamp(real_dt_s, 0.0, kMaxFrameTime_s);
  time_scale = std::max(time_scale, 1e-3);
  if (time_scale != time_scale_) measured_ = false, window_real_s_ = window_sim_s_ = 0.0;
  time_scale_ = time_scale;
  step_s_ = step_s(time_scale);
  // In steps rather than seconds: a scripted frame of exactly kFrameTime_s adds exactly 1.0 (the
  // same product on both sides of the division), so scripted runs step once per frame.
  accumulator_steps_ += real_dt_s * time_scale / step_s_;
  window_real_s_ += real_dt_s;
  pending_steps_ = static_cast<int>(std::floor(accumulator_steps_ + kJitter));
  pending_steps_ = std::min(pending_steps_, kMaxStepsPerFrame);
  return pending_steps_;
}

void SimClock::end_frame(int steps_run) {
  steps_run = std::clamp(steps_run, 0, pending_steps_);
  accumulator_steps_ -= steps_run;
  // Whatever could not run this frame (the cap, the caller's budget) is dropped, not owed.
  if (steps_run < pending_steps_ || accumulator_steps_ + kJitter >= 1.0) accumulator_steps_ = 0.0;
  window_sim_s_ += steps_run * step_s_;
  pending_steps_ = 0;
  if (window_real_s_ >= kMeasureWindow_s) {
    achieved_rate_ = window_sim_s_ / window_real_s_;
    measured_ = true;
    window_real_s_ = window_sim_s_ = 0.0;
  }
}

void SimClock::reset() {
  accumulator_steps_ = 0.0;
  pending_steps_ = 0;
  window_real_s_ = window_sim_s_ = 0.0;
  measured_ = false;
  achieved_rate_ = 0.0;
}

}  // namespace gk::app
