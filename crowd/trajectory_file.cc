#include "crowd/trajectory_file.h"

#include <algorithm>
#include <charconv>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <limits>
#include <tuple>

#include "common/ascii.h"
#include "common/file_io.h"
#include "common/text_snippet.h"

namespace gk {
namespace {

// Frame numbers are video frame indices; ids index nothing (they are only sorted), so any 32-bit
// value is fine. Coordinates are metres on a ground plane: a bound keeps float maths exact enough.
constexpr double kMaxFrame = 2147483647.0;
constexpr double kMaxId = 4294967295.0;
constexpr double kMaxCoordinate_m = 1.0e5;
constexpr uint64_t kMaxFileBytes = uint64_t(1) << 30;

struct Row {
  uint32_t id;
  int64_t frame;
  glm::vec2 position;
  int line;
};

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

std::string_view trim(std::string_view t) {
  while (!t.empty() && is_space(t.front())) t.remove_prefix(1);
  while (!t.empty() && is_space(t.back())) t.remove_suffix(1);
  return t;
}

// How a file's fields are separated: runs of spaces and tabs (the ETH/UCY releases), or one comma
// or semicolon each (CSV: two separators in a row leave an empty field, reported as such).
enum class Separator : uint8_t { kBlank, kComma, kSemicolon };

// True for a row of text: printable ASCII and blanks only (not a binary file's bytes).
bool is_text(std::string_view row) {
  return std::all_of(row.begin(), row.end(),
                     [](char ch) { return (ch >= 0x20 && ch < 0x7F) || is_space(ch); });
}

// Judged on the file's first row: a comma or semicolon in a row of text makes the file CSV (a
// row that is not text is split on blanks and fails as data).
Separator separator_of(std::string_view first_row) {
  if (!is_text(first_row)) return Separator::kBlank;
  if (first_row.find(',') != std::string_view::npos) return Separator::kComma;
  if (first_row.find(';') != std::string_view::npos) return Separator::kSemicolon;
  return Separator::kBlank;
}

// Splits a line into at most `max_tokens` tokens; returns the total token count (which may
// exceed max_tokens, to report it).
int split_tokens(std::string_view line, Separator sep, std::string_view* out_tokens,
                 int max_tokens) {
  int count = 0;
  if (sep != Separator::kBlank) {
    const char c = sep == Separator::kComma ? ',' : ';';
    line = trim(line);
    size_t start = 0;
    while (true) {
      const size_t end = line.find(c, start);
      const std::string_view field =
          trim(line.substr(start, end == std::string_view::npos ? std::string_view::npos
                                                                : end - start));
      if (count < max_tokens) out_tokens[count] = field;
      ++count;
      if (end == std::string_view::npos) break;
      start = end + 1;
    }
    return count;
  }
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_space(line[i])) ++i;
    if (i >= line.size()) break;
    const size_t start = i;
    while (i < line.size() && !is_space(line[i])) ++i;
    if (count < max_tokens) out_tokens[count] = line.substr(start, i - start);
    ++count;
  }
  return count;
}

Status parse_number(std::string_view token, const std::string& column, const std::string& file,
                    int line, double* out_value) {
  double value = 0.0;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (ec != std::errc() || end != token.data() + token.size()) {
    return Status::AtLine(file, line, column + ": expected a number, found " + quoted_snippet(token));
  }
  if (!std::isfinite(value)) {
    return Status::AtLine(file, line,
                          column + ": expected a finite number, found " + quoted_snippet(token));
  }
  *out_value = value;
  return Status::Ok();
}

// The two layouts a trajectory file without a header may have, by their column count (all of a
// file's rows alike): 4, the common one of the Social-LSTM/GAN releases; 8, the ETH (BIWI)
// authors' obsmat.txt, whose ground plane is (pos_x, pos_y) and whose pos_z and velocity columns
// are not used (the replay derives velocity from the positions). A file with a header row names
// its columns instead, in any order and with any others beside them.
constexpr const char* kLayouts =
    "expected 4 numbers (frame id x y) or 8 (ETH obsmat: frame id pos_x pos_z pos_y v_x v_z v_y)";
