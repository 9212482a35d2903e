#include "app/offscreen.h"

namespace gk::app {

glm::ivec2 parse_size(const std::string& command, const std::string& text) {
  const size_t x = text.find('x');
  if (x == std::string::npos) {
    fail(command, 2, "--size: expected WxH such as 1280x720, got '" + text + "'");
  }
  const int w = parse_number<int>(command, text.substr(0, x), "--size width", 16, 8192);
  const int h = parse_number<int>(command, text.substr(x + 1), "--size height", 16, 8192);
  return {w, h};
}

OffscreenScene open_offscreen_scene(const std::string& command, const CrowdSession& session,
                                    const std::string& size_text) {
  OffscreenScene scene;
  scene.size = parse_size(command, size_text);
  ContextOptions options;
  options.width = scene.size.x;
  options.height = scene.size.y;
  auto context = GlContext::create_offscreen(options);
  if (!context.ok()) fail(command, 1, "no OpenGL context available: " + context.message());
  scene.context = std::move(context).value();
  auto view = SceneView::create(session);
  if (!view.ok()) fail(command, 1, "renderer: " + view.message());
  scene.view = std::move(view).value();
  scene.view->camera() = frame_bounds(session.bounds_min(), session.bounds_max(), scene.size);
  return scene;
}

}  // namespace gk::app
