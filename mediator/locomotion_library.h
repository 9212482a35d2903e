#pragma once
// The mediator's view of a clip library, prepared once at load: every clip retargeted onto one
// skeleton, analysed, made in-place (travel removed from the root, facing turned to +z), with a
// phase->time table over one gait cycle, per-frame contact flags and toe heights, and grouped into
// a (speed, direction) blend space. Works from two clips or twenty, of any proportions that share
// joint names.

#include <memory>
#include <string>
#include <vector>

#include "animation/analysis.h"
#include "animation/clip.h"
#include "animation/mesh.h"
#include "animation/segmentation.h"
#include "mediator/params.h"

namespace gk {

inline constexpr int kPhaseTableSize = 64;

struct LocomotionClip {
  Clip clip;  // in place, facing +z, on the library skeleton
  // The clip as pose synthesis samples it where that is not `clip` itself: a capture below 60 fps
  // (Clip::sampled_capture) upsampled on a monotone cubic through its frames (upsample_clip), so
  // its joints do not move in straight segments whose velocity jumps at every captured frame;
  // empty otherwise. Sampled at a captured frame's time it is that frame; clip analysis, the foot
  // flags and the metrics' references all read `clip`, at the frames as captured.
  Clip played;
  const Clip& playback() const { return played.num_frames > 0 ? played : clip; }
  // The take as captured, with its root motion, on the library skeleton and floor (empty for a
  // clip authored in place): what the metrics' clip references and floors play.
  Clip source;
  ClipAnalysis analysis;  // of the original (retargeted) clip
  // Native ground speed: for a gait clip with root motion, the speed its planted feet are carried
  // under the body at (clip analysis reports the root's; a retargeted take's feet may slide).
  float speed_m_s = 0.0f;
  float direction_rad = 0.0f;  // travel direction relative to facing (0 forward, +pi/2 left)
  // direction_rad less its direction group's (a forward walk that drifts a few degrees) [rad]
  float direction_offset_rad = 0.0f;
  bool gait = false;  // has a gait cycle (alternating contacts) and travels
  float cycle_start_s = 0.0f;
  float cycle_s = 1.0f;  // duration of one gait cycle (stride) in clip time
  // Clip time [s] at phase k / kPhaseTableSize over one cycle (monotone, may exceed the duration of
  // a looping clip; sampling wraps).
  float phase_to_time[kPhaseTableSize + 1] = {};
  // Per clip frame and foot (Side): `plant` where a foot lock may start (clip analysis has the
  // foot in contact), `hold` where an existing lock is kept (in contact, or the ball still no
  // higher and no faster over the ground than in 90% of this clip's contact frames: heel-off).
  std::vector<uint8_t> plant[2];
  std::vector<uint8_t> hold[2];
  std::vector<float> toe_height_m[2];  // toe height above its lowest point
  // The ball's speed over the ground per frame at native rate (the clip's own: a blend's weights
  // moving the drawn foot are not in it) [m/s]; empty where not known.
  std::vector<float> toe_speed_m_s[2];
  // Both feet are in contact on some frame (a walk; a run has a flight phase instead): a foot then
  // keeps its weight until the other has taken it over.
  bool double_support = false;
  // How far through its swing each foot is, 0 where it leaves the ground to 1 where it lands
  // (0 while planted).
  std::vector<float> swing_progress[2];
  // The gait phase at which each foot leaves the ground (its swing's first frame; -1: it never
  // swings). A standing agent sets off there: its first step is a whole swing.
  float lift_phase[2] = {-1.0f, -1.0f};
  float toe_floor_m[2] = {0.0f, 0.0f};    // lowest toe height in the clip
  float ankle_floor_m[2] = {0.0f, 0.0f};  // lowest ankle height in the clip
  // Why this gait clip's contact analysis is doubtful (empty when it is sound): contacts that do
  // not alternate, a cycle that is not one stride, feet down for very different times. A doubtful
  // clip is still played (its speed and cycle are usable), but no foot lock is planted on its
  // contacts: pinning a foot where the clip is not standing makes legs snap, which is worse than
  // the clip's own motion.
  std::vector<std::string> doubts;
  // A start or stop cut from a take (LocomotionLibrary::transitions): played on its own clock,
  // never in the blend space (it is neither `gait` nor the standing clip). Its root travel is
  // taken out frame by frame (not at one mean speed), so the pose keeps only the pelvis's sway.
  bool transition = false;
  float time_at_phase(float phase) const;  // phase in [0, 1)
  // Clip seconds per unit of phase there (the table's local slope: the cycle's own steps may run
  // faster or slower than its mean, cycle_s).
  float time_per_phase(float phase) const;
  // Frame index i of the clip wrapped (a loop) or clamped into range; one already in range is
  // its own (no division: the per-frame contacts pass calls it per layer).
  int wrap_frame(int i) const {
    const int nf = clip.num_frames;
    if (i >= 0 && i < nf) return i;
    return clip.loops ? ((i % nf) + nf) % nf : (i < 0 ? 0 : nf - 1);
  }
  // The toe's height in the clip [m] between frames f0 and f0 + 1 (fu of the way, in [0, 1);
  // frames as wrap_frame has them): toe_height_m above toe_floor_m. toe_height_m[side] must not be
  // empty.
  float toe_y_at(int side, int f0, float fu) const {
    const std::vector<float>& h = toe_height_m[side];
    const float a = h[wrap_frame(f0)], b = h[wrap_frame(f0 + 1)];
    return a + fu * (b - a) + toe_floor_m[side];
  }
};

// A start (standing -> steady gait) or a stop (steady gait -> standing) found in a take, kept as
// a transition the mediator plays when an agent starts or stops (mediator_passes.h,
// transition_pass).
enum class TransitionKind : uint8_t { kStart, kStop };
const char* transition_kind_name(TransitionKind kind);
struct Transition {
  TransitionKind kind = TransitionKind::kStart;
  int clip = -1;  // its clip in LocomotionLibrary::clips (LocomotionClip::transition)
  float duration_s = 0.0f;
  float fps = 30.0f;
  // The root's speed along its path [m/s] per clip frame (smoothed over a quarter second): what
  // the playback rate follows, so the clip's feet move with the agent.
  std::vector<float> speed_m_s;
  float moving_speed_m_s = 0.0f;  // over its moving end: a start's last or a stop's first 0.25 s
  // The steady cycle (forward, nearest in speed) a start hands over to or a stop takes over from,
  // and that cycle's gait phase at the transition's moving end (matched on the foot contacts:
  // the same foot landed as long ago; phase_track has the phase at every clip time).
  int cycle_clip = -1;
  float cycle_phase = 0.0f;
  // Side of the foot that leads: a start's first foot to leave the ground, a stop's last to land.
  int lead_foot = 0;
  // Clip time [s] where its root moves: a start's last and a stop's first frame below the
  // standing speed (0.15 m/s, as take segmentation) lies before / after it.
  float moving_from_s = 0.0f;
  float moving_to_s = 0.0f;
  // The cycle's gait phase per clip frame, unwrapped (in cycles): at each of the clip's own
  // landings the phase at which the cycle lands that foot, in between as time goes (a stop's
  // slowing steps take longer than the cycle's), beyond the first and last at the cycle's own
  // rate. What the gait phase follows while the transition plays, and where a stop may begin:
  // the blend's cycle steps with the transition's feet, not with a clock that drifts from them.
  std::vector<float> phase_track;
  float speed_at(float t_s) const;  // speed_m_s between frames, held beyond the ends
  float phase_at(float t_s) const;  // phase_track between frames, in [0, 1)
  float phase_rate_at(float t_s) const;  // its slope there [cycles per clip second], > 0
};

// What the library made of a take with root motion: its segments and the clips cut from it.
struct TakeReport {
  std::string name;
  TakeSegmentation segmentation;
  std::vector<std::string> clips;  // names of the library clips cut from it
};

// Clips of one travel direction, sorted by speed.
struct DirectionGroup {
  float direction_rad = 0.0f;
  std::vector<int> clips;
};

struct LocomotionLibrary {
  std::shared_ptr<const Skeleton> skeleton;
  std::shared_ptr<const SkinnedMesh> mesh;
  std::vector<LocomotionClip> clips;
  int idle = -1;  // a standing clip (speed 0), possibly synthesised from a gait clip's frame
  std::vector<DirectionGroup> groups;  // sorted by direction in (-pi, pi]
  int forward_group = -1;
  float max_speed_m_s = 0.0f;
  float leg_length_m[2] = {0.0f, 0.0f};  // hip-knee + knee-ankle in the rest pose
  // Where people switch from walking to running (GAIT.md: about 2 m/s): Froude number
  // v^2 / (g h) = 0.5 for this skeleton's hip height h over a planted ankle [m/s]. Below it the
  // blend of a walk and a run keeps the walk the heavier (its feet and contacts): mediator_passes.
  float walk_run_speed_m_s = 2.0f;
  // A ball moving faster than this over the ground is not at rest, however fast the body goes:
  // clip analysis's still speed (half the travel speed) at Froude 0.5 on this skeleton's mean leg
  // length, hip-knee-ankle (a little below walk_run_speed_m_s, which takes the hip's height over a
  // planted ankle) [m/s]. A foot lock starts where the clip's ball rests; a runner's planted ball
  // rests as a walker's does, and at half a run's speed it is still landing. Gait clips and the
  // starts and stops cut from takes are both trimmed with it.
  float max_rest_speed_m_s = 1.0f;
  // Height of each toe joint when the foot is flat on the ground [m] (lowest over the gait clips):
  // planted feet are locked at this height.
  float toe_floor_m[2] = {0.0f, 0.0f};
  float ankle_floor_m[2] = {0.0f, 0.0f};  // likewise for the ankle joints
  // The floor the clips were authored on (METRICS.md v2): median height of each toe and ankle over
  // the frames clip analysis marks as contact, over the locomotion clips [m]. Every clip is moved
  // up or down at load so that its planted toes stand on it. Pose synthesis never draws a foot
  // below it.
  float planted_toe_m[2] = {0.0f, 0.0f};
  float planted_ankle_m[2] = {0.0f, 0.0f};
  // How much higher than authored the feet are drawn so that a flat foot stands on planted_toe_m
  // (the median of planted toes lies above a flat foot) [m].
  float ground_lift_m = 0.0f;
  // How high the slowest forward clip lifts a toe above planted_toe_m in swing (median of its
  // swings) [m]: the height of a re-planting step.
  float swing_height_m = 0.05f;
  // How fast the slowest forward clip moves a toe at the peak of its swing, over the ground at
  // its native speed (median of its swings) [m/s]: the fastest a released foot is carried.
  float swing_speed_m_s = 3.0f;
  // The way each knee bends, in its hip joint's frame (the thigh's, in which a hinge's plane is
  // fixed): the mean direction from the hip-ankle line to the knee over the gait clips' frames
  // where the knee is bent by at least 20 degrees (unit; zero: no such frame). The leg IK bends
  // the knee toward the drawn knee and, where the drawn leg is nearly straight (its knee's offset
  // from that line says little, or points backwards a centimetre where a capture overextends
  // it), toward this: a knee never flips backwards through a straight leg.
  glm::vec3 knee_bend_local[2] = {glm::vec3(0.0f), glm::vec3(0.0f)};
  // Largest per-frame change of any joint's local rotation over all source clips, resampled to
  // 60 Hz [rad] (the pop metric of METRICS.md compares against twice this).
  float max_rotation_step_rad = 0.0f;
  std::vector<TakeReport> takes;  // takes with root motion, as segmented
  // Starts and stops cut from the takes (none for clips authored as loops, such as the built-in
  // set): their clips are in `clips`, marked `transition`, after the standing clip.
  std::vector<Transition> transitions;
  bool has_transitions(TransitionKind kind) const {
    for (const Transition& t : transitions) {
      if (t.kind == kind) return true;
    }
    return false;
  }
  // Clips of the given sets that are not in the library and why (a standing clip without
  // contacts, a name that says it is no locomotion, ...): reported, never silent.
  struct LeftOut {
    std::string clip, file, why;
  };
  std::vector<LeftOut> left_out;
  std::vector<std::string> clip_names() const;
  bool has_direction_clips() const { return groups.size() > 1; }
};

// The clips left out, one line per file and reason: "file: why: clip, clip, ...".
std::vector<std::string> describe_left_out(const LocomotionLibrary& library);

// The gait clips whose contact analysis is doubtful, one line per clip: "clip: why; why"; when
// every gait clip is, a last line says the library is played as the naive mode plays it.
std::vector<std::string> describe_doubts(const LocomotionLibrary& library);

// What the library's forward clips cannot play with these parameters (their playback rate limits
// and stride stretch), one line each, for a user to be told rather than find out: no walking
// clip (every forward gait clip has a flight phase: walkers are shown running slowly), a walk and
// a run too far apart in speed for either to play alone in between (a walk's double support
// blended with a run's flight), or no running clip (faster agents are slowed through feedback,
// and a recorded crowd's, which takes none, drag their feet). Empty when none of these.
std::vector<std::string> describe_gaps(const LocomotionLibrary& library,
                                       const MediatorParams& params);

// True when the library has gait clips and the contact analysis of every one is doubtful: nothing
// the mediator adds (foot locks, rate and phase matching, blends aligned on contacts) can be
// trusted with it, so apm plays it as naive does and is never worse than naive.
bool gait_analysis_doubtful(const LocomotionLibrary& library);

// Why a gait clip's analysis is doubtful (see LocomotionClip::doubts); empty when it is sound.
// Needs the clip's analysis and phase table.
std::vector<std::string> gait_doubts(const LocomotionClip& clip);
// Sets clip->lift_phase from its phase table and swing progress (a gait clip's; -1 for a clip
// whose contacts are doubtful).
void set_lift_phases(LocomotionClip* clip);

// One line per segmented take: its segments (kind and span), the clips cut from it, and its
// problems.
std::vector<std::string> describe_takes(const LocomotionLibrary& library);

// Builds the library from one or more clip sets. The first set's skeleton is the library skeleton;
// clips of other sets are retargeted to it (retarget_clip). Errors name the set and what is
// missing.
Result<LocomotionLibrary> build_locomotion_library(const std::vector<ClipSet>& sets);

// Which source joint drives each destination joint (-1: none): by joint role (whatever the naming
// convention), then by equal name, then down single chains from mapped joints (elbows, wrists).
std::vector<int> retarget_joint_map(const Skeleton& src, const Skeleton& dst);

// Retargets a clip onto `dst` through retarget_joint_map, rest-pose aware (model-space rotations
// relative to each skeleton's rest pose); the hips travel as the source hips, scaled by
// `root_scale` (the ratio of leg lengths).
Clip retarget_clip(const Clip& clip, const Skeleton& src, const Skeleton& dst, float root_scale);

}  // namespace gk
