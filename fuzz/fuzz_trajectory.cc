// libFuzzer harness: ETH/UCY trajectory text ("frame id x y" rows) through parse_trajectory_text;
// a table that parses is also replayed through load_trajectory_replay (which only takes a path:
// the input goes to a temporary file) for a few steps.

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <string_view>

#include "crowd/trajectory_file.h"
#include "crowd/trajectory_replay.h"

namespace {

const std::string& temp_path() {
  static const std::string path = (std::filesystem::temp_directory_path() /
                                   ("gk_fuzz_trajectory_" + std::to_string(getpid()) + ".txt"))
                                      .string();
  return path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  gk::Result<gk::TrajectoryTable> table = gk::parse_trajectory_text(text, "fuzz.txt");
  if (!table.ok()) return 0;
  {
    std::ofstream out(temp_path(), std::ios::binary | std::ios::trunc);
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
  }
  gk::Result<std::unique_ptr<gk::CrowdSource>> replay = gk::load_trajectory_replay(temp_path());
  std::filesystem::remove(temp_path());
  if (!replay.ok()) return 0;
  // 0.4 s per sample step: 50 steps of 0.1 s cover the first dozen samples of every track.
  for (int i = 0; i < 50; ++i) {
    if (!(*replay)->step(0.1f).ok()) break;
    (void)(*replay)->frame();
  }
  return 0;
}
