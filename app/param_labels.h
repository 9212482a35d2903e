#pragma once
// Plain-language names of the mediator parameters for the demo panel (the identifier of
// mediator/params.h stays in the tooltip, and is what --set and the JSON files use).


namespace gk::app {

// "Max torso twist" for "torsion_limit_deg"; `name` itself for a parameter without one. A string
// literal (or `name`): the panel draws it every frame without building a string.
const char* param_label(const char* name);

}  // namespace gk::app
