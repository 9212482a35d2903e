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

Exhibits make_exhibits(const CrowdSetup& setup, glm::vec2 scene_center, float wall_thickness_m) {
  constexpr glm::vec3 kBoard(0.85f, 0.95f, 0.05f);   // half size [m]: 1.7 m wide, 1.9 m tall
  constexpr glm::vec3 kCanvas(0.68f, 0.45f, 0.02f);  // half size [m]
  constexpr float kCanvasHeight_m = 1.3f;            // eye level of the people looking at it
  constexpr glm::vec3 kBoardColor(0.10f, 0.07f, 0.05f);
  Exhibits out;
  for (const AttentionTarget& t : setup.attention_targets) {
    // The nearest wall within 1 m holds the board; its normal points from the wall to the target.
    float best = 1.0f;
    glm::vec2 normal = scene_center - t.position, base = t.position;
    for (const WallSegment& w : setup.walls) {
      const glm::vec2 d = w.b - w.a;
      const float len2 = glm::dot(d, d);
      const float u = len2 > 1e-9f ? std::clamp(glm::dot(t.position - w.a, d) / len2, 0.0f, 1.0f)
                                   : 0.0f;
      const glm::vec2 q = w.a + u * d;
      const float dist = glm::length(t.position - q);
      if (dist < best && dist > 1e-4f) {
        best = dist;
        normal = t.position - q;
        base = q + glm::normalize(normal) * (0.5f * wall_thickness_m + kBoard.z);
      }
    }
    if (glm::length(normal) < 1e-4f) normal = glm::vec2(0.0f, 1.0f);
    normal = glm::normalize(normal);
    const float yaw = std::atan2(normal.x, normal.y);
    PropBox board;
    board.center = glm::vec3(base.x, kBoard.y, base.y);
    board.half_size = kBoard;
    board.yaw_rad = yaw;
    board.color = kBoardColor;
    PropBox canvas = board;
    const glm::vec2 front = base + normal * (kBoard.z + kCanvas.z);
    canvas.center = glm::vec3(front.x, kCanvasHeight_m, front.y);
    canvas.half_size = kCanvas;
    canvas.color = kExhibitCanvasColor;
    out.boxes.push_back(board);
    out.boxes.push_back(canvas);
    out.canvas_centers.push_back(canvas.center + glm::vec3(normal.x, 0.0f, normal.y) * kCanvas.z);
  }
  return out;
}

namespace {

std::optional<FollowedAgent> find_in_lane(const CrowdSession& session, const AnimationLane& lane,
                                          int64_t id) {
  const AgentFrame& frame = session.frame_of(lane);
  const auto draws = lane.draw_span();
  for (size_t i = 0; i < draws.size() && i < frame.size(); ++i) {
    if (frame.ids[i] == id) return FollowedAgent{draws[i].position, frame.velocities[i]};
  }
  return std::nullopt;
}

}  // namespace

std::optional<FollowedAgent> followed_agent(const CrowdSession& session, int64_t id) {
  std::optional<FollowedAgent> a = find_in_lane(session, session.lane(), id);
  if (a && session.has_compare() && session.compare_has_own_crowd()) {
    if (const std::optional<FollowedAgent> b = find_in_lane(session, session.compare_lane(), id)) {
      a->twin = b->position;
      a->velocity_xz = 0.5f * (a->velocity_xz + b->velocity_xz);
    }
  }
  return a;
}

Result<std::unique_ptr<SceneView>> SceneView::create(const CrowdSession& session) {
  auto view = std::unique_ptr<SceneView>(new SceneView());
  view->renderer_ = std::make_unique<CrowdRenderer>();
  GK_RETURN_IF_ERROR(view->renderer_->init());
  auto mesh = view->renderer_->add_mesh(session.mesh());
  if (!mesh.ok()) return Status::Error("mesh: " + mesh.message());
  GK_RETURN_IF_ERROR(view->renderer_->set_walls(session.wall_segments()));
  const glm::vec2 center = 0.5f * (session.bounds_min() + session.bounds_max());
  const Exhibits exhibits = make_exhibits(session.setup(), center,
                                          view->renderer_->settings().wall_thickness_m);
  GK_RETURN_IF_ERROR(view->renderer_->set_props(exhibits.boxes));
  return view;
}

Status SceneView::upload(const CrowdSession& session, const AnimationLane& lane) {
  if (lane.pipeline) lane.pipeline->update_palettes();  // a recorded lane has its own
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
  // Palettes are re-uploaded between the halves: each lane's draws index its own palettes.
  const int left = viewport_px.x / 2;
  GK_RETURN_IF_ERROR(upload(session, session.compare_lane()));
  GK_RETURN_IF_ERROR(draw(session.compare_lane(), glm::ivec2(0), {left, viewport_px.y}));
  GK_RETURN_IF_ERROR(upload(session, session.lane()));
  return draw(session.lane(), glm::ivec2(left, 0), {viewport_px.x - left, viewport_px.y});
}

}  // namespace gk::app
