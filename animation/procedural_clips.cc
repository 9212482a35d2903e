// The built-in locomotion set: one row of gait parameters per clip, numbers from
// ../shared/docs/GAIT.md (cadence from the walk ratio for walks, 160-180 steps/min for running,
// stance and double-support fractions, pelvis motion, arm swing).

#include "animation/gait_generator.h"
#include "animation/procedural.h"

namespace gk {
namespace {

constexpr float kBuiltinFps = 60.0f;

GaitParams walk(const char* name, float speed, float stance, float scale) {
  // scale runs from 0 (slow) to 1 (fast): larger pelvis motion, arm swing and heel-off with speed.
  GaitParams p;
  p.name = name;
  p.kind = GaitKind::kWalk;
  p.speed_m_s = speed;
  p.cadence_steps_min = walk_ratio_cadence(speed);
  p.stance_fraction = stance;
  p.heel_strike_deg = 10.0f + 2.0f * scale;
  p.toe_off_deg = 30.0f + 10.0f * scale;
  p.swing_peak_m = 0.07f + 0.02f * scale;
  p.swing_mid_m = 0.035f + 0.01f * scale;
  p.loading_knee_deg = 13.0f + 6.0f * scale;
  p.sway_m = 0.045f - 0.01f * scale;
  p.pelvis_yaw_deg = 3.5f + 1.5f * scale;
  p.pelvis_roll_deg = 3.5f + 1.0f * scale;
  p.trunk_lean_deg = 1.0f + 2.0f * scale;
  p.arm_swing_deg = 11.0f + 9.0f * scale;
  p.elbow_deg = 20.0f + 12.0f * scale;  // GAIT.md: 20-40 deg, more at higher speed
  return p;
}

GaitParams run(const char* name, float speed, float cadence, float stance, float scale) {
  GaitParams p;
  p.name = name;
  p.kind = GaitKind::kRun;
  p.speed_m_s = speed;
  p.cadence_steps_min = cadence;
  p.stance_fraction = stance;
  p.heel_strike_deg = 6.0f - 4.0f * scale;  // jogging lands on the heel, running on the midfoot
  p.toe_off_deg = 40.0f + 5.0f * scale;
  p.swing_peak_m = 0.20f + 0.08f * scale;
  p.swing_mid_m = 0.10f + 0.04f * scale;
  p.loading_knee_deg = 40.0f + 4.0f * scale;
  p.sway_m = 0.02f - 0.005f * scale;
  p.pelvis_yaw_deg = 6.0f + 1.0f * scale;
  p.pelvis_roll_deg = 4.0f;
  p.trunk_lean_deg = 5.0f + 3.0f * scale;
  p.arm_swing_deg = 25.0f + 5.0f * scale;
  p.elbow_deg = 80.0f + 10.0f * scale;
  p.arm_back_phase = 0.78f;
  p.foot_lateral = 0.5f - 0.15f * scale;  // runners place the feet closer to the midline
  return p;
}

GaitParams strafe(const char* name, bool right) {
  GaitParams p;
  p.name = name;
  p.kind = GaitKind::kSideStep;
  p.speed_m_s = 0.9f;
  p.direction = glm::vec3(right ? -1.0f : 1.0f, 0.0f, 0.0f);
  p.mirror = right;
  p.cadence_steps_min = 150.0f;
  p.stance_fraction = 0.62f;
  p.swing_peak_m = 0.06f;
  p.swing_mid_m = 0.05f;
  p.bob_m = 0.05f;
  p.sway_m = 0.0f;
  p.pelvis_yaw_deg = 1.0f;
  p.pelvis_roll_deg = 3.0f;
  p.trunk_lean_deg = 1.0f;
  p.arm_swing_deg = 4.0f;
  p.elbow_deg = 15.0f;
  p.foot_lateral = 1.0f;
  return p;
}

}  // namespace

std::vector<GaitParams> builtin_gait_params() {
  std::vector<GaitParams> params;
  GaitParams idle;
  idle.name = "idle";
  idle.kind = GaitKind::kIdle;
  idle.speed_m_s = 0.0f;
  idle.idle_duration_s = 8.0f;
  idle.bob_m = 0.006f;
  idle.sway_m = 0.03f;
  idle.pelvis_yaw_deg = 2.0f;
  idle.pelvis_roll_deg = 2.0f;
  idle.trunk_lean_deg = 0.5f;
  idle.arm_swing_deg = 2.0f;
  idle.elbow_deg = 12.0f;
  idle.foot_lateral = 1.1f;
  params.push_back(idle);
  // Double support shrinks with speed: stance 63 % -> 57 % of the cycle.
  params.push_back(walk("walk_slow", 0.8f, 0.63f, 0.0f));
  params.push_back(walk("walk", 1.3f, 0.60f, 0.5f));
  params.push_back(walk("walk_fast", 1.8f, 0.57f, 1.0f));
  params.push_back(run("jog", 2.6f, 164.0f, 0.38f, 0.0f));
  params.push_back(run("run", 3.6f, 176.0f, 0.32f, 1.0f));
  params.push_back(strafe("strafe_left", false));
  params.push_back(strafe("strafe_right", true));
  // Backward: a forward gait played in reverse (toe contacts first), with shorter steps and a
  // higher cadence than forward walking at the same speed.
  GaitParams back = walk("walk_backward", 0.9f, 0.62f, 0.0f);
  back.direction = glm::vec3(0.0f, 0.0f, -1.0f);
  back.reverse_time = true;
  back.cadence_steps_min = 125.0f;
  back.heel_strike_deg = 8.0f;
  back.toe_off_deg = 25.0f;
  back.arm_swing_deg = 8.0f;
  params.push_back(back);
  return params;
}

ClipSet make_builtin_clip_set(const HumanoidParams& params) {
  ClipSet set;
  auto skeleton = make_humanoid_skeleton(params);
  set.skeleton = skeleton;
  for (const GaitParams& gait : builtin_gait_params()) {
    set.clips.push_back(generate_gait_clip(*skeleton, gait, kBuiltinFps));
  }
  set.mesh = make_mannequin_mesh(*skeleton);
  set.scale_m_per_unit = 1.0f;
  set.scale_reason = "builtin (metres)";
  set.source = "builtin";
  return set;
}

}  // namespace gk
