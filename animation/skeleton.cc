// Skeleton utilities: role names, role detection from joint names (several rig conventions) with
// topology checks, the JSON role manifest and structural validation.

#include "animation/skeleton.h"

#include <algorithm>
#include <cctype>
#include <cmath>

#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include "common/ascii.h"
#include "common/file_io.h"
#include "common/json_text.h"
#include "common/text_snippet.h"

namespace gk {
namespace {

// The roles the mediator needs for locomotion (has_locomotion_roles).
constexpr JointRole kLocomotionRoles[] = {
    JointRole::kHips,       JointRole::kChest,   JointRole::kLeftHip,  JointRole::kLeftKnee,
    JointRole::kLeftAnkle,  JointRole::kLeftToe, JointRole::kRightHip, JointRole::kRightKnee,
    JointRole::kRightAnkle, JointRole::kRightToe};

constexpr uint64_t kMaxManifestBytes = 1u << 20;  // a manifest names a few dozen joints

constexpr std::array<std::string_view, kNumJointRoles> kRoleNames = {
    "hips",       "spine",       "chest",      "neck",          "head",
    "left_hip",   "left_knee",   "left_ankle", "left_toe",      "right_hip",
    "right_knee", "right_ankle", "right_toe",  "left_shoulder", "right_shoulder"};

// What a joint name says once the rig prefix and the side marker are stripped.
enum class Part {
  kNone,
  kHips,
  kSpine,
  kNeck,
  kHead,
  kThigh,
  kShin,
  kFoot,
  kToe,
  kArm,
  kShoulder,
  kClavicle
};
enum class NameSide { kNone, kLeft, kRight };

struct NameInfo {
  Part part = Part::kNone;
  NameSide side = NameSide::kNone;
};

bool is_separator(char c) { return c == '_' || c == '.' || c == '-' || c == ' '; }

// Base words (separators removed) of each body part, from CMU/cgspeed, Mixamo, Rigify, Unity
// humanoid, ASF (lfemur, ltibia) and plain (l_knee) conventions.
Part part_of_base(const std::string& b, bool sided) {
  if (sided) {
    if (b == "upleg" || b == "upperleg" || b == "thigh" || b == "hip" || b == "femur") {
      return Part::kThigh;
    }
    if (b == "leg" || b == "knee" || b == "shin" || b == "calf" || b == "lowerleg" ||
        b == "lowleg" || b == "tibia") {
      return Part::kShin;
    }
    if (b == "foot" || b == "ankle") return Part::kFoot;
    if (b == "toebase" || b == "toe" || b == "toes" || b == "ball") return Part::kToe;
    if (b == "arm" || b == "upperarm" || b == "uparm" || b == "humerus") return Part::kArm;
    if (b == "shoulder") return Part::kShoulder;
    if (b == "clavicle" || b == "collar") return Part::kClavicle;
    return Part::kNone;
  }
  if (b == "hips" || b == "hip" || b == "pelvis") return Part::kHips;
  if (b == "head") return Part::kHead;
  if (b.find("neck") != std::string::npos) return Part::kNeck;
  if (b.rfind("spine", 0) == 0 || b.rfind("chest", 0) == 0 || b == "upperchest" ||
      b == "lowerback" || b == "upperback" || b == "thorax" || b == "abdomen" || b == "torso") {
    return Part::kSpine;
  }
  return Part::kNone;
}

std::string compact(std::string_view s) {
  std::string out;
  for (char c : s) {
    if (!is_separator(c)) out += c;
  }
  return out;
}

// The words of a name, lower case: split at anything but letters and digits and where camel case
// starts a word ("Bip01 L Thigh" -> bip01 l thigh, "J_Bip_L_UpperLeg" -> j bip l upper leg,
// "LHipJoint" -> l hip joint); digits stay with the word before them ("Toe0", "Spine1").
std::vector<std::string> words_of(std::string_view raw) {
  std::vector<std::string> words;
  std::string cur;
  auto flush = [&] {
    if (!cur.empty()) words.push_back(lower_ascii(cur));
    cur.clear();
  };
  for (size_t i = 0; i < raw.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(raw[i]);
    if (!std::isalnum(c)) {
      flush();
      continue;
    }
    const bool upper = std::isupper(c);
    const unsigned char prev = i > 0 ? static_cast<unsigned char>(raw[i - 1]) : 0;
    const unsigned char next = i + 1 < raw.size() ? static_cast<unsigned char>(raw[i + 1]) : 0;
    // A capital after a lower-case letter or digit starts a word, and so does the last capital
    // of a run followed by lower case ("LHip" -> L, Hip).
    if (upper && !cur.empty() &&
        (std::islower(prev) || std::isdigit(prev) || (std::isupper(prev) && std::islower(next)))) {
      flush();
    }
    cur += static_cast<char>(c);
  }
  flush();
  return words;
}

// Names the plain rules below do not read, word by word: a side word anywhere ("Bip01 L Thigh",
// "CC_Base_L_Calf", "J_Bip_L_UpperLeg"; "C" marks the middle in VRM), and the body-part word
// after a rig prefix (leading words with digits or of at most three letters, or "base":
// "Bip01", "J_Bip", "CC_Base"). A part word must end the name ("thigh_twist_01_l" is no thigh).
NameInfo classify_by_words(std::string_view raw) {
  NameInfo info;
  std::vector<std::string> words = words_of(raw);
  std::vector<std::string> rest;
  int sides = 0;
  for (const std::string& w : words) {
    if (w == "l" || w == "left") {
      info.side = NameSide::kLeft;
      ++sides;
    } else if (w == "r" || w == "right") {
      info.side = NameSide::kRight;
      ++sides;
    } else if (w != "c" && w != "m" && w != "mid" && w != "center" && w != "centre") {
      rest.push_back(w);
    }
  }
  if (sides > 1) return {};
  auto droppable = [](const std::string& w) {
    return w.size() <= 3 || w == "base" || std::any_of(w.begin(), w.end(), [](char c) {
             return std::isdigit(static_cast<unsigned char>(c));
           });
  };
  for (size_t k = 0; k < rest.size(); ++k) {
    std::string base;
    for (size_t i = k; i < rest.size(); ++i) base += rest[i];
    while (!base.empty() && std::isdigit(static_cast<unsigned char>(base.back()))) base.pop_back();
    Part p = part_of_base(base, info.side != NameSide::kNone);
    if (p == Part::kNone && info.side == NameSide::kNone) {
      p = part_of_base(base, true);  // a leg word without a side: the side comes from geometry
      if (p != Part::kThigh && p != Part::kShin && p != Part::kFoot && p != Part::kToe) {
        p = Part::kNone;
      }
    }
    if (p != Part::kNone) {
      info.part = p;
      return info;
    }
    if (!droppable(rest[k])) break;
  }
  return {};
}

NameInfo classify_plain(std::string_view raw) {
  std::string n = lower_ascii(raw);
  // Namespaces (mixamorig:, rig|) and Rigify's deform prefix say nothing about the body part.
  if (size_t p = n.find_last_of(":|"); p != std::string::npos) n = n.substr(p + 1);
  if (n.rfind("def-", 0) == 0 || n.rfind("def_", 0) == 0) n = n.substr(4);
  if (n.rfind("mixamorig", 0) == 0) n = n.substr(9);

  NameInfo info;
  std::string base = n;
  auto strip_prefix = [&](std::string_view word, NameSide side) {
    if (n.rfind(word, 0) != 0) return false;
    info.side = side;
    base = n.substr(word.size());
    return true;
  };
  auto strip_suffix = [&](std::string_view word, NameSide side) {
    if (n.size() <= word.size() || n.compare(n.size() - word.size(), word.size(), word) != 0) {
      return false;
    }
    info.side = side;
    base = n.substr(0, n.size() - word.size());
    return true;
  };
  const bool sided =
      strip_prefix("left", NameSide::kLeft) || strip_prefix("right", NameSide::kRight) ||
      strip_suffix("left", NameSide::kLeft) || strip_suffix("right", NameSide::kRight) ||
      (n.size() > 2 && n[0] == 'l' && is_separator(n[1]) &&
       strip_prefix(n.substr(0, 2), NameSide::kLeft)) ||
      (n.size() > 2 && n[0] == 'r' && is_separator(n[1]) &&
       strip_prefix(n.substr(0, 2), NameSide::kRight)) ||
      (n.size() > 2 && n.back() == 'l' && is_separator(n[n.size() - 2]) &&
       strip_suffix(n.substr(n.size() - 2), NameSide::kLeft)) ||
      (n.size() > 2 && n.back() == 'r' && is_separator(n[n.size() - 2]) &&
       strip_suffix(n.substr(n.size() - 2), NameSide::kRight));
  if (sided) {
    info.part = part_of_base(compact(base), true);
    return info;
  }
  // CamelCase with a bare capital side letter at the end (RobotExpressive's "UpperLegL",
  // "FootR"): only when the rest is a known leg or arm word, so that "Ball" is not read as sided.
  const char last = raw.empty() ? '\0' : raw.back();
  if ((last == 'L' || last == 'R') && raw.size() > 2 &&
      std::islower(static_cast<unsigned char>(raw[raw.size() - 2]))) {
    const Part p = part_of_base(compact(n.substr(0, n.size() - 1)), true);
    if (p != Part::kNone) {
      info.part = p;
      info.side = last == 'L' ? NameSide::kLeft : NameSide::kRight;
      return info;
    }
  }
  const std::string c = compact(n);
  info.part = part_of_base(c, false);
  // ASF style ("lfemur", "rtibia"): a bare l/r prefix counts only when the rest is a known part,
  // so that "leg" or "lowerback" are not read as sided.
  if (info.part == Part::kNone && c.size() > 1 && (c[0] == 'l' || c[0] == 'r')) {
    Part p = part_of_base(c.substr(1), true);
    if (p != Part::kNone) {
      info.part = p;
      info.side = c[0] == 'l' ? NameSide::kLeft : NameSide::kRight;
    }
  }
  // A leg word without a side ("Thigh", "Foot.001"): the side comes from where the joint sits
  // (resolve_sides_by_geometry).
  if (info.part == Part::kNone) {
    std::string word = c;
    while (!word.empty() && std::isdigit(static_cast<unsigned char>(word.back()))) word.pop_back();
    const Part p = part_of_base(word, true);
    if (p == Part::kThigh || p == Part::kShin || p == Part::kFoot || p == Part::kToe) info.part = p;
  }
  return info;
}

NameInfo classify(std::string_view raw) {
  NameInfo info = classify_plain(raw);
  if (info.part == Part::kNone) info = classify_by_words(raw);
  return info;
}

// Rest-pose positions in model space: the geometry that pairs IK-style feet with their legs.
std::vector<glm::vec3> rest_positions(const Skeleton& s) {
  const int n = s.num_joints();
  std::vector<glm::vec3> pos(n);
  std::vector<glm::quat> rot(n);
  for (int j = 0; j < n; ++j) {
    const int p = s.parents[j];
    rot[j] = p < 0 ? s.rest_rotations[j] : rot[p] * s.rest_rotations[j];
    pos[j] = p < 0 ? s.rest_translations[j] : pos[p] + rot[p] * s.rest_translations[j];
  }
  return pos;
}

bool is_descendant(const Skeleton& s, int joint, int ancestor) {
  for (int j = s.parents[joint]; j >= 0; j = s.parents[j]) {
    if (j == ancestor) return true;
  }
  return false;
}

int depth_below(const Skeleton& s, int joint, int ancestor) {
  int d = 0;
  for (int j = joint; j >= 0 && j != ancestor; j = s.parents[j]) ++d;
  return d;
}

// Among the joints tagged `part` on `side` below `ancestor` (any joint when -1), the one closest to
// it; the topology check that keeps a knee below its hip.
int nearest_below(const Skeleton& s, const std::vector<NameInfo>& info, Part part, NameSide side,
                  int ancestor) {
  int best = -1;
  int best_depth = 1 << 30;
  for (int j = 0; j < s.num_joints(); ++j) {
    if (info[j].part != part || info[j].side != side) continue;
    if (ancestor >= 0 && !is_descendant(s, j, ancestor)) continue;
    const int d = ancestor >= 0 ? depth_below(s, j, ancestor) : depth_below(s, j, -1);
    if (d < best_depth) {
      best = j;
      best_depth = d;
    }
  }
  return best;
}

int common_ancestor(const Skeleton& s, int a, int b) {
  for (int x = a; x >= 0; x = s.parents[x]) {
    if (x == b || is_descendant(s, b, x)) return x;
  }
  return -1;
}

void set_role(Skeleton* s, JointRole r, int joint) { s->roles[static_cast<int>(r)] = joint; }

bool is_descendant_or_self(const Skeleton& s, int joint, int ancestor) {
  return joint == ancestor || is_descendant(s, joint, ancestor);
}

// An IK-style rig's foot (or toe) is not below its shin (or foot): it hangs from the root or the
// hips and follows an IK target. Among the joints named `part` on `side` that are not below
// `upper` (the knee, or the ankle for a toe) nor above the thigh, the one that sits where the
// bone below `upper` would end: lower than `upper` by a plausible bone length (0.4 to 2 thigh
// lengths for a shin, up to one shin length for a foot), nearest to it horizontally.
int ik_style_joint(const Skeleton& s, const std::vector<NameInfo>& info,
                   const std::vector<glm::vec3>& pos, Part part, NameSide side, int thigh,
                   int upper, float bone_m) {
  int best = -1;
  float best_d = 0.0f;
  for (int j = 0; j < s.num_joints(); ++j) {
    if (info[j].part != part || info[j].side != side) continue;
    if (is_descendant_or_self(s, j, upper) || is_descendant_or_self(s, thigh, j)) continue;
    const glm::vec3 d = pos[j] - pos[upper];
    const float len = glm::length(d);
    const bool plausible = part == Part::kFoot
                               ? len > 0.4f * bone_m && len < 2.0f * bone_m && -d.y > 0.5f * len
                               : len > 0.05f * bone_m && len < bone_m && d.y < 0.1f * bone_m;
    if (!plausible) continue;
    const float horizontal = std::hypot(d.x, d.z);
    if (best < 0 || horizontal < best_d) {
      best = j;
      best_d = horizontal;
    }
  }
  return best;
}

void detect_leg(Skeleton* s, const std::vector<NameInfo>& info, const std::vector<glm::vec3>& pos,
                NameSide side, int hips) {
  const bool left = side == NameSide::kLeft;
  int hip = -1, knee = -1, ankle = -1, toe = -1;
  // Prefer the thigh candidate that has a complete chain below it (some rigs name a pelvis-side
  // helper "LeftHip" above the real thigh).
  for (int j = 0; j < s->num_joints(); ++j) {
    if (info[j].part != Part::kThigh || info[j].side != side) continue;
    if (hips >= 0 && !is_descendant(*s, j, hips)) continue;
    const int k = nearest_below(*s, info, Part::kShin, side, j);
    const int a = k >= 0 ? nearest_below(*s, info, Part::kFoot, side, k) : -1;
    if (hip < 0 || (a >= 0 && ankle < 0)) {
      hip = j;
      knee = k;
      ankle = a;
    }
  }
  if (knee >= 0 && ankle < 0) {
    ankle = ik_style_joint(*s, info, pos, Part::kFoot, side, hip, knee,
                           glm::length(pos[knee] - pos[hip]));
  }
  if (ankle >= 0) toe = nearest_below(*s, info, Part::kToe, side, ankle);
  // Below an ankle, a foot is the toe (SMPL: L_Knee -> L_Ankle -> L_Foot).
  if (ankle >= 0 && toe < 0) toe = nearest_below(*s, info, Part::kFoot, side, ankle);
  if (ankle >= 0 && toe < 0) {
    toe = ik_style_joint(*s, info, pos, Part::kToe, side, hip, ankle,
                         glm::length(pos[ankle] - pos[knee]));
  }
  // A toe of any other name ("LeftFootToe", "LeftToe_End"): the ankle's child joint with the
  // longest bone, the foot's own (a heel or helper joint beside it is shorter).
  if (ankle >= 0 && toe < 0) {
    float longest = 0.0f;
    for (int j = ankle + 1; j < s->num_joints(); ++j) {
      if (s->parents[j] != ankle) continue;
      const float len = glm::length(pos[j] - pos[ankle]);
      if (len > longest) {
        longest = len;
        toe = j;
      }
    }
  }
  set_role(s, left ? JointRole::kLeftHip : JointRole::kRightHip, hip);
  set_role(s, left ? JointRole::kLeftKnee : JointRole::kRightKnee, knee);
  set_role(s, left ? JointRole::kLeftAnkle : JointRole::kRightAnkle, ankle);
  set_role(s, left ? JointRole::kLeftToe : JointRole::kRightToe, toe);
}

// spine_chain: the path from just above the hips up to the chest.
void rebuild_spine_chain(Skeleton* s) {
  s->spine_chain.clear();
  const int hips = s->role(JointRole::kHips);
  const int chest = s->role(JointRole::kChest);
  if (hips < 0 || chest < 0 || !is_descendant(*s, chest, hips)) return;
  for (int j = chest; j >= 0 && j != hips; j = s->parents[j]) {
    s->spine_chain.push_back(static_cast<int16_t>(j));
  }
  std::reverse(s->spine_chain.begin(), s->spine_chain.end());
}

}  // namespace

std::string_view joint_role_name(JointRole role) {
  const int i = static_cast<int>(role);
  return i >= 0 && i < kNumJointRoles ? kRoleNames[i] : "unknown";
}

bool joint_role_from_name(std::string_view name, JointRole* out_role) {
  for (int i = 0; i < kNumJointRoles; ++i) {
    if (kRoleNames[i] == name) {
      *out_role = static_cast<JointRole>(i);
      return true;
    }
  }
  return false;
}

int Skeleton::find(std::string_view name) const {
  for (size_t i = 0; i < names.size(); ++i) {
    if (names[i] == name) return static_cast<int>(i);
  }
  return -1;
}

bool Skeleton::has_locomotion_roles() const {
  for (JointRole r : kLocomotionRoles) {
    if (!has(r)) return false;
  }
  return true;
}

std::string missing_locomotion_roles(const Skeleton& s) {
  std::string out;
  for (JointRole r : kLocomotionRoles) {
    if (!s.has(r)) out += (out.empty() ? "" : ", ") + std::string(joint_role_name(r));
  }
  return out;
}

std::string role_manifest_hint() {
  return "roles are found from joint names (LeftUpLeg/LeftLeg/LeftFoot/LeftToeBase, "
         "thigh_l/calf_l/foot_l/ball_l, UpperLeg.L, lfemur/ltibia/lfoot/ltoes, ...), and a foot "
         "parented to the root is matched to the knee above it; otherwise give a role manifest "
         "with --roles FILE.json (in the demo panel: Crowd > roles...) naming this skeleton's "
         "joint for each role: {\"roles\": {\"hips\": \"...\", \"chest\": \"...\", "
         "\"left_hip\": \"...\", \"left_knee\": \"...\", \"left_ankle\": \"...\", "
         "\"left_toe\": \"...\", \"right_hip\": \"...\", \"right_knee\": \"...\", "
         "\"right_ankle\": \"...\", \"right_toe\": \"...\"}}";
}

void detect_joint_roles(Skeleton* s) {
  s->roles.fill(-1);
  s->spine_chain.clear();
  const int n = s->num_joints();
  std::vector<NameInfo> info(n);
  for (int j = 0; j < n; ++j) info[j] = classify(s->names[j]);

  int hips = nearest_below(*s, info, Part::kHips, NameSide::kNone, -1);
  const std::vector<glm::vec3> pos = rest_positions(*s);
  // Leg words without a side take the side they stand on (left at +x, the rest pose facing +z),
  // relative to the hips or, without them, the middle of the skeleton.
  const float mid_x = hips >= 0 ? pos[hips].x : 0.0f;
  for (int j = 0; j < n; ++j) {
    if (info[j].side != NameSide::kNone || info[j].part == Part::kNone ||
        info[j].part == Part::kHips || info[j].part == Part::kSpine ||
        info[j].part == Part::kNeck || info[j].part == Part::kHead) {
      continue;
    }
    const float x = pos[j].x - mid_x;
    if (std::abs(x) > 1e-4f * (1.0f + std::abs(pos[j].y))) {
      info[j].side = x > 0.0f ? NameSide::kLeft : NameSide::kRight;
    }
  }
  detect_leg(s, info, pos, NameSide::kLeft, hips);
  detect_leg(s, info, pos, NameSide::kRight, hips);
  // Without a hips name, the pelvis is where the two legs meet.
  if (hips < 0 && s->has(JointRole::kLeftHip) && s->has(JointRole::kRightHip)) {
    hips = common_ancestor(*s, s->role(JointRole::kLeftHip), s->role(JointRole::kRightHip));
  }
  set_role(s, JointRole::kHips, hips);

  const int neck = nearest_below(*s, info, Part::kNeck, NameSide::kNone, hips);
  set_role(s, JointRole::kNeck, neck);
  const int head = nearest_below(*s, info, Part::kHead, NameSide::kNone, neck >= 0 ? neck : hips);
  set_role(s, JointRole::kHead, head);
  // Chest = the last joint below the neck (the neck base). With no neck, the topmost spine-named
  // joint of the chain.
  int chest = -1;
  const int top = neck >= 0 ? neck : head;
  if (top >= 0 && hips >= 0 && s->parents[top] != hips && s->parents[top] >= 0) {
    chest = s->parents[top];
  } else if (top < 0) {
    for (int j = 0; j < n; ++j) {
      if (info[j].part == Part::kSpine && (hips < 0 || is_descendant(*s, j, hips)) &&
          (chest < 0 || is_descendant(*s, j, chest))) {
        chest = j;
      }
    }
  }
  set_role(s, JointRole::kChest, chest);
  rebuild_spine_chain(s);
  if (!s->spine_chain.empty()) set_role(s, JointRole::kSpine, s->spine_chain.front());

  // Shoulder = the upper-arm joint (the shoulder's rotation centre). "LeftShoulder" is a clavicle
  // when the rig also has "LeftArm" (CMU, Mixamo; it sits on the spine there) and the upper arm
  // when it has "LeftCollar" instead (cgspeed's LeftHip/LeftKnee form).
  const int arms_root = chest >= 0 ? chest : hips;
  for (NameSide side : {NameSide::kLeft, NameSide::kRight}) {
    int j = nearest_below(*s, info, Part::kArm, side, arms_root);
    if (j < 0) j = nearest_below(*s, info, Part::kShoulder, side, arms_root);
    if (j < 0) j = nearest_below(*s, info, Part::kClavicle, side, arms_root);
    set_role(s, side == NameSide::kLeft ? JointRole::kLeftShoulder : JointRole::kRightShoulder, j);
  }
}

Status apply_role_manifest_text(std::string_view json_text, const std::string& source_name,
                                Skeleton* skeleton) {
  Result<nlohmann::json> parsed = parse_json_text(json_text, source_name);
  if (!parsed.ok()) return parsed.status();
  const nlohmann::json& doc = *parsed;
  if (!doc.is_object() || !doc.contains("roles")) {
    return Status::AtField(source_name, "roles", "missing (expected {\"roles\": {...}})");
  }
  const nlohmann::json& roles = doc["roles"];
  if (!roles.is_object()) {
    return Status::AtField(source_name, "roles", "expected an object of role: joint name");
  }
  Skeleton updated = *skeleton;
  for (const auto& [key, value] : roles.items()) {
    const std::string field = "roles." + printable_snippet(key, 80);
    JointRole role;
    if (!joint_role_from_name(key, &role)) {
      std::string known;
      for (std::string_view r : kRoleNames) known += (known.empty() ? "" : ", ") + std::string(r);
      return Status::AtField(source_name, field, "unknown role (expected one of " + known + ")");
    }
    if (value.is_null()) {  // null removes a wrongly detected role
      set_role(&updated, role, -1);
      continue;
    }
    if (!value.is_string()) {
      return Status::AtField(source_name, field, "expected a joint name (string) or null");
    }
    const int j = updated.find(value.get<std::string>());
    if (j < 0) {
      return Status::AtField(
          source_name, field,
          "no joint named " + quoted_snippet(value.get<std::string>(), 80) + " in the skeleton");
    }
    set_role(&updated, role, j);
  }
  rebuild_spine_chain(&updated);
  if (!updated.spine_chain.empty() && roles.contains("spine") && updated.has(JointRole::kSpine)) {
    // An explicit spine start trims the chain to begin there.
    auto it = std::find(updated.spine_chain.begin(), updated.spine_chain.end(),
                        updated.role(JointRole::kSpine));
    if (it != updated.spine_chain.end()) updated.spine_chain.erase(updated.spine_chain.begin(), it);
  } else if (!updated.spine_chain.empty()) {
    set_role(&updated, JointRole::kSpine, updated.spine_chain.front());
  }
  *skeleton = std::move(updated);
  return Status::Ok();
}

Status apply_role_manifest(const std::string& manifest_path, Skeleton* skeleton) {
  Result<std::string> text = read_file_bytes(manifest_path, kMaxManifestBytes, "role manifest");
  if (!text.ok()) return text.status();
  return apply_role_manifest_text(*text, manifest_path, skeleton);
}

Status validate_skeleton(const Skeleton& s, const std::string& source_name) {
  const size_t n = s.parents.size();
  if (n == 0) return Status::Error(source_name + ": skeleton has no joints");
  if (n > 32767)
    return Status::Error(source_name + ": too many joints (" + std::to_string(n) + ")");
  if (s.names.size() != n || s.rest_translations.size() != n || s.rest_rotations.size() != n) {
    return Status::Error(source_name + ": skeleton arrays disagree in size");
  }
  for (size_t i = 0; i < n; ++i) {
    const std::string where = "joint " + std::to_string(i) + " " + quoted_snippet(s.names[i], 80);
    if (s.parents[i] < -1 || s.parents[i] >= static_cast<int>(i)) {
      return Status::AtField(source_name, where,
                             "parent " + std::to_string(s.parents[i]) + " is not an earlier joint");
    }
    const glm::vec3& t = s.rest_translations[i];
    const glm::quat& q = s.rest_rotations[i];
    if (!std::isfinite(t.x) || !std::isfinite(t.y) || !std::isfinite(t.z)) {
      return Status::AtField(source_name, where, "rest translation is not finite");
    }
    const float len = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
    if (!std::isfinite(len) || std::abs(len - 1.0f) > 1e-3f) {
      return Status::AtField(source_name, where, "rest rotation is not a unit quaternion");
    }
  }
  for (int r = 0; r < kNumJointRoles; ++r) {
    if (s.roles[r] < -1 || s.roles[r] >= static_cast<int>(n)) {
      return Status::AtField(source_name, "roles." + std::string(kRoleNames[r]), "out of range");
    }
  }
  for (int16_t j : s.spine_chain) {
    if (j < 0 || j >= static_cast<int>(n)) {
      return Status::AtField(source_name, "spine_chain", "joint index out of range");
    }
  }
  return Status::Ok();
}

std::vector<int> subtree_ends(const Skeleton& s) {
  const int n = s.num_joints();
  std::vector<int> end(n, n);
  for (int j = 0; j < n; ++j) {
    if (s.parents[j] >= j || s.parents[j] < -1) return end;  // not parents-first: whole ranges
  }
  // Children after parents: one backward pass gathers each subtree's last joint and size.
  std::vector<int> last(n), size(n, 1);
  for (int j = 0; j < n; ++j) last[j] = j;
  for (int j = n - 1; j > 0; --j) {
    const int p = s.parents[j];
    if (p < 0) continue;
    last[p] = std::max(last[p], last[j]);
    size[p] += size[j];
  }
  for (int j = 0; j < n; ++j) {
    if (last[j] - j + 1 == size[j]) end[j] = last[j] + 1;  // contiguous: exactly the subtree
  }
  return end;
}

}  // namespace gk
