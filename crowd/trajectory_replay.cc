#include "crowd/trajectory_replay.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numeric>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>

#include "common/ascii.h"
#include "common/stats.h"
#include "crowd/trajectory_file.h"

namespace gk {
namespace {

constexpr float kPi = 3.14159265358979f;
// Time tolerance [s] for "is a pedestrian live now": stepping by exactly the frame time must land
// on a sample despite the rounding of summed float steps. Far below any frame period.
constexpr double kTimeEpsilon_s = 1e-4;
// Below this speed [m/s] the heading of the velocity is mostly annotation noise: hold theta.
constexpr float kHeadingMinSpeed_m_s = 0.1f;
// A heading is taken only from a velocity this many times its noise (heading_speed).
constexpr float kHeadingNoiseSigmas = 3.0f;
// Time constant [s] of the exponential smoothing of theta toward the velocity heading. Short: the
// interpolant is already smooth; this only rounds off the turn-on-the-spot of slow walkers.
constexpr float kThetaTau_s = 0.15f;

// Into [-pi, pi]; angles already there are returned unchanged (no fmod rounding).
float wrap_angle(float a) {
  if (a >= -kPi && a <= kPi) return a;
  a = std::fmod(a + kPi, 2.0f * kPi);
  if (a < 0.0f) a += 2.0f * kPi;
  return a - kPi;
}

// theta is about +y with 0 facing +z and pi/2 facing +x.
float heading_of(glm::vec2 v) { return std::atan2(v.x, v.y); }

// Monotone (PCHIP, Fritsch-Butland) slope from the two neighbouring secants on a non-uniform
// grid: zero at a local extremum, so the curve never overshoots the recorded samples on that axis.
float pchip_slope(float d0, float d1, double h0, double h1) {
  if (d0 * d1 <= 0.0f) return 0.0f;
  const double w0 = 2.0 * h1 + h0;
  const double w1 = h1 + 2.0 * h0;
  return static_cast<float>((w0 + w1) / (w0 / d0 + w1 / d1));
}

class TrajectoryReplay final : public CrowdSource {
 public:
  TrajectoryReplay(std::string name, const TrajectoryTable& table, double frame_time_s, bool loop);

  std::string name() const override { return name_; }
  Status step(float dt_s) override;
  AgentFrame frame() const override {
    return AgentFrame{std::span<const uint32_t>(out_ids_.data(), num_live_),
                      std::span<const glm::vec2>(out_positions_.data(), num_live_),
                      std::span<const glm::vec2>(out_velocities_.data(), num_live_),
                      std::span<const float>(out_thetas_.data(), num_live_)};
  }
  FeedbackPolicy feedback_policy() const override { return FeedbackPolicy::kIgnored; }
  Status apply_feedback(const AgentFeedback&) override { return Status::Ok(); }
  double time_s() const override { return time_s_; }
  size_t capacity() const override { return out_ids_.size(); }

 private:
  // The speed [m/s] above which track [begin, end)'s heading is its walking direction rather than
  // its samples' jitter: kHeadingMinSpeed_m_s, or three times the velocity noise its positions'
  // jitter makes (the jitter from the second differences of its evenly spaced samples, as clip
  // analysis takes a capture's: sigma_from_second_differences).
  float heading_speed(uint32_t begin, uint32_t end) const {
    std::vector<float> d2, steps;
    for (uint32_t i = begin + 1; i + 1 < end; ++i) {
      const double h0 = sample_time_s_[i] - sample_time_s_[i - 1];
      const double h1 = sample_time_s_[i + 1] - sample_time_s_[i];
      if (!(h0 > 0.0) || std::abs(h1 - h0) > 1e-3 * h0) continue;  // a gap: not a second difference
      d2.push_back(glm::length(sample_pos_[i + 1] - 2.0f * sample_pos_[i] + sample_pos_[i - 1]));
      steps.push_back(static_cast<float>(h0));
    }
    if (d2.size() < 3) return kHeadingMinSpeed_m_s;
    // The velocity between two samples h apart has a noise of sqrt(2) sigma / h per axis.
    const float noise =
        std::sqrt(2.0f) * sigma_from_second_differences(std::move(d2)) / percentile(steps, 0.5);
    return std::max(kHeadingMinSpeed_m_s, kHeadingNoiseSigmas * noise);
  }
  void update_live(float dt_s);

