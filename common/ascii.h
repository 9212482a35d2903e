#pragma once
// ASCII case folding for names, keywords and file extensions (never for text shown back to a
// user): bytes outside A-Z pass through unchanged, whatever the locale.

#include <string>
#include <string_view>

namespace gk {

inline std::string lower_ascii(std::string_view s) {
  std::string out(s);
  for (char& c : out) {
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  }
  return out;
}

}  // namespace gk
