#pragma once
// An offscreen (EGL) GL context with a SceneView of a session, for `render` and `bench --render`.
// No GL context at all (no EGL, GL too old) ends the command with a clear message and exit code 1.

#include <memory>
#include <string>

#include <glm/vec2.hpp>

#include "app/crowd_session.h"
#include "app/scene_view.h"
#include "render/gl_context.h"

namespace gk::app {

struct OffscreenScene {
  std::unique_ptr<GlContext> context;  // declared first: destroyed last, after the renderer
  std::unique_ptr<SceneView> view;
  glm::ivec2 size{1280, 720};
};

// "1280x720" -> (1280, 720); bad text ends the command with exit code 2.
glm::ivec2 parse_size(const std::string& command, const std::string& text);

// The camera frames the session's bounds (3/4 view).
OffscreenScene open_offscreen_scene(const std::string& command, const CrowdSession& session,
                                    const std::string& size_text);

}  // namespace gk::app
