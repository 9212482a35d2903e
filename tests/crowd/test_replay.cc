// Trajectory replay checked against the raw rows of the ETH/UCY files (parsed here, independently
// of the loader) and against the median speeds stated in shared/data/PROVENANCE.md.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <random>
#include <sstream>
#include <vector>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "crowd/trajectory_replay.h"
#include "tests/test_data.h"

namespace gk {
namespace {

constexpr int kFramesPerSample = 10;  // PROVENANCE.md: "step 10" in every file

struct RawRow {
  long frame;
  long id;
  double x, y;
};

std::vector<RawRow> read_raw(const std::string& path) {
  std::vector<RawRow> rows;
  std::ifstream in(path);
  double f, id, x, y;
  while (in >> f >> id >> x >> y) rows.push_back({std::lround(f), std::lround(id), x, y});
  return rows;
}

// Per pedestrian: rows in frame order.
std::map<long, std::vector<RawRow>> by_ped(const std::vector<RawRow>& rows) {
  std::map<long, std::vector<RawRow>> peds;
  for (const RawRow& r : rows) peds[r.id].push_back(r);
  for (auto& [id, track] : peds) {
    std::sort(track.begin(), track.end(),
              [](const RawRow& a, const RawRow& b) { return a.frame < b.frame; });
  }
  return peds;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// Median of the speeds between consecutive samples of each pedestrian, from the raw rows; only
// steps faster than `min_speed_m_s` count.
double raw_median_step_speed(const std::vector<RawRow>& rows, double frame_time_s,
                             double min_speed_m_s = -1.0) {
  std::vector<double> speeds;
  for (const auto& [id, t] : by_ped(rows)) {
    for (size_t i = 1; i < t.size(); ++i) {
      const double dt = double(t[i].frame - t[i - 1].frame) / kFramesPerSample * frame_time_s;
      const double speed = std::hypot(t[i].x - t[i - 1].x, t[i].y - t[i - 1].y) / dt;
      if (speed > min_speed_m_s) speeds.push_back(speed);
    }
  }
  return median(speeds);
}

std::unique_ptr<CrowdSource> load(const std::string& path, float frame_time_s) {
  Result<std::unique_ptr<CrowdSource>> r = load_trajectory_replay(path, {frame_time_s});
  EXPECT_TRUE(r.ok()) << r.message();
  return r.ok() ? std::move(*r) : nullptr;
}

// Median of the replay's speeds over every live agent of every 60 Hz frame (time-weighted, like
// the per-step median of the raw data) and over the agents moving faster than 0.1 m/s.
struct ReplaySpeeds {
  double median_all = 0.0, median_moving = 0.0;
};
ReplaySpeeds replay_median_speeds(CrowdSource& replay, double duration_s) {
  std::vector<double> all, moving;
  constexpr float kDt = 1.0f / 60.0f;
  while (replay.time_s() < duration_s) {
    EXPECT_TRUE(replay.step(kDt).ok());
    for (const glm::vec2& v : replay.frame().velocities) {
      const double s = std::hypot(v.x, v.y);
      all.push_back(s);
      if (s > 0.1) moving.push_back(s);
    }
  }
  return {median(all), median(moving)};
}

double duration_s(const std::vector<RawRow>& rows, double frame_time_s) {
  long lo = rows[0].frame, hi = rows[0].frame;
  for (const RawRow& r : rows) lo = std::min(lo, r.frame), hi = std::max(hi, r.frame);
  return double(hi - lo) / kFramesPerSample * frame_time_s;
}

// Steps through the whole file at a quarter sample step; at every recorded frame compares each
// raw row with the replayed agent of that id, and the live count with the pedestrians whose
// recorded span contains the frame.
void check_reproduces_rows(const std::string& rel, size_t expected_capacity) {
  const std::vector<RawRow> rows = read_raw(test::data_path(rel));
  ASSERT_FALSE(rows.empty());
  const auto peds = by_ped(rows);
  std::map<long, std::vector<RawRow>> at_frame;
  for (const RawRow& r : rows) at_frame[r.frame].push_back(r);
  const long first = at_frame.begin()->first, last = at_frame.rbegin()->first;

  auto replay = load(test::data_path(rel), 0.4f);
  ASSERT_TRUE(replay);
  EXPECT_EQ(replay->capacity(), expected_capacity);
  double max_error_m = 0.0;
  size_t rows_checked = 0;
  for (long frame = first; frame <= last; frame += kFramesPerSample) {
    if (frame != first) {
      for (int k = 0; k < 4; ++k) ASSERT_TRUE(replay->step(0.1f).ok());
    }
    const AgentFrame f = replay->frame();
    size_t spanning = 0;
    for (const auto& [id, t] : peds)
      spanning += t.front().frame <= frame && frame <= t.back().frame;
    EXPECT_EQ(f.size(), spanning) << "frame " << frame;
    // These files have no missing frames inside a track, so that is also the frame's row count.
    EXPECT_EQ(f.size(), at_frame[frame].size()) << "frame " << frame;
    for (const RawRow& r : at_frame[frame]) {
      const auto it = std::find(f.ids.begin(), f.ids.end(), static_cast<uint32_t>(r.id));
      ASSERT_NE(it, f.ids.end()) << "ped " << r.id << " missing at frame " << frame;
      const glm::vec2 p = f.positions[it - f.ids.begin()];
      max_error_m = std::max(max_error_m, std::hypot(p.x - r.x, p.y - r.y));
      ++rows_checked;
    }
  }
  EXPECT_EQ(rows_checked, rows.size());
  EXPECT_LT(max_error_m, 0.01);
  std::cout << rel << ": max position error " << max_error_m << " m over " << rows_checked
            << " rows\n";
}

TEST(TrajectoryReplay, ReproducesEveryRecordedRowZara1) {
  GK_REQUIRE_DATA("trajectories/zara1/crowds_zara01.txt");
  check_reproduces_rows("trajectories/zara1/crowds_zara01.txt", 20);  // PROVENANCE: max 20/frame
}

TEST(TrajectoryReplay, ReproducesEveryRecordedRowHotel) {
  GK_REQUIRE_DATA("trajectories/hotel/biwi_hotel.txt");
  check_reproduces_rows("trajectories/hotel/biwi_hotel.txt", 18);  // PROVENANCE: max 18/frame
}

// PROVENANCE.md: median step speeds at 0.4 s per 10 frame ids.
TEST(TrajectoryReplay, MedianSpeedsMatchTheData) {
  const struct {
    const char* rel;
    double provenance_m_s;
  } kFiles[] = {{"trajectories/zara1/crowds_zara01.txt", 1.15},
                {"trajectories/hotel/biwi_hotel.txt", 1.27},
                {"trajectories/zara3/crowds_zara03.txt", 1.13}};
  for (const auto& file : kFiles) {
    GK_REQUIRE_DATA(file.rel);
    const std::vector<RawRow> rows = read_raw(test::data_path(file.rel));
    const double raw = raw_median_step_speed(rows, 0.4);
    EXPECT_NEAR(raw, file.provenance_m_s, 0.006) << file.rel;  // the table rounds to 0.01
    auto replay = load(test::data_path(file.rel), 0.4f);
    ASSERT_TRUE(replay);
    const ReplaySpeeds s = replay_median_speeds(*replay, duration_s(rows, 0.4));
    EXPECT_NEAR(s.median_all, file.provenance_m_s, 0.1 * file.provenance_m_s) << file.rel;
    // The table counts standing people too; over walkers only, compare with the raw walkers.
    const double raw_moving = raw_median_step_speed(rows, 0.4, 0.1);
    EXPECT_NEAR(s.median_moving, raw_moving, 0.1 * raw_moving) << file.rel;
    std::cout << file.rel << ": raw median step speed " << raw
              << " m/s (steps > 0.1 m/s: " << raw_moving << "), replay median " << s.median_all
              << " (moving agents " << s.median_moving << ")\n";
  }
}

// PROVENANCE.md's ETH caveat: 2.45 m/s at the usual 0.4 s per step, 1.47 m/s at the physically
// right 0.667 s (the file is resampled from 6-frame annotations).
TEST(TrajectoryReplay, EthTimingCaveat) {
  const char* rel = "trajectories/eth/biwi_eth.txt";
  GK_REQUIRE_DATA(rel);
  const std::vector<RawRow> rows = read_raw(test::data_path(rel));
  EXPECT_NEAR(raw_median_step_speed(rows, 0.4), 2.45, 0.01);
  EXPECT_NEAR(raw_median_step_speed(rows, 0.667), 1.47, 0.01);
  auto nominal = load(test::data_path(rel), 0.4f);
  auto physical = load(test::data_path(rel), 0.667f);
  ASSERT_TRUE(nominal && physical);
  const double fast = replay_median_speeds(*nominal, duration_s(rows, 0.4)).median_all;
  const double slow = replay_median_speeds(*physical, duration_s(rows, 0.667)).median_all;
  EXPECT_NEAR(fast, 2.45, 0.245);
  EXPECT_NEAR(slow, 1.47, 0.147);
  // Same curves, time stretched: speeds scale exactly with 0.4 / 0.667 (up to frame sampling).
  EXPECT_NEAR(slow / fast, 0.4 / 0.667, 0.01);
  std::cout << rel << ": replay median " << fast << " m/s at 0.4 s, " << slow << " at 0.667 s\n";
}

// The ETH authors' own annotations (obsmat.txt: frame ped pos_x pos_z pos_y v_x v_z v_y) replay
// as they are. PROVENANCE.md: ETH's are annotated every 6 video frames, 0.4 s apart, with a median
// speed of 1.47 m/s; hotel's are biwi_hotel.txt's rows with frame numbers one higher, the values
// matching to about 0.05 m.
std::vector<RawRow> read_raw_obsmat(const std::string& path) {
  std::vector<RawRow> rows;
  std::ifstream in(path);
  double f, id, x, z, y, vx, vz, vy;
  while (in >> f >> id >> x >> z >> y >> vx >> vz >> vy) {
    rows.push_back({std::lround(f), std::lround(id), x, y});
  }
  return rows;
}

TEST(TrajectoryReplay, EthObsmatReplaysAtItsOwnTiming) {
  const char* rel = "trajectories/eth/original/obsmat.txt";
  GK_REQUIRE_DATA(rel);
  const std::vector<RawRow> rows = read_raw_obsmat(test::data_path(rel));
  ASSERT_EQ(rows.size(), 8908u);  // PROVENANCE.md
  // Raw step speeds at 0.4 s per 6 frames (the helper counts kFramesPerSample frames per step).
  const double raw = raw_median_step_speed(rows, 0.4 * kFramesPerSample / 6.0);
  EXPECT_NEAR(raw, 1.47, 0.01);
  auto replay = load(test::data_path(rel), 0.4f);
  ASSERT_TRUE(replay);
  EXPECT_EQ(replay->capacity(), 27u);  // PROVENANCE.md: at most 27 pedestrians on one frame
  const double span = double(rows.back().frame - rows.front().frame) / 6.0 * 0.4;
  const double s = replay_median_speeds(*replay, span).median_all;
  EXPECT_NEAR(s, 1.47, 0.147);
  std::cout << rel << ": raw median step speed " << raw << " m/s, replay median " << s << "\n";
}

TEST(TrajectoryReplay, HotelObsmatMatchesTheSocialGanRows) {
  const char* obsmat = "trajectories/hotel/original/obsmat.txt";
  const char* txt = "trajectories/hotel/biwi_hotel.txt";
  GK_REQUIRE_DATA(obsmat);
  GK_REQUIRE_DATA(txt);
  auto a = load(test::data_path(obsmat), 0.4f);
  auto b = load(test::data_path(txt), 0.4f);
  ASSERT_TRUE(a && b);
  // Both start at their first frame (obsmat's 1 is biwi_hotel's 0): step side by side.
  std::vector<double> errors;
  constexpr float kDt = 1.0f / 60.0f;
  for (int f = 0; f < 60 * 120; ++f) {
    ASSERT_TRUE(a->step(kDt).ok());
    ASSERT_TRUE(b->step(kDt).ok());
    const AgentFrame fa = a->frame(), fb = b->frame();
    for (size_t i = 0; i < fa.size(); ++i) {
      const auto it = std::find(fb.ids.begin(), fb.ids.end(), fa.ids[i]);
      if (it == fb.ids.end()) continue;
      errors.push_back(glm::length(fa.positions[i] - fb.positions[it - fb.ids.begin()]));
    }
  }
  ASSERT_GT(errors.size(), 10000u);
  const double med = median(errors);
  std::sort(errors.begin(), errors.end());
  const double p99 = errors[errors.size() * 99 / 100];
  EXPECT_LT(med, 0.05);
  EXPECT_LT(p99, 0.1);
  std::cout << "hotel obsmat vs biwi_hotel.txt over 120 s: median " << med << " m, p99 " << p99
            << " m over " << errors.size() << " agent-frames\n";
}

// Largest change of one agent's velocity between consecutive frames, over the first `span_s`.
double max_velocity_change(CrowdSource& replay, float dt_s, double span_s) {
  std::map<uint32_t, glm::vec2> last;
  double max_dv = 0.0;
  while (replay.time_s() < span_s) {
    EXPECT_TRUE(replay.step(dt_s).ok());
    const AgentFrame f = replay.frame();
    std::map<uint32_t, glm::vec2> now;
    for (size_t i = 0; i < f.size(); ++i) {
      now[f.ids[i]] = f.velocities[i];
      if (auto it = last.find(f.ids[i]); it != last.end()) {
        max_dv = std::max(max_dv, double(glm::length(f.velocities[i] - it->second)));
      }
    }
    last.swap(now);
  }
  return max_dv;
}

// C1 continuity: a velocity jump at a sample would give the same frame-to-frame change at any
// frame rate; a continuous velocity changes ten times less over a ten times shorter frame.
TEST(TrajectoryReplay, VelocityIsContinuousAcrossSamples) {
  const char* rel = "trajectories/zara1/crowds_zara01.txt";
  GK_REQUIRE_DATA(rel);
  const double span_s = 120.0;
  auto at_60 = load(test::data_path(rel), 0.4f);
  auto at_600 = load(test::data_path(rel), 0.4f);
  ASSERT_TRUE(at_60 && at_600);
  const double dv_60 = max_velocity_change(*at_60, 1.0f / 60.0f, span_s);
  const double dv_600 = max_velocity_change(*at_600, 1.0f / 600.0f, span_s);
  // Piecewise-linear interpolation would jump by the change between consecutive secants.
  double max_secant_jump = 0.0;
  for (const auto& [id, t] : by_ped(read_raw(test::data_path(rel)))) {
    if (t.front().frame > span_s / 0.4 * kFramesPerSample) continue;
    for (size_t i = 2; i < t.size(); ++i) {
      const double ax = (t[i - 1].x - t[i - 2].x) / 0.4, ay = (t[i - 1].y - t[i - 2].y) / 0.4;
      const double bx = (t[i].x - t[i - 1].x) / 0.4, by = (t[i].y - t[i - 1].y) / 0.4;
      max_secant_jump = std::max(max_secant_jump, std::hypot(bx - ax, by - ay));
    }
  }
  EXPECT_LT(dv_600, 0.2 * dv_60);
  EXPECT_LT(dv_60, 0.5 * max_secant_jump);
  std::cout << "max |dv| per frame: " << dv_60 << " m/s at 60 Hz, " << dv_600
            << " at 600 Hz; raw secant jump " << max_secant_jump << "\n";
}

std::string write_scratch(const std::string& name, const std::string& text) {
  const std::string path = test::scratch_dir("replay") + "/" + name;
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

// Each malformed file fails with "path:line: what".
TEST(TrajectoryReplay, MalformedFilesNameFileAndLine) {
  const struct {
    const char* fixture;
    int line;
    const char* what;
  } kCases[] = {
      {"wrong_column_count.txt", 2, "expected 4 numbers (frame id x y) or 8 (ETH obsmat"},
      {"mixed_layouts.txt", 3, "expected 4 numbers as on the file's first row, found 8"},
      {"non_numeric.txt", 2, "column 3 (x): expected a number, found 'abc'"},
      {"nan_value.txt", 4, "column 3 (x): expected a finite number"},
      {"empty.txt", 1, "no trajectory rows"},
      {"duplicate_row.txt", 4, "duplicate row for frame 10, pedestrian 1 (first at line 2)"},
      {"huge_id.txt", 2, "column 2 (id): expected a whole number"},
      {"negative_frame.txt", 2, "column 1 (frame): expected a whole number"},
  };
  for (const auto& c : kCases) {
    const std::string path = test::source_path("tests/data/bad/trajectories/") + c.fixture;
    Result<std::unique_ptr<CrowdSource>> r = load_trajectory_replay(path);
    ASSERT_FALSE(r.ok()) << c.fixture;
    const std::string prefix = path + ":" + std::to_string(c.line) + ": ";
    EXPECT_EQ(r.message().rfind(prefix, 0), 0u) << r.message();
    EXPECT_NE(r.message().find(c.what), std::string::npos) << r.message();
  }
  // Written here rather than as fixtures: whitespace-only lines and a fractional frame number.
  const std::string blank = write_scratch("blank.txt", "\n  \t\n\r\n");
  Result<std::unique_ptr<CrowdSource>> r = load_trajectory_replay(blank);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.message().rfind(blank + ":3: no trajectory rows", 0), 0u) << r.message();
  const std::string frac = write_scratch("frac.txt", "0 1 0 0\n5.5 1 1 1\n");
  r = load_trajectory_replay(frac);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.message().rfind(frac + ":2: column 1 (frame)", 0), 0u) << r.message();
  r = load_trajectory_replay(test::scratch_dir("replay") + "/does_not_exist.txt");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.message().find("does_not_exist.txt: cannot open"), std::string::npos);
}

// A CSV export of a recorded crowd replays exactly as the ETH/UCY file it came from: the rows of
// crowds_zara01.txt rewritten here with commas (then semicolons and CRLF), a header that names
// the columns in another order, an extra column and a comment line.
TEST(TrajectoryReplay, CsvWithAHeaderReplaysAsTheEthUcyFile) {
  const char* rel = "trajectories/zara1/crowds_zara01.txt";
  GK_REQUIRE_DATA(rel);
  std::ifstream in(test::data_path(rel));
  std::string f, id, x, y;
  std::string comma = "# zara01 as CSV\nagent_id,Pos_Y,speed,pos_x,frame_id\n";
  std::string semi = "\"ped\";\"frame\";\"x\";\"y\"\r\n";
  size_t rows = 0;
  while (in >> f >> id >> x >> y) {
    comma += id + "," + y + ",1.0," + x + "," + f + "\n";
    semi += id + " ; " + f + ";" + x + ";" + y + "\r\n";
    ++rows;
  }
  ASSERT_GT(rows, 5000u);
  auto txt = load(test::data_path(rel), 0.4f);
  auto csv = load(write_scratch("zara01.csv", comma), 0.4f);
  auto dat = load(write_scratch("zara01.dat", semi), 0.4f);
  ASSERT_TRUE(txt && csv && dat);
  size_t compared = 0;
  for (int frame = 0; frame < 60 * 90; ++frame) {
    for (CrowdSource* s : {txt.get(), csv.get(), dat.get()}) ASSERT_TRUE(s->step(1.0f / 60.0f).ok());
    const AgentFrame a = txt->frame();
    for (const AgentFrame& b : {csv->frame(), dat->frame()}) {
      ASSERT_EQ(a.size(), b.size());
      for (size_t i = 0; i < a.size(); ++i) {
        ASSERT_EQ(a.ids[i], b.ids[i]);
        ASSERT_EQ(a.positions[i], b.positions[i]);
        ++compared;
      }
    }
  }
  EXPECT_GT(compared, 50000u);
  // The comment line of the old fixture is skipped rather than refused.
  auto commented = load(test::source_path("tests/data/good/trajectories/comment_line.txt"), 0.4f);
  ASSERT_TRUE(commented);
  EXPECT_EQ(commented->capacity(), 1u);
  // Columns found by name: x = 1.0, 1.5, 2.0 at frames 0, 10, 20 of pedestrian 1, y = 2.
  auto named = load(test::source_path("tests/data/good/trajectories/header_semicolon.csv"), 0.4f);
  ASSERT_TRUE(named);
  ASSERT_TRUE(named->step(0.4f).ok());
  ASSERT_EQ(named->frame().size(), 1u);
  EXPECT_EQ(named->frame().ids[0], 1u);
  EXPECT_NEAR(named->frame().positions[0].x, 1.5f, 1e-5f);
  EXPECT_NEAR(named->frame().positions[0].y, 2.0f, 1e-5f);
}

// A CSV with a time column [s] is replayed at its times, whatever frame_time_s says: zara01's rows
// with t = frame / 10 * 0.4 s replay as the file does at 0.4 s per 10 frames.
TEST(TrajectoryReplay, ATimeColumnTimesTheRows) {
  const char* rel = "trajectories/zara1/crowds_zara01.txt";
  GK_REQUIRE_DATA(rel);
  std::string timed = "ped_id,x,y,timestamp\n";
  for (const RawRow& r : read_raw(test::data_path(rel))) {
    char row[160];
    std::snprintf(row, sizeof(row), "%ld,%.10g,%.10g,%.3f\n", r.id, r.x, r.y,
                  static_cast<double>(r.frame) / kFramesPerSample * 0.4);
    timed += row;
  }
  const std::string path = write_scratch("zara01_timed.csv", timed);
  auto txt = load(test::data_path(rel), 0.4f);
  auto csv = load(path, 1.7f);  // not used: the file gives its times
  ASSERT_TRUE(txt && csv);
  double worst = 0.0;
  size_t compared = 0;
  for (int frame = 0; frame < 60 * 90; ++frame) {
    ASSERT_TRUE(txt->step(1.0f / 60.0f).ok());
    ASSERT_TRUE(csv->step(1.0f / 60.0f).ok());
    const AgentFrame a = txt->frame(), b = csv->frame();
    ASSERT_EQ(a.size(), b.size()) << "at " << frame;
    for (size_t i = 0; i < a.size(); ++i) {
      ASSERT_EQ(a.ids[i], b.ids[i]);
      worst = std::max(worst, double(glm::length(a.positions[i] - b.positions[i])));
      ++compared;
    }
  }
  EXPECT_GT(compared, 20000u);
  EXPECT_LT(worst, 1e-4);  // the same samples at the same times (float rounding apart)
}

// A file in centimetres or millimetres (zara01's rows times 100 and 1000) is recognised by its
// pedestrians' walking speeds and replays as the file in metres; every shared file, in metres, is
// read as metres.
TEST(TrajectoryReplay, CentimetresAndMillimetresAreRecognisedByWalkingSpeeds) {
  const char* rel = "trajectories/zara1/crowds_zara01.txt";
  GK_REQUIRE_DATA(rel);
  const std::vector<RawRow> raw = read_raw(test::data_path(rel));
  auto txt = load(test::data_path(rel), 0.4f);
  ASSERT_TRUE(txt);
  EXPECT_EQ(txt->name().find("(in "), std::string::npos) << txt->name();
  for (const auto& [scale, unit] : {std::pair<double, const char*>{100.0, "centimetres"},
                                    std::pair<double, const char*>{1000.0, "millimetres"}}) {
    std::string text;
    for (const RawRow& r : raw) {
      char row[160];
      std::snprintf(row, sizeof(row), "%ld %ld %.6f %.6f\n", r.frame, r.id, r.x * scale,
                    r.y * scale);
      text += row;
    }
    auto scaled = load(write_scratch(std::string("zara01_") + unit + ".txt", text), 0.4f);
    auto plain = load(test::data_path(rel), 0.4f);
    ASSERT_TRUE(scaled && plain);
    EXPECT_NE(scaled->name().find(unit), std::string::npos) << scaled->name();
    double worst = 0.0;
    for (int frame = 0; frame < 60 * 60; ++frame) {
      ASSERT_TRUE(plain->step(1.0f / 60.0f).ok());
      ASSERT_TRUE(scaled->step(1.0f / 60.0f).ok());
      const AgentFrame a = plain->frame(), b = scaled->frame();
      ASSERT_EQ(a.size(), b.size());
      for (size_t i = 0; i < a.size(); ++i) {
        worst = std::max(worst, double(glm::length(a.positions[i] - b.positions[i])));
      }
    }
    EXPECT_LT(worst, 1e-3) << unit;
  }
  for (const char* other : {"trajectories/eth/biwi_eth.txt", "trajectories/hotel/biwi_hotel.txt",
                            "trajectories/zara3/crowds_zara03.txt",
                            "trajectories/eth/original/obsmat.txt",
                            "trajectories/hotel/original/obsmat.txt"}) {
    GK_REQUIRE_DATA(other);
    auto r = load(test::data_path(other), 0.4f);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->name().find("(in "), std::string::npos) << other << ": " << r->name();
  }
}

