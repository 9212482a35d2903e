#include "animation/joint_list_fk.h"

#include <cstring>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "animation/pose_jobs.h"
#include "animation/procedural.h"

namespace gk {
namespace {

void random_pose(const Skeleton& s, std::mt19937& rng, std::vector<glm::quat>* r,
                 std::vector<glm::vec3>* t) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int j = 0; j < s.num_joints(); ++j) {
    r->push_back(glm::normalize(glm::quat(u(rng), u(rng), u(rng), u(rng))));
    t->push_back(s.rest_translations[j] + 0.05f * glm::vec3(u(rng), u(rng), u(rng)));
  }
}

bool same_bits(const glm::mat4& a, const glm::mat4& b) {
  return std::memcmp(&a, &b, sizeof(glm::mat4)) == 0;
}

// Every joint once, in order, is the full pass to the bit.
TEST(LocalToModelListJob, AllJointsEqualTheRangeJobBitForBit) {
  const auto s = make_humanoid_skeleton();
  const int n = s->num_joints();
  std::mt19937 rng(3);
  std::vector<glm::quat> r;
  std::vector<glm::vec3> t;
  random_pose(*s, rng, &r, &t);
  const glm::mat4 root = glm::translate(glm::mat4(1), glm::vec3(2, 0.1f, -1)) *
                         glm::mat4_cast(glm::angleAxis(0.4f, glm::vec3(0, 1, 0)));
  std::vector<glm::mat4> want(n), got(n);
  LocalToModelJob{s.get(), r, t, root, want}.run();
  std::vector<int16_t> all;
  for (int j = 0; j < n; ++j) all.push_back(static_cast<int16_t>(j));
  LocalToModelListJob job{s.get(), r, t, &root, got, all};
  ASSERT_TRUE(job.validate());
  job.run();
  for (int j = 0; j < n; ++j) EXPECT_TRUE(same_bits(got[j], want[j])) << s->names[j];
}

// Two subtrees changed at once (as both legs after IK), in one list: the same as the range job
// over each, and the joints not listed are left alone.
TEST(LocalToModelListJob, TwoSubtreesEqualTwoRangeUpdates) {
  const auto s = make_humanoid_skeleton();
  const int n = s->num_joints();
  const std::vector<int> ends = subtree_ends(*s);
  std::mt19937 rng(8);
  std::vector<glm::quat> r;
  std::vector<glm::vec3> t;
  random_pose(*s, rng, &r, &t);
  const glm::mat4 root = glm::translate(glm::mat4(1), glm::vec3(-1, 0.02f, 3));
  std::vector<glm::mat4> before(n);
  LocalToModelJob{s.get(), r, t, root, before}.run();
  const int a = s->hip(Side::kLeft), b = s->hip(Side::kRight);
  r[a] = glm::normalize(r[a] * glm::angleAxis(0.3f, glm::vec3(1, 0, 0)));
  r[b] = glm::normalize(r[b] * glm::angleAxis(-0.2f, glm::vec3(0, 0, 1)));
  std::vector<glm::mat4> want = before, got = before;
  LocalToModelJob{s.get(), r, t, root, want, a, ends[a]}.run();
  LocalToModelJob{s.get(), r, t, root, want, b, ends[b]}.run();
  std::vector<int16_t> list;
  for (int j = a; j < ends[a]; ++j) list.push_back(static_cast<int16_t>(j));
  for (int j = b; j < ends[b]; ++j) list.push_back(static_cast<int16_t>(j));
  LocalToModelListJob{s.get(), r, t, &root, got, list}.run();
  for (int j = 0; j < n; ++j) EXPECT_TRUE(same_bits(got[j], want[j])) << s->names[j];
}

TEST(LocalToModelListJob, ValidateRefusesJointsOutsideTheSkeleton) {
  const auto s = make_humanoid_skeleton();
  const int n = s->num_joints();
  std::vector<glm::quat> r(n, glm::quat(1, 0, 0, 0));
  std::vector<glm::vec3> t(n, glm::vec3(0.0f));
  std::vector<glm::mat4> m(n);
  const glm::mat4 root(1.0f);
  const std::vector<int16_t> bad = {0, static_cast<int16_t>(n)};
  EXPECT_FALSE((LocalToModelListJob{s.get(), r, t, &root, m, bad}.validate()));
  EXPECT_FALSE((LocalToModelListJob{s.get(), r, t, nullptr, m, {}}.validate()));
}

}  // namespace
}  // namespace gk
