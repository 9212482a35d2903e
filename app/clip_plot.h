#pragma once
// `analyze-clip --plot FILE.png`: each foot's toe height and speed over the take, with the
// contacts clip analysis found shaded under the curves and the take's segments (idle, start,
// steady, turn, stop) as a coloured band with the cut-out loops marked (white; yellow: the step
// whose mirror image completes a take's loop), so a user sees at a glance whether the analysis is
// right.

#include <string>
#include <vector>

#include "animation/analysis.h"
#include "animation/clip.h"
#include "animation/segmentation.h"
#include "animation/skeleton.h"
#include "common/status.h"

namespace gk::app {

struct ClipPlotInput {
  const Clip* clip = nullptr;
  const Skeleton* skeleton = nullptr;
  const ClipAnalysis* analysis = nullptr;
  const TakeSegmentation* segmentation = nullptr;
};

// Layout, for readers of the image (tests): each clip takes kClipPlotHeight rows; within it the
// four panels (left toe height, left toe speed, right toe height, right toe speed) start at
// kClipPlotPanelTop + i * kClipPlotPanelStride and span x from kClipPlotLeft to kClipPlotRight
// over the clip's duration.
inline constexpr int kClipPlotWidth = 1200, kClipPlotLeft = 90, kClipPlotRight = 1180;
inline constexpr int kClipPlotPanelTop = 26 + 22 + 8, kClipPlotPanelStride = 110 + 8;
inline constexpr int kClipPlotPanelHeight = 110;
inline constexpr int kClipPlotHeight = 26 + 22 + 4 * (110 + 8) + 26;

// One row of panels per clip, stacked; written as PNG. Errors name the path.
Status write_clip_plot(const std::string& path, const std::vector<ClipPlotInput>& clips);

}  // namespace gk::app
