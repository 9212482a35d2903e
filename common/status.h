#pragma once
// Errors from outside the program (files, command line, scenario JSON, a simulator's NaN) travel as
// a Status or Result<T> carrying where it happened and what was expected, e.g.
//   "walk.bvh:112: expected 96 channel values, found 93".
// Programmer errors use assert(); nothing read from outside may crash the program.

#include <cassert>
#include <optional>
#include <string>
#include <utility>

namespace gk {

class [[nodiscard]] Status {
 public:
  Status() = default;  // ok
  static Status Ok() { return Status(); }
  static Status Error(std::string message) {
    Status s;
    s.message_ = std::move(message);
    s.ok_ = false;
    return s;
  }
  // "file:line: what" (line <= 0 leaves it out).
  static Status AtLine(const std::string& file, int line, const std::string& what) {
    if (line > 0) return Error(file + ":" + std::to_string(line) + ": " + what);
    return Error(file + ": " + what);
  }
  // "file: field: what" for structured formats (JSON, glTF).
  static Status AtField(const std::string& file, const std::string& field,
                        const std::string& what) {
    return Error(file + ": " + field + ": " + what);
  }

  bool ok() const { return ok_; }
  explicit operator bool() const { return ok_; }
  const std::string& message() const { return message_; }

 private:
  bool ok_ = true;
  std::string message_;
};

template <typename T>
class [[nodiscard]] Result {
 public:
  Result(T value) : value_(std::move(value)) {}  // NOLINT: implicit by design
  Result(Status status) : status_(std::move(status)) { assert(!status_.ok()); }  // NOLINT

  bool ok() const { return value_.has_value(); }
  explicit operator bool() const { return ok(); }
  const Status& status() const { return status_; }
  const std::string& message() const { return status_.message(); }

  T& value() & {
    assert(ok());
    return *value_;
  }
  const T& value() const& {
    assert(ok());
    return *value_;
  }
  T&& value() && {
    assert(ok());
    return std::move(*value_);
  }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }
  T& operator*() & { return value(); }
  const T& operator*() const& { return value(); }

 private:
  std::optional<T> value_;
  Status status_;
};

}  // namespace gk

namespace gk {
inline const Status& StatusOf(const Status& s) { return s; }
template <typename T>
const Status& StatusOf(const Result<T>& r) {
  return r.status();
}
}  // namespace gk

// Propagate a failed Status/Result from a function returning Status or Result<U>.
#define GK_RETURN_IF_ERROR(expr)                                   \
  do {                                                             \
    const auto& gk_status_or_ = (expr);                            \
    if (!gk_status_or_.ok()) return ::gk::StatusOf(gk_status_or_); \
  } while (0)
