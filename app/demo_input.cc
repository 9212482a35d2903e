// The demo window's input: keys (Space pause, H help, R restart, Esc quit), the mouse (orbit,
// pan, zoom toward the cursor, picking), and scripted input for tests (`--input`), which is fed to
// Dear ImGui where the GLFW backend puts real input, so it takes the same path.
#include <cmath>
#include <string>

#include <GLFW/glfw3.h>
#include <imgui.h>

#include "app/demo_app.h"
#include "common/ascii.h"

namespace gk::app {
namespace {

// "space", "escape", "enter", "tab" or a single letter or digit -> GLFW key code; -1 if unknown.
int key_code(std::string_view key) {
  const std::string name = lower_ascii(key);
  if (name == "space") return GLFW_KEY_SPACE;
  if (name == "escape" || name == "esc") return GLFW_KEY_ESCAPE;
  if (name == "enter") return GLFW_KEY_ENTER;
  if (name == "tab") return GLFW_KEY_TAB;
  if (name == "left") return GLFW_KEY_LEFT;
  if (name == "right") return GLFW_KEY_RIGHT;
  if (name == "pageup") return GLFW_KEY_PAGE_UP;
  if (name == "pagedown") return GLFW_KEY_PAGE_DOWN;
  if (name.size() == 1 && name[0] >= 'a' && name[0] <= 'z') return GLFW_KEY_A + (name[0] - 'a');
  if (name.size() == 1 && name[0] >= '0' && name[0] <= '9') return GLFW_KEY_0 + (name[0] - '0');
  return -1;
}

std::vector<float> numbers(const std::string& text, const std::string& what) {
  std::vector<float> v;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t comma = text.find(',', start);
    const std::string item = text.substr(start, comma == std::string::npos ? comma : comma - start);
    v.push_back(parse_number<float>("demo", item, what.c_str(), -1e5f, 1e5f));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return v;
}

}  // namespace

void DemoApp::parse_inputs() {
  for (const std::string& text : options_.inputs) {
    const std::string where = "--input '" + text + "'";
    const size_t a = text.find(':');
    const size_t b = a == std::string::npos ? a : text.find(':', a + 1);
    if (b == std::string::npos) {
      fail("demo", 2,
           where + ": expected FRAME:key:NAME, FRAME:click:X,Y or FRAME:wheel:X,Y,STEPS");
    }
    ScriptedInput in;
    in.frame = parse_number<int>("demo", text.substr(0, a), "--input frame", 0, 1 << 30);
    const std::string kind = text.substr(a + 1, b - a - 1), arg = text.substr(b + 1);
    if (kind == "key") {
      in.kind = ScriptedInput::Kind::kKey;
      in.key = key_code(arg);
      if (in.key < 0) {
        fail("demo", 2, where + ": unknown key '" + arg +
                            "' (space, escape, enter, tab, left, right, pageup, pagedown, a letter or a digit)");
      }
    } else if (kind == "click" || kind == "wheel") {
      const std::vector<float> v = numbers(arg, where);
      const size_t expected = kind == "click" ? 2 : 3;
      if (v.size() != expected) {
        fail("demo", 2, where + ": expected " + (kind == "click" ? "X,Y" : "X,Y,STEPS"));
      }
      in.kind = kind == "click" ? ScriptedInput::Kind::kClick : ScriptedInput::Kind::kWheel;
      in.pos = {v[0], v[1]};
      if (kind == "wheel") in.wheel = v[2];
    } else {
      fail("demo", 2, where + ": expected key, click or wheel, got '" + kind + "'");
    }
    scripted_.push_back(in);
  }
}

void DemoApp::feed_scripted_input(int frame) {
  // Called between the GLFW backend's NewFrame (which sets mouse and keys from the window) and
  // ImGui::NewFrame (which turns them into presses and clicks). A press lasts one frame.
  ImGuiIO& io = ImGui::GetIO();
  for (const ScriptedInput& in : scripted_) {
    if (in.kind == ScriptedInput::Kind::kKey) {
      if (in.frame == frame) io.KeysDown[in.key] = true;
      if (in.frame + 1 == frame) io.KeysDown[in.key] = false;
      continue;
    }
    if (in.frame != frame && in.frame + 1 != frame) continue;
    io.MousePos = ImVec2(in.pos.x, in.pos.y);
    if (in.kind == ScriptedInput::Kind::kClick) io.MouseDown[0] = in.frame == frame;
    if (in.kind == ScriptedInput::Kind::kWheel && in.frame == frame) io.MouseWheel += in.wheel;
  }
}

void DemoApp::handle_input() {
  const ImGuiIO& io = ImGui::GetIO();
  // A text field or an open popup (the file browser) takes the keyboard.
  if (!io.WantCaptureKeyboard && !browser_.is_open()) {
    if (ImGui::IsKeyPressed(GLFW_KEY_SPACE, false)) paused_ = !paused_;
    if (ImGui::IsKeyPressed(GLFW_KEY_H, false)) help_ = !help_;
    if (ImGui::IsKeyPressed(GLFW_KEY_R, false)) restart_requested_ = true;
    if (ImGui::IsKeyPressed(GLFW_KEY_ESCAPE, false)) quit_ = true;
    // The timeline: one record (1/20 s) or 5 s back and forth; pauses.
    if (ImGui::IsKeyPressed(GLFW_KEY_LEFT)) scrub_by(-1);
    if (ImGui::IsKeyPressed(GLFW_KEY_RIGHT)) scrub_by(1);
    if (ImGui::IsKeyPressed(GLFW_KEY_PAGE_UP, false)) scrub_by(-CrowdRecorder::kRecordsPer5s);
    if (ImGui::IsKeyPressed(GLFW_KEY_PAGE_DOWN, false)) scrub_by(CrowdRecorder::kRecordsPer5s);
  }
  if (io.WantCaptureMouse) return;
  const glm::vec2 mouse(io.MousePos.x, io.MousePos.y);
  const glm::vec2 delta(io.MouseDelta.x, io.MouseDelta.y);
  if (ImGui::IsMouseDragging(ImGuiMouseButton_Right, 0.0f)) {
    camera_.orbit(-delta.x * 0.006f, delta.y * 0.006f);
    director_.user_took_camera();
  }
  if (ImGui::IsMouseDragging(ImGuiMouseButton_Middle, 0.0f)) {
    camera_.pan(delta, view_size());
    director_.user_took_camera();
    director_.stop_following();
  }
  if (io.MouseWheel != 0.0f) {
    const float factor = std::pow(0.88f, io.MouseWheel);
    director_.user_took_camera();
    if (director_.following()) {
      camera_.zoom(factor);  // the followed agent stays at the centre
    } else {
      // Toward the ground under the cursor, in the half of the split it is over.
      glm::vec2 px = mouse;
      const glm::ivec2 size = view_size();
      if (session_->has_compare() && px.x >= size.x) px.x -= static_cast<float>(size.x);
      camera_.zoom_about(px, size, factor);
    }
  }
  if (ImGui::IsMouseClicked(ImGuiMouseButton_Left)) pick(mouse);
}

void DemoApp::pick(glm::vec2 mouse_px) {
  glm::vec2 px = mouse_px;
  const glm::ivec2 size = view_size();
  if (session_->has_compare() && px.x >= size.x) px.x -= static_cast<float>(size.x);
  const Ray ray = camera_.pick_ray(px, size);
  const auto draws = shown_lane(false).draw_span();
  float best = 0.6f;  // [m] from the ray to the body's axis point at hip height
  int64_t picked = -1;
  for (size_t i = 0; i < draws.size(); ++i) {
    const glm::vec3 c = draws[i].position + glm::vec3(0, 0.9f, 0);
    const float along = glm::dot(c - ray.origin, ray.direction);
    if (along <= 0.0f) continue;
    const float d = glm::length(c - (ray.origin + along * ray.direction));
    if (d < best) best = d, picked = shown_id(false, i);
  }
  select(picked);
}

void DemoApp::select(int64_t id) {
  selected_id_ = id;
  if (id < 0) {
    director_.stop_following();
    return;
  }
  // Close enough to see the feet of the followed agent.
  director_.follow(id);
}

}  // namespace gk::app
