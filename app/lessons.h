#pragma once
// Lessons: one preset per idea of the mediator (foot sliding, playback-rate matching, foot locking,
// torso decoupling, feedback). Each sets the scenario, the camera (close on one agent where that
// helps), the speed, the overlays, and a split screen that compares exactly that one idea off
// (left) and on (right), with two or three sentences that say what to look at. The demo's Lessons
// menu and `--lesson NAME` of `demo` and `render` read this table.

#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include <glm/vec2.hpp>

#include "app/overlays.h"
#include "crowd/crowd_source.h"
#include "mediator/params.h"

namespace gk::app {

struct Lesson {
  const char* name;      // `--lesson NAME`
  const char* title;     // the menu entry and the heading over the scene
  const char* scenario;  // data/scenarios/NAME.json
  int agents;            // 0: the scenario's default
  uint64_t seed;
  float time_scale;      // the window's simulation speed (0.5: half speed)
  bool follow;           // follow the agent nearest the scene's middle after the first step
  float yaw_deg;         // camera yaw (the follow camera's, or the overview's)
  float distance_m;      // follow distance [m]
  OverlayToggles overlays;
  // The split: the compare lane (left) with the idea off, the primary lane (right) with it on.
  // Both start from the default parameters; `on` may also change the mode (e.g. `rate`).
  const char* off_label;
  const char* on_label;
  void (*off)(MediatorParams*);
  void (*on)(MediatorParams*);
  bool own_crowd;     // the idea changes the simulation (feedback): each half runs its own crowd
  bool rate_plot;     // the panel plots stride length and cadence against speed
  // Built-in clips without strafe and backward clips (CrowdOptions::builtin_walks_only): the
  // legs must turn to follow the path, which is where feedback acts.
  bool walk_clips_only;
  const char* text;   // what to look at, two or three sentences (the window)
  const char* caption;  // the same in a few upper-case words (stamped into rendered frames)
};

std::span<const Lesson> lessons();
// nullptr for an unknown name.
const Lesson* find_lesson(std::string_view name);
// "foot-sliding, playback-rate, ..." for messages and --help.
std::string lesson_names();

// The live agent nearest `point` [m], or -1 in an empty frame: the agent a lesson follows.
int64_t agent_nearest(const AgentFrame& frame, glm::vec2 point);

}  // namespace gk::app
