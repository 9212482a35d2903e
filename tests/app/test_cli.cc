// The gaitkeeper executable end to end: analyze-clip over the real clips, bench reports, and the
// METRICS.md rule that a metric recomputed from the --dump-joints CSV equals the JSON's.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <glm/vec3.hpp>
#include <nlohmann/json.hpp>

#include "tests/app/cli_support.h"
#include "app/clip_plot.h"
#include "tests/test_data.h"

namespace gk {
namespace {

using test::read_json;

using test::CommandResult;
CommandResult run(const std::string& args) { return test::run_gaitkeeper(args); }


TEST(Cli, AnalyzeClipCoversEverySharedClip) {
  GK_REQUIRE_DATA("clips/bvh/cmu_07_01_walk.bvh");
  const std::string out = test::scratch_dir("cli") + "/analysis.json";
  const CommandResult r =
      run("analyze-clip --json " + test::data_path("clips/bvh") + " " +
          test::data_path("clips/gltf/ual_mannequin_quaternius.glb") + " > " + out);
  ASSERT_EQ(r.code, 0) << r.out;
  const nlohmann::json all = read_json(out);
  // 8 BVH clips + 44 glb animations (PROVENANCE.md).
  ASSERT_EQ(all.size(), 52u);
  std::map<std::string, nlohmann::json> by_name;
  for (const auto& c : all) {
    for (const char* field :
         {"name", "frames", "fps", "duration_s", "joints", "scale", "native_speed_m_s",
          "direction_deg", "cycle", "contacts", "foot_slide_floor_cm_s"}) {
      EXPECT_TRUE(c.contains(field)) << field;
    }
    by_name[c["name"].get<std::string>()] = c;
  }
  EXPECT_NEAR(by_name["cmu_07_01_walk"]["native_speed_m_s"].get<double>(), 1.36, 0.068);
  EXPECT_NEAR(by_name["cmu_09_11_run"]["native_speed_m_s"].get<double>(), 3.50, 0.175);
  EXPECT_NEAR(by_name["cmu_07_01_walk"]["scale"].get<double>(), 0.056444, 1e-6);
  EXPECT_EQ(by_name["cmu_07_01_walk"]["frames"].get<int>(), 316);
  EXPECT_EQ(by_name["Walk_Loop"]["joints"].get<int>(), 53);
}

// analyze-clip says how a capture below 60 fps is played (upsampled, its analysis on the captured
// frames), and says nothing of it for a 120 fps capture.
TEST(Cli, AnalyzeClipSaysWhichClipsArePlayedUpsampled) {
  GK_REQUIRE_DATA("clips/bvh/more/cmu_16_15_walk_mrl30.bvh");
  CommandResult r =
      run("analyze-clip " + test::data_path("clips/bvh/more/cmu_16_15_walk_mrl30.bvh"));
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("played at 60 fps: 1 clip(s) captured at 30 fps, upsampled"),
            std::string::npos)
      << r.out;
  r = run("analyze-clip " + test::data_path("clips/bvh/cmu_07_01_walk.bvh"));
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(r.out.find("upsampled"), std::string::npos) << r.out;
}

TEST(Cli, AnalyzeClipNamesTheBrokenFile) {
  const std::string bad = test::source_path("tests/data/bad/channel_count.bvh");
  const CommandResult r = run("analyze-clip " + bad);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.out.find("channel_count.bvh:"), std::string::npos) << r.out;
}

// Foot slide recomputed from the CSV with the METRICS.md definitions, independently of the code.
struct Slide {
  double mean = 0.0, skate = 0.0, drift = 0.0;
  size_t samples = 0;
};

