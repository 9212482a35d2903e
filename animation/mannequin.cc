// Mannequin for any skeleton: a tapered capsule per bone (sized by stature and, when roles are
// known, by body part), an ellipsoid head, wedge feet on the sole plane and block hands, smoothly
// skinned (each bone blends half-and-half with its neighbour at a shared joint, so both sides of a
// joint deform alike). Built once at load time, so it may allocate freely.

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

#include "animation/gait_generator.h"
#include "animation/gait_pose.h"
#include "animation/procedural.h"

namespace gk {
namespace {

enum class Part : uint8_t {
  kGeneric,
  kTorso,
  kPelvis,
  kNeck,
  kHead,
  kClavicle,
  kUpperArm,
  kForearm,
  kHand,
  kFinger,
  kThigh,
  kShank,
  kFoot,
  kToe
};

// One neutral grey for the whole body and a darker one for the shoes: the renderer multiplies
// them by the agent's tint, so each mannequin reads as one colour (no bands at the joints, no
// differently shaded head that could be taken for another agent's limb).
const glm::vec3 kSkin(0.64f, 0.64f, 0.64f);
const glm::vec3 kShoeShade(0.32f, 0.32f, 0.32f);
constexpr float kPi = 3.14159265358979f;
// Radii of the widest parts as fractions of stature; body_radius uses the same numbers.
constexpr float kPelvisRadius = 0.055f;
constexpr float kUpperArmRadius = 0.033f;

struct Influence {
  int a = 0, b = -1;
  float wa = 1.0f;  // weight of a; b gets the rest
};

class MeshBuilder {
 public:
  explicit MeshBuilder(SkinnedMesh* mesh) : mesh_(mesh) {}
  uint32_t vertex(glm::vec3 p, glm::vec3 n, glm::vec3 color, Influence inf) {
    mesh_->positions.push_back(p);
    mesh_->normals.push_back(glm::length(n) > 1e-8f ? glm::normalize(n) : glm::vec3(0, 1, 0));
    mesh_->colors.push_back(color);
    if (inf.b < 0 || inf.wa >= 1.0f) {
      mesh_->joints.emplace_back(inf.a, 0, 0, 0);
      mesh_->weights.emplace_back(1.0f, 0.0f, 0.0f, 0.0f);
    } else {
      mesh_->joints.emplace_back(inf.a, inf.b, 0, 0);
      mesh_->weights.emplace_back(inf.wa, 1.0f - inf.wa, 0.0f, 0.0f);
    }
    return static_cast<uint32_t>(mesh_->positions.size() - 1);
  }
  void tri(uint32_t a, uint32_t b, uint32_t c) {
    mesh_->indices.insert(mesh_->indices.end(), {a, b, c});
  }
  // Eight corners (bottom face 0-3, top face 4-7, both counter-clockwise seen from above), one
  // flat-shaded quad per face.
  void box(const glm::vec3 (&c)[8], glm::vec3 color, Influence inf) {
    static const int kFaces[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                                     {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
    glm::vec3 centre(0.0f);
    for (const glm::vec3& p : c) centre += p / 8.0f;
    for (const auto& f : kFaces) {
      glm::vec3 n = glm::cross(c[f[1]] - c[f[0]], c[f[2]] - c[f[0]]);
      const glm::vec3 face_centre = (c[f[0]] + c[f[1]] + c[f[2]] + c[f[3]]) / 4.0f;
      const bool flip = glm::dot(n, face_centre - centre) < 0.0f;
      if (flip) n = -n;
      uint32_t v[4];
      for (int k = 0; k < 4; ++k) v[k] = vertex(c[f[k]], n, color, inf);
      if (flip) {
        tri(v[0], v[2], v[1]);
        tri(v[0], v[3], v[2]);
      } else {
        tri(v[0], v[1], v[2]);
        tri(v[0], v[2], v[3]);
      }
    }
  }

 private:
  SkinnedMesh* mesh_;
};

struct Capsule {
  glm::vec3 start, end;
  float r0, r1;                // radius at start and end
  float lateral_scale = 1.0f;  // ellipse: x-ish axis radius multiplier (torso is wider than deep)
  int joint, parent = -1, child = -1;  // driving joint; neighbours blended at the ends
};

// Lat-long capsule: hemispherical caps and a tapered cylinder, ring by ring.
void add_capsule(MeshBuilder* mb, const Capsule& c, int segments) {
  const glm::vec3 axis_full = c.end - c.start;
  const float len = glm::length(axis_full);
  const glm::vec3 a = axis_full / len;
  glm::vec3 u = glm::vec3(1, 0, 0) - a * a.x;  // lateral axis when possible
  if (glm::dot(u, u) < 0.1f) u = glm::vec3(0, 0, 1) - a * a.z;
  u = glm::normalize(u);
  const glm::vec3 v = glm::cross(a, u);
  struct Ring {
    float t, along, radius;
  };  // t: 0..1 along the bone for the weights
  std::vector<Ring> rings;
  constexpr int kCap = 3, kBody = 4;
  for (int i = 0; i <= kCap; ++i) {
    const float phi = 0.5f * kPi * (1.0f - float(i) / kCap);
    rings.push_back({0.0f, -c.r0 * std::sin(phi), c.r0 * std::cos(phi)});
  }
  for (int i = 1; i < kBody; ++i) {
    const float t = float(i) / kBody;
    rings.push_back({t, t * len, c.r0 + (c.r1 - c.r0) * t});
  }
  for (int i = 0; i <= kCap; ++i) {
    const float phi = 0.5f * kPi * float(i) / kCap;
    rings.push_back({1.0f, len + c.r1 * std::sin(phi), c.r1 * std::cos(phi)});
  }
  std::vector<uint32_t> first(rings.size());
  for (size_t r = 0; r < rings.size(); ++r) {
    const Ring& ring = rings[r];
    // Half-and-half with the neighbour at each end, fading to the bone's own joint by 25 %.
    Influence inf{c.joint, -1, 1.0f};
    const float t = std::clamp(ring.along / len, 0.0f, 1.0f);
    if (t < 0.25f && c.parent >= 0) inf = {c.joint, c.parent, 0.5f + 2.0f * t};
    if (t > 0.75f && c.child >= 0) inf = {c.joint, c.child, 0.5f + 2.0f * (1.0f - t)};
    const glm::vec3 color = kSkin;
    const glm::vec3 centre = c.start + a * ring.along;
    const float slope = (c.r0 - c.r1) / len;  // cone normal tilt on the body
    first[r] = 0;
    for (int s = 0; s <= segments; ++s) {
      const float th = 2.0f * kPi * s / segments;
      const glm::vec3 radial = std::cos(th) * u * c.lateral_scale + std::sin(th) * v;
      const glm::vec3 p = centre + ring.radius * radial;
      glm::vec3 n;
      if (ring.along < 0.0f)
        n = (p - c.start);
      else if (ring.along > len)
        n = (p - c.end);
      else
        n = std::cos(th) * u / c.lateral_scale + std::sin(th) * v + a * slope;
      const uint32_t id = mb->vertex(p, n, color, inf);
      if (s == 0) first[r] = id;
    }
  }
  for (size_t r = 0; r + 1 < rings.size(); ++r) {
    for (int s = 0; s < segments; ++s) {
      const uint32_t a0 = first[r] + s, a1 = a0 + 1, b0 = first[r + 1] + s, b1 = b0 + 1;
      if (rings[r].radius > 1e-7f) mb->tri(a0, a1, b1);
      if (rings[r + 1].radius > 1e-7f) mb->tri(a0, b1, b0);
    }
  }
}

void add_ellipsoid(MeshBuilder* mb, glm::vec3 centre, glm::vec3 radii, int joint) {
  constexpr int kLat = 10, kLon = 16;
  std::vector<uint32_t> first(kLat + 1);
  for (int i = 0; i <= kLat; ++i) {
    const float phi = kPi * float(i) / kLat;  // 0 = top
    for (int s = 0; s <= kLon; ++s) {
      const float th = 2.0f * kPi * s / kLon;
      const glm::vec3 unit(std::sin(phi) * std::cos(th), std::cos(phi),
                           std::sin(phi) * std::sin(th));
      const uint32_t id = mb->vertex(centre + unit * radii, unit / radii, kSkin, {joint});
      if (s == 0) first[i] = id;
    }
  }
  for (int i = 0; i < kLat; ++i) {
    for (int s = 0; s < kLon; ++s) {
      const uint32_t a0 = first[i] + s, a1 = a0 + 1, b0 = first[i + 1] + s, b1 = b0 + 1;
      if (i > 0) mb->tri(a0, b0, a1);
      if (i + 1 < kLat) mb->tri(a1, b0, b1);
    }
  }
}

// Part of the body each joint's outgoing bones belong to, from the roles (kGeneric without them).
std::vector<Part> classify(const Skeleton& s) {
  const int n = s.num_joints();
  std::vector<Part> part(n, Part::kGeneric);
  auto mark = [&](JointRole role, Part p) {
    if (s.has(role)) part[s.role(role)] = p;
  };
  mark(JointRole::kHips, Part::kTorso);
  for (int16_t j : s.spine_chain) part[j] = Part::kTorso;
  mark(JointRole::kChest, Part::kTorso);
  mark(JointRole::kNeck, Part::kNeck);
  mark(JointRole::kHead, Part::kHead);
  for (Side side : {Side::kLeft, Side::kRight}) {
    if (s.hip(side) >= 0) part[s.hip(side)] = Part::kThigh;
    if (s.knee(side) >= 0) part[s.knee(side)] = Part::kShank;
    if (s.ankle(side) >= 0) part[s.ankle(side)] = Part::kFoot;
    if (s.toe(side) >= 0) part[s.toe(side)] = Part::kToe;
    const int arm =
        s.role(side == Side::kLeft ? JointRole::kLeftShoulder : JointRole::kRightShoulder);
    if (arm < 0) continue;
    part[arm] = Part::kUpperArm;
    const int p = s.parents[arm];
    if (p >= 0 && part[p] == Part::kGeneric) part[p] = Part::kClavicle;
  }
  // Propagate down chains: forearm and hand below the upper arm, fingers below the hand, and
  // whatever hangs below the head or toes belongs to them.
  for (int j = 0; j < n; ++j) {
    const int p = s.parents[j];
    if (p < 0 || part[j] != Part::kGeneric) continue;
    switch (part[p]) {
      case Part::kUpperArm:
        part[j] = Part::kForearm;
        break;
      case Part::kForearm:
        part[j] = Part::kHand;
        break;
      case Part::kHand:
      case Part::kFinger:
        part[j] = Part::kFinger;
        break;
      case Part::kHead:
        part[j] = Part::kHead;
        break;
      case Part::kToe:
        part[j] = Part::kToe;
        break;
      case Part::kTorso:
        if (s.has(JointRole::kHips)) part[j] = Part::kPelvis;
        break;
      default:
        break;
    }
  }
  return part;
}

}  // namespace

std::shared_ptr<const SkinnedMesh> make_mannequin_mesh(const Skeleton& skeleton) {
  auto mesh = std::make_shared<SkinnedMesh>();
  const int n = skeleton.num_joints();
  std::vector<glm::mat4> model(n);
  for (int j = 0; j < n; ++j) {
    const glm::mat4 local = glm::translate(glm::mat4(1.0f), skeleton.rest_translations[j]) *
                            glm::mat4_cast(skeleton.rest_rotations[j]);
    const int p = skeleton.parents[j];
    model[j] = p >= 0 ? model[p] * local : local;
  }
  mesh->inverse_bind.resize(n);
  for (int j = 0; j < n; ++j) mesh->inverse_bind[j] = glm::inverse(model[j]);
  if (n == 0) return mesh;
  auto pos = [&](int j) { return glm::vec3(model[j][3]); };
  const float h = estimate_stature(skeleton);
  const std::vector<Part> part = classify(skeleton);
  MeshBuilder mb(mesh.get());

  std::vector<Capsule> capsules;
  for (int j = 0; j < n; ++j) {
    const int p = skeleton.parents[j];
    if (p < 0) continue;
    const float len = glm::distance(pos(p), pos(j));
    if (len < 0.01f * h) continue;  // zero-length helper joints (CMU LHipJoint)
    Capsule c{pos(p), pos(j), 0.0f, 0.0f, 1.0f, p, skeleton.parents[p], j};
    switch (part[p]) {
      case Part::kTorso:
        if (part[j] == Part::kTorso || part[j] == Part::kNeck) {
          c.r0 = 0.065f * h, c.r1 = 0.068f * h, c.lateral_scale = 1.45f;
        } else if (part[j] == Part::kThigh || part[j] == Part::kPelvis) {
          c.r0 = c.r1 = kPelvisRadius * h;
        } else {
          c.r0 = c.r1 = 0.035f * h;
        }
        break;
      case Part::kPelvis:
        c.r0 = c.r1 = kPelvisRadius * h;
        break;
      case Part::kNeck:
        c.r0 = c.r1 = 0.028f * h;
        break;
      case Part::kClavicle:
        c.r0 = c.r1 = 0.032f * h;
        break;
      case Part::kUpperArm:
        c.r0 = kUpperArmRadius * h, c.r1 = 0.026f * h;
        break;
      case Part::kForearm:
        c.r0 = 0.025f * h, c.r1 = 0.018f * h;
        break;
      case Part::kThigh:
        c.r0 = 0.045f * h, c.r1 = 0.032f * h;  // a gap between the thighs: two legs, not one
        break;
      case Part::kShank:
        c.r0 = 0.032f * h, c.r1 = 0.021f * h;
        break;
      case Part::kGeneric:
        c.r0 = c.r1 = std::clamp(0.15f * len, 0.01f * h, 0.04f * h);
        break;
      default:
        continue;  // head, hand, fingers, feet and toes get their own shapes
    }
    capsules.push_back(c);
  }
  const int segments = capsules.size() > 30 ? 8 : 10;
  for (const Capsule& c : capsules) add_capsule(&mb, c, segments);

  for (int j = 0; j < n; ++j) {
    const int p = skeleton.parents[j];
    if (part[j] == Part::kHead && (p < 0 || part[p] != Part::kHead)) {
      // Head: an ellipsoid above the head joint, sized by stature (head height about 0.13 h).
      glm::vec3 up(0, 1, 0);
      if (p >= 0 && glm::distance(pos(p), pos(j)) > 1e-4f) up = glm::normalize(pos(j) - pos(p));
      add_ellipsoid(&mb, pos(j) + up * (0.055f * h), glm::vec3(0.052f, 0.068f, 0.06f) * h, j);
    } else if (part[j] == Part::kHand && part[p] == Part::kForearm) {
      // Hand: a flat block continuing the forearm.
      const glm::vec3 d = glm::normalize(pos(j) - pos(p));
      glm::vec3 side = glm::cross(d, glm::vec3(0, 0, 1));
      if (glm::dot(side, side) < 1e-4f) side = glm::cross(d, glm::vec3(0, 1, 0));
      side = glm::normalize(side) * (0.012f * h);
      const glm::vec3 wide = glm::normalize(glm::cross(d, side)) * (0.028f * h);
      const glm::vec3 a = pos(j) - d * (0.005f * h), b = pos(j) + d * (0.1f * h);
      const glm::vec3 c[8] = {a - side - wide, b - side - wide, b - side + wide, a - side + wide,
                              a + side - wide, b + side - wide, b + side + wide, a + side + wide};
      mb.box(c, kSkin, {j});
    }
  }
  // Feet: wedges from heel to ball on the sole plane, toes from ball to tip.
  for (Side side : {Side::kLeft, Side::kRight}) {
    const int ankle = skeleton.ankle(side), toe = skeleton.toe(side);
    if (ankle < 0) continue;
    const FootShape fs = estimate_foot_shape(skeleton, side);
    glm::vec3 fwd = toe >= 0 ? pos(toe) - pos(ankle) : glm::vec3(0, 0, 1);
    fwd.y = 0.0f;
    fwd = glm::dot(fwd, fwd) > 1e-8f ? glm::normalize(fwd) : glm::vec3(0, 0, 1);
    const glm::vec3 lat = glm::normalize(glm::cross(glm::vec3(0, 1, 0), fwd)) * (0.5f * fs.width_m);
    const float sole = pos(ankle).y - fs.ankle_height_m;
    glm::vec3 heel = pos(ankle) - fwd * fs.heel_back_m, ball = pos(ankle) + fwd * fs.ball_forward_m;
    heel.y = ball.y = sole;
    const glm::vec3 up(0, 1, 0);
    const float top_back = fs.ankle_height_m + 0.012f * h,
                top_front = fs.ball_height_m + 0.012f * h;
    const glm::vec3 foot[8] = {heel - 0.8f * lat,
                               ball - lat,
                               ball + lat,
                               heel + 0.8f * lat,
                               heel - 0.6f * lat + up * top_back,
                               ball - lat + up * top_front,
                               ball + lat + up * top_front,
                               heel + 0.6f * lat + up * top_back};
    mb.box(foot, kShoeShade, {ankle});
    if (toe < 0) continue;
    const glm::vec3 tip = ball + fwd * fs.toe_length_m;
    const float top_tip = 0.6f * top_front;
    const glm::vec3 toes[8] = {ball - lat,
                               tip - 0.8f * lat,
                               tip + 0.8f * lat,
                               ball + lat,
                               ball - lat + up * top_front,
                               tip - 0.8f * lat + up * top_tip,
                               tip + 0.8f * lat + up * top_tip,
                               ball + lat + up * top_front};
    mb.box(toes, kShoeShade, {toe});
  }
  return mesh;
}

float body_radius(const Skeleton& skeleton) {
  const float h = estimate_stature(skeleton);
  const std::vector<glm::vec3> pos = gait::rest_positions(skeleton);
  auto half_apart = [&](int a, int b) {
    if (a < 0 || b < 0) return -1.0f;
    return 0.5f * std::hypot(pos[a].x - pos[b].x, pos[a].z - pos[b].z);
  };
  float radius = -1.0f;
  const float shoulders =
      half_apart(skeleton.role(JointRole::kLeftShoulder), skeleton.role(JointRole::kRightShoulder));
  if (shoulders >= 0.0f) radius = shoulders + kUpperArmRadius * h;
  const float hips = half_apart(skeleton.hip(Side::kLeft), skeleton.hip(Side::kRight));
  if (hips >= 0.0f) radius = std::max(radius, hips + kPelvisRadius * h);
  return radius > 0.0f ? radius : 0.14f * h;
}

}  // namespace gk
