#pragma once
// Whitespace-separated token scanner over text in memory that tracks line numbers (LF or CRLF,
// tabs or spaces), for the BVH loader's error messages. Private to animation/.

#include <charconv>
#include <cmath>
#include <cstdint>
#include <string_view>
#include <system_error>

namespace gk::internal {

class TextScanner {
 public:
  explicit TextScanner(std::string_view text) : text_(text) {}

  // Next token, or an empty view at the end of the text. line() is then the token's line, or at
  // the end the line of the last token (where a truncated file stops making sense).
  std::string_view next() {
    skip_space(/*stop_at_newline=*/false);
    const size_t start = pos_;
    while (pos_ < text_.size() && !is_space(text_[pos_])) ++pos_;
    if (pos_ > start) token_line_ = line_;
    return text_.substr(start, pos_ - start);
  }
  // Next token on the current line only (empty when the line ends first).
  std::string_view next_on_line() {
    skip_space(/*stop_at_newline=*/true);
    const size_t start = pos_;
    while (pos_ < text_.size() && !is_space(text_[pos_])) ++pos_;
    token_line_ = line_;
    return text_.substr(start, pos_ - start);
  }
  // The rest of the current line, trimmed (joint names may contain spaces).
  std::string_view rest_of_line() {
    skip_space(/*stop_at_newline=*/true);
    const size_t start = pos_;
    while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
    size_t end = pos_;
    while (end > start && is_space(text_[end - 1])) --end;
    token_line_ = line_;
    return text_.substr(start, end - start);
  }
  // Moves past the end of the current line.
  void skip_line() {
    while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
    if (pos_ < text_.size()) {
      ++pos_;
      ++line_;
    }
  }
  bool at_end() const { return pos_ >= text_.size(); }
  int line() const { return token_line_; }
  int current_line() const { return line_; }
  size_t bytes_left() const { return text_.size() - pos_; }

 private:
  static bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }
  void skip_space(bool stop_at_newline) {
    while (pos_ < text_.size() && is_space(text_[pos_])) {
      if (text_[pos_] == '\n') {
        if (stop_at_newline) return;
        ++line_;
      }
      ++pos_;
    }
  }

  std::string_view text_;
  size_t pos_ = 0;
  int line_ = 1;
  int token_line_ = 1;
};

enum class NumberParse { kOk, kNotANumber, kNotFinite };

// Parses the whole token as a decimal number ("nan" and "inf" parse but are reported separately).
inline NumberParse parse_double(std::string_view token, double* out) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return NumberParse::kNotANumber;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), *out);
  if (end != token.data() + token.size()) return NumberParse::kNotANumber;
  if (ec == std::errc::result_out_of_range) return NumberParse::kNotFinite;  // e.g. 1e999
  if (ec != std::errc()) return NumberParse::kNotANumber;
  return std::isfinite(*out) ? NumberParse::kOk : NumberParse::kNotFinite;
}

inline bool parse_int64(std::string_view token, int64_t* out) {
  if (token.empty()) return false;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), *out);
  return ec == std::errc() && end == token.data() + token.size();
}

}  // namespace gk::internal
