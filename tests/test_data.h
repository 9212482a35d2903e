#pragma once
// Where tests find the shared real data: $GAITKEEPER_DATA, else the CMake option GK_DATA_DIR
// (default ../shared/data). When it is absent, tests skip with a message, except under CI=true
// where the absence is a failure.

#include <cstdlib>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

namespace gk::test {

inline std::string data_dir() {
  if (const char* env = std::getenv("GAITKEEPER_DATA"); env && *env) return env;
  return GK_DEFAULT_DATA_DIR;
}
inline std::string data_path(const std::string& rel) { return data_dir() + "/" + rel; }
inline bool under_ci() {
  const char* ci = std::getenv("CI");
  return ci && std::string(ci) == "true";
}
inline std::string source_path(const std::string& rel) {
  return std::string(GK_SOURCE_DIR) + "/" + rel;
}
// Scratch folder for files a test writes.
inline std::string scratch_dir(const std::string& name) {
  std::string dir = std::string(GK_BINARY_DIR) + "/test_scratch/" + name;
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace gk::test

// Skips the test (or fails it under CI=true) when a shared data file is missing.
#define GK_REQUIRE_DATA(rel)                                                                   \
  do {                                                                                         \
    const std::string gk_p_ = ::gk::test::data_path(rel);                                      \
    if (!std::filesystem::exists(gk_p_)) {                                                     \
      if (::gk::test::under_ci()) FAIL() << "shared data missing under CI: " << gk_p_;         \
      GTEST_SKIP() << "shared data not found: " << gk_p_                                       \
                   << " (set GAITKEEPER_DATA to the folder holding clips/ and trajectories/)"; \
    }                                                                                          \
  } while (0)
