// libFuzzer harness: `--set name=value` strings (one per input line) through set_mediator_param,
// and the same strings as `--mode` names through parse_mediator_mode.

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "mediator/params.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view text(reinterpret_cast<const char*>(data), size);
  gk::MediatorParams params;
  while (!text.empty()) {
    const size_t eol = text.find('\n');
    const std::string_view line = text.substr(0, eol);
    (void)gk::set_mediator_param(line, &params);
    (void)gk::parse_mediator_mode(line);
    if (eol == std::string_view::npos) break;
    text.remove_prefix(eol + 1);
  }
  return 0;
}