Slide slide_from_csv(const std::string& path, const std::string& toe_l, const std::string& ankle_l,
                     const std::string& toe_r, const std::string& ankle_r, double dt) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "frame,time_s,agent,joint,x,y,z");
  // agent -> joint -> frame -> position
  std::map<int, std::map<std::string, std::map<int, glm::vec3>>> data;
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::string f, t, a, j, x, y, z;
    std::getline(ss, f, ',');
    std::getline(ss, t, ',');
    std::getline(ss, a, ',');
    std::getline(ss, j, ',');
    std::getline(ss, x, ',');
    std::getline(ss, y, ',');
    std::getline(ss, z, ',');
    data[std::stoi(a)][j][std::stoi(f)] = glm::vec3(std::stof(x), std::stof(y), std::stof(z));
  }
  std::vector<double> speeds;
  double drift_sum = 0.0;
  int intervals = 0;
  for (auto& [agent, joints] : data) {
    for (auto [toe_name, ankle_name] : {std::pair{toe_l, ankle_l}, std::pair{toe_r, ankle_r}}) {
      auto& toe = joints[toe_name];
      auto& ankle = joints[ankle_name];
      float min_t = 1e9f, min_a = 1e9f;
      for (auto& [f, p] : toe) min_t = std::min(min_t, p.y);
      for (auto& [f, p] : ankle) min_a = std::min(min_a, p.y);
      std::vector<int> frames;
      for (auto& [f, p] : toe) frames.push_back(f);
      std::vector<bool> contact(frames.size());
      for (size_t k = 0; k < frames.size(); ++k) {
        contact[k] = toe[frames[k]].y <= min_t + 0.025f && ankle[frames[k]].y <= min_a + 0.05f;
      }
      size_t run_start = 0;
      for (size_t k = 0; k < frames.size(); ++k) {
        const glm::vec3 p = toe[frames[k]];
        if (contact[k] && (k == 0 || !contact[k - 1])) run_start = k;
        if (k > 0 && contact[k] && contact[k - 1]) {
          const glm::vec3 q = toe[frames[k - 1]];
          speeds.push_back(100.0 * std::hypot(double(p.x) - q.x, double(p.z) - q.z) / dt);
        }
        const bool ends = contact[k] && (k + 1 == frames.size() || !contact[k + 1]);
        if (ends && k > run_start) {
          const glm::vec3 s = toe[frames[run_start]];
          drift_sum += 100.0 * std::hypot(double(p.x) - s.x, double(p.z) - s.z);
          ++intervals;
        }
      }
    }
  }
  Slide out;
  out.samples = speeds.size();
  for (double v : speeds) {
    out.mean += v;
    out.skate += v > 30.0;
  }
  if (!speeds.empty()) {
    out.mean /= speeds.size();
    out.skate /= speeds.size();
  }
  if (intervals) out.drift = drift_sum / intervals;
  return out;
}

TEST(Cli, MetricRecomputedFromTheJointDumpEqualsTheReport) {
  const std::string dir = test::scratch_dir("cli");
  const std::string csv = dir + "/joints.csv", json = dir + "/report.json";
  const CommandResult r =
      run("bench --scenario crossing --agents 16 --frames 240 --mode apm --json " + json +
          " --dump-joints " + csv);
  ASSERT_EQ(r.code, 0) << r.out;
  const nlohmann::json rep = read_json(json);
  const auto& m = rep["metrics"];
  // The built-in skeleton's feet: CMU-style names.
  const Slide s = slide_from_csv(csv, "LeftToeBase", "LeftFoot", "RightToeBase", "RightFoot",
                                 rep["frame_time_s"].get<double>());
  ASSERT_GT(s.samples, 100u);
  EXPECT_EQ(static_cast<int64_t>(s.samples), m["foot_slide_samples"].get<int64_t>());
  EXPECT_NEAR(s.mean, m["foot_slide_cm_s"].get<double>(), 1e-3 * s.mean + 1e-6);
  EXPECT_NEAR(s.skate, m["skate_ratio"].get<double>(), 1e-6);
  EXPECT_NEAR(s.drift, m["foot_drift_cm_per_step"].get<double>(), 1e-3 * s.drift + 1e-6);
  // Headless: no upload or render stage, and they are null, not 0.
  EXPECT_TRUE(rep["timing_ms"]["render"].is_null());
  EXPECT_TRUE(rep["render"].is_null());
  EXPECT_TRUE(rep["timing_ms"]["upload"].is_null());
  EXPECT_TRUE(rep["timing_ms"]["pose"]["median"].is_number());
  EXPECT_EQ(rep["joints"].get<int>(), 25);
}

