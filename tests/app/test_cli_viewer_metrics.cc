// METRICS.md v2 ("what a viewer sees of the feet") recomputed from the --dump-joints CSV of a
// bench run by this test's own code, and compared with the JSON report.

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <glm/vec3.hpp>
#include <nlohmann/json.hpp>

#include "tests/app/cli_support.h"
#include "tests/test_data.h"

namespace gk {
namespace {

using DVec3 = glm::dvec3;

// One agent's joints per frame, in the dump's default order (mediator/joint_dump.cc): left
// ankle, left toe, right ankle, right toe, left knee, right knee, left hip, right hip, hips.
constexpr int kJoints = 9;
constexpr int kAnkle[2] = {0, 2}, kToe[2] = {1, 3}, kHips = 8;
using Frame = std::array<DVec3, kJoints>;

struct Dump {
  std::vector<std::string> names;              // the dump's joint order
  std::map<int, std::map<int, Frame>> agents;  // agent -> frame -> joints
};

Dump read_dump(const std::string& path) {
  Dump d;
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "frame,time_s,agent,joint,x,y,z");
  std::map<std::pair<int, int>, int> next;  // (agent, frame) -> joints read so far
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::string f, t, a, j, x, y, z;
    for (std::string* s : {&f, &t, &a, &j, &x, &y, &z}) std::getline(ss, *s, ',');
    const int frame = std::stoi(f), agent = std::stoi(a);
    int& k = next[{agent, frame}];
    if (d.names.size() < kJoints) d.names.push_back(j);
    EXPECT_LT(k, kJoints);
    if (k >= kJoints) break;
    EXPECT_EQ(j, d.names[k]) << line;
    // %.17g: the exact value of the float as a double.
    d.agents[agent][frame][k] = DVec3(std::stod(x), std::stod(y), std::stod(z));
    ++k;
  }
  return d;
}

double horizontal(const DVec3& a, const DVec3& b) { return std::hypot(a.x - b.x, a.z - b.z); }

struct Figures {
  std::vector<double> support_cm_s;
  double support_skates = 0.0;
  int64_t float_samples = 0, float_frames = 0;
  double penetration_max_cm = 0.0;
  int64_t gmd_frames = 0, gmd_skates = 0;
};

// The METRICS.md v2 definitions over one run of consecutive frames of one agent.
void add_run(const std::vector<const Frame*>& run, const double toe_floor[2],
             const double ankle_floor[2], double dt, Figures* out) {
  const size_t n = run.size();
  auto rel = [&](int s, size_t f) { return (*run[f])[kToe[s]].y - toe_floor[s]; };
  auto near = [&](int s, size_t f) { return rel(s, f) <= 0.05; };
  // Ties (both toes exactly on their floors) go to the left foot, as the report breaks them.
  auto support = [&](size_t f) { return rel(1, f) < rel(0, f) ? 1 : 0; };
  for (size_t f = 0; f < n; ++f) {
    const Frame& p = *run[f];
    for (int s = 0; s < 2; ++s) {
      const double depth =
          std::max({0.0, toe_floor[s] - p[kToe[s]].y, ankle_floor[s] - p[kAnkle[s]].y});
      out->penetration_max_cm = std::max(out->penetration_max_cm, 100.0 * depth);
    }
    if (f == 0) continue;
    const Frame& q = *run[f - 1];
    const int s = support(f);
    if (s == support(f - 1) && near(s, f) && near(s, f - 1)) {
      const double v = 100.0 * horizontal(p[kToe[s]], q[kToe[s]]) / dt;
      out->support_cm_s.push_back(v);
      out->support_skates += v > 30.0;
    }
    const double root_speed = horizontal(p[kHips], q[kHips]) / dt;
    if (root_speed >= 0.1 && root_speed <= 2.2) {
      ++out->float_samples;
      out->float_frames += !near(0, f) && !near(1, f);
    }
  }
  // 20 fps from 60 Hz: every third frame; a frame skates when a toe within 5 cm of its floor on
  // it and on the previous 20 fps frame moved more than 2.5 cm (0.5 m/s); every 20 fps frame
  // with a previous one counts in the ratio.
  for (size_t f = 3; f < n; f += 3) {
    bool skates = false;
    for (int s = 0; s < 2; ++s) {
      const DVec3& a = (*run[f])[kToe[s]];
      const DVec3& b = (*run[f - 3])[kToe[s]];
      const bool contact = a.y - toe_floor[s] <= 0.05 && b.y - toe_floor[s] <= 0.05;
      skates |= contact && horizontal(a, b) / (3.0 * dt) > 0.5;
    }
    ++out->gmd_frames;
    out->gmd_skates += skates;
  }
}