// A header or CSV row that cannot be read names the line and what was expected.
TEST(TrajectoryReplay, MalformedCsvNamesLineAndColumn) {
  const struct {
    const char* text;
    int line;
    const char* what;
  } kCases[] = {
      {"frame,id,x\n0,1,2\n", 1, "header: no column for y among 'frame', 'id', 'x'"},
      {"id,x,y\n0,1,2\n", 1, "header: no column for frame (or time) among 'id', 'x', 'y'"},
      {"t,id,x,y\n1e9,1,2,3\n", 2, "column 1 (t): expected a time within +-1e7 s, found '1e9'"},
      {"t,id,x,y\n0.5,1,2,3\n0.5004,1,2,3\n", 3, "duplicate row for time 0.500 s, pedestrian 1"},
      {"frame,id,x,pos_x,y\n", 1, "header: columns 3 ('x') and 4 ('pos_x') name the same"},
      {"\n# c\nframe;id;x;y\n0;1;2;3\n10;1;2\n", 5, "expected 4 fields as the header names, found 3"},
      {"frame,id,x,y\n0,1,,3\n", 2, "column 3 (x): expected a number, found ''"},
      {"id,frame,x,y\n1,2.5,0,0\n", 2, "column 2 (frame): expected a whole number"},
      {"0,1,2,3\n10,1,2,3,4,5\n", 2, "expected 4 numbers (frame id x y) or 8"},
      {"0,1,2\n", 1, "or a header names the columns frame"},
      {"frame,id,x,y\n", 1, "no trajectory rows"},
  };
  int k = 0;
  for (const auto& c : kCases) {
    const std::string path = write_scratch("bad" + std::to_string(k++) + ".csv", c.text);
    Result<std::unique_ptr<CrowdSource>> r = load_trajectory_replay(path);
    ASSERT_FALSE(r.ok()) << c.text;
    const std::string prefix = path + ":" + std::to_string(c.line) + ": ";
    EXPECT_EQ(r.message().rfind(prefix, 0), 0u) << r.message();
    EXPECT_NE(r.message().find(c.what), std::string::npos) << r.message();
  }
}

