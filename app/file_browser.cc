#include "app/file_browser.h"

#include <algorithm>
#include <cstdlib>

#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_stdlib.h>

#include "common/ascii.h"

namespace gk::app {
namespace fs = std::filesystem;

std::string browse_start(const std::string& current, const std::string& sub) {
  std::error_code ec;
  if (!current.empty() && fs::exists(current, ec)) return current;
  const char* env = std::getenv("GAITKEEPER_DATA");
  const fs::path data = env && *env ? fs::path(env) : fs::path("../shared/data");
  if (fs::is_directory(data / sub, ec)) return (data / sub).string();
  return fs::current_path(ec).string();
}

void FileBrowser::open(const std::string& title, const std::string& start,
                       std::vector<std::string> extensions, Mode mode, bool pick_folders,
                       int tag) {
  title_ = title;
  extensions_ = std::move(extensions);
  mode_ = mode;
  pick_folders_ = pick_folders;
  tag_ = tag;
  open_requested_ = true;
  file_name_.clear();
  std::error_code ec;
  fs::path p = start.empty() ? fs::current_path(ec) : fs::path(start);
  if (!fs::is_directory(p, ec)) {
    if (fs::is_regular_file(p, ec)) file_name_ = p.filename().string();
    p = p.has_parent_path() ? p.parent_path() : fs::current_path(ec);
  }
  enter(p);
}

void FileBrowser::enter(const fs::path& folder) {
  std::error_code ec;
  fs::path canonical = fs::weakly_canonical(folder, ec);
  if (ec) canonical = folder;
  entries_.clear();
  error_.clear();
  fs::directory_iterator it(canonical, fs::directory_options::skip_permission_denied, ec);
  if (ec) {
    error_ = canonical.string() + ": " + ec.message();
    folder_ = canonical;
    return;
  }
  folder_ = canonical;
  for (const fs::directory_entry& e : it) {
    const std::string name = e.path().filename().string();
    if (name.empty() || name[0] == '.') continue;  // hidden files and folders
    std::error_code type_ec;
    if (e.is_directory(type_ec)) {
      entries_.push_back({name, "[folder] " + name, true});
      continue;
    }
    const std::string ext = lower_ascii(e.path().extension().string());
    if (extensions_.empty() ||
        std::find(extensions_.begin(), extensions_.end(), ext) != extensions_.end()) {
      entries_.push_back({name, name, false});
    }
  }
  std::sort(entries_.begin(), entries_.end(), [](const Entry& a, const Entry& b) {
    return a.folder != b.folder ? a.folder : a.name < b.name;
  });
}

bool FileBrowser::accept(const fs::path& path) {
  chosen_ = path.string();
  open_ = false;
  ImGui::CloseCurrentPopup();
  return true;
}

bool FileBrowser::draw() {
  if (open_requested_) {
    ImGui::OpenPopup(title_.c_str());
    open_requested_ = false;
    open_ = true;
  }
  if (!open_) return false;
  const ImGuiIO& io = ImGui::GetIO();
  ImGui::SetNextWindowSize(ImVec2(560.0f, 420.0f), ImGuiCond_Appearing);
  ImGui::SetNextWindowPos(ImVec2(io.DisplaySize.x * 0.5f, io.DisplaySize.y * 0.5f),
                          ImGuiCond_Appearing, ImVec2(0.5f, 0.5f));
  bool keep = true;
  if (!ImGui::BeginPopupModal(title_.c_str(), &keep)) {
    open_ = false;
    return false;
  }
  bool chose = false;
  if (!keep || ImGui::IsKeyPressed(GLFW_KEY_ESCAPE, false)) {
    open_ = false;
    ImGui::CloseCurrentPopup();
    ImGui::EndPopup();
    return false;
  }
  if (ImGui::Button("up")) enter(folder_.parent_path());
  ImGui::SameLine();
  ImGui::TextWrapped("%s", folder_.string().c_str());
  if (!error_.empty()) ImGui::TextColored(ImVec4(1.0f, 0.4f, 0.3f, 1.0f), "%s", error_.c_str());
  const float footer = ImGui::GetFrameHeightWithSpacing() * 2.2f;
  ImGui::BeginChild("entries", ImVec2(0.0f, -footer), true);
  // Entering a folder rebuilds entries_: leave the loop and do it after.
  const Entry* enter_folder = nullptr;
  for (const Entry& e : entries_) {
    if (ImGui::Selectable(e.label.c_str(), !e.folder && e.name == file_name_,
                          ImGuiSelectableFlags_AllowDoubleClick)) {
      if (e.folder) {
        enter_folder = &e;
      } else if (!e.folder) {
        file_name_ = e.name;
        if (ImGui::IsMouseDoubleClicked(0)) chose = accept(folder_ / e.name);
      }
    }
    if (chose) break;
  }
  ImGui::EndChild();
  if (enter_folder && !chose) enter(folder_ / enter_folder->name);
  if (!chose) {
    ImGui::SetNextItemWidth(300.0f);
    ImGui::InputText("file", &file_name_);
    ImGui::SameLine();
    if (ImGui::Button(mode_ == Mode::kSave ? "save" : "open") && !file_name_.empty()) {
      chose = accept(folder_ / file_name_);
    }
    if (pick_folders_ && !chose) {
      ImGui::SameLine();
      if (ImGui::Button("this folder")) chose = accept(folder_);
    }
    if (!chose) {
      ImGui::SameLine();
      if (ImGui::Button("cancel")) {
        open_ = false;
        ImGui::CloseCurrentPopup();
      }
      ImGui::TextDisabled("click a folder to enter it; double-click a file to choose it");
    }
  }
  ImGui::EndPopup();
  return chose;
}

}  // namespace gk::app
