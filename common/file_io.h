#pragma once
// Files from outside: reading a whole input file, and checking an output path before the work
// starts. Errors name the path and say what was expected ("x.txt: is a directory, expected a
// trajectory file"), so a folder, a device or a missing folder never reaches a parser or a writer.

#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>

#include "common/status.h"

namespace gk {

// "1 GiB", "16 MiB", "512 KiB" or "100 bytes" (exact multiples only, else bytes).
inline std::string byte_size_text(uint64_t bytes) {
  if (bytes > 0 && bytes % (uint64_t(1) << 30) == 0) return std::to_string(bytes >> 30) + " GiB";
  if (bytes > 0 && bytes % (uint64_t(1) << 20) == 0) return std::to_string(bytes >> 20) + " MiB";
  if (bytes > 0 && bytes % (uint64_t(1) << 10) == 0) return std::to_string(bytes >> 10) + " KiB";
  return std::to_string(bytes) + " bytes";
}

// Ok when `path` names an existing regular file (or a link to one); `what` names the expected
// kind in the error ("scenario file").
inline Status check_input_file(const std::string& path, const std::string& what) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (st.type() == fs::file_type::not_found || st.type() == fs::file_type::none) {
    return Status::Error(path + ": cannot open the " + what + ": " +
                         (ec ? ec.message() : std::string("no such file")));
  }
  if (fs::is_directory(st)) return Status::Error(path + ": is a directory, expected a " + what);
  if (!fs::is_regular_file(st)) {
    return Status::Error(path + ": not a regular file (a device, pipe or socket), expected a " +
                         what);
  }
  return Status::Ok();
}

// The whole content of the regular file at `path`. Checks the kind and the size (at most
// max_bytes) before allocating; never throws.
inline Result<std::string> read_file_bytes(const std::string& path, uint64_t max_bytes,
                                           const std::string& what) {
  GK_RETURN_IF_ERROR(check_input_file(path, what));
  std::error_code ec;
  const uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) return Status::Error(path + ": cannot read the " + what + " size: " + ec.message());
  if (size > max_bytes) {
    return Status::Error(path + ": " + what + " too large (" + std::to_string(size) +
                         " bytes, expected at most " + byte_size_text(max_bytes) + ")");
  }
  try {
    std::ifstream in(path, std::ios::binary);
    if (!in) {
      return Status::Error(path + ": cannot open the " + what + ": " + std::strerror(errno));
    }
    std::string bytes(static_cast<size_t>(size), '\0');
    if (size > 0 && !in.read(bytes.data(), static_cast<std::streamsize>(size))) {
      return Status::Error(path + ": read error after " + std::to_string(in.gcount()) + " of " +
                           std::to_string(size) + " bytes");
    }
    return bytes;
  } catch (const std::exception& e) {  // std::ios_failure, std::bad_alloc
    return Status::Error(path + ": cannot read the " + what + ": " + e.what());
  }
}

namespace internal {

// The folder a file at `path` goes into ("." for a bare name).
inline std::filesystem::path parent_folder(const std::string& path) {
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  return parent.empty() ? std::filesystem::path(".") : parent;
}

inline Status check_writable_folder(const std::string& option, const std::string& path,
                                    const std::filesystem::path& folder) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(folder, ec);
  if (st.type() == fs::file_type::not_found) {
    return Status::Error(option + " " + path + ": the folder " + folder.string() +
                         " does not exist");
  }
  if (!fs::is_directory(st)) {
    return Status::Error(option + " " + path + ": " + folder.string() + " is not a folder");
  }
  if (access(folder.c_str(), W_OK | X_OK) != 0) {
    return Status::Error(option + " " + path + ": the folder " + folder.string() +
                         " is not writable (" + std::strerror(errno) + ")");
  }
  return Status::Ok();
}

}  // namespace internal

// Checks before any work that a file can be written at `path`: it is not a directory, its folder
// exists and is writable, and an existing file is writable. `option` names it ("--out").
inline Status check_output_file(const std::string& path, const std::string& option) {
  namespace fs = std::filesystem;
  if (path.empty()) return Status::Error(option + ": expected a file name");
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (fs::is_directory(st)) {
    return Status::Error(option + " " + path + ": is a directory, expected a file name");
  }
  GK_RETURN_IF_ERROR(internal::check_writable_folder(option, path, internal::parent_folder(path)));
  if (fs::exists(st) && access(path.c_str(), W_OK) != 0) {
    return Status::Error(option + " " + path + ": the file is not writable (" +
                         std::strerror(errno) + ")");
  }
  return Status::Ok();
}

// Checks before any work that `path` is a writable folder or can be created as one: an existing
// `path` must be a folder, else its nearest existing ancestor must be a writable folder.
inline Status check_output_folder(const std::string& path, const std::string& option) {
  namespace fs = std::filesystem;
  if (path.empty()) return Status::Error(option + ": expected a folder name");
  std::error_code ec;
  fs::path folder = path;
  while (true) {
    const fs::file_status st = fs::status(folder, ec);
    if (st.type() != fs::file_type::not_found) break;
    const fs::path up = folder.parent_path();
    if (up.empty() || up == folder) {
      folder = ".";
      break;
    }
    folder = up;
  }
  if (fs::exists(fs::status(path, ec)) && !fs::is_directory(fs::status(path, ec))) {
    return Status::Error(option + " " + path + ": exists and is not a folder");
  }
  return internal::check_writable_folder(option, path, folder);
}

}  // namespace gk