TEST(TrajectoryReplay, TrajectoryFileNames) {
  for (const char* yes : {"a.txt", "dir.x/b.CSV", "c.tsv", "../d/e.dat", "obsmat.txt"}) {
    EXPECT_TRUE(is_trajectory_file_name(yes)) << yes;
  }
  for (const char* no : {"plaza", "scene.json", "a.vsp", "dir.csv/plaza", "csv", "a.txt.json"}) {
    EXPECT_FALSE(is_trajectory_file_name(no)) << no;
  }
}

// True when every byte is printable ASCII or a newline: no raw file bytes reached the message.
bool printable_ascii(const std::string& s) {
  return std::all_of(s.begin(), s.end(),
                     [](char c) { return (c >= 0x20 && c < 0x7F) || c == '\n'; });
}

// Issue #12: a folder named like a trajectory file was reported as "file too large
// (9223372036854775807 bytes)".
TEST(TrajectoryReplay, DirectoryIsNamedAsADirectory) {
  const std::string dir = test::scratch_dir("replay") + "/folder.txt";
  std::filesystem::create_directories(dir);
  Result<std::unique_ptr<CrowdSource>> r = load_trajectory_replay(dir);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.message(), dir + ": is a directory, expected a trajectory file");
}

// Issue #12: a binary file's bytes were echoed raw into "expected a number, found '...'".
TEST(TrajectoryReplay, BinaryFileBytesAreEscapedInTheMessage) {
  static constexpr char kBytes[] =
      "0 1 \x7f"
      "ELF\x01\x1b[31m\xff\xfe\x00z 2\n";
  const std::string bin = write_scratch("binary.txt", std::string(kBytes, sizeof(kBytes) - 1));
  Result<std::unique_ptr<CrowdSource>> r = load_trajectory_replay(bin);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.message().rfind(bin + ":1: column 3 (x): expected a number, found ", 0), 0u)
      << r.message();
  EXPECT_NE(r.message().find(R"('\x7fELF\x01\x1b[31m\xff\xfe\x00z')"), std::string::npos)
      << r.message();
  EXPECT_TRUE(printable_ascii(r.message())) << r.message();
}

