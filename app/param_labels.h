#pragma once
// Plain-language names of the mediator parameters for the demo panel (the identifier of
// mediator/params.h stays in the tooltip, and is what --set and the JSON files use).

#include <string_view>

namespace gk::app {

// "Max torso twist" for "torsion_limit_deg"; the identifier itself for a parameter without one.
std::string_view param_label(std::string_view name);

}  // namespace gk::app
