// libFuzzer harness: a mediator parameter file (JSON object of name: value) through
// parse_mediator_params_json.

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "mediator/params.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  gk::MediatorParams params;
  (void)gk::parse_mediator_params_json(text, "fuzz.json", &params);
  return 0;
}
