#include "mediator/joint_dump.h"

#include <cerrno>
#include <cstring>

#include "animation/pose_jobs.h"

namespace gk {

Result<JointDumpWriter> JointDumpWriter::open(const std::string& path, const Skeleton& skeleton,
                                              const std::vector<std::string>& names) {
  std::vector<int> joints;
  std::vector<std::string> used;
  if (names.empty()) {
    // METRICS.md v2: per foot the ankle and toe, then both knees, both hip joints and the hips.
    auto add = [&](int j) {
      if (j >= 0) {
        joints.push_back(j);
        used.push_back(skeleton.names[j]);
      }
    };
    for (Side s : {Side::kLeft, Side::kRight}) {
      add(skeleton.ankle(s));
      add(skeleton.toe(s));
    }
    for (Side s : {Side::kLeft, Side::kRight}) add(skeleton.knee(s));
    for (Side s : {Side::kLeft, Side::kRight}) add(skeleton.hip(s));
    add(skeleton.role(JointRole::kHips));
  } else {
    for (const std::string& n : names) {
      const int j = skeleton.find(n);
      if (j < 0) {
        std::string known;
        for (const std::string& k : skeleton.names) known += (known.empty() ? "" : ", ") + k;
        return Status::Error("--dump-joint-names: no joint '" + n +
                             "' in the skeleton (joints: " + known + ")");
      }
      joints.push_back(j);
      used.push_back(n);
    }
  }
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (!f) return Status::Error(path + ": cannot write joint dump: " + std::strerror(errno));
  std::fputs("frame,time_s,agent,joint,x,y,z\n", f);
  return JointDumpWriter(f, path, std::move(joints), std::move(used));
}

JointDumpWriter::JointDumpWriter(JointDumpWriter&& o) noexcept
    : file_(o.file_),
      path_(std::move(o.path_)),
      joints_(std::move(o.joints_)),
      names_(std::move(o.names_)) {
  o.file_ = nullptr;
}

JointDumpWriter::~JointDumpWriter() {
  if (file_) std::fclose(file_);
}

Status JointDumpWriter::write_frame(int frame, double time_s, const AgentFrame& agents,
                                    const Mediator& mediator, const PoseSynthesizer& poses) {
  for (size_t i = 0; i < agents.size(); ++i) {
    const int slot = mediator.plans().slot_of_agent[i];
    for (size_t k = 0; k < joints_.size(); ++k) {
      const glm::vec3 p = poses.joint_position(slot, joints_[k]);
      // Each float as the exact decimal of its double value (17 digits): a reader that
      // parses doubles gets the very numbers the metrics used, so ties between feet break alike.
      std::fprintf(file_, "%d,%.9g,%u,%s,%.17g,%.17g,%.17g\n", frame, time_s, agents.ids[i],
                   names_[k].c_str(), static_cast<double>(p.x), static_cast<double>(p.y),
                   static_cast<double>(p.z));
    }
  }
  if (std::ferror(file_)) return Status::Error(path_ + ": write failed (disk full?)");
  return Status::Ok();
}

Status JointDumpWriter::close() {
  if (!file_) return Status::Ok();
  const bool bad = std::fclose(file_) != 0;
  file_ = nullptr;
  return bad ? Status::Error(path_ + ": could not finish writing the joint dump") : Status::Ok();
}

}  // namespace gk
