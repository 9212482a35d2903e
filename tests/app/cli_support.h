#pragma once
// Runs the gaitkeeper executable for the end-to-end tests and reads what it writes.

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include <glm/gtc/type_precision.hpp>
#include <nlohmann/json.hpp>

namespace gk::test {

struct CommandResult {
  int code = -1;
  std::string out;  // stdout and stderr
};

// `env` is prepended to the command line (e.g. "DISPLAY= "). Mesa keeps driver allocations past
// context destruction, so commands that open a GL context run with leak detection off under ASan
// (ASan and UBSan themselves stay on).
// A JSON file a command wrote (null when it cannot be read).
inline nlohmann::json read_json(const std::string& path) {
  std::ifstream in(path);
  return in ? nlohmann::json::parse(in) : nlohmann::json();
}

inline CommandResult run_gaitkeeper(const std::string& args, const std::string& env = "") {
  CommandResult r;
  const std::string cmd =
      "ASAN_OPTIONS=detect_leaks=0 " + env + std::string(GK_GAITKEEPER_BIN) + " " + args + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return r;
  std::array<char, 4096> buf;
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) r.out.append(buf.data(), n);
  const int status = pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

// An RGBA8 image read from a PNG (rows top first); empty when unreadable.
struct Image {
  int width = 0, height = 0;
  std::vector<uint8_t> rgba;
  glm::u8vec4 at(int x, int y) const {
    if (x < 0 || y < 0 || x >= width || y >= height) return {0, 0, 0, 0};
    const uint8_t* p = &rgba[(static_cast<size_t>(y) * width + x) * 4];
    return {p[0], p[1], p[2], p[3]};
  }
};
Image read_png(const std::string& path);

inline int pixel_difference(glm::u8vec4 a, glm::u8vec4 b) {
  return std::abs(a.x - b.x) + std::abs(a.y - b.y) + std::abs(a.z - b.z);
}

}  // namespace gk::test

// Runs a render command into `result`; skips the test (fails it under CI) when no OpenGL context
// can be had, and asserts success otherwise.
#define GK_RUN_RENDER(result, args)                                                    \
  const ::gk::test::CommandResult result = ::gk::test::run_gaitkeeper(args);           \
  if (result.code != 0 && result.out.find("no OpenGL context") != std::string::npos) { \
    if (::gk::test::under_ci()) FAIL() << "offscreen GL required under CI: " << result.out; \
    GTEST_SKIP() << "offscreen GL unavailable: " << result.out;                        \
  }                                                                                    \
  ASSERT_EQ(result.code, 0) << result.out
