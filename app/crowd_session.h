#pragma once
// One running crowd with its animation, for `bench`, `render` and the demo: the crowd source and
// clip library built from the command line, and a CrowdPipeline (pipeline/crowd_pipeline.h, the
// frame loop itself) per lane. collect() then lays out what the renderer needs: an AgentDraw per
// live agent, in frame order, pointing at its palette in the pipeline's slot order (no copy).
//
// A second "compare" lane (another pipeline, e.g. naive) can animate the very same crowd frames
// (CrowdPipeline::follow: the primary's frame as it was planned, before feedback); only the
// primary lane's feedback reaches the simulator, so both lanes show one crowd. Everything per
// frame is sized at creation: step() and collect() allocate nothing.

#include <array>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <tbb/global_control.h>
#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>

#include "animation/mesh.h"
#include "app/crowd_setup.h"
#include "mediator/mediator.h"
#include "mediator/pose_synthesis.h"
#include "pipeline/crowd_pipeline.h"
#include "render/crowd_renderer.h"

namespace gk::app {

// Milliseconds of the last step's stages.
struct SessionTimes {
  double sim_ms = 0.0;
  double mediator_ms = 0.0;  // plan + apply_feedback (+ the compare lane's)
  double pose_ms = 0.0;
};

// One animation of the crowd and its draw data. A live lane runs a pipeline and draws its
// palettes in slot order; a recorded lane (the demo's timeline) has no pipeline and holds the
// palettes it restored, in draw order.
struct AnimationLane {
  std::unique_ptr<CrowdPipeline> pipeline;   // null in a recorded lane
  std::vector<glm::mat4> recorded_palettes;  // a recorded lane's: capacity * joints
  std::vector<AgentDraw> draws;              // capacity; collect() fills the live agents'
  size_t num_collected = 0;
  size_t num_palettes = 0;  // palette blocks the draws refer to (slots, or recorded agents)
  std::span<const glm::mat4> palette_span(int joints) const {
    const size_t n = num_palettes * static_cast<size_t>(joints);
    return pipeline ? pipeline->poses().palettes().first(n)
                    : std::span<const glm::mat4>(recorded_palettes).first(n);
  }
  std::span<const AgentDraw> draw_span() const { return {draws.data(), num_collected}; }
  // A live lane's plans, poses and parameters.
  const AnimationPlans& plans() const { return pipeline->plans(); }
  const PoseSynthesizer& poses() const { return pipeline->poses(); }
  const MediatorParams& params() const { return pipeline->params(); }
};

class CrowdSession {
 public:
  // Builds the crowd source, the clip library and the primary lane's pipeline (palettes on;
  // METRICS.md recorded with `record_metrics`) from the options. Bad options end the command
  // through fail() (ExitRequest).
  static std::unique_ptr<CrowdSession> create(const CrowdOptions& options,
                                              bool record_metrics = false);
  ~CrowdSession();

  // Adds (or replaces) the compare lane with its own mode; the other parameters are the primary's.
  void enable_compare(MediatorMode mode);
  // The compare lane with the primary's parameters changed by `adjust` (the mode, or one idea
  // switched off: `foot_locking`, `feedback`, ...), also after every set_params. With `own_crowd`
  // the lane drives its own copy of the crowd (same options and seed, from the start: call it
  // before the first step) and feeds back to it: for ideas that change the simulation itself
  // (feedback), which the primary's crowd cannot show.
  void enable_compare(std::function<void(MediatorParams*)> adjust, bool own_crowd = false);
  void disable_compare() { compare_.reset(), compare_crowd_.reset(), compare_adjust_ = nullptr; }
  bool has_compare() const { return compare_.has_value(); }

  Status step(double dt_s);
  // Fills the draws of the primary lane (and the compare lane, when present).
  void collect();

  // The crowd frame of the last step as the primary lane planned it (before feedback).
  AgentFrame frame() const { return primary_.pipeline->frame(); }
  // The crowd frame a live lane animates: the primary's, or the compare lane's own crowd's.
  AgentFrame frame_of(const AnimationLane& lane) const { return lane.pipeline->frame(); }
  bool compare_has_own_crowd() const { return compare_crowd_.has_value(); }
  const AnimationLane& lane() const { return primary_; }
  const AnimationLane& compare_lane() const { return *compare_; }
  const Mediator& mediator() const { return primary_.pipeline->mediator(); }
  const PoseSynthesizer& poses() const { return primary_.pipeline->poses(); }
  // The primary lane's pipeline (its metrics, frame hooks).
  CrowdPipeline& pipeline() { return *primary_.pipeline; }
  const CrowdPipeline& pipeline() const { return *primary_.pipeline; }
  CrowdSource& crowd() { return *setup_.crowd; }
  double crowd_time_s() const { return setup_.crowd->time_s(); }
  const CrowdSetup& setup() const { return setup_; }
  const CrowdOptions& options() const { return options_; }  // what the session was built from
  const LocomotionLibrary& library() const { return *library_; }
  // Radius [m] of the drawn body that the simulator keeps between agents (body_radius).
  float body_radius_m() const { return body_radius_m_; }
  const SkinnedMesh& mesh() const { return *mesh_; }
  int joints() const { return num_joints_; }
  const MediatorParams& params() const { return params_; }
  // New parameters for both lanes (the compare lane keeps its mode).
  void set_params(const MediatorParams& params);
  const SessionTimes& times() const { return times_; }
  int64_t frames_run() const { return frames_run_; }
  // Walls as (x0, z0, x1, z1) [m] for CrowdRenderer::set_walls.
  const std::vector<glm::vec4>& wall_segments() const { return walls_; }
  // Region worth looking at [m]: the walls' box, else the scenario's bounds, else (replay) the box
  // of the tracks' first minute.
  glm::vec2 bounds_min() const { return bounds_min_; }
  glm::vec2 bounds_max() const { return bounds_max_; }

 private:
  CrowdSession() = default;
  AnimationLane make_lane(const MediatorParams& params, bool record_metrics) const;
  void collect_lane(AnimationLane* lane) const;

  CrowdSetup setup_;
  CrowdOptions options_;  // to build the compare lane's own crowd
  int threads_ = 1;
  uint64_t seed_ = 1;
  float body_radius_m_ = 0.0f;  // the simulator's agent radius, from the library's skeleton [m]
  std::optional<CrowdSetup> compare_crowd_;
  std::function<void(MediatorParams*)> compare_adjust_;
  std::unique_ptr<LocomotionLibrary> library_;  // stable address: the mediators refer to it
  std::shared_ptr<const SkinnedMesh> mesh_;
  std::optional<tbb::global_control> thread_cap_;
  MediatorParams params_;
  size_t capacity_ = 1;
  int num_joints_ = 0;
  AnimationLane primary_;
  std::optional<AnimationLane> compare_;
  SessionTimes times_;
  int64_t frames_run_ = 0;
  std::vector<glm::vec4> walls_;
  glm::vec2 bounds_min_{-10.0f}, bounds_max_{10.0f};
};

// A distinct, muted colour per agent id (linear RGB), so agents can be told apart and followed.
glm::vec3 agent_tint(uint32_t id);

}  // namespace gk::app
