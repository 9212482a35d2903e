#!/usr/bin/env bash
# Scaling with and without level of detail (issue #11): per rig (built-in clips, the two CMU BVH
# clips, the glTF mannequin), 1,000 / 10,000 / 100,000 agents of the plaza, 1 and 2 threads, LOD
# off and on (`--lod`, default distances 15,30,60 m from the scenario's centre): the median ms of
# sim, mediator, pose and the whole frame, the agents at each level, and the v2 support slide of
# the agents the metrics cover (all without LOD, level 0 with it). Then `bench --render` (built-in
# clips, offscreen) at 100 / 1,000 / 5,000 agents with and without --lod. Writes bench/scale.md
# (SCALE_OUT) and keeps the JSON reports in SCALE_DIR. Wall-clock medians: run it on an idle
# machine; the load average at the start and the end is written into the table's notes.
# Usage: bench/scale.sh [--quick]   (--quick: 1,000 and 10,000 agents only, fewer frames)
#        SCALE_AGENTS="1000 10000" SCALE_RIGS="builtin" SCALE_THREADS="2" bench/scale.sh
# Needs jq and a built ./build/app/gaitkeeper.
set -euo pipefail
cd "$(dirname "$0")/.."
gk=${GAITKEEPER:-./build/app/gaitkeeper}
data=${GAITKEEPER_DATA:-$(cd .. && pwd)/shared/data}
out=${SCALE_OUT:-bench/scale.md}
dir=${SCALE_DIR:-build/scale}
agents_list=${SCALE_AGENTS:-"1000 10000 100000"}
rigs=${SCALE_RIGS:-"builtin cmu mannequin"}
threads_list=${SCALE_THREADS:-"1 2"}
render_list=${SCALE_RENDER_AGENTS:-"100 1000 5000"}
if [[ ${1:-} == --quick ]]; then
  agents_list=${SCALE_AGENTS:-"1000 10000"}
  render_list=${SCALE_RENDER_AGENTS:-"100 1000"}
elif [[ $# -gt 0 ]]; then
  echo "scale.sh: unknown option $1" >&2
  exit 2
fi
command -v jq >/dev/null || { echo "scale.sh: needs jq (apt-get install jq)" >&2; exit 2; }
[[ -x $gk ]] || { echo "scale.sh: $gk not built (run scripts/setup.sh)" >&2; exit 2; }
mkdir -p "$dir"

declare -A clipsets=(
  [builtin]=""
  [cmu]="--clips $data/clips/bvh/cmu_07_01_walk.bvh $data/clips/bvh/cmu_09_11_run.bvh"
  [mannequin]="--clips $data/clips/gltf/ual_mannequin_quaternius.glb"
)
# Frames per run: the first 30 are warm-up (untimed); 100,000 agents take a second or more a
# frame without LOD, so they get the fewest.
frames_for() {
  if (($1 >= 100000)); then echo 45; elif (($1 >= 10000)); then echo 90; else echo 240; fi
}
ms() { jq -r "if .timing_ms.$2 == null then \"-\" else (.timing_ms.$2.median * 100 | round / 100 | tostring) end" "$1"; }

load_start=$(cut -d' ' -f1-3 /proc/loadavg)
started=$(date -u +%H:%M)
{
  echo "| rig | agents | threads | lod | sim ms | mediator ms | pose ms | total ms | agents per level 0/1/2/3 | updated per frame | support slide cm/s (metrics cover) |"
  echo "|---|---|---|---|---|---|---|---|---|---|---|"
} > "$out.tmp"
total=0
for _ in $rigs; do for _ in $agents_list; do for _ in $threads_list; do total=$((total + 2)); done; done; done
k=0
for rig in $rigs; do
  for n in $agents_list; do
    for t in $threads_list; do
      for lod in off on; do
        k=$((k + 1))
        json="$dir/${rig}_${n}_t${t}_lod${lod}.json"
        lod_args=""
        [[ $lod == on ]] && lod_args="--lod"
        frames=$(frames_for "$n")
        echo "[$k/$total] $rig, $n agents, $t thread(s), lod $lod, $frames frames" >&2
        # shellcheck disable=SC2086
        if ! $gk bench --scenario plaza --agents "$n" --threads "$t" --frames "$frames" \
            ${clipsets[$rig]} $lod_args --json "$json" >/dev/null 2>"$json.err"; then
          echo "| $rig | $n | $t | $lod | failed: $(tail -1 "$json.err") |||||||" >> "$out.tmp"
          continue
        fi
        levels=$(jq -r 'if .lod == null then "-" else (.lod.mean_agents_per_level | map(round | tostring) | join(" / ")) end' "$json")
        updated=$(jq -r 'if .lod == null then .agents else (.lod.mean_agents_updated | round) end' "$json")
        cover=$(jq -r 'if .lod == null then "all" else "level 0" end' "$json")
        slide=$(jq -r '.metrics.support_slide_cm_s // "n/a" | if type == "number" then (. * 100 | round / 100) else . end' "$json")
        echo "| $rig | $n | $t | $lod | $(ms "$json" sim) | $(ms "$json" mediator) | $(ms "$json" pose) | $(ms "$json" total) | $levels | $updated | $slide ($cover) |" >> "$out.tmp"
      done
    done
  done
done

{
  echo
  echo "| render: agents | lod | sim ms | mediator ms | pose ms | upload ms | render ms | total ms |"
  echo "|---|---|---|---|---|---|---|---|"
} >> "$out.tmp"
for n in $render_list; do
  for lod in off on; do
    json="$dir/render_${n}_lod${lod}.json"
    lod_args=""
    [[ $lod == on ]] && lod_args="--lod"
    echo "[render] $n agents, lod $lod" >&2
    # shellcheck disable=SC2086
    if ! $gk bench --scenario plaza --agents "$n" --threads 2 --frames 120 --render $lod_args \
        --json "$json" >/dev/null 2>"$json.err"; then
      echo "| $n | $lod | failed: $(tail -1 "$json.err") ||||||" >> "$out.tmp"
      continue
    fi
    echo "| $n | $lod | $(ms "$json" sim) | $(ms "$json" mediator) | $(ms "$json" pose) | $(ms "$json" upload) | $(ms "$json" render) | $(ms "$json" total) |" >> "$out.tmp"
  done
done

{
  echo
  echo "Measured $(date -u +%Y-%m-%d) from $started UTC by bench/scale.sh on $(nproc) cores; load average"
  echo "$load_start at the start, $(cut -d' ' -f1-3 /proc/loadavg) at the end (wall-clock medians: a"
  echo "loaded machine inflates every stage). Plaza scenario, 60 Hz, LOD distances 15 / 30 / 60 m from"
  echo "the scenario's centre; levels are updated every 1 / 2 / 4 / 8 frames (docs/pipeline.md)."
  echo "This run: rigs $rigs; agents $agents_list; threads $threads_list; render at $render_list agents."
} >> "$out.tmp"
mv "$out.tmp" "$out"
cat "$out"
