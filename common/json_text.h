#pragma once
// Parsing JSON read from a file, for the modules that link nlohmann-json (scenarios, mediator
// parameters, role manifests). nlohmann reports a syntax error as parse_error but a number too
// large for a double ("1e400") as out_of_range; both become a Status naming the file, the line
// and column and what was expected, with any quoted file content made printable.

#include <cstddef>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "common/status.h"
#include "common/text_snippet.h"

namespace gk {

namespace internal {

// A SAX handler that accepts every value and records where the parser gave up: nlohmann's
// out_of_range errors carry no position, so a second, failing pass finds it.
class JsonErrorLocator : public nlohmann::json_sax<nlohmann::json> {
 public:
  using json = nlohmann::json;
  bool null() override { return true; }
  bool boolean(bool) override { return true; }
  bool number_integer(json::number_integer_t) override { return true; }
  bool number_unsigned(json::number_unsigned_t) override { return true; }
  bool number_float(json::number_float_t, const json::string_t&) override { return true; }
  bool string(json::string_t&) override { return true; }
  bool binary(json::binary_t&) override { return true; }
  bool start_object(std::size_t) override { return true; }
  bool key(json::string_t&) override { return true; }
  bool end_object() override { return true; }
  bool start_array(std::size_t) override { return true; }
  bool end_array() override { return true; }
  bool parse_error(std::size_t position, const std::string& last_token,
                   const json::exception&) override {
    position_ = position;
    last_token_ = last_token;
    return false;
  }
  std::size_t position() const { return position_; }
  const std::string& last_token() const { return last_token_; }

 private:
  std::size_t position_ = 0;
  std::string last_token_;
};

// "line L, column C" of the byte just before `position` (the end of the offending token).
inline std::string json_text_location(std::string_view text, std::size_t position) {
  const std::size_t end = position < text.size() ? position : text.size();
  std::size_t line = 1, line_start = 0;
  for (std::size_t i = 0; i + 1 < end; ++i) {
    if (text[i] == '\n') ++line, line_start = i + 1;
  }
  return "line " + std::to_string(line) + ", column " + std::to_string(end - line_start);
}

// The exception's message without nlohmann's "[json.exception.parse_error.101] " prefix.
inline std::string json_message(const nlohmann::json::exception& e) {
  std::string what = e.what();
  if (const std::size_t at = what.find("] "); at != std::string::npos) what = what.substr(at + 2);
  return printable_snippet(what, 300);
}

}  // namespace internal

// Parses `text` read from `file` (`file` only labels the errors):
//   "s.json: invalid JSON: parse error at line 3, column 5: ..."
//   "s.json: invalid JSON: number too large at line 2, column 24: '1e400' (expected a number
//    within +-1.7e308, the range of a double)"
inline Result<nlohmann::json> parse_json_text(std::string_view text, const std::string& file,
                                              bool ignore_comments = false) {
  using json = nlohmann::json;
  try {
    return json::parse(text.begin(), text.end(), nullptr, /*allow_exceptions=*/true,
                       ignore_comments);
  } catch (const json::parse_error& e) {
    return Status::Error(file + ": invalid JSON: " + internal::json_message(e));
  } catch (const json::exception& e) {
    internal::JsonErrorLocator locator;
    bool located = false;
    try {
      located = !json::sax_parse(text.begin(), text.end(), &locator, json::input_format_t::json,
                                 /*strict=*/true, ignore_comments);
    } catch (const json::exception&) {
      located = false;
    }
    const std::string where =
        located ? " at " + internal::json_text_location(text, locator.position()) : "";
    if (e.id == 406) {  // out_of_range.406: "number overflow parsing '1e400'"
      const std::string number =
          located ? quoted_snippet(locator.last_token()) : internal::json_message(e);
      return Status::Error(file + ": invalid JSON: number too large" + where + ": " + number +
                           " (expected a number within +-1.7e308, the range of a double)");
    }
    return Status::Error(file + ": invalid JSON" + where + ": " + internal::json_message(e));
  }
}

}  // namespace gk