TEST(TrajectoryReplay, ReportsThePedestrianIdsOfTheFile) {
  const std::string path = write_scratch("ids.txt", "0 7 0 0\n10 7 1 0\n10 3 0 1\n20 3 1 1\n");
  std::vector<uint32_t> ids;
  Result<std::unique_ptr<CrowdSource>> r = load_trajectory_replay(path, {}, &ids);
  ASSERT_TRUE(r.ok()) << r.message();
  EXPECT_EQ(ids, (std::vector<uint32_t>{3, 7}));
}

TEST(TrajectoryReplay, RejectsBadFrameTimeAndSteps) {
  const std::string path = write_scratch("ok.txt", "0 1 0 0\n10 1 1 0\n");
  for (float bad : {0.0f, -0.4f, std::nanf(""), INFINITY}) {
    Result<std::unique_ptr<CrowdSource>> r = load_trajectory_replay(path, {bad});
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.message().rfind(path + ": frame_time_s: ", 0), 0u) << r.message();
  }
  auto replay = load(path, 0.4f);
  ASSERT_TRUE(replay);
  for (float bad : {0.0f, -1.0f, std::nanf("")}) EXPECT_FALSE(replay->step(bad).ok());
  EXPECT_EQ(replay->time_s(), 0.0);
}

// Mixed separators, CRLF, blank lines, rows out of order, a track with missing frames (20, 30),
// a pedestrian that stands still and one whose id needs all 32 bits.
TEST(TrajectoryReplay, SyntheticTracksGapsAndHeadings) {
  const std::string path = write_scratch("synthetic.txt",
                                         "10\t1\t1.0\t0.0\r\n"
                                         "0 1 0.0 0.0\n\n"
                                         "40\t1  4.0\t0.0\n"
                                         "50 1 5.0 0.0\n"
                                         "0 4294967295 2.0 0.0\n"
                                         "10 4294967295 2.0 1.0\n"
                                         "20 4294967295 2.0 1.0\n"
                                         "30 4294967295 2.0 1.0\n");
  auto replay = load(path, 0.4f);
  ASSERT_TRUE(replay);
  EXPECT_EQ(replay->capacity(), 2u);
  EXPECT_EQ(replay->feedback_policy(), FeedbackPolicy::kIgnored);
  const auto find = [&](uint32_t id) -> int {
    const AgentFrame f = replay->frame();
    const auto it = std::find(f.ids.begin(), f.ids.end(), id);
    return it == f.ids.end() ? -1 : int(it - f.ids.begin());
  };
  // Walking 1 m per 0.4 s along +x: inside the gap it keeps walking at 2.5 m/s, facing +x.
  for (int k = 0; k < 3 * 4; ++k) ASSERT_TRUE(replay->step(0.1f).ok());  // t = 1.2 s: frame 30
  int i = find(1);
  ASSERT_GE(i, 0);
  EXPECT_NEAR(replay->frame().positions[i].x, 3.0f, 1e-3f);
  EXPECT_NEAR(replay->frame().velocities[i].x, 2.5f, 1e-3f);
  EXPECT_NEAR(replay->frame().thetas[i], 1.5707963f, 1e-3f);  // pi/2 faces +x
  // The other one walked +z (file y) and then stood still: it keeps facing +z.
  i = find(4294967295u);
  ASSERT_GE(i, 0);
  EXPECT_NEAR(replay->frame().velocities[i].y, 0.0f, 1e-4f);
  EXPECT_NEAR(replay->frame().thetas[i], 0.0f, 1e-3f);
  // Feedback is ignored and changes nothing.
  const uint8_t has[2] = {1, 1};
  const glm::vec2 p[2] = {glm::vec2(9.0f), glm::vec2(9.0f)};
  const float th[2] = {1.0f, 1.0f};
  const glm::vec2 before = replay->frame().positions[0];
  EXPECT_TRUE(replay->apply_feedback({has, p, p, th}).ok());
  EXPECT_EQ(replay->frame().positions[0], before);
  // After its last sample (frame 30 = 1.2 s) the stander vanishes; ped 1 goes on to 2.0 s.
  ASSERT_TRUE(replay->step(0.1f).ok());
  EXPECT_EQ(find(4294967295u), -1);
  EXPECT_EQ(replay->frame().size(), 1u);
  for (int k = 0; k < 8; ++k) ASSERT_TRUE(replay->step(0.1f).ok());
  EXPECT_EQ(replay->frame().size(), 0u);
}

