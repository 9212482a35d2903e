// gaitkeeper: real-time crowd animation. One executable: the interactive demo (no arguments),
// `bench` (headless benchmark with metrics as JSON), `analyze-clip` (clip analysis), `render`.

#include <cstdio>

#include <CLI/CLI.hpp>

#include "app/commands.h"

int main(int argc, char** argv) {
  CLI::App app{"gaitkeeper " GK_VERSION
               " - crowd animation without foot skating.\n"
               "An Animation Planning Mediator between a crowd simulator and skeletal animation."};
  app.require_subcommand(0, 1);
  gk::app::add_analyze_clip_command(app);
  gk::app::add_bench_command(app);
  gk::app::add_render_command(app);
  gk::app::add_demo_command(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const gk::app::ExitRequest& e) {
    return e.code;
  }
  if (app.get_subcommands().empty()) {
    try {
      return gk::app::run_default_demo();
    } catch (const gk::app::ExitRequest& e) {
      return e.code;
    }
  }
  return 0;
}