constexpr const char* kHeaderNames =
    "a header names the columns frame (or frame_id; or time, t or timestamp in seconds), id (or "
    "ped, ped_id, agent_id, track_id, person_id), x (or pos_x) and y (or pos_y)";
// A time column [s] is read to the millisecond: its rows become frames of this length.
constexpr double kTimeQuantum_s = 1e-3;
constexpr double kMaxTime_s = 1e7;
constexpr int kMaxColumns = 64;

// The file's layout: its separator, its column count and where frame, id, x and y are.
struct Layout {
  Separator sep = Separator::kBlank;
  int columns = 0;  // 0 until the first row sets it
  bool header = false;
  bool timed = false;        // at[0] is a time column [s] rather than frame numbers
  int at[4] = {0, 1, 2, 3};  // frame (or time), id, x, y
  std::string names[4] = {"column 1 (frame)", "column 2 (id)", "column 3 (x)", "column 4 (y)"};
};

// A header's name, lower case, without quotes, blanks, '_', '-' or '.'.
std::string normalised_name(std::string_view t) {
  std::string n;
  for (char c : t) {
    if (c == '"' || c == '\'' || c == '_' || c == '-' || c == '.' || is_space(c)) continue;
    n.push_back(c);
  }
  return lower_ascii(n);
}

// Which of frame (0), id (1), x (2), y (3) or time (4) a header name stands for; -1 for none.
int header_role(const std::string& n) {
  static const std::pair<const char*, int> kNames[] = {
      {"frame", 0},       {"frameid", 0},  {"framenumber", 0}, {"framenum", 0},
      {"frameindex", 0},  {"id", 1},       {"ped", 1},         {"pedid", 1},
      {"pedestrian", 1},  {"pedestrianid", 1}, {"agent", 1},   {"agentid", 1},
      {"track", 1},       {"trackid", 1},  {"person", 1},      {"personid", 1},
      {"objectid", 1},    {"objid", 1},    {"x", 2},           {"posx", 2},
      {"positionx", 2},   {"xm", 2},       {"y", 3},           {"posy", 3},
      {"positiony", 3},   {"ym", 3},       {"t", 4},           {"time", 4},
      {"times", 4},       {"timestamp", 4}, {"seconds", 4},    {"sec", 4}};
  for (const auto& [name, role] : kNames) {
    if (n == name) return role;
  }
  return -1;
}

// A first row whose first field is not a number is a header: it sets the layout by its names.
Status parse_header(const std::string_view* tokens, int count, const std::string& file, int line,
                    Layout* layout) {
  if (count > kMaxColumns) {
    return Status::AtLine(file, line,
                          "header: at most " + std::to_string(kMaxColumns) + " columns, found " +
                              std::to_string(count));
  }
  int found[5] = {-1, -1, -1, -1, -1};
  for (int c = 0; c < count; ++c) {
    const int role = header_role(normalised_name(tokens[c]));
    if (role < 0) continue;
    if (found[role] >= 0) {
      return Status::AtLine(file, line,
                            "header: columns " + std::to_string(found[role] + 1) + " (" +
                                quoted_snippet(tokens[found[role]]) + ") and " +
                                std::to_string(c + 1) + " (" + quoted_snippet(tokens[c]) +
                                ") name the same quantity");
    }
    found[role] = c;
  }
  // A time column, when there is one, times the rows (a frame number says less).
  if (found[4] >= 0) {
    found[0] = found[4];
    layout->timed = true;
  }
  static constexpr const char* kWhat[4] = {"frame (or time)", "id", "x", "y"};
  for (int r = 0; r < 4; ++r) {
    if (found[r] < 0) {
      std::string names;
      for (int c = 0; c < count && c < 8; ++c) {
        names += (c ? ", " : "") + quoted_snippet(tokens[c]);
      }
      return Status::AtLine(file, line,
                            std::string("header: no column for ") + kWhat[r] + " among " + names +
                                "; " + kHeaderNames);
    }
    layout->at[r] = found[r];
    layout->names[r] = "column " + std::to_string(found[r] + 1) + " (" +
                       std::string(trim(tokens[found[r]])) + ")";
  }
  layout->columns = count;
  layout->header = true;
  return Status::Ok();
}

