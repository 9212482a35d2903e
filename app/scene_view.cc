#include "app/scene_view.h"

#include <algorithm>
#include <cmath>

#include <glm/trigonometric.hpp>

namespace gk::app {

OrbitCamera frame_bounds(glm::vec2 lo, glm::vec2 hi, glm::ivec2 viewport_px) {
  OrbitCamera c;
  const glm::vec2 center = 0.5f * (lo + hi);
  const glm::vec2 half = glm::max(0.5f * (hi - lo), glm::vec2(2.0f));
  c.target = glm::vec3(center.x, 0.0f, center.y);
  c.yaw_rad = glm::radians(35.0f);
  c.pitch_rad = glm::radians(40.0f);
  // Fit the bounding circle of the box into the narrower field of view; a 3/4 view sees the box
  // foreshortened, so the circle is a slightly generous fit.
  const float radius = glm::length(half);
  const float aspect = static_cast<float>(std::max(viewport_px.x, 1)) /
                       static_cast<float>(std::max(viewport_px.y, 1));
  const float half_fov_y = glm::radians(c.fov_y_deg) * 0.5f;
  const float half_fov_x = std::atan(std::tan(half_fov_y) * aspect);
  const float half_fov = std::min(half_fov_y, half_fov_x);
  c.distance_m = std::max(radius * 0.95f / std::sin(half_fov), 3.0f);
  c.far_m = std::max(500.0f, c.distance_m * 4.0f);
  return c;
}

Result<std::unique_ptr<SceneView>> SceneView::create(const CrowdSession& session) {
  auto view = std::unique_ptr<SceneView>(new SceneView());
  view->renderer_ = std::make_unique<CrowdRenderer>();
  GK_RETURN_IF_ERROR(view->renderer_->init());
  auto mesh = view->renderer_->add_mesh(session.mesh());
  if (!mesh.ok()) return Status::Error("mesh: " + mesh.message());
  GK_RETURN_IF_ERROR(view->renderer_->set_walls(session.wall_segments()));
  return view;
}

Status SceneView::upload(const CrowdSession& session, const AnimationLane& lane) {
  return renderer_->upload_palettes(lane.palette_span(session.joints()), session.joints());
}

Status SceneView::draw(const AnimationLane& lane, glm::ivec2 origin_px, glm::ivec2 size_px) {
  return renderer_->draw_region(camera_, origin_px, size_px, lane.draw_span());
}

Status SceneView::render(const CrowdSession& session, glm::ivec2 viewport_px, bool split) {
  if (!split || !session.has_compare()) {
    GK_RETURN_IF_ERROR(upload(session, session.lane()));
    return draw(session.lane(), glm::ivec2(0), viewport_px);
  }
  // Palettes are re-uploaded between the halves: the renderer maps agent i to palette block i.
  const int left = viewport_px.x / 2;
  GK_RETURN_IF_ERROR(upload(session, session.compare_lane()));
  GK_RETURN_IF_ERROR(draw(session.compare_lane(), glm::ivec2(0), {left, viewport_px.y}));
  GK_RETURN_IF_ERROR(upload(session, session.lane()));
  return draw(session.lane(), glm::ivec2(left, 0), {viewport_px.x - left, viewport_px.y});
}

}  // namespace gk::app
