#include "app/crowd_session.h"

#include <algorithm>

#include "animation/procedural.h"

namespace gk::app {
namespace {

// A replayed file carries no bounds: replay a private copy for up to a minute of its time and take
// the box of every position seen (cheap: spline evaluation only).
void replay_bounds(const CrowdOptions& o, glm::vec2* lo, glm::vec2* hi) {
  CrowdOptions quiet = o;
  quiet.agents.clear();  // its notice was printed for the real crowd already
  CrowdSetup probe = make_crowd(quiet, /*threads=*/1, /*seed=*/1);
  glm::vec2 a(1e30f), b(-1e30f);
  for (int f = 0; f < 3600; ++f) {
    if (!probe.crowd->step(static_cast<float>(kFrameTime_s)).ok()) break;
    for (const glm::vec2& p : probe.crowd->frame().positions)
      a = glm::min(a, p), b = glm::max(b, p);
  }
  if (a.x <= b.x) *lo = a, *hi = b;
}

}  // namespace

glm::vec3 agent_tint(uint32_t id) {
  // Golden-ratio hue walk; saturation kept low so the shading still reads.
  const float hue = std::fmod(static_cast<float>(id) * 0.618034f, 1.0f);
  const glm::vec3 k = glm::clamp(
      glm::abs(glm::mod(hue * 6.0f + glm::vec3(0.0f, 4.0f, 2.0f), 6.0f) - 3.0f) - 1.0f, 0.0f, 1.0f);
  return glm::mix(glm::vec3(1.0f), k, 0.45f) * 0.95f;
}

std::unique_ptr<CrowdSession> CrowdSession::create(const CrowdOptions& o, bool record_metrics) {
  const int threads = parse_number<int>(o.command, o.threads, "--threads", 0, 256);
  const auto seed =
      parse_number<uint64_t>(o.command, o.seed, "--seed", 0, std::numeric_limits<uint64_t>::max());
  std::unique_ptr<CrowdSession> s(new CrowdSession());
  // The library first: its skeleton gives the simulator the radius of the body that is drawn.
  s->library_ = std::make_unique<LocomotionLibrary>(load_library(o));
  s->body_radius_m_ = body_radius(*s->library_->skeleton);
  s->setup_ = make_crowd(o, threads, seed, s->body_radius_m_);
  s->options_ = o;
  s->threads_ = threads;
  s->seed_ = seed;
  s->params_ = make_params(o, seed);
  // The mediator and pose passes run on TBB: cap its workers at --threads (0 = all cores).
  if (threads > 0) s->thread_cap_.emplace(tbb::global_control::max_allowed_parallelism, threads);
  s->capacity_ = std::max<size_t>(s->setup_.crowd->capacity(), 1);
  const Skeleton& skeleton = *s->library_->skeleton;
  s->num_joints_ = skeleton.num_joints();
  const auto& lib_mesh = s->library_->mesh;
  s->mesh_ = lib_mesh && lib_mesh->inverse_bind.size() == static_cast<size_t>(s->num_joints_)
                 ? lib_mesh
                 : make_mannequin_mesh(skeleton);
  s->primary_ = s->make_lane(s->params_, record_metrics);
  for (const WallSegment& w : s->setup_.walls) s->walls_.emplace_back(w.a.x, w.a.y, w.b.x, w.b.y);
  if (!s->setup_.walls.empty()) {
    // The walls show where the action is; a scenario's bounds often include empty margins.
    glm::vec2 lo(1e30f), hi(-1e30f);
    for (const WallSegment& w : s->setup_.walls) {
      lo = glm::min(lo, glm::min(w.a, w.b));
      hi = glm::max(hi, glm::max(w.a, w.b));
    }
    s->bounds_min_ = glm::max(lo, s->setup_.bounds_min);
    s->bounds_max_ = glm::min(hi, s->setup_.bounds_max);
  } else if (s->setup_.has_bounds) {
    s->bounds_min_ = s->setup_.bounds_min;
    s->bounds_max_ = s->setup_.bounds_max;
  } else {
    replay_bounds(o, &s->bounds_min_, &s->bounds_max_);
  }
  return s;
}

CrowdSession::~CrowdSession() = default;

AnimationLane CrowdSession::make_lane(const MediatorParams& params, bool record_metrics) const {
  AnimationLane lane;
  PipelineOptions options;
  options.capacity = capacity_;
  options.make_palettes = true;
  options.record_metrics = record_metrics;
  options.frame_time_s = static_cast<float>(kFrameTime_s);
  lane.pipeline = std::make_unique<CrowdPipeline>(*library_, params, options);
  lane.draws.assign(capacity_, AgentDraw{});
  return lane;
}

void CrowdSession::enable_compare(MediatorMode mode) {
  enable_compare([mode](MediatorParams* p) { p->mode = mode; });
}

void CrowdSession::enable_compare(std::function<void(MediatorParams*)> adjust, bool own_crowd) {
  compare_adjust_ = std::move(adjust);
  MediatorParams p = params_;
  if (compare_adjust_) compare_adjust_(&p);
  compare_ = make_lane(p, /*record_metrics=*/false);
  compare_crowd_.reset();
  if (own_crowd) {
    compare_crowd_.emplace(make_crowd(options_, threads_, seed_, body_radius_m_));
  }
}

void CrowdSession::set_params(const MediatorParams& params) {
  params_ = params;
  primary_.pipeline->set_params(params);
  if (compare_) {
    MediatorParams p = params;
    if (compare_adjust_) compare_adjust_(&p);
    compare_->pipeline->set_params(p);
  }
}

Status CrowdSession::step(double dt_s) {
  const float dt = static_cast<float>(dt_s);
  CrowdPipeline& primary = *primary_.pipeline;
  GK_RETURN_IF_ERROR(primary.step(*setup_.crowd, dt));
  times_ = {primary.times().sim_ms, primary.times().mediator_ms, primary.times().pose_ms};
  if (compare_) {
    CrowdPipeline& other = *compare_->pipeline;
    // Its own crowd gets its own feedback; otherwise it animates the primary's frame as planned.
    GK_RETURN_IF_ERROR(compare_crowd_
                           ? other.step(*compare_crowd_->crowd, dt)
                           : other.follow(primary.frame(), setup_.crowd->feedback_policy(), dt));
    times_.sim_ms += other.times().sim_ms;
    times_.mediator_ms += other.times().mediator_ms;
    times_.pose_ms += other.times().pose_ms;
  }
  ++frames_run_;
  return Status::Ok();
}

void CrowdSession::collect_lane(AnimationLane* lane) const {
  const CrowdPipeline& pipeline = *lane->pipeline;
  const AnimationPlans& plans = pipeline.plans();
  const AgentFrame frame = pipeline.frame();
  const size_t n = std::min(frame.size(), capacity_);
  for (size_t i = 0; i < n; ++i) {
    const int slot = plans.slot_of_agent[i];
    const glm::vec2 root = plans.root_xz[slot];
    // A held pose (level of detail) is drawn where its root is now, not where it was posed.
    const glm::vec2 offset = pipeline.poses().root_offset(slot);
    lane->draws[i] = AgentDraw{glm::vec3(root.x, 0.0f, root.y), agent_tint(frame.ids[i]), 0, slot,
                               glm::vec3(offset.x, 0.0f, offset.y)};
  }
  lane->num_collected = n;
  lane->num_palettes = pipeline.num_slots();
}

void CrowdSession::collect() {
  collect_lane(&primary_);
  if (compare_) collect_lane(&compare_.value());
}

}  // namespace gk::app
