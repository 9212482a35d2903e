// BVH loader: HIERARCHY (joints, End Sites, any channel order) and MOTION (one frame per line).

#include "animation/bvh_loader.h"

#include <cmath>
#include <sstream>

#include <glm/gtc/quaternion.hpp>

#include "animation/ik_rig.h"
#include "animation/loader_internal.h"
#include "animation/text_scanner.h"
#include "common/file_io.h"
#include "common/text_snippet.h"

namespace gk {
namespace {

enum class Channel : uint8_t { kXpos, kYpos, kZpos, kXrot, kYrot, kZrot };

struct BvhJoint {
  std::string name;
  int parent = -1;
  glm::vec3 offset{0.0f};
  glm::vec3 end_site{0.0f};  // the End Site's OFFSET, when the joint ends a chain
  std::vector<Channel> channels;
};

bool iequals(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (std::tolower(static_cast<unsigned char>(a[i])) !=
        std::tolower(static_cast<unsigned char>(b[i]))) {
      return false;
    }
  }
  return true;
}

bool channel_from_name(std::string_view s, Channel* out) {
  static constexpr std::pair<std::string_view, Channel> kNames[] = {
      {"Xposition", Channel::kXpos}, {"Yposition", Channel::kYpos}, {"Zposition", Channel::kZpos},
      {"Xrotation", Channel::kXrot}, {"Yrotation", Channel::kYrot}, {"Zrotation", Channel::kZrot}};
  for (const auto& [name, c] : kNames) {
    if (iequals(s, name)) {
      *out = c;
      return true;
    }
  }
  return false;
}

// A token from the file as echoed in messages (printable: a binary file is no text).
std::string quoted(std::string_view token) {
  if (token.empty()) return "end of file";
  return quoted_snippet(token);
}

constexpr uint64_t kMaxFileBytes = uint64_t(1) << 30;  // hours of mocap; refuse anything absurd

class BvhParser {
 public:
  BvhParser(std::string_view text, std::string source, const LoadOptions& options)
      : scan_(text), source_(std::move(source)), options_(options) {}

  Status parse_hierarchy();
  Result<Clip> parse_motion(float scale);
  const std::vector<BvhJoint>& joints() const { return joints_; }

 private:
  Status error(int line, const std::string& what) const {
    return Status::AtLine(source_, line, what);
  }
  Status expect(std::string_view want) {
    const std::string_view tok = scan_.next();
    if (tok != want)
      return error(scan_.line(), "expected '" + std::string(want) + "', found " + quoted(tok));
    return Status::Ok();
  }
  Status read_vec3(glm::vec3* out);
  Status parse_joint(int parent, int depth);
  Status parse_end_site(int joint);

