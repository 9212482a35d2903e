// BVH loading: the real CMU and UAL clips against the numbers in PROVENANCE.md, the hand-written
// fixtures in tests/data/{good,bad}, unit-scale detection and the clip library entry points.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/quaternion.hpp>

#include "animation/bvh_loader.h"
#include "animation/clip_library.h"
#include "animation/pose_jobs.h"
#include "common/text_snippet.h"
#include "tests/test_data.h"

namespace gk {
namespace {

std::string zeros(int n) {
  std::string out;
  for (int i = 0; i < n; ++i) out += " 0";
  return out;
}

std::string fixture(const std::string& rel) { return test::source_path("tests/data/" + rel); }

// World position of every joint on every frame, through the runtime FK job.
std::vector<std::vector<glm::vec3>> joint_positions(const ClipSet& set, int clip_index = 0) {
  const Clip& clip = set.clips[clip_index];
  const int n = clip.num_joints;
  std::vector<glm::mat4> model(n);
  std::vector<std::vector<glm::vec3>> out;
  for (int f = 0; f < clip.num_frames; ++f) {
    LocalToModelJob job;
    job.skeleton = set.skeleton.get();
    job.rotations = {clip.frame_rotations(f), static_cast<size_t>(n)};
    job.translations = {clip.frame_translations(f), static_cast<size_t>(n)};
    job.out_model = model;
    EXPECT_TRUE(job.validate());
    job.run();
    out.emplace_back();
    for (const glm::mat4& m : model) out.back().push_back(glm::vec3(m[3]));
  }
  return out;
}

struct CmuCase {
  const char* file;
  int frames;
  float mean_root_height_m;
  float root_speed_m_s;
};

class CmuClip : public testing::TestWithParam<CmuCase> {};

// PROVENANCE.md: 31 joints, 120 fps, frame counts, 0.056444 m per unit, mean root height and the
// root speed along +Z; the clips travel, so they are not loops.
TEST_P(CmuClip, MatchesProvenance) {
  const CmuCase& c = GetParam();
  const std::string rel = std::string("clips/bvh/") + c.file;
  GK_REQUIRE_DATA(rel);
  Result<ClipSet> set = load_bvh(test::data_path(rel));
  ASSERT_TRUE(set.ok()) << set.message();
  ASSERT_EQ(set->clips.size(), 1u);
  const Clip& clip = set->clips[0];
  EXPECT_EQ(set->skeleton->num_joints(), 31);
  EXPECT_FLOAT_EQ(clip.fps, 120.0f);
  EXPECT_EQ(clip.num_frames, c.frames);
  EXPECT_FALSE(clip.loops);
  EXPECT_NEAR(set->scale_m_per_unit, 0.056444f, 1e-6f);
  EXPECT_NE(set->scale_reason.find("CMU"), std::string::npos) << set->scale_reason;

  const int hips = set->skeleton->role(JointRole::kHips);
  ASSERT_GE(hips, 0);
  const auto pos = joint_positions(*set);
  double sum_y = 0.0;
  for (const auto& frame : pos) sum_y += frame[hips].y;
  EXPECT_NEAR(sum_y / pos.size(), c.mean_root_height_m, 0.025);
  const glm::vec3 travel = pos.back()[hips] - pos.front()[hips];
  const float speed = glm::length(glm::vec2(travel.x, travel.z)) / clip.duration_s();
  EXPECT_NEAR(speed, c.root_speed_m_s, 0.05f * c.root_speed_m_s);
  EXPECT_GT(travel.z, 0.9f * glm::length(glm::vec2(travel.x, travel.z)));  // straight along +Z
}

INSTANTIATE_TEST_SUITE_P(Provenance, CmuClip,
                         testing::Values(CmuCase{"cmu_07_01_walk.bvh", 316, 0.94f, 1.36f},
                                         CmuCase{"cmu_09_11_run.bvh", 165, 0.99f, 3.50f}));

struct UalCase {
  const char* file;
  int frames_in_file;
};

// PROVENANCE.md: 52 joints, 24 fps, metres; the last frame duplicates the first and is dropped.
TEST(BvhUal, LoopClipsDropTheDuplicateLastFrame) {
  const UalCase cases[] = {{"ual_idle_loop.bvh", 61},        {"ual_walk_loop.bvh", 33},
                           {"ual_walk_formal_loop.bvh", 33}, {"ual_jog_fwd_loop.bvh", 23},
                           {"ual_sprint_loop.bvh", 17},      {"ual_crouch_fwd_loop.bvh", 49}};
  for (const UalCase& c : cases) {
    const std::string rel = std::string("clips/bvh/") + c.file;
    GK_REQUIRE_DATA(rel);
    Result<ClipSet> set = load_bvh(test::data_path(rel));
    ASSERT_TRUE(set.ok()) << set.message();
    SCOPED_TRACE(c.file);
    EXPECT_EQ(set->skeleton->num_joints(), 52);
    EXPECT_FLOAT_EQ(set->clips[0].fps, 24.0f);
    EXPECT_TRUE(set->clips[0].loops);
    EXPECT_EQ(set->clips[0].num_frames, c.frames_in_file - 1);
    EXPECT_FLOAT_EQ(set->scale_m_per_unit, 1.0f);
    EXPECT_NE(set->scale_reason.find("metres"), std::string::npos) << set->scale_reason;
  }
}

// PROVENANCE.md: mean hip heights 0.86-0.88 m standing, jog 0.84, sprint 0.89, crouch 0.48 m
// (rounded figures: within 2.5 cm).
TEST(BvhUal, HipHeights) {
  const std::pair<const char*, float> cases[] = {{"ual_idle_loop.bvh", 0.87f},
                                                 {"ual_walk_loop.bvh", 0.87f},
                                                 {"ual_jog_fwd_loop.bvh", 0.84f},
                                                 {"ual_sprint_loop.bvh", 0.89f},
                                                 {"ual_crouch_fwd_loop.bvh", 0.48f}};
  for (const auto& [file, height] : cases) {
    const std::string rel = std::string("clips/bvh/") + file;
    GK_REQUIRE_DATA(rel);
    Result<ClipSet> set = load_bvh(test::data_path(rel));
    ASSERT_TRUE(set.ok()) << set.message();
    const int hips = set->skeleton->role(JointRole::kHips);
    ASSERT_GE(hips, 0);
    double sum = 0.0;
    const auto pos = joint_positions(*set);
    for (const auto& frame : pos) sum += frame[hips].y;
    EXPECT_NEAR(sum / pos.size(), height, 0.025) << file;
  }
}

// CRLF, tabs, rotation channels before position channels in X Y Z order (R = Rx*Ry*Rz), and a
// single position channel on a non-root joint replacing that component of its OFFSET.
TEST(BvhFixtures, UnusualChannelOrderCrlfTabs) {
  LoadOptions options;
  options.scale_m_per_unit = 1.0f;
  Result<ClipSet> set = load_bvh(fixture("good/two_joint_crlf_tabs.bvh"), options);
  ASSERT_TRUE(set.ok()) << set.message();
  ASSERT_EQ(set->skeleton->num_joints(), 2);  // the End Site is not a joint
  EXPECT_EQ(set->skeleton->names[1], "Tip");
  const Clip& clip = set->clips[0];
  EXPECT_EQ(clip.num_frames, 2);
  EXPECT_FLOAT_EQ(clip.fps, 2.0f);
  EXPECT_FALSE(clip.loops);
  EXPECT_NE(set->scale_reason.find("given"), std::string::npos);
  const auto pos = joint_positions(*set);
  // Frame 0: root at (1,2,3) turned +90 deg about X (y -> z, z -> -y); tip local (0,10,4).
  EXPECT_NEAR(glm::distance(pos[0][0], glm::vec3(1, 2, 3)), 0.0f, 1e-5f);
  EXPECT_NEAR(glm::distance(pos[0][1], glm::vec3(1, -2, 13)), 0.0f, 1e-5f);
  // Frame 1: Rx(0)*Ry(90)*Rz(90) applied to (0,10,0): Rz gives (-10,0,0), Ry then (0,0,10).
  // The reverse order would give (-10,0,0).
  EXPECT_NEAR(glm::distance(pos[1][1], glm::vec3(0, 0, 10)), 0.0f, 1e-5f);
}

TEST(BvhFixtures, ClosedLoopDetectedAndOpenClipNot) {
  const std::string hierarchy =
      "HIERARCHY\nROOT Hips\n{\nOFFSET 0 0 0\nCHANNELS 6 Xposition Yposition Zposition "
      "Zrotation Yrotation Xrotation\nJOINT Spine\n{\nOFFSET 0 0.5 0\nCHANNELS 3 Zrotation "
      "Yrotation Xrotation\n}\n}\nMOTION\nFrames: 4\nFrame Time: 0.1\n";
  LoadOptions options;
  options.scale_m_per_unit = 1.0f;
  // The root travels 1 m per frame in x (ignored by the test), the spine bends and comes back.
  Result<ClipSet> loop = parse_bvh(hierarchy +
                                       "0 1 0 0 0 0 0 0 0\n1 1 0 0 0 0 30 0 0\n"
                                       "2 1 0 0 0 0 -30 0 0\n3 1 0 0 0 0 0 0 0\n",
                                   "loop.bvh", options);
  ASSERT_TRUE(loop.ok()) << loop.message();
  EXPECT_TRUE(loop->clips[0].loops);
  EXPECT_EQ(loop->clips[0].num_frames, 3);
  Result<ClipSet> open = parse_bvh(hierarchy +
                                       "0 1 0 0 0 0 0 0 0\n1 1 0 0 0 0 30 0 0\n"
                                       "2 1 0 0 0 0 60 0 0\n3 1 0 0 0 0 90 0 0\n",
                                   "open.bvh", options);
  ASSERT_TRUE(open.ok()) << open.message();
  EXPECT_FALSE(open->clips[0].loops);
  EXPECT_EQ(open->clips[0].num_frames, 4);
}

struct BadCase {
  const char* file;
  std::string expected;  // "file:line: what"
  LoadOptions options;
};

TEST(BvhFixtures, EachBadFileHasItsSpecificError) {
  LoadOptions shallow;
  shallow.max_depth = 4;
  LoadOptions few;
  few.max_joints = 3;
  const BadCase cases[] = {
      {"channel_count.bvh", "channel_count.bvh:20: expected 9 channel values, found 8", {}},
      {"truncated_motion.bvh", "truncated_motion.bvh:21: file ends after 2 of 3 frames", {}},
      {"truncated_hierarchy.bvh",
       "truncated_hierarchy.bvh:9: unexpected end of file inside joint 'Spine'",
       {}},
      {"unknown_keyword.bvh", "unknown_keyword.bvh:6: unknown keyword 'JIONT'", {}},
      {"nan_value.bvh", "nan_value.bvh:20: channel value 5 'nan' is not a finite number", {}},
      {"not_a_number.bvh", "not_a_number.bvh:20: expected a number, found '1.2.3'", {}},
      {"bad_channel_name.bvh", "bad_channel_name.bvh:9: expected a channel name", {}},
      {"missing_motion.bvh", "missing_motion.bvh:15: missing MOTION section", {}},
      {"bad_frame_time.bvh", "bad_frame_time.bvh:18: expected a Frame Time > 0", {}},
      {"huge_frames.bvh", "huge_frames.bvh:17: Frames: 10000000000 needs at least 18 bytes", {}},
      {"extra_frames.bvh", "extra_frames.bvh:20: expected 1 frames, found more data", {}},
      {"deep.bvh", "deep.bvh:18: hierarchy deeper than 4 levels", shallow},
      {"deep.bvh", "deep.bvh:14: more than 3 joints", few},
  };
  for (const BadCase& c : cases) {
    Result<ClipSet> set = load_bvh(fixture(std::string("bad/") + c.file), c.options);
    ASSERT_FALSE(set.ok()) << c.file;
    EXPECT_NE(set.message().find(c.expected), std::string::npos)
        << "expected '" << c.expected << "' in '" << set.message() << "'";
  }
}

TEST(BvhFixtures, HugeFrameCountFailsBeforeAllocating) {
  // 10^10 frames x 2 joints would be ~280 GB: the check against the bytes left must come first.
  const auto start = std::chrono::steady_clock::now();
  Result<ClipSet> set = load_bvh(fixture("bad/huge_frames.bvh"));
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_FALSE(set.ok());
  EXPECT_NE(set.message().find("only"), std::string::npos) << set.message();
  EXPECT_LT(seconds, 1.0);
}

TEST(BvhFixtures, DefaultDepthLimitRejectsDeepHierarchy) {
  std::string text =
      "HIERARCHY\nROOT J0\n{\nOFFSET 0 0 0\nCHANNELS 3 Xposition Yposition Zposition\n";
  for (int i = 1; i < 70; ++i) text += "JOINT J" + std::to_string(i) + "\n{\nOFFSET 0 1 0\n";
  for (int i = 0; i < 70; ++i) text += "}\n";
  Result<ClipSet> set = parse_bvh(text + "MOTION\nFrames: 1\nFrame Time: 1\n0 0 0\n", "deep.bvh");
  ASSERT_FALSE(set.ok());
  EXPECT_NE(set.message().find("hierarchy deeper than 64 levels"), std::string::npos)
      << set.message();
}

// Nothing from a file may crash: every prefix of a valid file either loads or returns an error
// naming the file (run under ASan/UBSan in CI).
TEST(BvhFixtures, EveryTruncationFailsCleanly) {
  std::ifstream in(fixture("good/two_joint_crlf_tabs.bvh"), std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(text.size(), 100u);
  int loaded = 0;
  for (size_t n = 0; n < text.size(); ++n) {
    Result<ClipSet> set = parse_bvh(std::string_view(text).substr(0, n), "cut.bvh");
    if (set.ok()) {
      ++loaded;
    } else {
      EXPECT_EQ(set.message().rfind("cut.bvh:", 0), 0u) << set.message();
    }
  }
  // Only cuts inside the last frame's final value can still parse (as a shorter number).
  EXPECT_LE(loaded, 3);
}

// A leg of 0.85 m written in centimetres, inches and metres: each must be recognised; a given
// scale wins over detection.
TEST(BvhUnitScale, DetectsCentimetresInchesMetresAndHonoursOverride) {
  auto text_in_units = [](float m_per_unit) {
    const float hip = 0.1f / m_per_unit, thigh = 0.45f / m_per_unit, shin = 0.40f / m_per_unit;
    std::string leg;
    for (const char* side : {"Left", "Right"}) {
      const float x = std::string(side) == "Left" ? hip : -hip;
      leg += "JOINT " + std::string(side) + "UpLeg\n{\nOFFSET " + std::to_string(x) +
             " 0 0\nCHANNELS 3 Zrotation Yrotation Xrotation\nJOINT " + side + "Leg\n{\nOFFSET 0 " +
             std::to_string(-thigh) + " 0\nCHANNELS 3 Zrotation Yrotation Xrotation\nJOINT " +
             side + "Foot\n{\nOFFSET 0 " + std::to_string(-shin) +
             " 0\nCHANNELS 3 Zrotation Yrotation Xrotation\n}\n}\n}\n";
    }
    return "HIERARCHY\nROOT Hips\n{\nOFFSET 0 0 0\nCHANNELS 6 Xposition Yposition Zposition "
           "Zrotation Yrotation Xrotation\n" +
           leg + "}\nMOTION\nFrames: 1\nFrame Time: 0.04\n" + std::to_string(1.0f / m_per_unit) +
           " 0 0 0 0 0" + zeros(6 * 3) + "\n";
  };
  const std::pair<float, const char*> units[] = {
      {0.01f, "centimetres"}, {0.0254f, "inches"}, {1.0f, "metres"}, {0.056444f, "CMU"}};
  for (const auto& [m_per_unit, name] : units) {
    Result<ClipSet> set = parse_bvh(text_in_units(m_per_unit), "legs.bvh");
    ASSERT_TRUE(set.ok()) << set.message();
    EXPECT_FLOAT_EQ(set->scale_m_per_unit, m_per_unit) << name;
    EXPECT_NE(set->scale_reason.find(name), std::string::npos) << set->scale_reason;
    // The root x channel (1 m in file units) comes out in metres.
    EXPECT_NEAR(set->clips[0].translations[0].x, 1.0f, 1e-4f) << name;
  }
  LoadOptions forced;
  forced.scale_m_per_unit = 0.5f;
  Result<ClipSet> set = parse_bvh(text_in_units(0.01f), "legs.bvh", forced);
  ASSERT_TRUE(set.ok()) << set.message();
  EXPECT_FLOAT_EQ(set->scale_m_per_unit, 0.5f);
  EXPECT_NEAR(set->clips[0].translations[0].x, 50.0f, 1e-3f);  // 100 units x 0.5 m
  EXPECT_NEAR(set->skeleton->rest_translations[2].y, -0.45f / 0.01f * 0.5f, 1e-3f);
}

TEST(ClipLibrary, LoadsByExtensionCaseInsensitiveAndExpandsFolders) {
  const std::string dir = test::scratch_dir("clip_library");
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir + "/sub");
  for (const char* name : {"b.BVH", "a.bvh", "c.txt", "sub/d.bvh"}) {
    std::filesystem::copy_file(fixture("good/two_joint_crlf_tabs.bvh"), dir + "/" + name);
  }
  Result<std::vector<std::string>> paths = expand_clip_paths({dir, fixture("bad/deep.bvh")});
  ASSERT_TRUE(paths.ok()) << paths.message();
  ASSERT_EQ(paths->size(), 3u);  // a.bvh, b.BVH (sorted, not recursive, .txt skipped), deep.bvh
  EXPECT_EQ(std::filesystem::path((*paths)[0]).filename(), "a.bvh");
  EXPECT_EQ(std::filesystem::path((*paths)[1]).filename(), "b.BVH");
  EXPECT_EQ((*paths)[2], fixture("bad/deep.bvh"));

  Result<ClipSet> upper = load_clip_file(dir + "/b.BVH");
  ASSERT_TRUE(upper.ok()) << upper.message();
  EXPECT_EQ(upper->clips[0].name, "b");
  Result<ClipSet> txt = load_clip_file(dir + "/c.txt");
  ASSERT_FALSE(txt.ok());
  EXPECT_NE(txt.message().find("unknown clip file type '.txt'"), std::string::npos);
  EXPECT_FALSE(expand_clip_paths({dir + "/missing"}).ok());
  EXPECT_FALSE(load_clip_file(dir + "/missing.bvh").ok());
}

// True when every byte is printable ASCII or a newline: no raw file bytes reached the message.
bool printable_ascii(const std::string& s) {
  return std::all_of(s.begin(), s.end(),
                     [](char c) { return (c >= 0x20 && c < 0x7F) || c == '\n'; });
}

// Issue #12: the shared helper every loader uses to quote file content.
TEST(PrintableSnippet, EscapesControlBytesAndBrokenUtf8KeepsText) {
  EXPECT_EQ(printable_snippet("HIERARCHY"), "HIERARCHY");
  EXPECT_EQ(printable_snippet(std::string("a\0b\x1b[2J\t\r\n", 10)), "a\\x00b\\x1b[2J\\t\\r\\n");
  EXPECT_EQ(printable_snippet("\xff\xfe\x80 ok"), "\\xff\\xfe\\x80 ok");
  EXPECT_EQ(printable_snippet("Hüfte 腰"), "Hüfte 腰");  // well-formed UTF-8 stays
  EXPECT_EQ(printable_snippet("\xc2\x9b"
                              "31m"),
            "\\xc2\\x9b31m");                                       // C1 CSI is a control
  EXPECT_EQ(printable_snippet("\xed\xa0\x80"), "\\xed\\xa0\\x80");  // a surrogate is not UTF-8
  EXPECT_EQ(printable_snippet(std::string(100, 'x'), 40), std::string(40, 'x') + "...");
  EXPECT_EQ(quoted_snippet("\x7f"
                           "ELF"),
            "'\\x7fELF'");
}

// Issue #12: a binary file given as BVH echoed its raw bytes into the error message.
TEST(BvhFixtures, BinaryFileIsQuotedPrintably) {
  static constexpr char kBytes[] =
      "\x7f"
      "ELF\x02\x01\x01\x00\x00\x1b]0;pwned\x07\xff\xfe\n\x00";
  const std::string path = test::scratch_dir("bvh_binary") + "/binary.bvh";
  std::ofstream(path, std::ios::binary) << std::string(kBytes, sizeof(kBytes) - 1);
  Result<ClipSet> set = load_bvh(path);
  ASSERT_FALSE(set.ok());
  EXPECT_EQ(set.message(), path + ":1: expected 'HIERARCHY', found " +
                               "'\\x7fELF\\x02\\x01\\x01\\x00\\x00\\x1b]0;pwned\\x07\\xff\\xfe'")
      << set.message();
  EXPECT_TRUE(printable_ascii(set.message())) << set.message();
  // A joint name is quoted from the file too.
  Result<ClipSet> joint = parse_bvh("HIERARCHY\nROOT Hips\x1b[31m\xff\n{\n", "j.bvh");
  ASSERT_FALSE(joint.ok());
  EXPECT_NE(joint.message().find("joint 'Hips\\x1b[31m\\xff'"), std::string::npos)
      << joint.message();
  EXPECT_TRUE(printable_ascii(joint.message())) << joint.message();
}

TEST(BvhFixtures, DirectoryIsNotABvhFile) {
  const std::string dir = test::scratch_dir("bvh_binary") + "/folder.bvh";
  std::filesystem::create_directories(dir);
  Result<ClipSet> set = load_bvh(dir);
  ASSERT_FALSE(set.ok());
  EXPECT_EQ(set.message(), dir + ": is a directory, expected a BVH file");
}

// Issue #12: analyze-clip on an empty folder printed nothing and exited 0.
TEST(ClipLibrary, FolderWithoutClipsIsAnError) {
  const std::string dir = test::scratch_dir("clip_library_empty");
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  std::ofstream(dir + "/notes.txt") << "no clips here\n";
  Result<std::vector<std::string>> paths = expand_clip_paths({dir});
  ASSERT_FALSE(paths.ok());
  EXPECT_EQ(paths.message(),
            dir + ": the folder holds no clips (expected .bvh, .gltf or .glb files)");
}

}  // namespace
}  // namespace gk
