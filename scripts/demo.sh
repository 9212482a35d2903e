#!/usr/bin/env bash
# Sets up a fresh Debian 12 machine (scripts/setup.sh: packages + build), then starts Gaitkeeper on
# its built-in data (procedural clips and mannequin): the interactive window's showcase when a
# display is available (the bottleneck's door, naive | apm, the camera close on a queuing agent,
# then the whole room), otherwise the same shot as a side-by-side video rendered offscreen.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
gk=./build/app/gaitkeeper
if [[ -n "${DISPLAY:-}${WAYLAND_DISPLAY:-}" ]]; then
  echo "== gaitkeeper (the demo window; close it to quit)"
  exec "$gk" "$@"
fi
echo "== no display: rendering the demo offscreen instead"
mkdir -p out
# The window's showcase: agent 18 is the one nearest the middle of the room (the window picks it the
# same way), seen from the side (yaw 180) from 8 m; 10 s close on it as it queues at the door, then
# 3 s pulling out to the whole room.
shot=(--scenario bottleneck --compare --overlay trails --follow 18 --camera 180,31.5,8)
"$gk" render "${shot[@]}" --frames 780 --pull-out 10 --out out/demo.mp4 "$@"
"$gk" render "${shot[@]}" --frames 300 --out out/demo.png "$@"
echo
echo "== gaitkeeper bench --scenario bottleneck --mode naive | apm  (the same crowd, measured)"
"$gk" bench --scenario bottleneck --mode naive | grep -E "foot slide|v2 feet|torsion"
"$gk" bench --scenario bottleneck --mode apm | grep -E "foot slide|v2 feet|torsion"
echo
echo "Wrote out/demo.mp4 and out/demo.png (left: naive, right: apm). Run it with a display"
echo "for the window, or see: $gk --help"
echo "Lessons, one idea off | on each: $gk render --lesson NAME --out FILE.png|FILE.mp4"
echo "  (foot-sliding, playback-rate, foot-locking, torso-decoupling, feedback; in the window:"
echo "  the Lessons menu, or $gk demo --lesson NAME)"
