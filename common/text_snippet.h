#pragma once
// Quoting file content in error messages. A binary file given as a BVH, a trajectory or JSON must
// not put raw bytes (NULs, terminal escape sequences, broken UTF-8) into a message: every loader
// that echoes what it read passes it through printable_snippet().

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace gk {

namespace internal {

// Length of the well-formed UTF-8 sequence of 2 to 4 bytes at the start of `s` that encodes a
// printable code point (no overlong forms, surrogates or C1 controls), or 0.
inline size_t printable_utf8_length(std::string_view s) {
  const auto byte = [&](size_t i) { return static_cast<uint8_t>(s[i]); };
  const auto cont = [&](size_t i, uint8_t lo = 0x80, uint8_t hi = 0xBF) {
    return i < s.size() && byte(i) >= lo && byte(i) <= hi;
  };
  const uint8_t b0 = byte(0);
  if (b0 == 0xC2) return cont(1, 0xA0) ? 2 : 0;  // U+0080..U+009F are C1 control codes
  if (b0 >= 0xC3 && b0 <= 0xDF) return cont(1) ? 2 : 0;
  if (b0 == 0xE0) return cont(1, 0xA0) && cont(2) ? 3 : 0;
  if (b0 == 0xED) return cont(1, 0x80, 0x9F) && cont(2) ? 3 : 0;  // no surrogates
  if (b0 >= 0xE1 && b0 <= 0xEF) return cont(1) && cont(2) ? 3 : 0;
  if (b0 == 0xF0) return cont(1, 0x90) && cont(2) && cont(3) ? 4 : 0;
  if (b0 >= 0xF1 && b0 <= 0xF3) return cont(1) && cont(2) && cont(3) ? 4 : 0;
  if (b0 == 0xF4) return cont(1, 0x80, 0x8F) && cont(2) && cont(3) ? 4 : 0;
  return 0;
}

}  // namespace internal

// `text` made safe to print: printable ASCII and well-formed UTF-8 stay as they are; tab, CR and LF
// become \t, \r, \n; every other byte becomes \xNN. At most `max_bytes` bytes of `text` are shown,
// then "..." marks the cut.
inline std::string printable_snippet(std::string_view text, size_t max_bytes = 40) {
  static constexpr char kHex[] = "0123456789abcdef";
  const bool cut = text.size() > max_bytes;
  if (cut) text = text.substr(0, max_bytes);
  std::string out;
  out.reserve(text.size() + 3);
  for (size_t i = 0; i < text.size();) {
    const auto c = static_cast<uint8_t>(text[i]);
    if (c >= 0x20 && c < 0x7F) {
      out += static_cast<char>(c);
      ++i;
    } else if (c == '\t' || c == '\r' || c == '\n') {
      out += c == '\t' ? "\\t" : c == '\r' ? "\\r" : "\\n";
      ++i;
    } else if (const size_t n = internal::printable_utf8_length(text.substr(i)); n > 0) {
      out.append(text.substr(i, n));
      i += n;
    } else {
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 0xF];
      ++i;
    }
  }
  if (cut) out += "...";
  return out;
}

// printable_snippet() in single quotes: the usual way to echo a token ("found 'abc'").
inline std::string quoted_snippet(std::string_view text, size_t max_bytes = 40) {
  return "'" + printable_snippet(text, max_bytes) + "'";
}

}  // namespace gk