  std::string name_;
  // Tracks, sorted by first sample time. Samples of track k: [sample_begin_[k], sample_end_[k]).
  std::vector<uint32_t> track_ids_;
  std::vector<uint32_t> sample_begin_, sample_end_;
  std::vector<float> initial_theta_;
  // Per track: theta follows v only faster than this [m/s] (kHeadingMinSpeed_m_s, or more for a
  // track whose samples jitter: heading_speed).
  std::vector<float> heading_speed_;
  // Samples: time [s], position (x, z) [m], C1 Hermite tangent [m/s].
  std::vector<double> sample_time_s_;
  std::vector<glm::vec2> sample_pos_;
  std::vector<glm::vec2> sample_tangent_;
  // Per-track state: current segment (first sample index) and smoothed theta.
  std::vector<uint32_t> cursor_;
  std::vector<float> theta_;
  // Live tracks in order of appearance; sized to capacity at creation.
  std::vector<uint32_t> live_;
  size_t num_live_ = 0;
  uint32_t next_start_ = 0;
  double time_s_ = 0.0;
  // Looping: the file's time is time_s_ - loop_start_s_; it starts over after period_s_.
  bool loop_ = false;
  double period_s_ = 0.0;
  double loop_start_s_ = 0.0;
  std::vector<uint32_t> out_ids_;
  std::vector<glm::vec2> out_positions_, out_velocities_;
  std::vector<float> out_thetas_;
};

TrajectoryReplay::TrajectoryReplay(std::string name, const TrajectoryTable& table,
                                   double frame_time_s, bool loop)
    : name_(std::move(name)), loop_(loop) {
  const size_t num_tracks = table.num_tracks();
  const size_t num_samples = table.frames.size();
  // The file's (x, y) become our (x, z) as they are (see the header): metres stay metres and the
  // recorded numbers can be checked against the file directly.
  std::vector<double> times(num_samples);
  for (size_t i = 0; i < num_samples; ++i) {
    times[i] = static_cast<double>(table.frames[i] - table.first_frame) /
               static_cast<double>(table.frame_step) * frame_time_s;
  }
  std::vector<uint32_t> order(num_tracks);
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    return times[table.track_begin[a]] < times[table.track_begin[b]];
  });

  sample_time_s_.reserve(num_samples);
  sample_pos_.reserve(num_samples);
  sample_tangent_.resize(num_samples);
  for (uint32_t k : order) {
    const uint32_t begin = static_cast<uint32_t>(sample_time_s_.size());
    for (uint32_t i = table.track_begin[k]; i < table.track_begin[k + 1]; ++i) {
      sample_time_s_.push_back(times[i]);
      sample_pos_.push_back(table.positions[i]);
    }
    const uint32_t end = static_cast<uint32_t>(sample_time_s_.size());
    track_ids_.push_back(table.ped_ids[k]);
    sample_begin_.push_back(begin);
    sample_end_.push_back(end);
    // Tangents: one-sided secant at the ends (the pedestrian enters and leaves walking), monotone
    // slopes inside. Gaps (missing frames) are just longer intervals of the same spline.
    float theta0 = 0.0f;
    bool have_theta0 = false;
    const float min_speed = heading_speed(begin, end);
    heading_speed_.push_back(min_speed);
    for (uint32_t i = begin; i < end; ++i) {
      glm::vec2 m(0.0f);
      if (end - begin >= 2) {
        const uint32_t lo = (i == begin) ? i : i - 1;
        const uint32_t hi = (i + 1 == end) ? i : i + 1;
        if (i == begin || i + 1 == end) {
          m = (sample_pos_[hi] - sample_pos_[lo]) /
              static_cast<float>(sample_time_s_[hi] - sample_time_s_[lo]);
        } else {
          const double h0 = sample_time_s_[i] - sample_time_s_[i - 1];
          const double h1 = sample_time_s_[i + 1] - sample_time_s_[i];
          const glm::vec2 d0 = (sample_pos_[i] - sample_pos_[i - 1]) / static_cast<float>(h0);
          const glm::vec2 d1 = (sample_pos_[i + 1] - sample_pos_[i]) / static_cast<float>(h1);
          m = glm::vec2(pchip_slope(d0.x, d1.x, h0, h1), pchip_slope(d0.y, d1.y, h0, h1));
        }
      }
      sample_tangent_[i] = m;
      if (!have_theta0 && glm::length(m) >= min_speed) {
        theta0 = heading_of(m);
        have_theta0 = true;
      }
    }
    initial_theta_.push_back(theta0);
  }

  // Capacity: the largest number of overlapping (tolerance-widened) live intervals.
  std::vector<double> starts(num_tracks), ends(num_tracks);
  for (size_t k = 0; k < num_tracks; ++k) {
    starts[k] = sample_time_s_[sample_begin_[k]] - kTimeEpsilon_s;
    ends[k] = sample_time_s_[sample_end_[k] - 1] + kTimeEpsilon_s;
  }
  std::sort(starts.begin(), starts.end());
  std::sort(ends.begin(), ends.end());
  size_t capacity = 0;
  for (size_t i = 0, j = 0; i < num_tracks; ++i) {
    while (j < num_tracks && ends[j] < starts[i]) ++j;
    capacity = std::max(capacity, i + 1 - j);
  }

