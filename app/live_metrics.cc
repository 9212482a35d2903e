#include "app/live_metrics.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

namespace gk::app {
namespace {

// Copies a ring into plot order (oldest first) so PlotLines can take a plain array.
void unroll(const std::array<float, LiveMetrics::kWindow>& ring, int count,
            std::array<float, LiveMetrics::kWindow>* out) {
  const int n = count < LiveMetrics::kWindow ? count : LiveMetrics::kWindow;
  const int first = count - n;
  for (int k = 0; k < n; ++k) (*out)[k] = ring[(first + k) % LiveMetrics::kWindow];
}

}  // namespace

void LiveMetrics::record(const CrowdSession& session, const AnimationLane& lane,
                         const OverlayHistory& history) {
  const AgentFrame& frame = session.frame_of(lane);
  const AnimationPlans& plans = lane.plans();
  double torsion = 0.0, rate = 0.0, root_error = 0.0;
  // METRICS.md v2 on this frame: walking agents with neither toe within 5 cm of its floor, and
  // the deepest foot (toe or ankle) below its floor.
  const LocomotionLibrary& lib = session.library();
  const Skeleton& sk = *lib.skeleton;
  int walking = 0, floating = 0;
  float deepest = 0.0f;
  for (size_t i = 0; i < frame.size(); ++i) {
    const int slot = plans.slot_of_agent[i];
    const auto w = lane.poses().world(slot);
    bool near = false;
    for (int s = 0; s < 2; ++s) {
      const float toe = w[sk.toe(static_cast<Side>(s))][3].y - lib.planted_toe_m[s];
      const float ankle = w[sk.ankle(static_cast<Side>(s))][3].y - lib.planted_ankle_m[s];
      near = near || toe <= 0.05f;
      deepest = std::max({deepest, -toe, -ankle});
    }
    const float speed = plans.speed_m_s[slot];
    if (speed >= 0.1f && speed <= 2.2f) {
      ++walking;
      if (!near) ++floating;
    }
    torsion += std::abs(lane.poses().torsion(slot));
    rate += plans.playback_rate[slot];
    // The rendered root is the skeleton's root joint (the pelvis) projected on the ground.
    const glm::vec3 pelvis = lane.poses().joint_position(slot, 0);
    root_error += glm::length(glm::vec2(pelvis.x, pelvis.z) - frame.positions[i]);
  }
  const double n = frame.size() ? static_cast<double>(frame.size()) : 1.0;
  std::array<float, kNumLiveSeries> v{};
  v[static_cast<int>(LiveSeries::kSlide)] = history.last_slide_m_s() * 100.0f;
  v[static_cast<int>(LiveSeries::kSkate)] = history.last_skate_ratio() * 100.0f;
  v[static_cast<int>(LiveSeries::kFloat)] = walking ? 100.0f * floating / walking : 0.0f;
  v[static_cast<int>(LiveSeries::kPenetration)] = 100.0f * deepest;
  v[static_cast<int>(LiveSeries::kTorsion)] = static_cast<float>(torsion / n * 57.29578);
  v[static_cast<int>(LiveSeries::kRate)] = static_cast<float>(rate / n);
  v[static_cast<int>(LiveSeries::kRootError)] = static_cast<float>(root_error / n * 100.0);
  for (int s = 0; s < kNumLiveSeries; ++s) ring_[s][count_ % kWindow] = v[s];
  ++count_;
  for (int s = 0; s < kNumLiveSeries; ++s) unroll(ring_[s], count_, &ordered_[s]);
}

void LiveMetrics::record_stage(LiveStage stage, float ms) {
  stage_ms_[static_cast<int>(stage)] = ms;
  if (stage == LiveStage::kFrame) {
    frame_ring_[stage_count_ % kWindow] = ms;
    ++stage_count_;
    unroll(frame_ring_, stage_count_, &frame_ordered_);
  }
}

float LiveMetrics::mean(LiveSeries s) const {
  const int n = count();
  if (n == 0) return 0.0f;
  double sum = 0.0;
  for (int k = 0; k < n; ++k) sum += ordered_[static_cast<int>(s)][k];
  return static_cast<float>(sum / n);
}

const char* LiveMetrics::label(LiveSeries s) {
  switch (s) {
    case LiveSeries::kSlide:
      return "support-foot slide";
    case LiveSeries::kSkate:
      return "skating feet";
    case LiveSeries::kFloat:
      return "floating walkers";
    case LiveSeries::kPenetration:
      return "deepest foot below floor";
    case LiveSeries::kTorsion:
      return "torsion";
    case LiveSeries::kRate:
      return "playback rate";
    case LiveSeries::kRootError:
      return "root error";
    default:
      return "?";
  }
}

const char* LiveMetrics::unit(LiveSeries s) {
  switch (s) {
    case LiveSeries::kSlide:
      return "cm/s";
    case LiveSeries::kSkate:
      return "%";
    case LiveSeries::kFloat:
      return "%";
    case LiveSeries::kPenetration:
      return "cm";
    case LiveSeries::kTorsion:
      return "deg";
    case LiveSeries::kRate:
      return "x";
    case LiveSeries::kRootError:
      return "cm";
    default:
      return "";
  }
}

const char* LiveMetrics::stage_name(LiveStage s) {
  switch (s) {
    case LiveStage::kSim:
      return "sim";
    case LiveStage::kMediator:
      return "mediator";
    case LiveStage::kPose:
      return "pose";
    case LiveStage::kUpload:
      return "upload";
    case LiveStage::kRender:
      return "render";
    case LiveStage::kFrame:
      return "frame";
    default:
      return "?";
  }
}

}  // namespace gk::app