// The feedback lesson's claim, measured: runners (the rush scenario) with only the built-in walks
// played at most at their own speed. Without feedback the simulator keeps them above what the
// legs can do and the support feet slide; with it they slow to the fastest walk and stand still.
TEST(Cli, FeedbackSlowsRunnersToWhatWalkingLegsCanDo) {
  const std::string dir = test::scratch_dir("cli");
  double speed[2], max_speed[2], slide[2];
  for (int on = 0; on < 2; ++on) {
    const std::string json = dir + "/rush_feedback_" + std::to_string(on) + ".json";
    const CommandResult r =
        run("bench --scenario rush --frames 360 --walk-clips-only --set max_playback_rate=1 "
            "--set max_stride_warp=0 --set max_accel_m_s2=20 --set feedback=" +
            std::string(on ? "true" : "false") + " --json " + json);
    ASSERT_EQ(r.code, 0) << r.out;
    const nlohmann::json rep = read_json(json);
    speed[on] = rep["crowd"]["mean_speed_m_s"].get<double>();
    max_speed[on] = rep["crowd"]["max_speed_m_s"].get<double>();
    slide[on] = rep["metrics"]["support_slide_cm_s"].get<double>();
  }
  // walk_fast is generated at 1.8 m/s (animation/procedural_clips.cc): the legs' maximum here.
  // (The speed-up limit is lifted to the simulator's own: this is about the top speed alone; the
  // speed-up has its own test, Mediator.FeedsBackAStartTheLegsCanMake.)
  // The crowd's speeds are those the simulator proposes, before feedback: one frame of its
  // driving force above what was fed back (dv/dt = (v0 - v) / tau with the fastest runner's
  // v0 = 3.8 m/s and tau = 0.5 s, crowd/social_forces.h), plus the other agents' pushes.
  EXPECT_LE(max_speed[1], 1.8 + (3.8 - 1.8) / 0.5 / 60.0 + 0.02);
  EXPECT_GT(speed[0], 1.8 * 1.2) << "without feedback the runners keep running";
  EXPECT_LT(slide[1], 0.25 * slide[0]) << "feet slide without feedback, stand with it";
}

TEST(Cli, BenchReplaysRealTrajectories) {
  GK_REQUIRE_DATA("trajectories/zara1/crowds_zara01.txt");
  const std::string json = test::scratch_dir("cli") + "/zara.json";
  const CommandResult r =
      run("bench --scenario " + test::data_path("trajectories/zara1/crowds_zara01.txt") +
          " --frames 300 --json " + json);
  ASSERT_EQ(r.code, 0) << r.out;
  const nlohmann::json rep = read_json(json);
  EXPECT_GT(rep["crowd"]["max_live_agents"].get<int>(), 0);
  // The data is the truth: no feedback, so the rendered root only sways about p.
  EXPECT_TRUE(rep["metrics"]["feedback_speed_change"].is_null());
  EXPECT_LT(rep["metrics"]["root_error_cm"]["mean"].get<double>(), 10.0);
}