  cursor_.assign(sample_begin_.begin(), sample_begin_.end());
  theta_.assign(initial_theta_.begin(), initial_theta_.end());
  // One sample step after the last sample: every pedestrian has left (their live intervals end
  // kTimeEpsilon_s after their last sample) before anyone comes back.
  double last_s = 0.0;
  for (double t : sample_time_s_) last_s = std::max(last_s, t);
  period_s_ = last_s + frame_time_s;
  live_.resize(capacity);
  out_ids_.resize(capacity);
  out_positions_.resize(capacity);
  out_velocities_.resize(capacity);
  out_thetas_.resize(capacity);
  update_live(0.0f);
}

Status TrajectoryReplay::step(float dt_s) {
  if (!std::isfinite(dt_s) || dt_s <= 0.0f) {
    return Status::Error(name_ + ": step: expected a finite dt > 0 s, found " +
                         std::to_string(dt_s));
  }
  time_s_ += dt_s;
  update_live(dt_s);
  return Status::Ok();
}

void TrajectoryReplay::update_live(float dt_s) {
  if (loop_) {
    while (time_s_ - loop_start_s_ >= period_s_) {
      // Everyone has left (see period_s_): start over from the file's first frame.
      loop_start_s_ += period_s_;
      num_live_ = 0;
      next_start_ = 0;
      cursor_.assign(sample_begin_.begin(), sample_begin_.end());
      theta_.assign(initial_theta_.begin(), initial_theta_.end());
    }
  }
  const double t = time_s_ - loop_start_s_;
  // Drop tracks past their last sample, keeping the order of the others.
  size_t kept = 0;
  for (size_t i = 0; i < num_live_; ++i) {
    const uint32_t k = live_[i];
    if (sample_time_s_[sample_end_[k] - 1] + kTimeEpsilon_s >= t) live_[kept++] = k;
  }
  num_live_ = kept;
  // Start the tracks whose first sample has come; a track that began and ended within one step is
  // never shown.
  const size_t first_new = num_live_;
  const uint32_t num_tracks = static_cast<uint32_t>(track_ids_.size());
  while (next_start_ < num_tracks &&
         sample_time_s_[sample_begin_[next_start_]] - kTimeEpsilon_s <= t) {
    const uint32_t k = next_start_++;
    if (sample_time_s_[sample_end_[k] - 1] + kTimeEpsilon_s < t) continue;
    assert(num_live_ < live_.size());  // capacity is the maximum overlap of these intervals
    if (num_live_ >= live_.size()) break;
    live_[num_live_++] = k;
  }

  const float blend = 1.0f - std::exp(-dt_s / kThetaTau_s);
  for (size_t i = 0; i < num_live_; ++i) {
    const uint32_t k = live_[i];
    const uint32_t last = sample_end_[k] - 1;
    uint32_t c = cursor_[k];
    while (c + 1 < last && t > sample_time_s_[c + 1]) ++c;
    cursor_[k] = c;

    glm::vec2 p = sample_pos_[c];
    glm::vec2 v(0.0f);
    if (c < last) {
      // Cubic Hermite on [t0, t1]: reproduces the samples at t0, t1 and the tangents there (C1).
      const double t0 = sample_time_s_[c];
      const double h = sample_time_s_[c + 1] - t0;
      const float s = static_cast<float>(std::clamp((t - t0) / h, 0.0, 1.0));
      const float hf = static_cast<float>(h);
      const glm::vec2 p0 = sample_pos_[c], p1 = sample_pos_[c + 1];
      const glm::vec2 m0 = sample_tangent_[c] * hf, m1 = sample_tangent_[c + 1] * hf;
      const float s2 = s * s, s3 = s2 * s;
      p = (2.0f * s3 - 3.0f * s2 + 1.0f) * p0 + (s3 - 2.0f * s2 + s) * m0 +
          (-2.0f * s3 + 3.0f * s2) * p1 + (s3 - s2) * m1;
      v = ((6.0f * s2 - 6.0f * s) * p0 + (3.0f * s2 - 4.0f * s + 1.0f) * m0 +
           (-6.0f * s2 + 6.0f * s) * p1 + (3.0f * s2 - 2.0f * s) * m1) /
          hf;
    }

    // Heading from v when the pedestrian walks: v fast enough, and on a jittering track (whose
    // spline overshoots between noisy samples) also the segment's own chord.
    const float min_speed = heading_speed_[k];
    const bool heading =
        glm::length(v) >= min_speed &&
        (min_speed <= kHeadingMinSpeed_m_s || c == last ||
         glm::length(sample_pos_[c + 1] - sample_pos_[c]) >=
             min_speed * static_cast<float>(sample_time_s_[c + 1] - sample_time_s_[c]));
    if (i >= first_new) {
      // A newcomer faces where it walks right away; no smoothing from a stale value.
      theta_[k] = heading ? heading_of(v) : initial_theta_[k];
    } else if (heading) {
      theta_[k] = wrap_angle(theta_[k] + wrap_angle(heading_of(v) - theta_[k]) * blend);
    }
    out_ids_[i] = track_ids_[k];
    out_positions_[i] = p;
    out_velocities_[i] = v;
    out_thetas_[i] = theta_[k];
  }
}

