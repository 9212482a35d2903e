// `gaitkeeper demo` (and `gaitkeeper` without arguments): the interactive window.
#include <memory>

#include <CLI/CLI.hpp>

#include "app/commands.h"
#include "app/demo_app.h"

namespace gk::app {

int run_default_demo() {
  DemoApp demo(DemoOptions{});
  return demo.run();
}

void add_demo_command(CLI::App& app) {
  auto options = std::make_shared<DemoOptions>();
  CLI::App* cmd = app.add_subcommand(
      "demo",
      "The interactive window: the crowd, a panel of parameters, overlays, live metrics "
      "(also what `gaitkeeper` without arguments opens). Without --scenario it opens on the "
      "showcase: the bottleneck's door, naive | apm, the camera on a queuing agent, then the "
      "whole room. Keys: Space pause, H help, R restart, Esc quit.");
  add_crowd_options(cmd, &options->crowd, /*scenario_required=*/false);
  cmd->add_option("--size", options->size, "Window size WxH (default 1280x720)");
  cmd->add_flag("--compare", options->compare, "Start in the naive | apm split screen");
  cmd->add_option("--overlay", options->overlays,
                  "Overlays on at start: velocity, theta, facing, planted, trails, paths, torso "
                  "(the selected agent's torso fan), legs (the selected agent's legs against its "
                  "path), all (default: torso; the showcase: trails)");
  cmd->add_option("--lesson", options->lesson,
                  "Open on a lesson: " + lesson_names() +
                      " (scenario, camera, speed, overlays and a split of that one idea off | on)");
  cmd->add_option("--select", options->select, "Agent id to select and follow from the start");
  cmd->add_option("--mesh-lod", options->mesh_lod,
                  "Lighter meshes for agents small on screen, on (default) or off")
      ->check(CLI::IsMember({"on", "off"}));
  cmd->add_option("--pull-out", options->pull_out,
                  "With --select: at this simulated time [s] the camera pulls out to the whole "
                  "scene");
  cmd->add_option("--click", options->click,
                  "With --frames: left-click at window pixel X,Y on the last frame (picking)");
  cmd->add_option("--frames", options->frames,
                  "Run this many frames (one simulation step each), then quit (scripted runs)");
  cmd->add_option("--input", options->inputs,
                  "With --frames: input at a frame, as a user would give it: FRAME:key:NAME "
                  "(space, escape, h, r, ...), FRAME:click:X,Y or FRAME:wheel:X,Y,STEPS "
                  "(repeatable)");
  cmd->add_option("--screenshot", options->screenshot,
                  "With --frames: save the last frame of the window (panel included) as PNG");
  cmd->add_option("--report", options->report,
                  "With --frames (or after Esc): write the panel rectangle, the agents' and "
                  "exhibits' pixels, the camera, simulated time, pause, help and selection as "
                  "JSON");
  cmd->callback([options] {
    DemoApp demo(*options);
    const int code = demo.run();
    if (code != 0) throw ExitRequest{code};
  });
}

}  // namespace gk::app