TEST(Cli, BenchLoopsAScenarioAndReportsProgress) {
  // The bottleneck empties through its door; --loop brings a new round in when the last agent has
  // left. --progress-every prints one JSON line per 300 frames.
  const CommandResult r =
      run("bench --scenario bottleneck --agents 20 --frames 3600 --loop --progress-every 300");
  ASSERT_EQ(r.code, 0) << r.out;
  std::vector<nlohmann::json> lines;
  std::istringstream in(r.out);
  for (std::string line; std::getline(in, line);) {
    if (!line.empty() && line[0] == '{') lines.push_back(nlohmann::json::parse(line));
  }
  ASSERT_EQ(lines.size(), 12u) << r.out;
  int rounds = 1;
  for (size_t k = 0; k < lines.size(); ++k) {
    const nlohmann::json& j = lines[k];
    EXPECT_EQ(j["frame"].get<int>(), 300 * static_cast<int>(k + 1));
    EXPECT_NEAR(j["sim_time_s"].get<double>(), 5.0 * (k + 1), 1e-3);
    EXPECT_EQ(j["live_tracks"].get<int>(), j["live_agents"].get<int>());
    EXPECT_GT(j["rss_kib"].get<int64_t>(), 0);
    EXPECT_GT(j["frame_ms"].get<double>(), 0.0);
    EXPECT_GE(j["frame_ms_max"].get<double>(), j["frame_ms"].get<double>());
    EXPECT_GT(j["cpu_ms"].get<double>(), 0.0);
    EXPECT_GT(j["cpu_us_per_agent_frame"].get<double>(), 0.0);
    for (const char* what : {"crowd", "poses", "joints"}) {
      EXPECT_EQ(j["non_finite"][what].get<int64_t>(), 0) << what;
    }
    if (k > 0 && j["live_agents"].get<int>() > lines[k - 1]["live_agents"].get<int>()) ++rounds;
  }
  EXPECT_GE(rounds, 2) << r.out;
  // The text report states how far METRICS.md v1's contact band was widened (docs/metrics.md).
  EXPECT_NE(r.out.find("v1 contact band excess"), std::string::npos) << r.out;
}

// Issue #11: --lod reports the agents per level (together the crowd) and that the metrics cover
// level 0 only; bad LOD options are refused naming the option.
TEST(Cli, BenchLodReportsAgentsPerLevel) {
  const std::string json = test::scratch_dir("cli") + "/lod.json";
  // The focus on one end of the corridor, where half the crowd starts.
  CommandResult r = run("bench --scenario corridor --frames 120 --lod --lod-distances 3,6,12 "
                        "--lod-focus 12,0 --json " + json);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("lod: focus"), std::string::npos) << r.out;
  const nlohmann::json rep = read_json(json);
  const nlohmann::json& lod = rep["lod"];
  ASSERT_TRUE(lod.is_object()) << rep.dump();
  double agents = 0.0;
  for (const nlohmann::json& n : lod["mean_agents_per_level"]) agents += n.get<double>();
  EXPECT_NEAR(agents, rep["crowd"]["mean_live_agents"].get<double>(), 1e-6);
  EXPECT_GT(lod["mean_agents_per_level"][0].get<double>(), 0.0);
  EXPECT_GT(lod["mean_agents_per_level"][3].get<double>(), 0.0);
  EXPECT_LT(lod["mean_agents_updated"].get<double>(), agents);
  EXPECT_EQ(lod["distances_m"][1].get<double>(), 6.0);
  EXPECT_EQ(lod["focus_m"][0].get<double>(), 12.0);
  EXPECT_NE(lod["metrics_cover"].get<std::string>().find("level 0"), std::string::npos);
  // Without --lod the report says null.
  r = run("bench --scenario corridor --frames 40 --json " + json);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(read_json(json)["lod"].is_null());
  r = run("bench --scenario corridor --frames 10 --lod --lod-distances 8,4,12");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--lod-distances"), std::string::npos) << r.out;
  r = run("bench --scenario corridor --frames 10 --lod --lod-focus 1,x");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--lod-focus"), std::string::npos) << r.out;
  r = run("bench --scenario corridor --frames 10 --lod-distances 4,8,12");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("need --lod"), std::string::npos) << r.out;
}

TEST(Cli, BadParametersAreRefusedWithTheirLimits) {
  CommandResult r = run("bench --scenario corridor --frames 10 --set torsion_limit_deg=400");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("torsion_limit_deg"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("0..90"), std::string::npos) << r.out;
  r = run("bench --scenario corridor --frames 10 --set no_such_thing=1");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("unknown parameter"), std::string::npos) << r.out;
  r = run("bench --scenario corridor --frames 10 --mode skate");
  EXPECT_EQ(r.code, 2);
  r = run("bench --scenario corridor --frames 10 --clips /no/such/file.bvh");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("/no/such/file.bvh"), std::string::npos) << r.out;
}

// --- Issue #12: bad input ends in a message naming what was wrong, a non-zero exit, no crash. ---

