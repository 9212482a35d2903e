#pragma once
// A Dear ImGui popup that browses folders and picks a file (clips, trajectories, parameter files),
// a folder (a folder of clips), or in save mode a file name in a folder. A folder is listed when
// it is entered, not on every frame; unreadable folders are a message in the popup, not an error.

#include <filesystem>
#include <string>
#include <vector>

namespace gk::app {

class FileBrowser {
 public:
  enum class Mode { kOpen, kSave };

  // Opens on the next draw() in `start` (a folder, or a file whose folder is used; the working
  // folder when neither exists). `extensions` (".bvh", ...) filter the files listed; with
  // `pick_folders` the folder shown can be chosen as well. `tag` tells the caller what the choice
  // is for.
  void open(const std::string& title, const std::string& start,
            std::vector<std::string> extensions, Mode mode, bool pick_folders, int tag);
  // Draws the popup while it is open; returns true on the frame a path is chosen (chosen()).
  // Escape or Cancel close it without a choice.
  bool draw();
  bool is_open() const { return open_ || open_requested_; }
  const std::string& chosen() const { return chosen_; }
  int tag() const { return tag_; }

 private:
  struct Entry {
    std::string name;
    std::string label;  // what the list shows, built when the folder is read
    bool folder = false;
  };
  void enter(const std::filesystem::path& folder);
  bool accept(const std::filesystem::path& path);

  std::string title_;
  std::vector<std::string> extensions_;
  Mode mode_ = Mode::kOpen;
  bool pick_folders_ = false;
  int tag_ = 0;
  bool open_ = false, open_requested_ = false;
  std::filesystem::path folder_;
  std::vector<Entry> entries_;
  std::string error_;
  std::string file_name_;  // selected (open) or typed (save) name
  std::string chosen_;
};

// Where a browser for data files starts: `current` when it names an existing file or folder,
// else $GAITKEEPER_DATA/<sub> (or ../shared/data/<sub>) when it exists, else the working folder.
std::string browse_start(const std::string& current, const std::string& sub);

}  // namespace gk::app
