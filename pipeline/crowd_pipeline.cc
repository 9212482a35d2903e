#include "pipeline/crowd_pipeline.h"

#include <algorithm>
#include <cassert>
#include <chrono>
#include <ctime>

namespace gk {
namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// CPU time of the calling thread [ms]: what the measurement costs, whatever else the machine runs.
double thread_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

}  // namespace

FrameSnapshot::FrameSnapshot(size_t capacity)
    : ids(capacity), positions(capacity), velocities(capacity), thetas(capacity) {}

void FrameSnapshot::assign(const AgentFrame& frame) {
  const size_t n = frame.size();
  assert(n <= ids.size() && frame.positions.size() == n && frame.velocities.size() == n &&
         frame.thetas.size() == n);
  std::copy_n(frame.ids.begin(), n, ids.begin());
  std::copy_n(frame.positions.begin(), n, positions.begin());
  std::copy_n(frame.velocities.begin(), n, velocities.begin());
  std::copy_n(frame.thetas.begin(), n, thetas.begin());
  size = n;
}

CrowdPipeline::CrowdPipeline(const LocomotionLibrary& library, const MediatorParams& params,
                             const PipelineOptions& options)
    : capacity_(std::max<size_t>(options.capacity, 1)),
      mediator_(std::make_unique<Mediator>(library, params, capacity_)),
      poses_(std::make_unique<PoseSynthesizer>(library, capacity_, options.make_palettes)),
      metrics_(options.record_metrics
                   ? std::make_unique<MetricsRecorder>(library, options.frame_time_s, capacity_)
                   : nullptr),
      snapshot_(capacity_),
      lod_(capacity_) {}

Status CrowdPipeline::set_lod(const LodParams& params) {
  GK_RETURN_IF_ERROR(validate(params));
  lod_params_ = params;
  return Status::Ok();
}

CrowdPipeline::~CrowdPipeline() = default;

std::span<const glm::mat4> CrowdPipeline::palettes() const {
  const std::span<const glm::mat4> all = poses_->palettes();
  return all.first(std::min(all.size(), num_slots_ * static_cast<size_t>(num_joints())));
}

Status CrowdPipeline::step(CrowdSource& source, float dt_s) {
  const auto t = Clock::now();
  const Status stepped = source.step(dt_s);
  times_.sim_ms = ms_since(t);
  GK_RETURN_IF_ERROR(stepped);
  return animate(source.frame(), source.feedback_policy(), &source, dt_s);
}

Status CrowdPipeline::follow(const AgentFrame& frame, FeedbackPolicy policy, float dt_s) {
  times_.sim_ms = 0.0;
  return animate(frame, policy, nullptr, dt_s);
}

Status CrowdPipeline::animate(const AgentFrame& frame, FeedbackPolicy policy, CrowdSource* source,
                              float dt_s) {
  auto t = Clock::now();
  // Level of detail: which slots are planned and posed this frame (from the last frame's roots).
  const bool lod = lod_params_.enabled;
  if (lod) lod_.assign(mediator_->plans(), lod_params_, frames_run_);
  mediator_->set_lod_due(lod ? lod_.due() : std::span<const uint8_t>());
  // The support's reach quickens the steps in every lane; the support hold moves the root only
  // where the held position is fed back: not in a lane that follows another pipeline's frame (no
  // source takes its feedback).
  mediator_->set_support_reach(poses_->support_reach(), source != nullptr);
  // plan() validates the frame before it writes anything: on failure the previous frame's plans,
  // snapshot and poses are untouched and still drawable.
  GK_RETURN_IF_ERROR(mediator_->plan(frame, dt_s, policy));
  // The snapshot before feedback: a source applies it in place, into the arrays `frame` views.
  snapshot_.assign(frame);
  const AnimationPlans& plans = mediator_->plans();
  int32_t top = -1;
  for (size_t i = 0; i < snapshot_.size; ++i) top = std::max(top, plans.slot_of_agent[i]);
  num_slots_ = static_cast<size_t>(top + 1);
  const Status fed =
      source ? source->apply_feedback(mediator_->feedback().view(snapshot_.size)) : Status::Ok();
  times_.mediator_ms = ms_since(t);

  // Posed even when the source refused the feedback, so that plans and poses stay one frame.
  t = Clock::now();
  if (lod) {
    poses_->run(plans, snapshot_.size, mediator_->params(), dt_s, lod_.pose_detail());
  } else {
    poses_->run(plans, snapshot_.size, mediator_->params(), dt_s);
  }
  times_.pose_ms = ms_since(t);
  GK_RETURN_IF_ERROR(fed);

  t = Clock::now();
  const double cpu_start_ms = thread_cpu_ms();
  const AgentFrame planned = snapshot_.view();
  if (metrics_) {
    metrics_->record(planned, *mediator_, *poses_,
                     lod ? lod_.full_detail() : std::span<const uint8_t>());
  }
  ++frames_run_;
  for (const FrameHook& hook : hooks_) {
    if (Status s = hook(*this); !s.ok()) {
      times_.measure_ms = ms_since(t);
      times_.measure_cpu_ms = thread_cpu_ms() - cpu_start_ms;
      return s;
    }
  }
  times_.measure_ms = ms_since(t);
  times_.measure_cpu_ms = thread_cpu_ms() - cpu_start_ms;
  return Status::Ok();
}

}  // namespace gk
