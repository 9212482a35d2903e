#pragma once
// The 3D view of a CrowdSession: a CrowdRenderer with the session's mesh and walls, an orbit
// camera, and drawing of one lane or of a split screen (compare lane left, primary lane right).
// Needs a current GL context for every call, including destruction.

#include <memory>
#include <optional>
#include <vector>

#include <glm/vec2.hpp>

#include "app/camera_director.h"
#include "app/crowd_session.h"
#include "common/status.h"
#include "render/camera.h"
#include "render/crowd_renderer.h"

namespace gk::app {

// A 3/4 view (yaw 35 deg, pitch 40 deg) that fits the ground box [lo, hi] into the viewport.
OrbitCamera frame_bounds(glm::vec2 lo, glm::vec2 hi, glm::ivec2 viewport_px);

// The scenario's attention targets drawn as exhibits: a dark display board standing against the
// nearest wall (or free, facing the scene's centre) with a teal canvas on its front.
struct Exhibits {
  std::vector<PropBox> boxes;
  std::vector<glm::vec3> canvas_centers;  // [m], for reports and tests
};
inline constexpr glm::vec3 kExhibitCanvasColor{0.02f, 0.42f, 0.48f};  // linear RGB
Exhibits make_exhibits(const CrowdSetup& setup, glm::vec2 scene_center, float wall_thickness_m);

// The agent `id` as drawn by the primary lane (after collect()) with its simulator velocity, or
// nullopt when it is not in the frame. When the split's halves run their own crowds, `twin` is
// where the compare lane draws it and the velocity the mean of the two.
std::optional<FollowedAgent> followed_agent(const CrowdSession& session, int64_t id);

class SceneView {
 public:
  // Builds the renderer and uploads the session's mesh and walls.
  static Result<std::unique_ptr<SceneView>> create(const CrowdSession& session);

  // Uploads one lane's palettes (the `upload` stage).
  Status upload(const CrowdSession& session, const AnimationLane& lane);
  // Draws the uploaded lane into a rectangle (GL origin bottom-left); `camera_viewport` is the
  // size the camera's aspect is computed for.
  Status draw(const AnimationLane& lane, glm::ivec2 origin_px, glm::ivec2 size_px);
  // Everything for one frame: the primary lane over the whole viewport, or with the session's
  // compare lane the split screen (compare left, primary right, same camera).
  Status render(const CrowdSession& session, glm::ivec2 viewport_px, bool split);

  OrbitCamera& camera() { return camera_; }
  CrowdRenderer& renderer() { return *renderer_; }

 private:
  std::unique_ptr<CrowdRenderer> renderer_;
  OrbitCamera camera_;
};

}  // namespace gk::app
