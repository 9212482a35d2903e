// gaitkeeper: real-time crowd animation. One executable: the interactive demo (no arguments),
// `bench` (headless benchmark with metrics as JSON), `analyze-clip` (clip analysis), `render`.

#include <cstdio>
#include <exception>
#include <new>

#include <CLI/CLI.hpp>

#include "app/commands.h"

namespace {

// Last line of defence: input errors are reported where they are found (Status, ExitRequest); an
// exception reaching main (out of memory for a huge --frames run, a library's throw) still ends
// in a message and exit code 1 rather than std::terminate.
int report_unexpected(const std::exception& e) {
  const bool out_of_memory = dynamic_cast<const std::bad_alloc*>(&e) != nullptr;
  std::fprintf(stderr, "gaitkeeper: %s: %s\n", out_of_memory ? "out of memory" : "unexpected error",
               e.what());
  return 1;
}

}  // namespace

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
  } catch (const std::exception& e) {
    return report_unexpected(e);
  }
  if (app.get_subcommands().empty()) {
    try {
      return gk::app::run_default_demo();
    } catch (const gk::app::ExitRequest& e) {
      return e.code;
    } catch (const std::exception& e) {
      return report_unexpected(e);
    }
  }
  return 0;
}
