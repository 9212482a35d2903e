#include "mediator/foot_slide_stream.h"

#include <algorithm>
#include <cassert>
#include <climits>
#include <cmath>

namespace gk {

FootSlideStream::FootSlideStream(size_t num_feet, float dt_s)
    : dt_s_(dt_s),
      lag_frames_(std::max(1, static_cast<int>(std::lround(kLag_s / dt_s)))),
      ring_size_(lag_frames_ + 1),
      feet_(num_feet),
      ring_(num_feet * static_cast<size_t>(ring_size_)) {}

void FootSlideStream::start(size_t foot) {
  if (feet_[foot].active) end(foot);
  feet_[foot] = Foot();
  feet_[foot].active = true;
}

void FootSlideStream::add(size_t foot, const glm::vec3& toe, float ankle_y) {
  Foot& f = feet_[foot];
  assert(f.active);
  ring_[foot * ring_size_ + static_cast<size_t>(f.added % ring_size_)] = {toe, ankle_y};
  f.min_toe_y = f.added == 0 ? toe.y : std::min(f.min_toe_y, toe.y);
  f.min_ankle_y = f.added == 0 ? ankle_y : std::min(f.min_ankle_y, ankle_y);
  ++f.added;
  // Frame t is decided once frame t + lag has come, against the lowest heights so far.
  if (f.added - f.decided > lag_frames_) {
    decide(f, ring_at(foot, f.decided), totals_);
  }
}

void FootSlideStream::end(size_t foot) {
  Foot& f = feet_[foot];
  if (!f.active) return;
  finish_foot(foot, f, totals_);
  f.active = false;
}

// METRICS.md's contact and the slide of SlideAccumulator::add_track_with_contacts, one frame at a
// time, in the same float arithmetic.
void FootSlideStream::decide(Foot& f, const Frame& x, Totals& t) const {
  const bool contact =
      x.toe.y <= f.min_toe_y + kToeBandM && x.ankle_y <= f.min_ankle_y + kAnkleBandM;
  const glm::vec2 xz(x.toe.x, x.toe.z);
  auto horizontal = [](const glm::vec2& a, const glm::vec2& b) {
    return std::hypot(a.x - b.x, a.y - b.y);
  };
  if (contact) {
    f.max_contact_toe_y = std::max(f.max_contact_toe_y, x.toe.y);
    f.max_contact_ankle_y = std::max(f.max_contact_ankle_y, x.ankle_y);
    if (!f.in_run) {
      f.in_run = true;
      f.run_start_xz = xz;
      f.run_frames = 0;
    }
    ++f.run_frames;
    if (f.prev_contact) {
      const float v = 100.0f * horizontal(xz, f.prev_xz) / dt_s_;
      t.speeds_cm_s.add(v);
      t.speed_sum_cm_s += v;
      t.skating += v > kSkateCmS;
    }
  } else if (f.in_run) {
    // The run ended on the previous frame; an interval is at least two contact frames.
    if (f.run_frames >= 2) {
      t.drift_sum_cm += 100.0 * horizontal(f.prev_xz, f.run_start_xz);
      ++t.intervals;
    }
    f.in_run = false;
  }
  f.prev_contact = contact;
  f.prev_xz = xz;
  ++f.decided;
}

void FootSlideStream::finish_foot(size_t foot, Foot& f, Totals& t) const {
  while (f.decided < f.added) decide(f, ring_at(foot, f.decided), t);
  if (f.in_run && f.run_frames >= 2) {
    t.drift_sum_cm +=
        100.0 * std::hypot(f.prev_xz.x - f.run_start_xz.x, f.prev_xz.y - f.run_start_xz.y);
    ++t.intervals;
  }
  f.in_run = false;
  // How far above METRICS.md's band (from the whole track's lowest heights) a frame counted in
  // contact lay: only frames decided before a later, lower height can.
  t.toe_excess_m = std::max(t.toe_excess_m, f.max_contact_toe_y - (f.min_toe_y + kToeBandM));
  t.ankle_excess_m =
      std::max(t.ankle_excess_m, f.max_contact_ankle_y - (f.min_ankle_y + kAnkleBandM));
}

FootSlideResult FootSlideStream::finish() const {
  Totals t = totals_;
  for (size_t i = 0; i < feet_.size(); ++i) {
    if (!feet_[i].active) continue;
    Foot f = feet_[i];
    finish_foot(i, f, t);
  }
  FootSlideResult r;
  r.samples = static_cast<int64_t>(t.speeds_cm_s.count());
  r.intervals = t.intervals;
  r.toe_band_excess_m = t.toe_excess_m;
  r.ankle_band_excess_m = t.ankle_excess_m;
  SlideStats& s = r.stats;
  s.num_samples = static_cast<int>(std::min<int64_t>(r.samples, INT_MAX));
  if (r.samples > 0) {
    const double n = static_cast<double>(r.samples);
    s.mean_cm_s = static_cast<float>(t.speed_sum_cm_s / n);
    s.skate_ratio = static_cast<float>(static_cast<double>(t.skating) / n);
    s.p95_cm_s = static_cast<float>(t.speeds_cm_s.nearest_rank(0.95));
  }
  if (t.intervals > 0) {
    s.drift_cm_per_step = static_cast<float>(t.drift_sum_cm / static_cast<double>(t.intervals));
  }
  return r;
}

}  // namespace gk
