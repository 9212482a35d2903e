#pragma once
// The mediator's frame as named whole-crowd passes, run in this order by Mediator::plan() (in the
// manner of DetourCrowd's dtCrowd::update: one phase over the whole crowd after the other):
//
//   filter    the simulator's p, v, theta sanitised and smoothed   (per agent -> per slot)
//   root      the drawn root pulled onto p, and its heading
//   facing    lower-body yaw (psi), upper-body yaw, travel direction relative to psi
//   weights   target clip weights, faded, cut to the heaviest kMaxBlendLayers layers
//   rate      playback rate and gait phase
//   transition  a start or stop clip as a layer on its own clock (libraries that have them)
//   contacts  clip times, plant / hold / swing progress of each foot, the gait clips' toe height
//   feedback  what the animation can deliver, for the simulator     (per slot -> per agent)
//
// Each pass reads and writes flat arrays only (spans: const what it reads, mutable what it writes;
// per slot unless it says per agent) and runs over every agent of the frame in parallel; an agent's
// work in a pass never touches another agent's data, so the passes' results do not depend on the
// order or the threads. Nothing here allocates.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include "crowd/crowd_source.h"
#include "mediator/animation_plans.h"
#include "mediator/locomotion_library.h"
#include "mediator/params.h"

namespace gk {

// What every pass sees: the library, the parameters, the step, and the agents to run over. Every
// pass visits the frame's agent i in slot slot_of_agent[i], for i < slot_of_agent.size(), through
// one loop (for_each_agent in mediator_passes.cc): a level of detail that plans only the agents
// due this frame would skip the others there, in one place.
struct PassCrowd {
  const LocomotionLibrary& library;
  const MediatorParams& params;
  float dt_s;                              // [s] (0, 1]
  std::span<const int32_t> slot_of_agent;  // per agent: its slot
  std::span<const uint8_t> fresh;          // per slot: 1 on the agent's first frame
  // Level of detail (empty: every agent, over dt_s): per slot, whether it is planned this frame,
  // and the step [s] it is planned over (the time since its last plan).
  std::span<const uint8_t> planned = {};
  std::span<const float> step_s = {};