std::string write_file(const std::string& name, const std::string& bytes) {
  const std::string path = test::scratch_dir("cli_bad_input") + "/" + name;
  std::ofstream(path, std::ios::binary) << bytes;
  return path;
}

std::string make_dir(const std::string& name) {
  const std::string dir = test::scratch_dir("cli_bad_input") + "/" + name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// No raw bytes of a binary input in what the program printed.
bool printable_text(const std::string& s) {
  return std::all_of(s.begin(), s.end(),
                     [](char c) { return (c >= 0x20 && c < 0x7F) || c == '\n' || c == '\r'; });
}

TEST(CliBadInput, ScenarioNumberTooLargeForADouble) {
  const std::string s =
      write_file("huge.json", "{\"name\": \"huge\", \"default_agents\": 1e400}\n");
  const CommandResult r = run("bench --scenario " + s + " --frames 2");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find(s + ": invalid JSON: number too large at line 1"), std::string::npos)
      << r.out;
  EXPECT_EQ(r.out.find("terminate"), std::string::npos) << r.out;
}

TEST(CliBadInput, ParamsNumberTooLargeForADouble) {
  const std::string p = write_file("huge_params.json", "{\"torsion_limit_deg\": 1e400}");
  const CommandResult r = run("bench --scenario corridor --frames 2 --params " + p);
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find(p + ": invalid JSON: number too large"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("'1e400'"), std::string::npos) << r.out;
}

TEST(CliBadInput, ParamsNamingADirectory) {
  const std::string dir = make_dir("params_dir");
  const CommandResult r = run("bench --scenario corridor --frames 2 --params " + dir);
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find(dir + ": is a directory, expected a parameter file"), std::string::npos)
      << r.out;
}

TEST(CliBadInput, TrajectoryNamingADirectory) {
  const std::string dir = make_dir("tracks.txt");
  const CommandResult r = run("bench --scenario " + dir + " --frames 2");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find(dir + ": is a directory, expected a trajectory file"), std::string::npos)
      << r.out;
  EXPECT_EQ(r.out.find("too large"), std::string::npos) << r.out;
}

TEST(CliBadInput, AnalyzeClipOnAFolderWithoutClips) {
  const std::string dir = make_dir("no_clips");
  const CommandResult r = run("analyze-clip " + dir);
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find(dir + ": the folder holds no clips (expected .bvh, .gltf or .glb files)"),
            std::string::npos)
      << r.out;
}

TEST(CliBadInput, TooManyAgentsAreRefusedBeforeTheSetup) {
  const CommandResult r = run("bench --scenario corridor --frames 2 --agents 500000");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("--agents: expected a number in [0, 250000], got '500000'"),
            std::string::npos)
      << r.out;
  EXPECT_EQ(r.out.find("exceed max_agents"), std::string::npos) << "refused up front: " << r.out;
  // A scenario whose own default is beyond the limit is refused the same way.
  std::ifstream in(test::source_path("data/scenarios/corridor.json"));
  std::string corridor((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t at = corridor.find("\"default_agents\": 60");
  ASSERT_NE(at, std::string::npos);
  corridor.replace(at, 20, "\"default_agents\": 300000");
  const std::string big = write_file("big_default.json", corridor);
  const CommandResult d = run("bench --scenario " + big + " --frames 2");
  EXPECT_EQ(d.code, 2) << d.out;
  EXPECT_NE(d.out.find("default_agents 300000 exceeds the limit of 250000 agents"),
            std::string::npos)
      << d.out;
}

TEST(CliBadInput, OutputPathsAreCheckedBeforeTheWork) {
  // 100,000 frames would run for minutes: the error must come first.
  CommandResult r = run("bench --scenario corridor --frames 100000 --json /nonexistent/r.json");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("--json /nonexistent/r.json: the folder /nonexistent does not exist"),
            std::string::npos)
      << r.out;
  r = run("bench --scenario corridor --frames 100000 --dump-joints /nonexistent/j.csv");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("--dump-joints /nonexistent/j.csv: the folder /nonexistent does not exist"),
            std::string::npos)
      << r.out;
  const std::string dir = make_dir("json_is_a_dir");
  r = run("bench --scenario corridor --frames 100000 --json " + dir);
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("--json " + dir + ": is a directory, expected a file name"),
            std::string::npos)
      << r.out;
}