  internal::TextScanner scan_;
  std::string source_;
  LoadOptions options_;
  std::vector<BvhJoint> joints_;
  int num_channels_ = 0;
};

Status BvhParser::read_vec3(glm::vec3* out) {
  for (int i = 0; i < 3; ++i) {
    const std::string_view tok = scan_.next();
    double v = 0.0;
    switch (internal::parse_double(tok, &v)) {
      case internal::NumberParse::kOk:
        (*out)[i] = static_cast<float>(v);
        break;
      case internal::NumberParse::kNotFinite:
        return error(scan_.line(), "OFFSET value " + quoted(tok) + " is not a finite number");
      default:
        return error(scan_.line(), "expected 3 OFFSET numbers, found " + quoted(tok));
    }
  }
  return Status::Ok();
}

Status BvhParser::parse_end_site(int joint) {
  // "End Site" ends a chain: its offset only gives the bone tip (kept: a toe's tip is where a
  // foot rolling off the ground touches it last), it is not a joint.
  scan_.rest_of_line();
  GK_RETURN_IF_ERROR(expect("{"));
  for (;;) {
    const std::string_view tok = scan_.next();
    if (tok == "}") return Status::Ok();
    if (tok.empty())
      return error(scan_.line(), "unexpected end of file inside End Site (expected '}')");
    if (tok != "OFFSET") {
      return error(scan_.line(),
                   "unknown keyword " + quoted(tok) + " in End Site (expected OFFSET or '}')");
    }
    GK_RETURN_IF_ERROR(read_vec3(&joints_[joint].end_site));
  }
}

Status BvhParser::parse_joint(int parent, int depth) {
  const int line = scan_.line();
  const std::string_view name = scan_.rest_of_line();
  if (name.empty()) return error(line, "expected a joint name");
  if (depth > options_.max_depth) {
    return error(line, "hierarchy deeper than " + std::to_string(options_.max_depth) + " levels");
  }
  if (static_cast<int>(joints_.size()) >= options_.max_joints) {
    return error(line, "more than " + std::to_string(options_.max_joints) + " joints");
  }
  const int self = static_cast<int>(joints_.size());
  joints_.push_back({std::string(name), parent, glm::vec3(0.0f), glm::vec3(0.0f), {}});
  GK_RETURN_IF_ERROR(expect("{"));
  for (;;) {
    const std::string_view tok = scan_.next();
    const int tok_line = scan_.line();
    if (tok == "}") return Status::Ok();
    if (tok.empty()) {
      return error(tok_line, "unexpected end of file inside joint " +
                                 quoted_snippet(joints_[self].name, 80) + " (expected '}')");
    }
    if (tok == "OFFSET") {
      GK_RETURN_IF_ERROR(read_vec3(&joints_[self].offset));
    } else if (tok == "CHANNELS") {
      const std::string_view count_tok = scan_.next();
      int64_t count = -1;
      if (!internal::parse_int64(count_tok, &count) || count < 0 || count > 6) {
        return error(scan_.line(),
                     "expected a channel count from 0 to 6, found " + quoted(count_tok));
      }
      joints_[self].channels.clear();
      for (int64_t c = 0; c < count; ++c) {
        const std::string_view ch = scan_.next();
        Channel channel;
        if (!channel_from_name(ch, &channel)) {
          return error(scan_.line(),
                       "expected a channel name (Xposition ... Zrotation), found " + quoted(ch));
        }
        joints_[self].channels.push_back(channel);
      }
      num_channels_ += static_cast<int>(count);
    } else if (tok == "JOINT") {
      GK_RETURN_IF_ERROR(parse_joint(self, depth + 1));
    } else if (tok == "End") {
      GK_RETURN_IF_ERROR(parse_end_site(self));
    } else {
      return error(tok_line, "unknown keyword " + quoted(tok) +
                                 " (expected OFFSET, CHANNELS, JOINT, End Site or '}')");
    }
  }
}

Status BvhParser::parse_hierarchy() {
  std::string_view tok = scan_.next();
  if (tok != "HIERARCHY") return error(scan_.line(), "expected 'HIERARCHY', found " + quoted(tok));
  for (;;) {
    tok = scan_.next();
    if (tok == "ROOT") {
      GK_RETURN_IF_ERROR(parse_joint(-1, 1));
    } else if (tok == "MOTION") {
      break;
    } else if (tok.empty()) {
      return error(scan_.line(), "missing MOTION section (file ends after the hierarchy)");
    } else {
      return error(scan_.line(), "unknown keyword " + quoted(tok) + " (expected ROOT or MOTION)");
    }
  }
  if (joints_.empty()) return error(scan_.line(), "no ROOT joint before MOTION");
  if (num_channels_ == 0) return error(scan_.line(), "the hierarchy declares no channels");
  return Status::Ok();
}

Result<Clip> BvhParser::parse_motion(float scale) {
  std::string_view tok = scan_.next();
  int64_t frames = -1;
  if (tok == "Frames:")
    tok = scan_.next();
  else
    return error(scan_.line(), "expected 'Frames:', found " + quoted(tok));
  const int frames_line = scan_.line();
  if (!internal::parse_int64(tok, &frames) || frames < 1) {
    return error(frames_line, "expected a frame count >= 1, found " + quoted(tok));
  }
  // Each value needs at least one character and one separator: a count the remaining bytes cannot
  // hold is rejected before anything is allocated.
  const int64_t min_bytes_per_frame = 2 * static_cast<int64_t>(num_channels_);
  const int64_t bytes_left = static_cast<int64_t>(scan_.bytes_left());
  if (frames > bytes_left / min_bytes_per_frame + 1) {
    return error(frames_line, "Frames: " + std::to_string(frames) + " needs at least " +
                                  std::to_string(min_bytes_per_frame) +
                                  " bytes per frame, but only " + std::to_string(bytes_left) +
                                  " bytes follow");
  }
  // Joints without channels take memory but no bytes, so the decoded size gets its own cap.
  constexpr int64_t kMaxSamples = int64_t{1} << 24;
  if (frames * static_cast<int64_t>(joints_.size()) > kMaxSamples) {
    return error(frames_line, "Frames: " + std::to_string(frames) + " x " +
                                  std::to_string(joints_.size()) + " joints exceeds the limit of " +
                                  std::to_string(kMaxSamples) + " joint samples");
  }
  if (tok = scan_.next(); tok != "Frame" || (tok = scan_.next()) != "Time:") {
    return error(scan_.line(), "expected 'Frame Time:', found " + quoted(tok));
  }
  tok = scan_.next();
  double frame_time = 0.0;
  if (internal::parse_double(tok, &frame_time) != internal::NumberParse::kOk || frame_time <= 0.0) {
    return error(scan_.line(), "expected a Frame Time > 0 [s], found " + quoted(tok));
  }
  scan_.skip_line();

  const int num_joints = static_cast<int>(joints_.size());
  Clip clip;
  clip.fps = static_cast<float>(1.0 / frame_time);
  // Frame times are printed rounded (0.0083333): snap to the integer rate they stand for.
  if (std::abs(clip.fps - std::round(clip.fps)) < 0.01f) clip.fps = std::round(clip.fps);
  clip.num_frames = static_cast<int>(frames);
  clip.num_joints = num_joints;
  clip.sampled_capture = true;  // motion capture sampled at the frame rate
  clip.rotations.resize(static_cast<size_t>(frames) * num_joints);
  clip.translations.resize(static_cast<size_t>(frames) * num_joints);
  std::vector<float> values(num_channels_);
  for (int64_t f = 0; f < frames; ++f) {
    tok = scan_.next_on_line();
    while (tok.empty() && !scan_.at_end()) {  // blank lines between frames are tolerated
      scan_.skip_line();
      tok = scan_.next_on_line();
    }
    const int line = scan_.current_line();
    if (tok.empty()) {
      return error(line, "file ends after " + std::to_string(f) + " of " + std::to_string(frames) +
                             " frames (truncated?)");
    }
    int count = 0;
    for (; !tok.empty(); tok = scan_.next_on_line(), ++count) {
      if (count >= num_channels_) continue;  // counted for the message below
      double v = 0.0;
      const internal::NumberParse p = internal::parse_double(tok, &v);
      if (p == internal::NumberParse::kNotFinite) {
        return error(line, "channel value " + std::to_string(count + 1) + " " + quoted(tok) +
                               " is not a finite number");
      }
      if (p != internal::NumberParse::kOk) {
        return error(line, "expected a number, found " + quoted(tok));
      }
      values[count] = static_cast<float>(v);
    }
    if (count != num_channels_) {
      return error(line, "expected " + std::to_string(num_channels_) + " channel values, found " +
                             std::to_string(count));
    }
    scan_.skip_line();
    int k = 0;
    for (int j = 0; j < num_joints; ++j) {
      glm::vec3 t = joints_[j].offset;
      glm::quat q(1.0f, 0.0f, 0.0f, 0.0f);
      // R is the product of the axis rotations in channel order (Z Y X -> Rz*Ry*Rx); a position
      // channel replaces that component of the OFFSET.
      for (Channel c : joints_[j].channels) {
        const float v = values[k++];
        switch (c) {
          case Channel::kXpos:
            t.x = v;
            break;
          case Channel::kYpos:
            t.y = v;
            break;
          case Channel::kZpos:
            t.z = v;
            break;
          case Channel::kXrot:
            q = q * glm::angleAxis(glm::radians(v), glm::vec3(1, 0, 0));
            break;
          case Channel::kYrot:
            q = q * glm::angleAxis(glm::radians(v), glm::vec3(0, 1, 0));
            break;
          case Channel::kZrot:
            q = q * glm::angleAxis(glm::radians(v), glm::vec3(0, 0, 1));
            break;
        }
      }
      const size_t i = static_cast<size_t>(f) * num_joints + j;
      clip.rotations[i] = glm::normalize(q);
      clip.translations[i] = t * scale;
    }
  }
  tok = scan_.next();
  if (!tok.empty()) {
    return error(scan_.line(),
                 "expected " + std::to_string(frames) + " frames, found more data: " + quoted(tok));
  }
  return clip;
}

}  // namespace

