#include "crowd/trajectory_file.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <tuple>

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

// Splits a line on spaces/tabs into at most `max_tokens` tokens; returns the total token count
// (which may exceed max_tokens, to report it).
int split_tokens(std::string_view line, std::string_view* out_tokens, int max_tokens) {
  int count = 0;
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

Status parse_number(std::string_view token, const char* column, const std::string& file, int line,
                    double* out_value) {
  double value = 0.0;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (ec != std::errc() || end != token.data() + token.size()) {
    return Status::AtLine(
        file, line, std::string(column) + ": expected a number, found " + quoted_snippet(token));
  }
  if (!std::isfinite(value)) {
    return Status::AtLine(
        file, line,
        std::string(column) + ": expected a finite number, found " + quoted_snippet(token));
  }
  *out_value = value;
  return Status::Ok();
}

// The two layouts a trajectory file may have, by their column count (all of a file's rows alike):
// 4, the common one of the Social-LSTM/GAN releases; 8, the ETH (BIWI) authors' obsmat.txt, whose
// ground plane is (pos_x, pos_y) and whose pos_z and velocity columns are not used (the replay
// derives velocity from the positions).
constexpr const char* kLayouts =
    "expected 4 numbers (frame id x y) or 8 (ETH obsmat: frame id pos_x pos_z pos_y v_x v_z v_y)";

// `columns`: the file's layout, 0 until its first row sets it.
Status parse_row(std::string_view text, const std::string& file, int line, int* columns,
                 Row* out_row) {
  constexpr int kMaxTokens = 8;
  std::string_view tokens[kMaxTokens];
  const int count = split_tokens(text, tokens, kMaxTokens);
  if (count != 4 && count != 8) {
    return Status::AtLine(file, line, std::string(kLayouts) + ", found " + std::to_string(count));
  }
  if (*columns == 0) *columns = count;
  if (count != *columns) {
    return Status::AtLine(file, line,
                          "expected " + std::to_string(*columns) +
                              " numbers as on the file's first row, found " +
                              std::to_string(count));
  }
  static constexpr const char* kColumns[4] = {"column 1 (frame)", "column 2 (id)",
                                              "column 3 (x)", "column 4 (y)"};
  static constexpr const char* kObsmatColumns[8] = {
      "column 1 (frame)", "column 2 (id)",  "column 3 (pos_x)", "column 4 (pos_z)",
      "column 5 (pos_y)", "column 6 (v_x)", "column 7 (v_z)",   "column 8 (v_y)"};
  const char* const* names = count == 8 ? kObsmatColumns : kColumns;
  double values[kMaxTokens];
  for (int c = 0; c < count; ++c) {
    GK_RETURN_IF_ERROR(parse_number(tokens[c], names[c], file, line, &values[c]));
  }
  // Ground-plane columns: x and y, or obsmat's pos_x and pos_y.
  const int gx = 2, gy = count == 8 ? 4 : 3;
  if (values[0] < 0.0 || values[0] > kMaxFrame || values[0] != std::floor(values[0])) {
    return Status::AtLine(file, line,
                          "column 1 (frame): expected a whole number in [0, 2^31), found " +
                              quoted_snippet(tokens[0]));
  }
  if (values[1] < 0.0 || values[1] > kMaxId || values[1] != std::floor(values[1])) {
    return Status::AtLine(
        file, line,
        "column 2 (id): expected a whole number in [0, 2^32), found " + quoted_snippet(tokens[1]));
  }
  for (const int c : {gx, gy}) {
    if (std::abs(values[c]) > kMaxCoordinate_m) {
      return Status::AtLine(file, line,
                            std::string(names[c]) + ": expected a coordinate within +-1e5 m, " +
                                "found " + quoted_snippet(tokens[c]));
    }
  }
  out_row->frame = static_cast<int64_t>(values[0]);
  out_row->id = static_cast<uint32_t>(values[1]);
  out_row->position = glm::vec2(static_cast<float>(values[gx]), static_cast<float>(values[gy]));
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
  int columns = 0;  // the file's layout (4 or 8), set by its first row
  while (pos < text.size()) {
    size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view line_text = text.substr(pos, end - pos);
    pos = end + 1;
    ++line;
    if (std::all_of(line_text.begin(), line_text.end(), is_space)) continue;  // blank line
    Row row{};
    GK_RETURN_IF_ERROR(parse_row(line_text, file_name, line, &columns, &row));
    rows.push_back(row);
  }
  if (rows.empty()) {
    return Status::AtLine(file_name, std::max(line, 1),
                          std::string("no trajectory rows: ") + kLayouts + " per line");
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
    return Status::AtLine(file_name, dup.line,
                          "duplicate row for frame " + std::to_string(dup.frame) + ", pedestrian " +
                              std::to_string(dup.id) + " (first at line " +
                              std::to_string(rows[duplicate_index - 1].line) + ")");
  }

  TrajectoryTable table;
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