void expect_same(double mine, const nlohmann::json& reported, const char* what) {
  ASSERT_TRUE(reported.is_number()) << what << ": " << reported;
  const double r = reported.get<double>();
  EXPECT_NEAR(mine, r, std::max(1e-3 * std::abs(r), 1e-6)) << what;
}

TEST(CliViewerMetrics, RecomputedFromTheJointDumpEqualTheReport) {
  const std::string dir = test::scratch_dir("cli_viewer_metrics");
  const std::string csv = dir + "/D.csv", json = dir + "/R.json";
  const test::CommandResult r =
      test::run_gaitkeeper("bench --scenario crossing --agents 12 --frames 240 --json " + json +
                           " --dump-joints " + csv);
  ASSERT_EQ(r.code, 0) << r.out;
  std::ifstream in(json);
  const nlohmann::json rep = nlohmann::json::parse(in);
  const nlohmann::json& m = rep["metrics"];
  // 60 Hz runs: a 20 fps frame is every third frame.
  const double dt = rep["frame_time_s"].get<double>();
  ASSERT_NEAR(dt, 1.0 / 60.0, 1e-5);
  const Dump d = read_dump(csv);
  ASSERT_EQ(d.names.size(), static_cast<size_t>(kJoints));
  double toe_floor[2], ankle_floor[2];
  for (int s = 0; s < 2; ++s) {
    ASSERT_TRUE(m["floor_m"].contains(d.names[kToe[s]])) << d.names[kToe[s]];
    ASSERT_TRUE(m["floor_m"].contains(d.names[kAnkle[s]])) << d.names[kAnkle[s]];
    toe_floor[s] = m["floor_m"][d.names[kToe[s]]].get<double>();
    ankle_floor[s] = m["floor_m"][d.names[kAnkle[s]]].get<double>();
  }
  Figures fig;
  int64_t agent_frames = 0;
  for (const auto& [agent, frames] : d.agents) {
    // An agent that vanished and came back is measured as two runs.
    std::vector<const Frame*> run;
    int last = -2;
    for (const auto& [f, joints] : frames) {
      if (f != last + 1 && !run.empty()) {
        add_run(run, toe_floor, ankle_floor, dt, &fig);
        run.clear();
      }
      run.push_back(&joints);
      last = f;
      ++agent_frames;
    }
    if (!run.empty()) add_run(run, toe_floor, ankle_floor, dt, &fig);
  }
  ASSERT_GT(agent_frames, 0);
  ASSERT_GT(fig.support_cm_s.size(), 100u);
  ASSERT_GT(fig.float_samples, 100);
  ASSERT_GT(fig.gmd_frames, 100);
  EXPECT_EQ(static_cast<int64_t>(fig.support_cm_s.size()),
            m["support_slide_samples"].get<int64_t>());
  double sum = 0.0;
  for (double v : fig.support_cm_s) sum += v;
  const double n = static_cast<double>(fig.support_cm_s.size());
  expect_same(sum / n, m["support_slide_cm_s"], "support_slide_cm_s");
  expect_same(fig.support_skates / n, m["support_skate_ratio"], "support_skate_ratio");
  expect_same(fig.penetration_max_cm, m["penetration_cm"]["max"], "penetration_cm.max");
  expect_same(static_cast<double>(fig.float_frames) / fig.float_samples, m["float_ratio"],
              "float_ratio");
  expect_same(static_cast<double>(fig.gmd_skates) / fig.gmd_frames, m["gmd_skate_ratio"],
              "gmd_skate_ratio");
}

}  // namespace
}  // namespace gk