// Pedestrians walk at about 1.3 m/s. A file whose pedestrians would move implausibly fast or slow
// in metres but at walking pace in centimetres or millimetres (trackers and lab datasets write
// both) is in those units: the scale [m per file unit] and its name, or 1 for metres. Judged on
// the median over pedestrians of each one's 75th-percentile speed between samples (standers and
// tracker jitter count little), and only outside 0.15-6 m/s, so no file in metres is rescaled.
std::pair<double, const char*> detect_position_unit(const TrajectoryTable& t,
                                                    double frame_time_s) {
  std::vector<double> typical;
  for (size_t k = 0; k < t.num_tracks(); ++k) {
    std::vector<double> v;
    for (uint32_t i = t.track_begin[k] + 1; i < t.track_begin[k + 1]; ++i) {
      const double dt = static_cast<double>(t.frames[i] - t.frames[i - 1]) /
                        static_cast<double>(t.frame_step) * frame_time_s;
      if (dt > 0.0) v.push_back(glm::length(t.positions[i] - t.positions[i - 1]) / dt);
    }
    if (v.size() < 2) continue;
    std::nth_element(v.begin(), v.begin() + v.size() * 3 / 4, v.end());
    typical.push_back(v[v.size() * 3 / 4]);
  }
  if (typical.empty()) return {1.0, "metres"};
  std::nth_element(typical.begin(), typical.begin() + typical.size() / 2, typical.end());
  const double speed = typical[typical.size() / 2];
  auto plausible = [](double s) { return s >= 0.15 && s <= 6.0; };
  if (plausible(speed) || !(speed > 0.0)) return {1.0, "metres"};
  for (const auto& [scale, name] : {std::pair<double, const char*>{0.01, "centimetres"},
                                    std::pair<double, const char*>{0.001, "millimetres"}}) {
    if (plausible(speed * scale)) return {scale, name};
  }
  return {1.0, "metres"};
}

}  // namespace

bool is_trajectory_file_name(std::string_view path) {
  const std::string ext = lower_ascii(std::filesystem::path(path).extension().string());
  return ext == ".txt" || ext == ".csv" || ext == ".tsv" || ext == ".dat";
}

Result<std::unique_ptr<CrowdSource>> load_trajectory_replay(
    const std::string& path, const ReplayOptions& options,
    std::vector<uint32_t>* out_pedestrian_ids) {
  if (!std::isfinite(options.frame_time_s) || options.frame_time_s <= 0.0f) {
    return Status::AtField(path, "frame_time_s",
                           "expected a finite time > 0 s per sample step, found " +
                               std::to_string(options.frame_time_s));
  }
  Result<TrajectoryTable> table = read_trajectory_file(path);
  if (!table.ok()) return table.status();
  if (out_pedestrian_ids) *out_pedestrian_ids = table->ped_ids;  // sorted: tracks are by id
  const size_t slash = path.find_last_of('/');
  std::string name = "replay " + (slash == std::string::npos ? path : path.substr(slash + 1));
  // A file that gives its times is replayed at them: frame_time_s is for frame numbers.
  const double frame_time_s =
      table->seconds_per_frame > 0.0
          ? table->seconds_per_frame * static_cast<double>(table->frame_step)
          : static_cast<double>(options.frame_time_s);
  const auto [unit_m, unit_name] = detect_position_unit(*table, frame_time_s);
  if (unit_m != 1.0) {
    for (glm::vec2& p : table->positions) p *= static_cast<float>(unit_m);
    name += std::string(" (in ") + unit_name + ", by its walking speeds)";
  }
  return std::unique_ptr<CrowdSource>(
      new TrajectoryReplay(std::move(name), *table, frame_time_s, options.loop));
}

}  // namespace gk
