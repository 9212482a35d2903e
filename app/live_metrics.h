#pragma once
// Per-frame animation metrics for the demo panel, over a sliding window: foot slide (from the
// overlay history's contact test), torsion, playback rate and root error, each as a ring of the
// last kWindow frames for ImGui::PlotLines, plus per-stage milliseconds. Approximations of the
// METRICS.md definitions computed live (the exact ones come from `gaitkeeper bench`).

#include <array>
#include <cstddef>

#include "app/crowd_session.h"
#include "app/overlays.h"

namespace gk::app {

enum class LiveSeries : int {
  kSlide,
  kSkate,
  kFloat,
  kPenetration,
  kTorsion,
  kRate,
  kRootError,
  kCount
};
inline constexpr int kNumLiveSeries = static_cast<int>(LiveSeries::kCount);

enum class LiveStage : int { kSim, kMediator, kPose, kUpload, kRender, kFrame, kCount };
inline constexpr int kNumLiveStages = static_cast<int>(LiveStage::kCount);

class LiveMetrics {
 public:
  static constexpr int kWindow = 300;  // frames (5 s at 60 Hz)

  void reset() { *this = LiveMetrics(); }
  // One simulated frame of the lane; `history` has recorded it already.
  void record(const CrowdSession& session, const AnimationLane& lane,
              const OverlayHistory& history);
  void record_stage(LiveStage stage, float ms);

  // Samples in plot order (oldest first) and the window mean.
  const float* series(LiveSeries s) const { return &ordered_[static_cast<int>(s)][0]; }
  int count() const { return count_ < kWindow ? count_ : kWindow; }
  float mean(LiveSeries s) const;
  float stage_ms(LiveStage s) const { return stage_ms_[static_cast<int>(s)]; }
  const float* stage_series() const { return &frame_ordered_[0]; }
  int stage_count() const { return stage_count_ < kWindow ? stage_count_ : kWindow; }
  static const char* label(LiveSeries s);
  static const char* unit(LiveSeries s);
  static const char* stage_name(LiveStage s);

 private:
  std::array<std::array<float, kWindow>, kNumLiveSeries> ring_{};
  std::array<std::array<float, kWindow>, kNumLiveSeries> ordered_{};
  int count_ = 0;
  std::array<float, kNumLiveStages> stage_ms_{};
  std::array<float, kWindow> frame_ring_{};
  std::array<float, kWindow> frame_ordered_{};
  int stage_count_ = 0;
};

}  // namespace gk::app