// Parses one data row into `out_row`; the first row of the file (`layout->columns` == 0) may be a
// header instead, which sets the layout and leaves `*is_header` true.
Status parse_row(std::string_view text_row, const std::string& file, int line, Layout* layout,
                 Row* out_row, bool* is_header) {
  *is_header = false;
  const bool first = layout->columns == 0;
  if (first) layout->sep = separator_of(text_row);
  std::string_view tokens[kMaxColumns];
  const int count = split_tokens(text_row, layout->sep, tokens, kMaxColumns);
  if (first) {
    double v = 0.0;
    const std::string_view t0 = count > 0 ? tokens[0] : std::string_view();
    const auto [end, ec] = std::from_chars(t0.data(), t0.data() + t0.size(), v);
    // A header is text with a letter in its first name (anything else, such as a binary file's
    // bytes, is a data row that fails as one).
    const bool text = is_text(text_row) && std::any_of(t0.begin(), t0.end(), [](char ch) {
                        return std::isalpha(static_cast<unsigned char>(ch)) != 0;
                      });
    if (text && (ec != std::errc() || end != t0.data() + t0.size())) {
      *is_header = true;
      return parse_header(tokens, count, file, line, layout);
    }
    if (count != 4 && count != 8) {
      return Status::AtLine(file, line,
                            std::string(kLayouts) + ", or " + kHeaderNames + "; found " +
                                std::to_string(count) + " fields");
    }
    layout->columns = count;
    if (count == 8) {
      // obsmat: frame id pos_x pos_z pos_y v_x v_z v_y; the ground plane is (pos_x, pos_y).
      layout->at[3] = 4;
      layout->names[2] = "column 3 (pos_x)";
      layout->names[3] = "column 5 (pos_y)";
    }
  } else if (count != layout->columns) {
    if (!layout->header && (count == 4 || count == 8)) {
      return Status::AtLine(file, line,
                            "expected " + std::to_string(layout->columns) +
                                " numbers as on the file's first row, found " +
                                std::to_string(count));
    }
    return Status::AtLine(file, line,
                          layout->header
                              ? "expected " + std::to_string(layout->columns) +
                                    " fields as the header names, found " + std::to_string(count)
                              : std::string(kLayouts) + ", found " + std::to_string(count));
  }
  double values[4];
  for (int r = 0; r < 4; ++r) {
    GK_RETURN_IF_ERROR(parse_number(tokens[layout->at[r]], layout->names[r], file, line, &values[r]));
  }
  const std::string_view frame_token = tokens[layout->at[0]], id_token = tokens[layout->at[1]];
  if (layout->timed) {
    if (std::abs(values[0]) > kMaxTime_s) {
      return Status::AtLine(file, line,
                            layout->names[0] + ": expected a time within +-1e7 s, found " +
                                quoted_snippet(frame_token));
    }
    values[0] = std::round(values[0] / kTimeQuantum_s);
  } else if (values[0] < 0.0 || values[0] > kMaxFrame || values[0] != std::floor(values[0])) {
    return Status::AtLine(file, line,
                          layout->names[0] + ": expected a whole number in [0, 2^31), found " +
                              quoted_snippet(frame_token));
  }
  if (values[1] < 0.0 || values[1] > kMaxId || values[1] != std::floor(values[1])) {
    return Status::AtLine(file, line,
                          layout->names[1] + ": expected a whole number in [0, 2^32), found " +
                              quoted_snippet(id_token));
  }
  for (const int r : {2, 3}) {
    if (std::abs(values[r]) > kMaxCoordinate_m) {
      return Status::AtLine(file, line,
                            layout->names[r] + ": expected a coordinate within +-1e5 m, " +
                                "found " + quoted_snippet(tokens[layout->at[r]]));
    }
  }
  out_row->frame = static_cast<int64_t>(values[0]);
  out_row->id = static_cast<uint32_t>(values[1]);
  out_row->position = glm::vec2(static_cast<float>(values[2]), static_cast<float>(values[3]));
  out_row->line = line;
  return Status::Ok();
}

