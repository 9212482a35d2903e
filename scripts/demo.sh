#!/usr/bin/env bash
# Sets up a fresh Debian 12 machine (scripts/setup.sh: packages + build), then starts Gaitkeeper on
# its built-in data (procedural clips and mannequin, the gallery scenario): the interactive window
# when a display is available, otherwise a side-by-side naive | apm video rendered offscreen.
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
"$gk" render --scenario gallery --frames 300 --compare --out out/demo.mp4 "$@"
"$gk" render --scenario gallery --frames 300 --compare --out out/demo.png "$@"
echo
echo "== gaitkeeper bench --scenario gallery --mode naive | apm  (the same crowd, measured)"
"$gk" bench --scenario gallery --mode naive | grep -E "foot slide|v2 feet|torsion"
"$gk" bench --scenario gallery --mode apm | grep -E "foot slide|v2 feet|torsion"
echo
echo "Wrote out/demo.mp4 and out/demo.png (left: naive, right: apm). Run it with a display"
echo "for the window, or see: $gk --help"
