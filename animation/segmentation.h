#pragma once
// Long takes: what a capture does over time. A take is cut into strides (one foot's contact start
// to its next), each stride measured (speed, how much it speeds up or slows down, how far the body
// turns), and the take into segments: standing (idle), starting, steady walking or running,
// turning, stopping. From each steady segment one stride per pace is cut out as a loop (its seam
// cross-faded with the neighbouring stride, its turn spread out so the loop travels straight):
// the cycles a blend space is made of (a take that walks, then walks faster, gives both). Starts,
// stops and turns stay available as transitions.

#include <array>
#include <string>
#include <vector>

#include "animation/analysis.h"
#include "animation/clip.h"
#include "animation/skeleton.h"

namespace gk {

enum class SegmentKind : uint8_t { kIdle, kStart, kSteady, kTurn, kStop, kTransition };
const char* segment_kind_name(SegmentKind kind);

struct Stride {
  TimeInterval span;        // one foot's contact start to its next contact start [s]
  int side = 0;             // Side of that foot
  float speed_m_s = 0.0f;   // horizontal root displacement over the stride / its duration
  float speed_change = 0.0f;  // (second-half speed - first-half speed) / stride speed
  float turn_rad = 0.0f;    // facing change over the stride (+: left)
  float direction_rad = 0.0f;  // travel direction relative to the mean facing (0: forward)
  bool steady = false;
};

struct TakeSegment {
  SegmentKind kind = SegmentKind::kTransition;
  TimeInterval span;
  float speed_m_s = 0.0f;   // root path length over the segment / its duration
  float speed_in_m_s = 0.0f;   // smoothed root speed where it begins
  float speed_out_m_s = 0.0f;  // and where it ends
  float turn_rad = 0.0f;    // facing change over the segment (+: left)
  // Steady segment: the stride cut out as its loop (index into strides), of its paces the one
  // whose ends match best (every pace's loop is in TakeSegmentation::cycles).
  int cycle = -1;
};

// Thresholds of the segmentation, from how people walk (see GAIT.md): in steady gait the two
// steps of a stride cover the ground at nearly the same speed and the body keeps its heading.
struct SegmentationThresholds {
  // [ratio] a stride is steady while its two halves' speeds differ by less than this share of its
  // speed (steady walking: a few percent; a start or stop: a third or more)
  float steady_speed_change = 0.15f;
  float steady_turn_rad = 0.52f;   // [rad] and it turns less than this (30 deg) in one stride
  float idle_speed_m_s = 0.15f;    // [m/s] standing: the root's smoothed speed below this
  float min_stride_s = 0.3f;       // [s] strides shorter or longer are not gait
  float max_stride_s = 2.5f;
  float min_segment_s = 0.2f;      // [s] shorter runs are merged into their neighbours
};

struct TakeSegmentation {
  std::vector<Stride> strides;  // sorted by start
  std::vector<TakeSegment> segments;  // cover the take, in time order
  // Strides cut out as loops: in each steady segment one per pace (its steady strides grouped by
  // speed, a group spanning no more than SegmentationThresholds::steady_speed_change of its
  // slowest), the one whose ends match best; when no stride is steady, the least unsteady one
  // (and `problems` says so).
  std::vector<int> cycles;
  bool fallback_cycle = false;  // `cycles` holds the least unsteady stride, not a steady one
  // Steps: one foot's contact start to the other foot's next (`side`: the first foot), measured
  // as strides are (their two halves' speeds, turn, direction), sorted by start.
  std::vector<Stride> steps;
  // Without a steady stride: the steadiest step (index into steps; -1 if none), which with its
  // mirror image makes a stride (extract_mirrored_cycle): a stop's or a start's one good step.
  int mirror_step = -1;
  // What is doubtful or unusable, and why (plain sentences for analyze-clip and the library).
  std::vector<std::string> problems;
};

// Segments a take (a clip that does not loop, with root motion). Loops and clips authored in place
// come back as one steady segment over the whole clip, without strides.
TakeSegmentation segment_take(const Clip& take, const Skeleton& skeleton, const ClipAnalysis& a,
                              const SegmentationThresholds& thresholds = {});

// The stride cut out of the take as a looping clip (`analysis`: the take's, for its contacts). Its
// turn is taken back a little each frame about the planted foot, so that the loop keeps one
// heading; its seam is closed by taking up each joint's mismatch between the stride's first frame
// and the one after its last gradually: a leg's joints only while that foot swings (a planted foot
// never slides for it), the rest of the body over the whole stride.
Clip extract_cycle(const Clip& take, const Skeleton& skeleton, const ClipAnalysis& analysis,
                   const Stride& stride);

// The vertical plane a stretch of a take travels along: through the middle of its hips' way
// (their sway to either side falls on both sides of it), along the body's mean facing. The
// plane a step or a stop is mirrored in, so that its mirror image travels the same way.
struct TravelPlane {
  glm::vec3 point{0.0f};
  glm::vec3 normal{1.0f, 0.0f, 0.0f};  // horizontal, unit
};
TravelPlane travel_plane(const Clip& clip, const Skeleton& skeleton);

// A loop made of one step of the take and its mirror image (the other foot's step, as the first
// foot's was): for a take with no steady stride, where one step is good and the next is not (a
// stop, a sudden stop). The step is reflected in its travel_plane, joints exchanged by
// `mirror_map` (mirror_joint_map), and placed where the step ends; the joins are closed as
// extract_cycle closes a stride's seam (a leg's mismatch taken up while that foot swings, the
// body's over the step). `contacts`: each foot's contacts in the loop's time, from the take's
// contacts of the step (a stance running through the loop's end goes on past its duration, as
// clip analysis gives a loop's); they alternate by construction.
struct MirroredCycle {
  Clip loop;
  std::array<std::vector<TimeInterval>, 2> contacts;
};
MirroredCycle extract_mirrored_cycle(const Clip& take, const Skeleton& skeleton,
                                     const ClipAnalysis& analysis, const Stride& step,
                                     const std::vector<int16_t>& mirror_map);

// A take's contacts within the stride cut from it (frames `first`..`first + frames`), in the
// loop's time: clip analysis of the whole take sees each stance with what comes before and after
// it; the loop analysed alone does not (a stride that slows down walks at no one speed, and its
// stance feet seem to move against the loop's mean travel). A stance that runs through the loop's
// end goes on at its start: one interval past the duration, as clip analysis gives a loop's.
std::array<std::vector<TimeInterval>, 2> stride_contacts(const ClipAnalysis& take, int first,
                                                         int frames, float fps);

// The take's frames from `span` as a clip that does not loop (a start, a stop, a turn).
Clip extract_span(const Clip& take, TimeInterval span);

}  // namespace gk