// A tracker's noise (2 cm per axis, Gaussian, every 0.4 s sample): a pedestrian who stands keeps
// facing where he faced instead of turning after each wobble (its velocity reaches 0.1-0.3 m/s in a
// new direction every sample), while one who walks at 0.5 m/s through the same noise faces his way.
// A track without noise keeps the 0.1 m/s threshold (SyntheticTracksGapsAndHeadings).
TEST(TrajectoryReplay, NoisyStanderKeepsItsHeadingAndANoisyWalkerFacesItsWay) {
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::ostringstream text;
  for (int k = 0; k <= 60; ++k) {  // 24 s
    text << 10 * k << " 1 " << 1.0 + noise(rng) << ' ' << 2.0 + noise(rng) << '\n';
    text << 10 * k << " 2 " << 0.2 * k + noise(rng) << ' ' << 5.0 + noise(rng) << '\n';
  }
  auto replay = load(write_scratch("noisy.txt", text.str()), 0.4f);
  ASSERT_TRUE(replay);
  double turned = 0.0, fast = 0.0;
  int off_course = 0, frames = 0;
  float last = replay->frame().thetas[0];
  for (int f = 0; f < 60 * 23; ++f) {
    ASSERT_TRUE(replay->step(1.0f / 60.0f).ok());
    const AgentFrame fr = replay->frame();
    ASSERT_EQ(fr.size(), 2u);
    const int stander = fr.ids[0] == 1 ? 0 : 1, walker = 1 - stander;
    float d = fr.thetas[stander] - last;
    d = std::atan2(std::sin(d), std::cos(d));
    turned += std::abs(d);
    last = fr.thetas[stander];
    fast = std::max(fast, static_cast<double>(glm::length(fr.velocities[stander])));
    // The walker goes +x (file x): theta pi/2.
    off_course += std::abs(fr.thetas[walker] - 1.5707963f) > 0.5f;
    ++frames;
  }
  EXPECT_GT(fast, 0.2) << "the noise moves the stander at walking-like speeds";
  EXPECT_LT(turned, 0.5) << "radians the stander turned in 23 s";
  EXPECT_LT(off_course, frames / 20) << "frames the walker faced 30 degrees off its way";
}

