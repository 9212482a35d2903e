#include "animation/joint_list_fk.h"

#include <cstddef>
#include <type_traits>

#if defined(__SSE2__)
#include <emmintrin.h>
#include <xmmintrin.h>
#endif

#include "animation/fk_compose.h"
#include "animation/quat_sse.h"

namespace gk {

bool LocalToModelListJob::validate() const {
  if (!skeleton || !root_transform) return false;
  const size_t n = static_cast<size_t>(skeleton->num_joints());
  if (rotations.size() < n || translations.size() < n || out_model.size() < n) return false;
  for (int16_t j : joints) {
    if (j < 0 || static_cast<size_t>(j) >= n) return false;
  }
  return true;
}

void LocalToModelListJob::run() const {
  const int16_t* parents = skeleton->parents.data();
  const float* root = &(*root_transform)[0].x;
  float* model = &(*out_model.data())[0].x;
  const glm::quat* rot = rotations.data();
  const glm::vec3* trans = translations.data();
  const size_t count = joints.size();
#if defined(__SSE2__)
  // As LocalToModelJob: four joints' rotation matrices at once, each lane glm::mat3_cast's
  // operations in its order, then each joint composed with its parent from its lane's entries
  // (glm's sums in its order, the local matrix's zeros left out): the same bits.
  // Indices as ptrdiff_t, read before the group's stores (may-alias vector stores would have
  // them read again): no reloads and sign extensions per joint.
  const float* t3 = &trans->x;
  auto group = [&](const int16_t* idx, int n) __attribute__((always_inline)) {
    const ptrdiff_t j4[4] = {idx[0], idx[1], idx[2], idx[3]};
    __m128 x = _mm_loadu_ps(&rot[j4[0]].x), y = _mm_loadu_ps(&rot[j4[1]].x),
           z = _mm_loadu_ps(&rot[j4[2]].x), w = _mm_loadu_ps(&rot[j4[3]].x);
    _MM_TRANSPOSE4_PS(x, y, z, w);
    __m128 e[9];
    quat_sse::rotation_entries4(x, y, z, w, e);
    // Lane k of the entries broadcast in one pshufd each (the lane is a compile-time constant).
    auto compose = [&](auto lane) __attribute__((always_inline)) {
      constexpr int k = decltype(lane)::value;
      auto at = [&](int r) {
        return _mm_castsi128_ps(_mm_shuffle_epi32(_mm_castps_si128(e[r]), _MM_SHUFFLE(k, k, k, k)));
      };
      const ptrdiff_t joint = j4[k];
      const ptrdiff_t parent = parents[joint];
      const float* t = t3 + 3 * joint;
      const __m128 r[9] = {at(0), at(1), at(2), at(3), at(4), at(5), at(6), at(7), at(8)};
      fk::compose(parent < 0 ? root : model + 16 * parent, r, _mm_load1_ps(t),
                  _mm_load1_ps(t + 1), _mm_load1_ps(t + 2), model + 16 * joint);
    };
    compose(std::integral_constant<int, 0>{});
    if (n > 1) compose(std::integral_constant<int, 1>{});
    if (n > 2) compose(std::integral_constant<int, 2>{});
    if (n > 3) compose(std::integral_constant<int, 3>{});
  };
  const int16_t* list = joints.data();
  size_t i = 0;
  for (; i + 4 <= count; i += 4) group(list + i, 4);
  if (i < count) {  // the last one to three, padded with the first of them (not composed)
    int16_t tail[4] = {list[i], list[i], list[i], list[i]};
    for (size_t k = i; k < count; ++k) tail[k - i] = list[k];
    group(tail, static_cast<int>(count - i));
  }
#else
  for (size_t i = 0; i < count; ++i) {
    const int joint = joints[i];
    const int parent = parents[joint];
    fk::compose(parent < 0 ? *root_transform : out_model[parent], rot[joint], trans[joint],
                out_model[joint]);
  }
  (void)model;
  (void)root;
#endif
}

}  // namespace gk