  bool plans(int slot) const { return planned.empty() || planned[slot] != 0; }
  float dt(int slot) const { return step_s.empty() ? dt_s : step_s[slot]; }
};

// The drawn root: pulled onto p this fast, and never further from it.
inline constexpr float kRootPullTime = 0.25f;   // [s]
inline constexpr float kMaxRootOffset = 0.06f;  // [m]
// A root held back by its support foot brakes no harder than this (about g: what friction lets
// legs put on a body) [m/s^2].
inline constexpr float kSupportBrake = 9.81f;

// The simulator's values are garbage beyond these (NaN, 1e30, a velocity no body has).
inline constexpr float kAbsurdSpeed = 15.0f;   // [m/s]
inline constexpr float kMaxCoordinate = 1e6f;  // [m] from the origin: a float cannot hold a step
inline bool finite2(const glm::vec2& v) { return std::isfinite(v.x) && std::isfinite(v.y); }
inline bool usable_position(const glm::vec2& p) {
  return finite2(p) && std::abs(p.x) <= kMaxCoordinate && std::abs(p.y) <= kMaxCoordinate;
}
// True when the simulator gave this agent nothing to sanitise.
inline bool sane_input(const glm::vec2& p, const glm::vec2& v, float theta) {
  return finite2(v) && !(glm::length(v) > kAbsurdSpeed) && usable_position(p) &&
         std::isfinite(theta);
}
// The pull of pulled_root over a step dt [s] (one exp, shared by every agent stepped by dt).
inline float root_pull(float dt) { return 1.0f - std::exp(-dt / kRootPullTime); }
// A drawn root no further than kMaxRootOffset from the simulator's p.
inline glm::vec2 near_p(const glm::vec2& root, const glm::vec2& p) {
  const glm::vec2 off = root - p;
  const float len = glm::length(off);
  return len > kMaxRootOffset ? p + off * (kMaxRootOffset / len) : root;
}
// The drawn root one step of dt [s] on: predicted from `root` with the filtered velocity and
// pulled onto the simulator's p, never more than kMaxRootOffset from it.
inline glm::vec2 pulled_root(const glm::vec2& root, const glm::vec2& vel, const glm::vec2& p,
                             float dt, float pull) {
  const glm::vec2 predicted = root + vel * dt;
  return near_p(predicted + (p - predicted) * pull, p);
}
// The drawn root of an agent held standing through its jitter (filter_pass): pulled toward where
// it stands, `still_at`, with no motion of its own, and never more than kMaxRootOffset from p.
inline glm::vec2 held_root(const glm::vec2& root, const glm::vec2& still_at, const glm::vec2& p,
                           float dt, float pull) {
  return near_p(pulled_root(root, glm::vec2(0.0f), still_at, dt, pull), p);
}

// A layer's clip time: a gait clip's at the shared gait phase, a standing clip's on its clock, a
// transition's on its own (`transition_time_s`).
inline float layer_time(const LocomotionClip& clip, float phase, float idle_time_s,
                        float transition_time_s) {
  if (clip.transition) return transition_time_s;
  return clip.gait ? clip.time_at_phase(phase)
                   : std::fmod(idle_time_s, std::max(clip.clip.duration_s(), 1e-3f));
}

// The gait cycles per second of a slot's layers at native rate (weighted over its gait clips),
// and the weight of those clips (0: no gait clip, and no frequency).
struct GaitFrequency {
  float cycles_per_s = 0.0f;
  float gait_weight = 0.0f;
};
GaitFrequency gait_frequency(const LocomotionLibrary& library, const int16_t* layer_clip,
                             const float* layer_weight);

// Ground heading of a direction (x, z) [rad]: 0 along +z.
inline float heading2(const glm::vec2& v) { return std::atan2(v.x, v.y); }

// Target clip weights (library.clips.size() of them, summing to 1) for a filtered speed [m/s] and
// a travel direction relative to the lower body [rad]: standing below the stop speed; the
// nearest-speed forward clip outside APM; else the (direction, speed) blend space.
// Below the slowest clip the standing clip's share shortens the stride and the playback rate
// slows the cadence, both about sqrt of the speed's share (GAIT.md's walk ratio), the cadence no
// lower than min_playback_rate nor min_cadence (an agent about to stop keeps its cadence).
void choose_clip_weights(const LocomotionLibrary& library, const MediatorParams& params,
                         float speed, float rel_dir, std::span<float> out_weights,
                         float min_cadence = 0.0f);

// --- filter -------------------------------------------------------------------------------------
// Per slot, carried from frame to frame: the simulator's velocity and theta through critically
// damped springs (APM; the other modes take them as they are).
struct FilterState {
  std::span<glm::vec2> vel, vel_rate;  // [m/s], [m/s^2]
  std::span<float> theta, theta_rate;  // unwrapped [rad], [rad/s]
  // With the gate (filter_pass): where a standing agent stands (p averaged over
  // kStillAverageTime while it stands with a slow p; kept while it is held, and when it stops
  // again within twice its hold of there), the mean square of p's distance from there over its
  // standing frames (each at most the hold's reach) [m^2] (-1: unknown, as when the gate was off:
  // Mediator::plan marks it), and (out, with the gate) whether it stands this frame only because
  // p moved within that jitter.
  std::span<glm::vec2> still_at;
  std::span<float> still_jitter2;
  std::span<uint8_t> jitter_held;
};
// A tracker's noise moves a standing pedestrian's recorded p back and forth at walking-like
// speeds (2 cm of noise every 0.4 s: about 0.1 m/s, in a new direction each sample), but never
// away: such an agent stays standing while p is within kStartJitterSigmas times the
// root-mean-square of its jitter of where it stands, and never further than a re-planting step
// (MediatorParams::idle_step_distance_m: a standing body's feet take up that much). The jitter is
// learnt on held frames too, so a start from a noisy stand is let go at about that distance. A
// clean track's jitter is about nil: its starts are not delayed. Averages over
// kStillAverageTime [s].
inline constexpr float kStartJitterSigmas = 3.0f;
inline constexpr float kStillAverageTime = 1.0f;
// Per agent: the frame's values with unusable ones replaced by the agent's last good ones.
struct SanitisedInput {
  std::span<glm::vec2> positions;   // [m]
  std::span<glm::vec2> velocities;  // [m/s]
  std::span<float> thetas;          // [rad]
};
// Reads the frame, last frame's filter state, `standing` and drawn root (a bad p holds it).
// Writes the sanitised input (per agent), the filter state, the filtered speed and `standing`.
// With stand_through_jitter (APM, MediatorParams::stand_through_jitter, a source that takes no
// feedback), a standing agent whose p is within its jitter's reach of where it stands stays
// standing (speed 0, FilterState::jitter_held; kStartJitterSigmas). A frame whose p is unusable
// leaves that state as it was.
void filter_pass(const PassCrowd& crowd, const AgentFrame& frame,
                 std::span<const glm::vec2> root_xz, FilterState state, bool stand_through_jitter,
                 SanitisedInput out, std::span<float> out_speed_m_s,
                 std::span<uint8_t> out_standing);

// --- root ---------------------------------------------------------------------------------------
// Reads the sanitised positions (per agent), the filtered velocity, `standing`, last frame's
// lower-body yaw and support reach (per slot, PoseSynthesizer::support_reach; empty: none).
// Writes the drawn root (predicted with the filtered velocity and pulled onto p, never far from
// it; with MediatorParams::support_hold, slowed where it would leave the reach of a foot that
// carries the body alone) and its heading, the direction it travels [rad] (the lower body's yaw
// when standing), per slot its speed (root_speed: last frame's in, this frame's out) [m/s], and
// the hold: how far the root was held back [m] and the share of its step it kept (both fed
// back). On a frame an agent is held standing through its p's jitter (FilterState::jitter_held,
// per slot; empty: none), its root is pulled toward where it stands (FilterState::still_at)
// instead of p, within kMaxRootOffset of p; on its other standing frames, toward p as always.
void root_pass(const PassCrowd& crowd, std::span<const glm::vec2> positions,
               std::span<const glm::vec2> vel, std::span<const uint8_t> standing,
               std::span<const float> lower_yaw, std::span<glm::vec2> root_xz,
               std::span<float> out_root_heading, std::span<const SupportReach> support_reach,
               bool honoured, std::span<float> root_speed, std::span<glm::vec2> out_hold,
               std::span<float> out_hold_scale, std::span<const glm::vec2> still_at = {},
               std::span<const uint8_t> jitter_held = {});

// --- facing -------------------------------------------------------------------------------------
// Reads the root's heading, the filtered theta, `standing` and last frame's layers. Writes the
// lower body's target and yaw psi (turned toward the target at a limited rate; APM picks the
// direction group that leaves the torso the least twist, and turns the body against the played
// gait clips' own offset from their group's direction, so they travel along v), the upper body's
// yaw and the travel direction relative to psi (0 standing or outside APM) [rad].
void facing_pass(const PassCrowd& crowd, std::span<const float> root_heading,
                 std::span<const float> theta, std::span<const uint8_t> standing,
                 std::span<float> lower_target, std::span<float> lower_yaw,
                 std::span<float> lower_yaw_rate, std::span<float> out_upper_yaw,
                 std::span<float> out_rel_dir, std::span<const int16_t> layer_clip,
                 std::span<const float> layer_weight);

// --- weights ------------------------------------------------------------------------------------
// Per slot [slot * num_clips + clip]: the faded clip weights (carried) and the target ones.
struct ClipWeights {
  std::span<float> faded;
  std::span<float> target;  // scratch
};
// Reads the filtered speed and the relative travel direction. Writes the clip weights (faded
// toward the target over the blend time in APM, switched at once otherwise), the blend progress,
// and the layers: the kMaxBlendLayers heaviest clips [slot * kMaxBlendLayers + k], normalised.
// A layer of weight 0 keeps the clip it had.
void weights_pass(const PassCrowd& crowd, std::span<const float> speed_m_s,
                  std::span<const float> rel_dir, std::span<const float> min_cadence,
                  ClipWeights weights, std::span<int16_t> layer_clip, std::span<float> layer_weight,
                  std::span<float> out_blend_progress);

// --- rate and phase -----------------------------------------------------------------------------
// Reads the layers, the filtered speed, each agent's cadence scale and the lower-body yaw. Writes
// the playback rate (speed over the blend's native speed, within the rate limits; 1 without gait
// clips), the gait phase (advanced by the blend's cycle frequency times the rate), the standing
// clip's clock, the share of gait clips and the travel direction the played clips imply [rad].
// An agent setting off from standing (no gait clip in last frame's blend, no transition playing:
// `transition_weight` is last frame's) starts its gait phase where a foot leaves the ground.
// In APM (quicken_steps) the rate is raised (within the limits) while the body would otherwise
// leave the reach of the foot that carries it alone before the other foot lands: a walker
// speeding up, or one the simulator pushes on, takes quicker steps (reach_boost in
// mediator_passes.cc). Not on an agent's first frame, nor while a start or stop plays.
//
// Where the drawn root is (root pass, this frame) and goes (the filtered velocity) against the
// reach of a foot that carries the body alone (last frame's pose, PoseSynthesizer::support_reach;
// empty: none), and the factor on the playback rate that lands the other foot before the body
// leaves that reach (carried per slot).
struct ReachInput {
  std::span<const SupportReach> support_reach;
  std::span<const glm::vec2> root_xz;
  std::span<const glm::vec2> velocity;
  std::span<float> boost;
};
// The reach factor goes from 1 to the fastest rate (or back) over this time [s] at the most, at an
// even pace (a quarter of a walking swing): the cadence rises within the step that needs it, with
// no jump in every joint's speed.
inline constexpr float kReachBoostTime = 0.1f;
void rate_phase_pass(const PassCrowd& crowd, std::span<const int16_t> layer_clip,
                     std::span<const float> layer_weight, std::span<const float> speed_m_s,
                     std::span<const float> cadence_scale, std::span<const float> lower_yaw,
                     std::span<const float> transition_weight, ReachInput reach,
                     std::span<float> phase, std::span<float> idle_time_s,
                     std::span<float> out_playback_rate, std::span<float> out_gait_weight,
                     std::span<float> out_travel_yaw);

// --- transitions --------------------------------------------------------------------------------
// Per slot, carried: the start or stop clip an agent plays (LocomotionLibrary::transitions) as a
// layer of its own, on its own clock.
enum class TransitionStage : uint8_t {
  kNone,     // nothing playing
  kWaiting,  // a stop chosen, waiting for the gait phase its first contacts match
  kPlaying,  // fading in or at full weight
  kLeaving,  // fading out: a start handing over to the cycle, a stop at rest, or an abort
};
// What transition_counts() sums: starts and stops seen and how many played a transition clip,
// and the creeping agents' stops, not counted as stops: an agent that came to rest without
// having moved as fast as a take's standing speed since it last stood (0.15 m/s, segmentation's
// idle speed: slower than any moving frame of a stop clip, which has no step to play for it).
enum TransitionCount : int {
  kStartsSeen,
  kStartsPlayed,
  kStopsSeen,
  kStopsPlayed,
  kCreepStops,
  kNumCounts
};
struct TransitionState {
  std::span<int16_t> index;  // into library.transitions, -1: none
  std::span<TransitionStage> stage;
  std::span<float> time_s;    // clip time [s]
  std::span<float> weight;    // layer weight, 0..1
  std::span<float> rate;      // clip-time step / real time
  std::span<float> waited_s;  // time waited for the phase [s]
  // Waiting: the playback rate when the stop was chosen, the cadence the weights pass holds
  // until the stop begins (0: none).
  std::span<float> min_cadence;
  // Waiting: the agent's speed when the stop was chosen [m/s]: the stop is given up once the
  // agent is faster again, not on a frame's rise of a speed that jitters while it slows.
  std::span<float> chosen_speed_m_s;
  std::span<float> lag_m;  // playing: the agent's distance travelled minus the clip's [m]
  std::span<float> prev_speed_m_s, prev_phase;
  std::span<float> still_s, moving_s;  // how long the agent has stood / moved [s]
  std::span<float> peak_speed_m_s;     // the fastest it has moved since it last stood [m/s]
  // 1: a start seen while a stop still played (the agent set off again as it faded out), to
  // begin once the stop has gone.
  std::span<uint8_t> start_due;
  std::span<uint32_t> counts;          // [slot * kNumCounts + TransitionCount], cumulative
  std::span<const float> rate_boost = {};  // the rate pass's reach factor (ReachInput; empty: 1)
};
// The agent has stood (or moved) at least this long before a start (stop) counts.
inline constexpr float kTransitionSettle = 0.25f;  // [s]
// A stop is chosen when the speed falls at least this fast [m/s^2]; a playing stop is left when
// it rises this fast.
inline constexpr float kStopDeceleration = 0.3f;

// Reads the filtered speed, `standing`, the layers and phase, and last frame's transition state.
// Counts starts (speed rising past the stop speed after standing kTransitionSettle) and stops
// (falling below it after moving as long). In APM, with a library that has them, plays them: a
// start as the agent starts, from the clip time where the clip moves as fast as the agent (or,
// seen while a stop still plays or fades out, as soon as that has gone); a stop
// once the speed falls fast enough to come to rest within the clip's own stopping time, entered
// where the clip has slowed to the agent's speed or later (where the agent can still play it and
// come to rest in time; of those, the one whose gait phase comes soonest) and begun when the
// gait phase reaches the one the stop's contacts match there (given up once the agent is faster
// than when it chose the stop, stands first, or the phase does not come within a cycle). The
// clock runs at the agent's speed over the clip's root speed, corrected so that the clip's root
// travels as far as the agent does (within the rate limits); the gait phase follows the clip's
// own steps (Transition::phase_track) so the cycle joins in step. A start the agent does not
// keep up with, or a stop it walks out of, fades out early. Writes the transition's layer (in a
// free layer, the others sharing 1 - its weight), the gait share and the phase. A library without
// transitions changes nothing.
void transition_pass(const PassCrowd& crowd, std::span<const float> speed_m_s,
                     std::span<const float> playback_rate, std::span<const uint8_t> standing,
                     std::span<int16_t> layer_clip, std::span<float> layer_weight,
                     std::span<float> gait_weight, std::span<float> phase, TransitionState state);

// --- contacts -----------------------------------------------------------------------------------
// Per slot, per foot: what the clips do with each foot this frame.
struct ContactPlans {
  std::span<float> plant[2];           // "a lock may start", 0..1
  std::span<float> hold[2];            // "keep the lock", 0..1
  std::span<float> swing_progress[2];  // 0 at lift-off, 1 at landing
  std::span<float> landing_s[2];       // when the clips land the foot [s] (< 0: none has it up)
  std::span<float> gait_toe_y[2];      // the gait clips' own toe height [m]
  std::span<float> stand_toe_y[2];     // the standing clips' own toe height [m] (lowest(): none)
  std::span<float> clip_toe_speed[2];  // the voting clips' own ball speed [m/s] (< 0: unknown)
  std::span<float> double_support;     // share of the voting clips that walk, 0..1
  std::span<uint8_t> standing_votes;   // 1: the standing clips vote the feet
};
// Reads the layers, the phase, the standing clip's and the transition's clocks, the share of
// gait clips and the playback rates (the gait clips' and the transition's). Writes each layer's
// clip time (phase-synchronised: a new clip starts in phase) and the feet's contacts, voted by the
// gait clips (and a transition) alone once they carry a quarter of the blend, with the voting
// clips' own ball speed at those rates.
void contacts_pass(const PassCrowd& crowd, std::span<const int16_t> layer_clip,
                   std::span<const float> layer_weight, std::span<const float> phase,
                   std::span<const float> idle_time_s, std::span<const float> transition_time_s,
                   std::span<const float> gait_weight, std::span<const float> playback_rate,
                   std::span<const float> transition_rate, std::span<float> out_layer_time_s,
                   ContactPlans out);

// --- feedback -----------------------------------------------------------------------------------
// Per agent, index-aligned with the frame.
struct FeedbackOut {
  std::span<uint8_t> has_feedback;
  std::span<glm::vec2> positions, velocities;
  std::span<float> thetas;
};
// Reads the sanitised input (per agent), the lower-body yaw, `standing` and the share of gait
// clips; fed_speed (per slot) is the speed the simulator was given last frame, and is updated.
// Writes the feedback (per agent): the sanitised input, unflagged, unless `honoured` (APM with
// feedback on and a source that takes it) and the animation cannot deliver it: a root held back
// by its support foot (`hold` and `hold_scale`, per slot: the position moves with it and the
// velocity keeps the share of the step the root kept), a speed-up faster
// than max_accel_m_s2 over fed_speed, a speed above the fastest clip's reach, with forward
// clips only a velocity turning away from psi faster than the legs, or a theta beyond the torsion
// limit.
void feedback_pass(const PassCrowd& crowd, bool honoured, std::span<const glm::vec2> positions,
                   std::span<const glm::vec2> velocities, std::span<const float> thetas,
                   std::span<float> fed_speed, std::span<const float> lower_yaw,
                   std::span<const uint8_t> standing, std::span<const float> gait_weight,
                   std::span<const glm::vec2> hold, std::span<const float> hold_scale,
                   FeedbackOut out);

}  // namespace gk
