#include "app/lessons.h"

#include <glm/geometric.hpp>

namespace gk::app {
namespace {

OverlayToggles overlays(bool trails, bool planted, bool velocity, bool theta, bool torso) {
  OverlayToggles t;
  t.trails = trails;
  t.planted = planted;
  t.velocity = velocity;
  t.theta = theta;
  t.torso = torso;
  return t;
}

// The feedback lesson: trails show the sliding, the fan and the label the selected agent's legs
// against its path and speed.
OverlayToggles legs_overlays() {
  OverlayToggles t = overlays(true, false, false, false, false);
  t.legs = true;
  return t;
}

void keep(MediatorParams*) {}
void naive(MediatorParams* p) { p->mode = MediatorMode::kNaive; }
void rate_only(MediatorParams* p) { p->mode = MediatorMode::kRate; }
void no_locking(MediatorParams* p) { p->foot_locking = false; }
// No twist allowed: the upper body cannot turn away from the legs.
void no_twist(MediatorParams* p) { p->torsion_limit_deg = 0.0f; }
void no_feedback(MediatorParams* p) { p->feedback = false; }
// The feedback lesson: clips played at most at their own speed, with no stride warp, so the legs
// go no faster than the fastest walk (1.8 m/s), and runners ask for far more.
void walk_speeds(MediatorParams* p) {
  p->max_playback_rate = 1.0f;
  p->max_stride_warp = 0.0f;
}
void walk_speeds_no_feedback(MediatorParams* p) {
  walk_speeds(p);
  no_feedback(p);
}

const Lesson kLessons[] = {
    {"foot-sliding", "Foot sliding", "bottleneck", 0, 1, 0.5f, true, 180.0f, 7.0f,
     overlays(true, false, false, false, false), "naive", "apm", naive, keep, false, false, false,
     "Left, naive animation: one clip at its own speed while the simulator moves the body at "
     "another, so feet smear over the ground (red trails). Right, the mediator: every planted "
     "foot leaves a still, green footprint. Watch the followed agent's feet at half speed.",
     "FOOT SLIDING - RED TRAILS: FEET SKATE. GREEN: FEET STAND STILL"},
    {"playback-rate", "Playback-rate matching", "crossing", 24, 1, 0.5f, true, 110.0f, 7.0f,
     overlays(true, false, false, false, false), "naive", "rate", naive, rate_only, false, true,
     false,
     "Left, naive: the clip plays at its native rate whatever the agent's speed, so feet of "
     "walkers slower or faster than the clip slip (yellow and red ticks). Right, rate matching "
     "only: the clip plays faster or slower so its stride speed equals the walking speed, and "
     "steady walkers leave green ticks; turns and speed changes still slip. The panel plots the "
     "selected agent's stride length and cadence against its speed beside the clip's own values.",
     "RATE MATCHING - CLIP PLAYED AT AGENT SPEED / CLIP SPEED"},
    {"foot-locking", "Foot locking", "crossing", 12, 1, 0.5f, true, 200.0f, 5.0f,
     overlays(true, true, false, false, false), "locking off", "locking on", no_locking, keep,
     false, false, false,
     "Both halves run the whole mediator; only foot locking differs (parameter foot_locking). "
     "White crosses, on the right only, mark feet pinned in world space by two-bone IK: the toe "
     "stays on its cross until the clip lifts it. On the left nothing holds the foot: in a "
     "steady walk it looks the same, but where the walker starts, turns or stops the feet slip "
     "(red ticks).",
     "FOOT LOCKING - WHITE CROSSES: PINNED FEET"},
    {"torso-decoupling", "Torso decoupling", "gallery", 24, 1, 0.5f, true, 160.0f, 6.0f,
     overlays(false, false, false, true, true), "no twist", "twist 60 deg", no_twist, keep, false,
     false, false,
     "Visitors walk past the exhibits and look at them (yellow: where the agent looks). Right: "
     "the legs follow the walking direction, the upper body turns toward the exhibit within the "
     "60 degree limit (fan: blue pelvis, orange chest, white arc the limit; the twist is written "
     "above the head). Left, no twist allowed: pelvis and chest turn as one piece and the chest "
     "stays off the yellow line.",
     "TORSO DECOUPLING - BLUE PELVIS, ORANGE CHEST, YELLOW LOOK"},
    {"feedback", "Feedback", "rush", 0, 1, 0.5f, true, 90.0f, 7.0f, legs_overlays(), "feedback off",
     "feedback on", walk_speeds_no_feedback, walk_speeds, true, false, true,
     "Runners (2.6-3.8 m/s) with only the built-in walking clips, played at most at their own "
     "speed: the legs can go 1.8 m/s. Each half runs its own crowd. Left, no feedback: the "
     "simulator moves the bodies at running speed while the legs walk, so the feet slide (red "
     "trails). Right: the mediator tells the simulator the speed the legs can deliver; the "
     "runners slow to a fast walk and leave still, green footprints. Above the head: the "
     "simulator's speed against the legs' maximum. The same agent is ringed on both sides; one "
     "camera aims between the two and backs away as the left one is carried ahead of where its "
     "legs could take it.",
     "FEEDBACK - SIMULATOR SPEED VS WHAT THE LEGS CAN DO (ABOVE THE HEAD)"},
};

}  // namespace

std::span<const Lesson> lessons() { return kLessons; }

const Lesson* find_lesson(std::string_view name) {
  for (const Lesson& l : kLessons) {
    if (name == l.name) return &l;
  }
  return nullptr;
}

std::string lesson_names() {
  std::string out;
  for (const Lesson& l : kLessons) {
    if (!out.empty()) out += ", ";
    out += l.name;
  }
  return out;
}

int64_t agent_nearest(const AgentFrame& frame, glm::vec2 point) {
  float best = 1e30f;
  int64_t id = -1;
  for (size_t i = 0; i < frame.size(); ++i) {
    const float d = glm::length(frame.positions[i] - point);
    if (d < best) best = d, id = frame.ids[i];
  }
  return id;
}

}  // namespace gk::app
