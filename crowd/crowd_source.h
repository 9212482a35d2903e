#pragma once
// The interface the mediator sees: any continuous-space crowd simulator. Per frame it yields, for
// every live agent, a stable id, position p on the ground (x, z) [m], velocity v [m/s] and desired
// torso orientation theta [rad about +y; 0 faces +z, pi/2 faces +x]. It accepts feedback (adjusted
// p, v, theta per agent) that it may honour or ignore, and says which.
//
// Data is a structure of arrays; spans returned by frame() stay valid until the next step().

#include <cstdint>
#include <span>
#include <string>

#include <glm/vec2.hpp>

#include "common/status.h"

namespace gk {

// Read-only view of the live agents after a step. Index i is the same agent in every array; the
// index of an agent may change between frames, its id does not.
struct AgentFrame {
  std::span<const uint32_t> ids;
  std::span<const glm::vec2> positions;   // (x, z) [m]
  std::span<const glm::vec2> velocities;  // (vx, vz) [m/s]
  std::span<const float> thetas;          // [rad]
  size_t size() const { return ids.size(); }
};

// Feedback for the agents of the last frame, index-aligned with it. A source applies, for each
// agent with has_feedback[i] != 0, the adjusted values before its next step.
struct AgentFeedback {
  std::span<const uint8_t> has_feedback;
  std::span<const glm::vec2> positions;
  std::span<const glm::vec2> velocities;
  std::span<const float> thetas;
};

enum class FeedbackPolicy : uint8_t {
  kIgnored,   // the data is the truth (recorded trajectories)
  kHonoured,  // positions, velocities and thetas are taken over
};

class CrowdSource {
 public:
  virtual ~CrowdSource() = default;
  virtual std::string name() const = 0;
  // Advances the simulation by dt_s [s] (> 0). Fails (without crashing) on invalid state.
  virtual Status step(float dt_s) = 0;
  virtual AgentFrame frame() const = 0;
  virtual FeedbackPolicy feedback_policy() const = 0;
  // Applies feedback for the current frame; sources that ignore it return Ok and do nothing.
  virtual Status apply_feedback(const AgentFeedback& feedback) = 0;
  // Simulated time [s] of the current frame.
  virtual double time_s() const = 0;
  // Upper bound on the number of simultaneously live agents (for sizing scratch at creation).
  virtual size_t capacity() const = 0;
};

}  // namespace gk