float detect_unit_scale(const Skeleton& s, std::string* reason) {
  struct Candidate {
    float m_per_unit;
    const char* name;
  };
  static constexpr Candidate kCandidates[] = {{1.0f, "metres"},
                                              {0.01f, "centimetres"},
                                              {0.001f, "millimetres"},
                                              {0.0254f, "inches"},
                                              {0.056444f, "CMU/cgspeed units (0.056444 m)"}};
  std::vector<glm::mat4> model;
  internal::local_to_model(s, s.rest_rotations.data(), s.rest_translations.data(), &model);
  float measure = 0.0f, nominal_m = 0.0f;
  std::string what;
  int sides = 0;
  for (Side side : {Side::kLeft, Side::kRight}) {
    if (s.hip(side) < 0 || s.ankle(side) < 0) continue;
    measure += glm::length(glm::vec3(model[s.hip(side)][3] - model[s.ankle(side)][3]));
    ++sides;
  }
  if (sides > 0) {
    measure /= sides;
    nominal_m = 0.85f;  // adult hip-to-ankle length
    what = "hip-to-ankle length";
  } else {
    float min_y = 0.0f, max_y = 0.0f;
    for (const glm::mat4& m : model) {
      min_y = std::min(min_y, m[3].y);
      max_y = std::max(max_y, m[3].y);
    }
    if (s.has(JointRole::kHips)) {
      measure = model[s.role(JointRole::kHips)][3].y - min_y;
      nominal_m = 0.95f;
      what = "hips height";
    } else {
      measure = max_y - min_y;
      nominal_m = 1.6f;
      what = "rest-pose height";
    }
  }
  if (!(measure > 0.0f) || !std::isfinite(measure)) {
    if (reason) *reason = "assumed metres (no leg, hips or height to measure)";
    return 1.0f;
  }
  const Candidate* best = &kCandidates[0];
  for (const Candidate& c : kCandidates) {
    if (std::abs(std::log(measure * c.m_per_unit / nominal_m)) <
        std::abs(std::log(measure * best->m_per_unit / nominal_m))) {
      best = &c;
    }
  }
  if (reason) {
    std::ostringstream os;
    os.precision(4);
    os << "detected: " << best->name << " (" << what << " " << measure
       << " units = " << measure * best->m_per_unit << " m, nominal " << nominal_m << " m)";
    *reason = os.str();
  }
  return best->m_per_unit;
}

