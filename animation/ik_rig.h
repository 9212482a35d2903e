#pragma once
// IK-style rigs: feet (or toes) that are not children of the shins (or feet) but hang from the
// root or the hips and follow IK targets in the tool that authored them. Clip analysis, pose
// synthesis and the mediator's two-bone IK work on the chain hip -> knee -> ankle -> toe, so such
// a rig is rebuilt at load with each foot under its shin and each toe under its foot: the rest
// pose and every key of every clip are re-expressed relative to the new parent (new local =
// inverse(new parent's model transform) * model transform), the joints reordered so that parents
// come first, and the mesh's joint indices and inverse bind matrices follow the new order. Every
// joint keeps its model-space transform on every frame, so skinning (model x inverse bind) draws
// exactly what the file draws.

#include <string>

#include "animation/clip.h"

namespace gk {

// Re-parents the IK-style feet and toes of `set` (found by the roles; detect_joint_roles pairs an
// IK-style foot with its shin by the rest pose). Returns what was done, one phrase per joint
// ("foot_l under calf_l (was under root)"), or "" when the legs already are chains.
std::string attach_ik_feet(ClipSet* set);

// Feet without toe joints (the foot ends a chain at an End Site, as many BVH rigs have it): each
// such foot gets a toe joint at its End Site, fixed to the foot (no channels of its own), that
// takes the toe role, so the leg is a full hip -> knee -> ankle -> toe chain and the foot rolls
// about its tip. Only where the ankle role is found, the toe role is not, the foot has no child
// joint and its End Site is at least 2 cm away. Returns what was done ("LeftFoot_tip at the End
// Site of LeftFoot"), or "".
std::string add_end_site_toes(ClipSet* set);

}  // namespace gk
