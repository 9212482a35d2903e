#pragma once
// Every parameter of the Animation Planning Mediator, with unit, default and limits, in one struct.
// The app's panel and the CLI (`--set name=value`, or a JSON file) set them through the descriptor
// table below, so names, units and limits are written once.

#include <span>
#include <string>
#include <string_view>

#include "common/status.h"

namespace gk {

enum class MediatorMode : uint8_t {
  kNaive,  // root at p facing v, nearest-speed clip at its native rate: the classic skating crowd
  kRate,   // nearest-speed clip, playback rate matched to speed (within the rate limits) only
  kApm,    // everything: blending, phase sync, stride warping, torso decoupling, foot locking
};
std::string_view mediator_mode_name(MediatorMode mode);
Result<MediatorMode> parse_mediator_mode(std::string_view name);

struct MediatorParams {
  // 1. Input filtering (critically damped springs).
  float velocity_halflife_s = 0.05f;  // [s] [Limit: 0.01..1] smoothing of the simulator's v
  float theta_halflife_s = 0.05f;     // [s] [Limit: 0.01..1] smoothing of the desired torso theta
  // 3. Torso decoupling.
  float torsion_limit_deg = 60.0f;       // [deg] [Limit: 0..90] max twist pelvis -> upper chest
  float lower_turn_rate_deg_s = 300.0f;  // [deg/s] [Limit: 30..1440] max lower-body turn rate
  // [deg/s^2] [Limit: 100..1000000] fastest change of that turn rate: a turn speeds up to it and
  // slows down onto its heading over a couple of frames (300 deg/s in 0.03 s), and a velocity
  // that zig-zags (a jam) never reverses the turn in one frame, which swung the knees around by
  // metres per second in a frame. 1000000: no limit (the turn starts and stops at once).
  float lower_turn_accel_deg_s2 = 10000.0f;
  // 4./6. Blending.
  float blend_time_s = 0.25f;  // [s] [Limit: 0.05..1] cross-fade duration on clip changes
  // 5. Playback rate and stride warping.
  float min_playback_rate = 0.7f;   // [ratio] [Limit: 0.1..1] slowest clip-time step / real time
  float max_playback_rate = 1.35f;  // [ratio] [Limit: 1..3] fastest clip-time step / real time
  // [ratio] [Limit: 0..0.5] how much longer than the clips' strides the feedback lets the legs
  // stretch beyond the fastest rate. 0: the simulator is held to the fastest clip at the fastest
  // rate. Legs pinned under a body that goes faster overstretch and are let go before the other
  // foot lands, and the foot catches up with a snap (one walk take alone, each of subject 16's
  // walks and the CMU walk: 0.2 met 1034 of 1400 metrics-v2 bounds in bench/quality.sh --takes,
  // 0 meets 1054, every walk better; the four-library matrix unchanged at 541 of 560).
  float max_stride_warp = 0.0f;
  float stop_speed_m_s = 0.08f;     // [m/s] [Limit: 0..0.5] below this the agent stands
  // 7. Foot locking.
  bool foot_locking = true;
  float lock_release_s = 0.12f;    // [s] [Limit: 0.02..0.5] shortest rejoin of a released foot
  float max_leg_stretch = 0.995f;  // [ratio of leg length] [Limit: 0.9..1] beyond: heel up, step
  float idle_step_distance_m =
      0.12f;                       // [m] [Limit: 0.02..0.5] planted-foot drift that triggers a step
  float idle_step_time_s = 0.35f;  // [s] [Limit: 0.1..1] duration of a re-planting step
  // The root is held within the reach of a foot that carries the body alone (the other in the
  // air): it slows as that leg straightens, braking no harder than about g (beyond, the foot
  // gives); with `feedback` on and a source that takes it, the simulator is given the held
  // position and speed (no hold otherwise).
  // Off by default: its estimate of the reach is cautious, and ordinary walking is slowed too
  // (the mannequin's corridor crowd by 0.9% with quicken_steps, 7% without; README).
  bool support_hold = false;
  // Quicker steps (a higher playback rate, within the limits) while the body would leave the
  // reach of the foot that carries it alone before the other foot lands (rate_phase_pass): the
  // swing ends sooner, rather than the support foot being overstretched and let go.
  bool quicken_steps = true;
  // A source that takes no feedback (a recording): a standing agent starts walking only once its
  // p leaves where it stands by more than three times its jitter (tracker noise), and at most by
  // a re-planting step (idle_step_distance_m: in practice a start from a noisy stand is let go
  // there), instead of walking and turning after every wobble (filter_pass).
  bool stand_through_jitter = true;
  // 8. Feedback to the simulator.
  bool feedback = true;
  float turn_feedback_deg = 10.0f;  // [deg] [Limit: 0..180] forward-only libraries: velocity kept
                                    // within this of the lower body's facing (180 = off)
  // [m/s^2] [Limit: 0.1..20] fastest speed-up the legs deliver: a start from rest takes about a
  // second to walking speed (CMU subject 16's start take: 0.17 -> 1.29 m/s in 1.23 s, about
  // 0.9 m/s^2 on average), not a frame. 20 = as the simulator asks.
  float max_accel_m_s2 = 1.5f;
  // Variety.
  float stride_variation = 0.05f;  // [ratio] [Limit: 0..0.2] per-agent clip speed spread
  uint64_t seed = 1;
  MediatorMode mode = MediatorMode::kApm;
};

// Halflife of the glide of a foot pinned while it still moves over the ground [s] (a quarter of
// lock_release_s: loaded, a foot stops faster than a landing one settles).
inline float glide_halflife_s(const MediatorParams& p) { return 0.25f * p.lock_release_s; }

// Descriptor of one parameter for the CLI and the panel.
struct ParamInfo {
  const char* name;
  const char* unit;
  const char* help;  // one line: what it does
  float min_value;
  float max_value;
  enum class Kind : uint8_t { kFloat, kBool } kind;
  float MediatorParams::*f = nullptr;
  bool MediatorParams::*b = nullptr;
};
std::span<const ParamInfo> mediator_param_infos();

// "torsion_limit_deg=40" or "foot_locking=false"; errors name the parameter and its limits.
Status set_mediator_param(std::string_view assignment, MediatorParams* params);
// {"torsion_limit_deg": 40, "mode": "apm", ...}; errors name the file and the field.
Status load_mediator_params_json(const std::string& path, MediatorParams* params);
// Same, from JSON text in memory; source_name labels the errors.
Status parse_mediator_params_json(std::string_view json_text, const std::string& source_name,
                                  MediatorParams* params);
Status validate_mediator_params(const MediatorParams& params);
// The parameters as a JSON object (every parameter of the table in its order, then "mode" and
// "seed") that parse_mediator_params_json reads back to the same values; a float is written as
// the shortest decimal that reads back to it.
std::string mediator_params_to_json(const MediatorParams& params);

}  // namespace gk
