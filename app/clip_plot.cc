#include "app/clip_plot.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>

#include <glm/vec3.hpp>

#include "animation/pose_jobs.h"
#include "render/frame_capture.h"
#include "render/label_font.h"

namespace gk::app {
namespace {

constexpr int kWidth = kClipPlotWidth;
constexpr int kPanelH = kClipPlotPanelHeight;  // one curve panel
constexpr int kBandH = 22;                      // the segment band
constexpr int kTitleH = 26;
constexpr int kMarginL = kClipPlotLeft, kMarginR = kClipPlotWidth - kClipPlotRight, kGap = 8;
constexpr int kClipH = kClipPlotHeight;
static_assert(kTitleH + kBandH + kGap == kClipPlotPanelTop && kPanelH + kGap == kClipPlotPanelStride &&
              kTitleH + kBandH + 4 * (kPanelH + kGap) + 26 == kClipPlotHeight);

struct Canvas {
  int w, h;
  std::vector<uint8_t> px;
  void put(int x, int y, glm::u8vec3 c, float a = 1.0f) {
    if (x < 0 || y < 0 || x >= w || y >= h) return;
    uint8_t* p = px.data() + (static_cast<size_t>(y) * w + x) * 4;
    for (int k = 0; k < 3; ++k) p[k] = static_cast<uint8_t>(p[k] + a * (c[k] - p[k]));
  }
  void rect(int x0, int y0, int x1, int y1, glm::u8vec3 c, float a = 1.0f) {
    for (int y = std::max(0, y0); y < std::min(h, y1); ++y) {
      for (int x = std::max(0, x0); x < std::min(w, x1); ++x) put(x, y, c, a);
    }
  }
  void line(float x0, float y0, float x1, float y1, glm::u8vec3 c) {
    const int steps = static_cast<int>(std::max(std::abs(x1 - x0), std::abs(y1 - y0))) + 1;
    for (int i = 0; i <= steps; ++i) {
      const float u = static_cast<float>(i) / steps;
      const int x = static_cast<int>(std::lround(x0 + u * (x1 - x0)));
      const int y = static_cast<int>(std::lround(y0 + u * (y1 - y0)));
      put(x, y, c);
      put(x, y + 1, c);
    }
  }
  void text(int x, int y, const std::string& s, glm::u8vec3 c = {255, 255, 255}) {
    std::string up = s;
    for (char& ch : up) ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
    stamp_label(px, {w, h}, {x, y}, up, 2, c);
  }
};

glm::u8vec3 segment_colour(SegmentKind k) {
  switch (k) {
    case SegmentKind::kIdle: return {150, 150, 150};
    case SegmentKind::kStart: return {90, 200, 90};
    case SegmentKind::kSteady: return {80, 140, 230};
    case SegmentKind::kTurn: return {230, 170, 60};
    case SegmentKind::kStop: return {220, 80, 80};
    case SegmentKind::kTransition: return {170, 110, 200};
  }
  return {255, 255, 255};
}

void draw_clip(Canvas& cv, int top, const ClipPlotInput& in) {
  const Clip& c = *in.clip;
  const Skeleton& sk = *in.skeleton;
  const ClipAnalysis& a = *in.analysis;
  const int n = c.num_frames;
  const float dur = std::max(a.duration_s, 1e-3f);
  const int x0 = kMarginL, x1 = kWidth - kMarginR;
  auto xt = [&](float t) { return x0 + (x1 - x0) * std::clamp(t / dur, 0.0f, 1.0f); };

  // Toe tracks over the fitted ground, and horizontal speeds over +-1/60 s.
  std::vector<glm::vec3> toe[2];
  std::vector<glm::mat4> model(sk.num_joints());
  for (int f = 0; f < n; ++f) {
    clip_frame_model(c, sk, f, model);
    for (int s = 0; s < 2; ++s) {
      glm::vec3 p = translation_of(model[sk.toe(static_cast<Side>(s))]);
      p.y -= a.ground_y0_m + a.ground_slope_m_s * (f / c.fps);
      toe[s].push_back(p);
    }
  }
  const int k = std::max(1, static_cast<int>(std::lround(c.fps / 60.0f)));
  std::vector<float> height[2], speed[2];
  float hmax = 0.05f, vmax = 1.0f;
  for (int s = 0; s < 2; ++s) {
    for (int f = 0; f < n; ++f) {
      const int lo = std::max(0, f - k), hi = std::min(n - 1, f + k);
      glm::vec3 d = hi > lo ? (toe[s][hi] - toe[s][lo]) * (c.fps / (hi - lo)) : glm::vec3(0.0f);
      d.y = 0.0f;
      height[s].push_back(toe[s][f].y);
      speed[s].push_back(glm::length(d));
      hmax = std::max(hmax, toe[s][f].y);
      vmax = std::max(vmax, speed[s].back());
    }
  }

  char buf[256];
  std::snprintf(buf, sizeof buf, "%s  %.0f FPS  %.2f S  %.2f M/S", c.name.c_str(), c.fps,
                a.duration_s, a.native_speed_m_s);
  cv.text(8, top + 4, buf);

  // Segment band, with each cut-out loop outlined in white below it.
  const int band = top + kTitleH;
  if (in.segmentation != nullptr) {
    for (const TakeSegment& s : in.segmentation->segments) {
      cv.rect(static_cast<int>(xt(s.span.start_s)), band, static_cast<int>(xt(s.span.end_s)),
              band + kBandH, segment_colour(s.kind));
      const std::string name = segment_kind_name(s.kind);
      const int sx = static_cast<int>(xt(s.span.start_s)) + 4;
      if (xt(s.span.end_s) - sx > label_width(name, 2) + 8) cv.text(sx, band + 3, name, {20, 20, 20});
    }
    const TakeSegmentation& seg = *in.segmentation;
    if (seg.fallback_cycle && seg.mirror_step >= 0) {
      // The step that, with its mirror image, makes the loop: marked in yellow.
      const Stride& st = seg.steps[seg.mirror_step];
      cv.rect(static_cast<int>(xt(st.span.start_s)), band + kBandH - 4,
              static_cast<int>(xt(st.span.end_s)), band + kBandH, {255, 220, 60});
    } else {
      for (int ci : seg.cycles) {
        const Stride& st = seg.strides[ci];
        cv.rect(static_cast<int>(xt(st.span.start_s)), band + kBandH - 4,
                static_cast<int>(xt(st.span.end_s)), band + kBandH, {255, 255, 255});
      }
    }
  }
  cv.text(6, band + 3, "PARTS", {200, 200, 200});

  const char* side_name[2] = {"LEFT", "RIGHT"};
  const glm::u8vec3 contact_col[2] = {{60, 120, 60}, {50, 90, 140}};
  for (int s = 0; s < 2; ++s) {
    for (int q = 0; q < 2; ++q) {
      const bool is_h = q == 0;
      const int py = band + kBandH + kGap + (2 * s + q) * (kPanelH + kGap);
      cv.rect(x0, py, x1, py + kPanelH, {35, 35, 40});
      for (const TimeInterval& iv : a.contacts[s]) {
        cv.rect(static_cast<int>(xt(iv.start_s)), py, static_cast<int>(xt(iv.end_s + 1.0f / c.fps)),
                py + kPanelH, contact_col[s], 0.8f);
      }
      const std::vector<float>& v = is_h ? height[s] : speed[s];
      const float vmax_panel = is_h ? hmax : vmax;
      auto yv = [&](float value) {
        return py + kPanelH - 2 - (kPanelH - 4) * std::clamp(value / vmax_panel, -0.1f, 1.0f);
      };
      if (is_h) cv.line(x0, yv(0.0f), x1, yv(0.0f), {90, 90, 90});  // the fitted ground
      for (int f = 1; f < n; ++f) {
        cv.line(xt((f - 1) / c.fps), yv(v[f - 1]), xt(f / c.fps), yv(v[f]), {250, 250, 250});
      }
      std::snprintf(buf, sizeof buf, "%s", side_name[s]);
      cv.text(6, py + 6, buf, {200, 200, 200});
      std::snprintf(buf, sizeof buf, is_h ? "%.0f CM" : "%.1f M/S", is_h ? 100.0f * hmax : vmax);
      cv.text(6, py + 26, is_h ? "TOE H" : "TOE V", {160, 160, 160});
      cv.text(6, py + 46, buf, {160, 160, 160});
    }
  }
  // Time ticks every second.
  const int axis = band + kBandH + kGap + 4 * (kPanelH + kGap);
  for (int t = 0; t <= static_cast<int>(dur); ++t) {
    cv.rect(static_cast<int>(xt(static_cast<float>(t))), axis - kGap, static_cast<int>(xt(t)) + 1,
            axis - kGap + 6, {200, 200, 200});
    std::snprintf(buf, sizeof buf, "%dS", t);
    cv.text(static_cast<int>(xt(static_cast<float>(t))) - 6, axis - 1, buf, {160, 160, 160});
  }
}

}  // namespace

Status write_clip_plot(const std::string& path, const std::vector<ClipPlotInput>& clips) {
  if (clips.empty()) return Status::Error(path + ": no clip to plot");
  Canvas cv{kWidth, static_cast<int>(clips.size()) * kClipH, {}};
  if (cv.h > 30000) {
    return Status::Error(path + ": " + std::to_string(clips.size()) +
                         " clips are too many for one plot (at most " +
                         std::to_string(30000 / kClipH) + "); plot fewer files");
  }
  cv.px.assign(static_cast<size_t>(cv.w) * cv.h * 4, 255);
  for (size_t i = 0; i < cv.px.size(); i += 4) {
    cv.px[i] = 18;
    cv.px[i + 1] = 18;
    cv.px[i + 2] = 22;
  }
  for (size_t i = 0; i < clips.size(); ++i) {
    draw_clip(cv, static_cast<int>(i) * kClipH, clips[i]);
  }
  return write_png_rgba(path, {cv.w, cv.h}, cv.px);
}

}  // namespace gk::app