TEST(CliBadInput, BinaryFilesAreNotEchoed) {
  static constexpr char kBytes[] =
      "\x7f"
      "ELF\x02\x01\x01\x00\x1b[2J\x1b]0;x\x07\xff\xfe 1 2 3\n";
  const std::string bytes(kBytes, sizeof(kBytes) - 1);
  const std::string bvh = write_file("binary.bvh", bytes);
  CommandResult r = run("analyze-clip " + bvh);
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find(bvh + ":1: expected 'HIERARCHY', found '\\x7fELF"), std::string::npos)
      << r.out;
  EXPECT_TRUE(printable_text(r.out)) << r.out;
  const std::string txt = write_file("binary.txt", bytes);
  r = run("bench --frames 2 --scenario " + txt);
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find(txt + ":1: column 1 (frame): expected a number, found '\\x7fELF"),
            std::string::npos)
      << r.out;
  EXPECT_TRUE(printable_text(r.out)) << r.out;
  const std::string json = write_file("binary.json", bytes);
  r = run("bench --frames 2 --scenario " + json);
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find(json + ": invalid JSON: parse error at line 1"), std::string::npos) << r.out;
  EXPECT_TRUE(printable_text(r.out)) << r.out;
}

// --frames keeps its limit of 10,000,000; such a run must start and keep running (it reserved
// agents x frames metric samples up front: 40 GB for 1,000 agents, std::bad_alloc). `timeout`
// ends it: exit 124.
TEST(CliBadInput, LongestRunStartsWithoutCrashing) {
  const CommandResult r = test::run_gaitkeeper(
      "bench --scenario corridor --agents 1000 --frames 10000000", "timeout 8 ");
  EXPECT_EQ(r.code, 124) << r.out;
  const CommandResult over = run("bench --scenario corridor --frames 10000001");
  EXPECT_EQ(over.code, 2) << over.out;
  EXPECT_NE(over.out.find("--frames: expected a number in [1, 10000000]"), std::string::npos)
      << over.out;
}

// --roles reaches the loader on every command that loads clips: a manifest that swaps the legs of
// the subject-16 skeleton turns the analysed travel direction round (the hip line, and so the
// facing, is reversed), and bench refuses a manifest naming a joint the skeleton lacks, naming the
// manifest and the field.
TEST(Cli, RolesManifestReachesAnalyzeClipAndBench) {
  const char* clip = "clips/bvh/more/cmu_16_15_walk_mrl30.bvh";
  GK_REQUIRE_DATA(clip);
  const std::string dir = test::scratch_dir("cli_roles");
  const std::string swapped = dir + "/swapped.json";
  {
    std::ofstream f(swapped);
    f << R"({"roles": {"left_hip": "rfemur", "left_knee": "rtibia", "left_ankle": "rfoot",
                       "left_toe": "rtoes", "right_hip": "lfemur", "right_knee": "ltibia",
                       "right_ankle": "lfoot", "right_toe": "ltoes"}})";
  }
  const std::string out_plain = dir + "/plain.json", out_swapped = dir + "/swapped_out.json";
  ASSERT_EQ(run("analyze-clip --json " + test::data_path(clip) + " > " + out_plain).code, 0);
  const CommandResult r = run("analyze-clip --json --roles " + swapped + " " +
                              test::data_path(clip) + " > " + out_swapped);
  ASSERT_EQ(r.code, 0) << r.out;
  const double plain = read_json(out_plain)[0]["direction_deg"].get<double>();
  const double turned = read_json(out_swapped)[0]["direction_deg"].get<double>();
  EXPECT_LT(std::abs(plain), 10.0);
  EXPECT_GT(std::abs(turned), 170.0);

  const std::string wrong = dir + "/wrong.json";
  {
    std::ofstream f(wrong);
    f << R"({"roles": {"left_knee": "Knee_L"}})";
  }
  const CommandResult b = run("bench --scenario corridor --agents 4 --frames 10 --clips " +
                              test::data_path(clip) + " --roles " + wrong);
  EXPECT_EQ(b.code, 2) << b.out;
  EXPECT_NE(b.out.find("wrong.json"), std::string::npos) << b.out;
  EXPECT_NE(b.out.find("roles.left_knee"), std::string::npos) << b.out;
  EXPECT_NE(b.out.find("Knee_L"), std::string::npos) << b.out;
}

