#include "app/param_labels.h"

#include <string_view>

namespace gk::app {
namespace {

struct Label {
  std::string_view name;
  const char* label;
};
// At most 26 characters: the panel's label column.
constexpr Label kLabels[] = {
    {"velocity_halflife_s", "Velocity smoothing"},
    {"theta_halflife_s", "Look direction smoothing"},
    {"torsion_limit_deg", "Max torso twist"},
    {"lower_turn_rate_deg_s", "Max hip turn speed"},
    {"lower_turn_accel_deg_s2", "Max hip turn speed-up"},
    {"blend_time_s", "Clip cross-fade time"},
    {"min_playback_rate", "Slowest playback"},
    {"max_playback_rate", "Fastest playback"},
    {"max_stride_warp", "Max stride stretch"},
    {"stop_speed_m_s", "Stand still below"},
    {"foot_locking", "Pin planted feet"},
    {"lock_release_s", "Foot release time"},
    {"max_leg_stretch", "Max leg stretch"},
    {"idle_step_distance_m", "Re-plant after drift of"},
    {"idle_step_time_s", "Re-planting step time"},
    {"support_hold", "Hold body at support foot"},
    {"quicken_steps", "Quicken steps at reach"},
    {"stand_through_jitter", "Stand through jitter"},
    {"feedback", "Feedback to simulator"},
    {"turn_feedback_deg", "Max path-to-legs angle"},
    {"max_accel_m_s2", "Max speed-up"},
    {"stride_variation", "Stride variety"},
};

}  // namespace

const char* param_label(const char* name) {
  for (const Label& l : kLabels) {
    if (l.name == name) return l.label;
  }
  return name;
}

}  // namespace gk::app