Result<ClipSet> parse_bvh(std::string_view text, const std::string& source_name,
                          const LoadOptions& options) {
  BvhParser parser(text, source_name, options);
  GK_RETURN_IF_ERROR(parser.parse_hierarchy());

  auto skeleton = std::make_shared<Skeleton>();
  for (const BvhJoint& j : parser.joints()) {
    skeleton->names.push_back(j.name);
    skeleton->parents.push_back(static_cast<int16_t>(j.parent));
    skeleton->rest_translations.push_back(j.offset);
    skeleton->rest_rotations.push_back(glm::quat(1.0f, 0.0f, 0.0f, 0.0f));
    skeleton->end_sites.push_back(j.end_site);
  }
  GK_RETURN_IF_ERROR(validate_skeleton(*skeleton, source_name));
  detect_joint_roles(skeleton.get());
  if (!options.role_manifest.empty()) {
    GK_RETURN_IF_ERROR(apply_role_manifest(options.role_manifest, skeleton.get()));
  }

  ClipSet set;
  set.source = source_name;
  if (options.scale_m_per_unit > 0.0f && std::isfinite(options.scale_m_per_unit)) {
    set.scale_m_per_unit = options.scale_m_per_unit;
    set.scale_reason = "given: " + std::to_string(options.scale_m_per_unit) + " m per unit";
  } else {
    set.scale_m_per_unit = detect_unit_scale(*skeleton, &set.scale_reason);
  }
  for (glm::vec3& t : skeleton->rest_translations) t *= set.scale_m_per_unit;
  for (glm::vec3& t : skeleton->end_sites) t *= set.scale_m_per_unit;

  Result<Clip> clip = parser.parse_motion(set.scale_m_per_unit);
  GK_RETURN_IF_ERROR(clip);
  clip->name = internal::file_stem(source_name);
  clip->source = source_name;
  set.up_reason = internal::stand_up_along_y(skeleton.get(), &clip.value());
  internal::finalize_loop(&clip.value(), *skeleton, internal::loop_tolerance_m(*skeleton));
  GK_RETURN_IF_ERROR(validate_clip(*clip, *skeleton));
  set.clips.push_back(std::move(clip).value());
  set.skeleton = std::move(skeleton);
  if (std::string moved = attach_ik_feet(&set); !moved.empty()) {
    set.rig_reason = "IK-style feet attached to the legs: " + moved;
    GK_RETURN_IF_ERROR(validate_skeleton(*set.skeleton, source_name));
  }
  if (std::string added = add_end_site_toes(&set); !added.empty()) {
    set.rig_reason += (set.rig_reason.empty() ? "" : "; ") + std::string("feet without toes: ") +
                      added;
    GK_RETURN_IF_ERROR(validate_skeleton(*set.skeleton, source_name));
  }
  return set;
}

Result<ClipSet> load_bvh(const std::string& path, const LoadOptions& options) {
  Result<std::string> text = read_file_bytes(path, kMaxFileBytes, "BVH file");
  if (!text.ok()) return text.status();
  return parse_bvh(*text, path, options);
}

}  // namespace gk
