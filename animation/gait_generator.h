#pragma once
// Procedural gait generation behind make_builtin_clip_set (animation/procedural.h): a table of gait
// parameters (from ../shared/docs/GAIT.md) and the generator that turns one row into a cyclic clip
// with root motion. Exposed so that tests can derive the intended speed, cadence and stride from
// the same parameters the clips were generated from.

#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "animation/clip.h"
#include "animation/skeleton.h"

namespace gk {

enum class GaitKind : uint8_t {
  kIdle,      // feet planted, breathing and weight shift
  kWalk,      // heel strike, foot flat, heel-off about the ball, toe-off; double support
  kRun,       // midfoot/heel landing, flight phase, pelvis lowest at mid-stance
  kSideStep,  // facing +z, travelling along x: flat feet, step-close pattern
};

struct GaitParams {
  std::string name;
  GaitKind kind = GaitKind::kWalk;
  float speed_m_s = 1.3f;                 // [m/s] travel speed [Limit: >= 0]
  glm::vec3 direction{0.0f, 0.0f, 1.0f};  // travel direction in the character frame (+z forward)
  float cadence_steps_min = 114.0f;       // target; a stride is rounded to whole frames
  int num_strides = 1;                    // strides per clip (idle: ignored)
  bool reverse_time = false;              // walking backward = a forward gait played in reverse
  bool mirror = false;                    // swap left and right (strafe_right from strafe_left)
  float stance_fraction = 0.6f;           // of the cycle, per foot
  float heel_strike_deg = 12.0f;          // foot pitch (toe up) at initial contact
  float toe_off_deg = 35.0f;              // foot pitch (heel up) at toe-off
  float swing_peak_m = 0.08f;             // ball height above stance in early swing
  float swing_mid_m = 0.04f;              // ball height above stance in mid swing
  float loading_knee_deg = 15.0f;         // stance knee flexion peak (loading / mid-stance run)
  float bob_m = 0.044f;                   // pelvis vertical excursion (idle, side step) [m]
  float sway_m = 0.04f;                   // pelvis lateral shift, peak to peak
  float pelvis_yaw_deg = 4.5f;            // amplitude of pelvis rotation about the vertical
  float pelvis_roll_deg = 4.0f;           // amplitude of pelvis obliquity
  float trunk_lean_deg = 2.0f;            // forward trunk lean
  float arm_swing_deg = 16.0f;            // shoulder flexion/extension amplitude
  float elbow_deg = 20.0f;                // mean elbow flexion
  // Cycle fraction (from the same-side contact) at which the arm is furthest back: when the thigh
  // is furthest forward (terminal swing in walking, late swing in running).
  float arm_back_phase = 0.02f;
  // Foot track half-width as a fraction of the hip joint's lateral offset. Walkers put the feet
  // closer together than the hip joints (step width 5-15 cm between the feet's contact points,
  // about 10 cm here), so the legs slant slightly inward and the knees stay over the feet.
  float foot_lateral = 0.6f;
  float max_leg_extension = 0.9985f;  // idle/side step: hip-ankle distance / leg length
  float idle_duration_s = 6.0f;
};

// The built-in locomotion set, in the clip order of make_builtin_clip_set.
std::vector<GaitParams> builtin_gait_params();

// Cadence from the walk ratio (GAIT.md): step [m] / cadence [steps/min] = 0.006 at and above
// 1 m/s; below, the ratio shrinks (people shorten the step more), so cadence is higher.
float walk_ratio_cadence(float speed_m_s);

// Frames per stride and the resulting cycle (the cadence actually generated).
int frames_per_stride(const GaitParams& params, float fps);

// Generates one cyclic clip on a humanoid skeleton that has all locomotion roles, an arm chain
// below each shoulder role and identity rest rotations (make_humanoid_skeleton).
Clip generate_gait_clip(const Skeleton& skeleton, const GaitParams& params, float fps);

// Foot geometry shared by the generator and the mannequin, estimated from any skeleton's rest pose
// in the foot's frame (origin at the ankle, +z toward the ball, y up): heel behind the ankle, sole
// below it, toe tip ahead of the ball. Anthropometric fractions of the ankle-to-ball distance.
struct FootShape {
  float ankle_height_m = 0.068f;  // ankle joint above the sole
  float heel_back_m = 0.05f;      // heel behind the ankle
  float ball_forward_m = 0.145f;  // ball (toe joint) ahead of the ankle
  float ball_height_m = 0.0245f;  // ball joint above the sole
  float toe_length_m = 0.07f;     // toe tip ahead of the ball
  float width_m = 0.096f;
};
// Stature estimate [m] from leg length (hip to ankle = 0.491 of stature) or the joint extent.
float estimate_stature(const Skeleton& skeleton);
FootShape estimate_foot_shape(const Skeleton& skeleton, Side side);

}  // namespace gk
