#pragma once
// CrowdPipeline: the frame of ARCHITECTURE.md, written once for every caller (the app's session,
// `gaitkeeper bench`, the tests and the benchmarks). One step():
//
//   1. sim       CrowdSource::step(dt)
//   2. plan      Mediator::plan(source.frame())   validates first: a failed plan writes nothing
//   3. snapshot  copy the frame as planned        (before feedback: a source may apply feedback in
//                                                  place, and AgentFrame is a view into its arrays)
//   4. feedback  CrowdSource::apply_feedback
//   5. pose      PoseSynthesizer::run(plans, params)
//   6. measure   MetricsRecorder::record(snapshot) and the frame hooks (joint dump, ...)
//
// follow() runs 2, 3, 5 and 6 on a frame someone else stepped (a second animation of the same
// crowd: the split screen's compare lane), without feedback. When a step fails, the snapshot,
// plans, poses and palettes are still those of the last good frame, so a caller can keep drawing.
//
// Plans, poses and palettes stay in the mediator's slot order; plans().slot_of_agent maps the
// frame's agent i to its slot, and a renderer draws agent i with palette block slot (no copy into
// agent order). Everything is sized for the capacity at construction: step() allocates nothing.
// Headless: no GL (docs/pipeline.md).

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>

#include "common/status.h"
#include "crowd/crowd_source.h"
#include "mediator/locomotion_library.h"
#include "mediator/mediator.h"
#include "mediator/metrics.h"
#include "mediator/params.h"
#include "mediator/pose_synthesis.h"
#include "pipeline/lod.h"

namespace gk {

// The crowd frame as planned, copied out of the source (structure of arrays, sized at
// construction).
struct FrameSnapshot {
  std::vector<uint32_t> ids;
  std::vector<glm::vec2> positions;   // (x, z) [m]
  std::vector<glm::vec2> velocities;  // (vx, vz) [m/s]
  std::vector<float> thetas;          // [rad]
  size_t size = 0;

  explicit FrameSnapshot(size_t capacity = 0);
  // Copies `frame` (its arrays index-aligned, at most the capacity: the mediator checked both).
  void assign(const AgentFrame& frame);
  AgentFrame view() const {
    return {{ids.data(), size},
            {positions.data(), size},
            {velocities.data(), size},
            {thetas.data(), size}};
  }
};

// Milliseconds of the last frame's stages.
struct PipelineTimes {
  double sim_ms = 0.0;       // CrowdSource::step (0 in follow())
  double mediator_ms = 0.0;  // plan, snapshot and apply_feedback
  double pose_ms = 0.0;      // pose synthesis (not the palettes: update_palettes)
  double measure_ms = 0.0;   // metrics and frame hooks: measurement, not the animation's cost
  double measure_cpu_ms = 0.0;  // their CPU time (they run on the calling thread alone)
};

struct PipelineOptions {
  size_t capacity = 1;                // most agents live at once [Limit: >= 1]
  bool make_palettes = true;          // skinning palettes for a renderer (model * inverse bind)
  bool record_metrics = false;        // METRICS.md, streamed in bounded memory (MetricsRecorder)
  float frame_time_s = 1.0f / 60.0f;  // the metrics' frame time [s] [Limit: > 0]
};

class CrowdPipeline;
// Called at the end of every successful frame (after the metrics); an error ends the step with it.
using FrameHook = std::function<Status(const CrowdPipeline&)>;

class CrowdPipeline {
 public:
  CrowdPipeline(const LocomotionLibrary& library, const MediatorParams& params,
                const PipelineOptions& options);
  ~CrowdPipeline();
  CrowdPipeline(const CrowdPipeline&) = delete;
  CrowdPipeline& operator=(const CrowdPipeline&) = delete;

  // One whole frame of `source` for dt_s [s]: sim, plan, snapshot, feedback, pose, measure.
  Status step(CrowdSource& source, float dt_s);
  // The same frame on a crowd stepped elsewhere: `frame` (e.g. another pipeline's frame()) is
  // planned with `policy` and animated; no feedback goes anywhere.
  Status follow(const AgentFrame& frame, FeedbackPolicy policy, float dt_s);

  // The crowd frame of the last good step as planned (before feedback).
  AgentFrame frame() const { return snapshot_.view(); }
  const Mediator& mediator() const { return *mediator_; }
  const AnimationPlans& plans() const { return mediator_->plans(); }
  const PoseSynthesizer& poses() const { return *poses_; }
  const MediatorParams& params() const { return mediator_->params(); }
  void set_params(const MediatorParams& params) { mediator_->set_params(params); }
  // Makes the skinning palettes of the agents posed since the last call (the renderer's work,
  // timed as its upload: a step does not make them); call it before reading palettes().
  void update_palettes() { poses_->update_palettes(); }
  // Skinning palettes in slot order, num_joints() matrices per slot: slots [0, num_slots()),
  // empty without make_palettes, as of the last update_palettes(). Slots no live agent holds keep
  // stale matrices (never drawn).
  std::span<const glm::mat4> palettes() const;
  // One past the highest slot a live agent of frame() holds.
  size_t num_slots() const { return num_slots_; }
  int num_joints() const { return poses_->num_joints(); }
  size_t capacity() const { return capacity_; }
  // The streamed METRICS.md figures (null without record_metrics).
  const MetricsRecorder* metrics() const { return metrics_.get(); }
  void add_frame_hook(FrameHook hook) { hooks_.push_back(std::move(hook)); }
  // Level of detail (pipeline/lod.h) from the next frame on; an error (and no change) when the
  // parameters are out of their limits. Off by default: every agent at full detail.
  Status set_lod(const LodParams& params);
  const LodParams& lod_params() const { return lod_params_; }
  // Levels, due flags and agents per level of the last frame (all level 0 with LOD off).
  const LodPolicy& lod() const { return lod_; }
  const PipelineTimes& times() const { return times_; }
  int64_t frames_run() const { return frames_run_; }

 private:
  // Steps 2-6 on `frame`; feedback goes to `source` when it is not null.
  Status animate(const AgentFrame& frame, FeedbackPolicy policy, CrowdSource* source, float dt_s);

  size_t capacity_;
  std::unique_ptr<Mediator> mediator_;
  std::unique_ptr<PoseSynthesizer> poses_;
  std::unique_ptr<MetricsRecorder> metrics_;
  std::vector<FrameHook> hooks_;
  FrameSnapshot snapshot_;
  size_t num_slots_ = 0;
  PipelineTimes times_;
  int64_t frames_run_ = 0;
  LodParams lod_params_;
  LodPolicy lod_;
};

}  // namespace gk
