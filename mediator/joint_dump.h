#pragma once
// The per-frame joint dump of METRICS.md: final world-space positions of named joints of every
// agent on every frame, exactly as rendered, as CSV `frame,time_s,agent,joint,x,y,z`. Positions
// are written with 17 significant digits, the exact value of each float read as a double, so a
// metric recomputed from the file equals the one in the JSON report (feet at equal heights too).

#include <cstdio>
#include <string>
#include <vector>

#include "crowd/crowd_source.h"
#include "mediator/mediator.h"
#include "mediator/pose_synthesis.h"

namespace gk {

class JointDumpWriter {
 public:
  // names: joint names of the library skeleton; empty = left/right ankle and toe, both knees,
  // both hip joints and the hips (METRICS.md v2).
  static Result<JointDumpWriter> open(const std::string& path, const Skeleton& skeleton,
                                      const std::vector<std::string>& names);
  JointDumpWriter(JointDumpWriter&& other) noexcept;
  JointDumpWriter& operator=(JointDumpWriter&&) = delete;
  ~JointDumpWriter();
  Status write_frame(int frame, double time_s, const AgentFrame& agents, const Mediator& mediator,
                     const PoseSynthesizer& poses);
  Status close();

 private:
  JointDumpWriter(std::FILE* f, std::string path, std::vector<int> joints,
                  std::vector<std::string> names)
      : file_(f), path_(std::move(path)), joints_(std::move(joints)), names_(std::move(names)) {}
  std::FILE* file_ = nullptr;
  std::string path_;
  std::vector<int> joints_;
  std::vector<std::string> names_;
};

}  // namespace gk