// analyze-clip --plot draws what the analysis found: one block of panels per clip, and in the left
// toe's height panel the pixels under the middle of each left contact are shaded (green), those in
// the middle of each gap between left contacts are not. An unwritable --plot path fails before the
// work.
TEST(Cli, AnalyzeClipPlotShadesTheContactsItReports) {
  const char* clip = "clips/bvh/more/cmu_16_15_walk_mrl30.bvh";
  GK_REQUIRE_DATA(clip);
  const std::string dir = test::scratch_dir("cli_plot");
  const std::string png = dir + "/plot.png", json = dir + "/analysis.json";
  const CommandResult r =
      run("analyze-clip --json --plot " + png + " " + test::data_path(clip) + " > " + json);
  ASSERT_EQ(r.code, 0) << r.out;
  const test::Image img = test::read_png(png);
  ASSERT_EQ(img.width, app::kClipPlotWidth);
  ASSERT_EQ(img.height, app::kClipPlotHeight);
  const nlohmann::json a = read_json(json)[0];
  const double dur = a["duration_s"].get<double>();
  auto pixel_x = [&](double t) {
    return static_cast<int>(app::kClipPlotLeft + (app::kClipPlotRight - app::kClipPlotLeft) * t / dur);
  };
  // A pixel near the top of the left-height panel (above the curve).
  const int y = app::kClipPlotPanelTop + 4;
  auto greenish = [&](int x) {
    const uint8_t* p = &img.rgba[(static_cast<size_t>(y) * img.width + x) * 4];
    return p[1] > p[0] + 30 && p[1] > p[2] + 30;
  };
  const auto& left = a["contacts"]["left"];
  ASSERT_GE(left.size(), 2u);
  for (size_t i = 0; i < left.size(); ++i) {
    const double t0 = left[i][0].get<double>(), t1 = left[i][1].get<double>();
    EXPECT_TRUE(greenish(pixel_x(0.5 * (t0 + t1)))) << "contact " << i;
    if (i + 1 < left.size()) {
      const double gap = 0.5 * (t1 + left[i + 1][0].get<double>());
      EXPECT_FALSE(greenish(pixel_x(gap))) << "gap after contact " << i;
    }
  }
  const CommandResult bad =
      run("analyze-clip --plot /nonexistent_dir/x.png " + test::data_path(clip));
  EXPECT_EQ(bad.code, 2) << bad.out;
  EXPECT_NE(bad.out.find("--plot"), std::string::npos) << bad.out;
}

// A take without a steady stride (a jog that stops at once) still gives a library (its least
// unsteady stride), and bench says so: the report lists the take's segments and the problem, in
// the text summary and in the JSON report.
TEST(Cli, BenchReportsWhatItMadeOfEachTake) {
  const char* clip = "clips/bvh/more/cmu_16_57_run_jog_sudden_stop_mrl30.bvh";
  GK_REQUIRE_DATA(clip);
  const std::string json = test::scratch_dir("cli_takes") + "/report.json";
  const CommandResult r = run("bench --scenario corridor --agents 6 --frames 30 --clips " +
                              test::data_path(clip) + " --json " + json);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("take cmu_16_57_run_jog_sudden_stop_mrl30: stop"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("no steady stride"), std::string::npos) << r.out;
  const nlohmann::json report = read_json(json);
  ASSERT_EQ(report["takes"].size(), 1u);
  EXPECT_NE(report["takes"][0].get<std::string>().find("idle"), std::string::npos);
}

}  // namespace
}  // namespace gk
