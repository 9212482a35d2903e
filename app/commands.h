#pragma once
// Each CLI mode registers itself as a CLI11 subcommand; main() only wires them.

namespace CLI {
class App;
}

namespace gk::app {

void add_analyze_clip_command(CLI::App& app);  // app/cmd_analyze_clip.cc
void add_bench_command(CLI::App& app);         // app/cmd_bench.cc
void add_render_command(CLI::App& app);        // app/cmd_render.cc
void add_demo_command(CLI::App& app);          // app/cmd_demo.cc
// The demo with its defaults (gaitkeeper without arguments); returns the exit code.
int run_default_demo();

// Thrown by a command to end the program with a message and exit code (no crash, no stack trace).
struct ExitRequest {
  int code = 1;
};

}  // namespace gk::app