// The most common positive frame difference between consecutive samples of one pedestrian
// (smallest on ties, so the result does not depend on the order of the rows).
int64_t usual_frame_step(const std::vector<Row>& sorted_rows) {
  std::vector<int64_t> diffs;
  diffs.reserve(sorted_rows.size());
  for (size_t i = 1; i < sorted_rows.size(); ++i) {
    if (sorted_rows[i].id == sorted_rows[i - 1].id) {
      diffs.push_back(sorted_rows[i].frame - sorted_rows[i - 1].frame);
    }
  }
  if (diffs.empty()) return 1;
  std::sort(diffs.begin(), diffs.end());
  int64_t best = diffs[0];
  size_t best_count = 0;
  for (size_t i = 0; i < diffs.size();) {
    size_t j = i;
    while (j < diffs.size() && diffs[j] == diffs[i]) ++j;
    if (j - i > best_count) {
      best_count = j - i;
      best = diffs[i];
    }
    i = j;
  }
  return best;
}

}  // namespace

Result<TrajectoryTable> parse_trajectory_text(std::string_view text, const std::string& file_name) {
  std::vector<Row> rows;
  // A row takes at least 8 bytes ("0 0 0 0\n"): reserve against the bytes actually present.
  rows.reserve(text.size() / 8 + 1);
  int line = 0;
  size_t pos = 0;
  Layout layout;  // set by the file's first row (a header, or 4 or 8 numbers)
  while (pos < text.size()) {
    size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view line_text = text.substr(pos, end - pos);
    pos = end + 1;
    ++line;
    const std::string_view content = trim(line_text);
    if (content.empty() || content.front() == '#') continue;  // blank line or comment
    Row row{};
    bool header = false;
    GK_RETURN_IF_ERROR(parse_row(content, file_name, line, &layout, &row, &header));
    if (!header) rows.push_back(row);
  }
  if (rows.empty()) {
    return Status::AtLine(file_name, std::max(line, 1),
                          std::string("no trajectory rows: ") + kLayouts + " per line, or " +
                              kHeaderNames);
  }

  std::sort(rows.begin(), rows.end(), [](const Row& a, const Row& b) {
    return std::tie(a.id, a.frame, a.line) < std::tie(b.id, b.frame, b.line);
  });
  // Report the duplicate that comes first in the file, whatever the sort order.
  int duplicate_line = std::numeric_limits<int>::max();
  size_t duplicate_index = 0;
  for (size_t i = 1; i < rows.size(); ++i) {
    if (rows[i].id == rows[i - 1].id && rows[i].frame == rows[i - 1].frame &&
        rows[i].line < duplicate_line) {
      duplicate_line = rows[i].line;
      duplicate_index = i;
    }
  }
  if (duplicate_line != std::numeric_limits<int>::max()) {
    const Row& dup = rows[duplicate_index];
    char when[64];
    if (layout.timed) {
      std::snprintf(when, sizeof(when), "time %.3f s", static_cast<double>(dup.frame) * kTimeQuantum_s);
    } else {
      std::snprintf(when, sizeof(when), "frame %lld", static_cast<long long>(dup.frame));
    }
    return Status::AtLine(file_name, dup.line,
                          "duplicate row for " + std::string(when) + ", pedestrian " +
                              std::to_string(dup.id) + " (first at line " +
                              std::to_string(rows[duplicate_index - 1].line) + ")");
  }

  TrajectoryTable table;
  table.seconds_per_frame = layout.timed ? kTimeQuantum_s : 0.0;
  table.frame_step = usual_frame_step(rows);
  table.first_frame = rows[0].frame;
  table.frames.reserve(rows.size());
  table.positions.reserve(rows.size());
  for (size_t i = 0; i < rows.size(); ++i) {
    if (i == 0 || rows[i].id != rows[i - 1].id) {
      table.ped_ids.push_back(rows[i].id);
      table.track_begin.push_back(static_cast<uint32_t>(i));
    }
    table.frames.push_back(rows[i].frame);
    table.positions.push_back(rows[i].position);
    table.first_frame = std::min(table.first_frame, rows[i].frame);
  }
  table.track_begin.push_back(static_cast<uint32_t>(rows.size()));
  return table;
}

Result<TrajectoryTable> read_trajectory_file(const std::string& path) {
  Result<std::string> text = read_file_bytes(path, kMaxFileBytes, "trajectory file");
  if (!text.ok()) return text.status();
  return parse_trajectory_text(*text, path);
}

}  // namespace gk