TEST(TrajectoryReplay, LoopStartsOverOneStepAfterTheLastSample) {
  // Ped 1 from 0 to 2.0 s, ped 2 from 0.4 to 1.2 s; one step of 0.4 s after the last sample the
  // file starts over: period 2.4 s, and each pedestrian is absent in between.
  const std::string path = write_scratch("loop.txt",
                                         "0 1 0.0 0.0\n10 1 1.0 0.0\n20 1 2.0 0.0\n"
                                         "30 1 3.0 0.0\n40 1 4.0 0.0\n50 1 5.0 0.0\n"
                                         "10 2 0.0 1.0\n20 2 0.0 2.0\n30 2 0.0 3.0\n");
  ReplayOptions options;
  options.frame_time_s = 0.4f;
  options.loop = true;
  auto loaded = load_trajectory_replay(path, options);
  ASSERT_TRUE(loaded.ok()) << loaded.message();
  CrowdSource& replay = **loaded;
  constexpr float kDt = 0.05f;
  constexpr int kPeriodSteps = 48;  // 2.4 s
  std::vector<std::vector<uint32_t>> ids;
  std::vector<std::vector<glm::vec2>> positions;
  for (int k = 0; k < 3 * kPeriodSteps; ++k) {
    ids.emplace_back(replay.frame().ids.begin(), replay.frame().ids.end());
    positions.emplace_back(replay.frame().positions.begin(), replay.frame().positions.end());
    ASSERT_TRUE(replay.step(kDt).ok());
  }
  // The third period replays the first (to the rounding of the summed steps).
  int compared = 0;
  for (int k = 0; k < kPeriodSteps - 1; ++k) {
    const int later = k + 2 * kPeriodSteps;
    ASSERT_EQ(ids[k], ids[later]) << "step " << k;
    for (size_t i = 0; i < ids[k].size(); ++i) {
      EXPECT_NEAR(positions[k][i].x, positions[later][i].x, 2e-3f) << "step " << k;
      EXPECT_NEAR(positions[k][i].y, positions[later][i].y, 2e-3f) << "step " << k;
      ++compared;
    }
  }
  EXPECT_GT(compared, 50);
  // Between two lives, a frame with nobody: every id is absent before it comes back.
  int empty_frames = 0;
  for (int k = kPeriodSteps / 2; k < 3 * kPeriodSteps; ++k) empty_frames += ids[k].empty();
  EXPECT_GE(empty_frames, 2 * (0.4f / kDt) - 4);
  EXPECT_NEAR(replay.time_s(), 3 * kPeriodSteps * kDt, 1e-4);
  // Without the option the file plays once.
  auto once = load_trajectory_replay(path, {0.4f});
  ASSERT_TRUE(once.ok());
  for (int k = 0; k < 3 * kPeriodSteps; ++k) ASSERT_TRUE((*once)->step(kDt).ok());
  EXPECT_EQ((*once)->frame().size(), 0u);
}

}  // namespace
}  // namespace gk
