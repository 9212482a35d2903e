#!/usr/bin/env bash
# Soak test: runs `gaitkeeper bench` for an hour of simulated time per leg (216,000 frames at
# 60 Hz) with agents entering and leaving, and checks that a long run stays healthy:
#   scenario leg: bench/soak_square.json at 1,000 agents with --loop: an open square whose
#                 agents walk one to five random goals and leave (`"at_goal": "remove"`); when
#                 the last has left a new round comes in (about every 7 simulated minutes);
#                 `--scenario bottleneck` (data/scenarios) is another, with ~40-minute rounds;
#   replay leg:   an ETH/UCY file replayed with --loop: pedestrians enter and leave with the
#                 data, and the file starts over, bringing every id back as a new agent.
# bench prints a JSON line every --every frames (bench --progress-every); they are gathered into
# OUT/soak.csv and checked per leg, after a warm-up of the first tenth of the leg (at least a
# simulated minute, at most half the leg):
#   - memory: resident memory (VmRSS) stays within 5% of its first value after warm-up;
#   - NaN: no NaN or infinity in the crowd, the world poses or the measured joints;
#   - tracks: the metrics follow no more tracks than there are live agents (released on leave);
#   - time: the median CPU time per agent-frame of the pipeline (sim + mediator + pose; process
#     CPU time, which a busy shared machine disturbs far less than wall time) over the last half
#     of the busy windows after warm-up (at least half the most agents seen) is within
#     --max-drift-pct of that of the first half.
# OUT/soak.png plots memory and time per frame over the run (gnuplot; skipped with a note when
# it is missing: scripts/setup.sh installs it). Exit 0 when every check passes, 1 when one fails,
# 2 on a usage or run error.
#
# Usage: bench/soak.sh [--sim-minutes M] [--agents N] [--scenario NAME] [--replay FILE|none]
#                      [--every F] [--out DIR] [--max-drift-pct P] [--max-rss-mib M]
#                      [--max-wall-minutes W] [-- BENCH OPTIONS...]
# Defaults: 60 simulated minutes per leg, 1000 agents, bench/soak_square.json, the zara1 file of
# $GAITKEEPER_DATA (default ../shared/data), a line every 600 frames (10 s), build/soak, drift
# 10%, 4096 MiB (the run stops there), no wall-time limit (a leg stopped by --max-wall-minutes is
# checked on what it ran and reported as partial). Options after -- go to every bench run, e.g.
# -- --threads 2 --clips ../shared/data/clips/bvh/cmu_07_01_walk.bvh. $GAITKEEPER_BIN overrides
# the program (default build/app/gaitkeeper).
set -euo pipefail
cd "$(dirname "$0")/.."

sim_minutes=60
agents=1000
scenario=bench/soak_square.json
data=${GAITKEEPER_DATA:-../shared/data}
replay="$data/trajectories/zara1/crowds_zara01.txt"
every=600
out=build/soak
max_drift_pct=10
max_rss_mib=4096
max_wall_minutes=0
while (($#)); do
  case "$1" in
    --sim-minutes) sim_minutes=$2; shift 2 ;;
    --agents) agents=$2; shift 2 ;;
    --scenario) scenario=$2; shift 2 ;;
    --replay) replay=$2; shift 2 ;;
    --every) every=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --max-drift-pct) max_drift_pct=$2; shift 2 ;;
    --max-rss-mib) max_rss_mib=$2; shift 2 ;;
    --max-wall-minutes) max_wall_minutes=$2; shift 2 ;;
    --) shift; break ;;
    -h | --help) sed -n '2,31p' "$0"; exit 0 ;;
    *) echo "soak: unknown option $1 (see --help)" >&2; exit 2 ;;
  esac
done
number='^[0-9]+([.][0-9]+)?$'
if ! [[ "$sim_minutes" =~ $number && "$max_drift_pct" =~ $number &&
  "$max_wall_minutes" =~ $number && "$agents" =~ ^[0-9]+$ && "$every" =~ ^[1-9][0-9]*$ &&
  "$max_rss_mib" =~ ^[1-9][0-9]*$ ]]; then
  echo "soak: --sim-minutes, --max-drift-pct and --max-wall-minutes take numbers; --agents," \
    "--every and --max-rss-mib whole numbers (--every and --max-rss-mib > 0)" >&2
  exit 2
fi
bin=${GAITKEEPER_BIN:-./build/app/gaitkeeper}
if [[ ! -x "$bin" ]]; then
  echo "soak: $bin not found: build it first (scripts/setup.sh)" >&2
  exit 2
fi
frames=$(awk -v m="$sim_minutes" 'BEGIN { printf "%d", m * 3600 }')
if ((frames < 2 * every)); then
  echo "soak: --sim-minutes $sim_minutes gives $frames frames: fewer than two lines of --every $every" >&2
  exit 2
fi
mkdir -p "$out"
csv="$out/soak.csv"
echo "leg,frame,sim_time_s,wall_s,live_agents,live_tracks,frame_ms,frame_ms_max,wall_ms_per_frame,us_per_agent_frame,rss_kib,non_finite,cpu_ms,cpu_us_per_agent_frame" >"$csv"

pid=
cleanup() {
  if [[ -n "$pid" ]] && kill -0 "$pid" 2>/dev/null; then kill "$pid" 2>/dev/null || true; fi
}
trap cleanup EXIT

# Runs one leg: bench in the background, its progress lines appended to the CSV, a watchdog on
# its memory and wall time. Sets leg_note to "" (complete) or why it stopped early.
run_leg() {
  local leg=$1
  shift
  local log="$out/$leg.log"
  echo "soak: $leg: $bin bench $* --frames $frames --progress-every $every"
  nice -n 19 "$bin" bench "$@" --frames "$frames" --progress-every "$every" >"$log" 2>&1 &
  pid=$!
  local start=$SECONDS rss
  leg_note=""
  while kill -0 "$pid" 2>/dev/null; do
    sleep 1
    rss=$(awk '/^VmRSS:/ { print $2 }' "/proc/$pid/status" 2>/dev/null || true)
    if [[ -n "$rss" ]] && ((rss > max_rss_mib * 1024)); then
      leg_note="stopped: RSS passed --max-rss-mib $max_rss_mib"
      kill "$pid" 2>/dev/null || true
    elif awk -v w="$max_wall_minutes" -v s=$((SECONDS - start)) 'BEGIN { exit !(w > 0 && s >= w * 60) }'; then
      leg_note="partial: stopped by --max-wall-minutes $max_wall_minutes"
      kill "$pid" 2>/dev/null || true
    fi
  done
  local code=0
  wait "$pid" || code=$?
  pid=
  if [[ -z "$leg_note" && $code -ne 0 ]]; then
    echo "soak: $leg: bench failed (exit $code):" >&2
    grep -v '^{' "$log" | tail -5 >&2
    exit 2
  fi
  # {"frame": 600, "sim_time_s": 10.000, ...} -> one CSV row, each value found by its key.
  grep '^{' "$log" | awk -v leg="$leg" '
    function val(key) {
      if (!match($0, "\"" key "\": [-0-9.e+]+")) return ""
      return substr($0, RSTART + length(key) + 4, RLENGTH - length(key) - 4)
    }
    {
      printf "%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%d,%s,%s\n", leg, val("frame"), val("sim_time_s"),
             val("wall_s"), val("live_agents"), val("live_tracks"), val("frame_ms"),
             val("frame_ms_max"), val("wall_ms_per_frame"), val("us_per_agent_frame"),
             val("rss_kib"), val("crowd") + val("poses") + val("joints"), val("cpu_ms"),
             val("cpu_us_per_agent_frame")
    }' >>"$csv"
}

legs=()
run_leg scenario --scenario "$scenario" --agents "$agents" --loop "$@"
legs+=("scenario:$leg_note")
if [[ "$replay" != none ]]; then
  if [[ -f "$replay" ]]; then
    run_leg replay --scenario "$replay" --loop "$@"
    legs+=("replay:$leg_note")
  else
    echo "soak: replay leg skipped: $replay not found (set GAITKEEPER_DATA or --replay FILE|none)"
  fi
fi

# The checks, per leg.
status=0
for entry in "${legs[@]}"; do
  leg=${entry%%:*}
  note=${entry#*:}
  awk -F, -v leg="$leg" -v note="$note" -v drift_max="$max_drift_pct" '
    $1 != leg { next }
    { n++; t[n] = $3; live[n] = $5; tracks[n] = $6; us[n] = $14; rss[n] = $11; bad += $12
      if ($6 > $5) extra++ }
    END {
      if (n < 2) { printf "soak: %s: FAIL: only %d progress lines\n", leg, n; exit 1 }
      last_t = t[n]
      warm = last_t / 10; if (warm < 60) warm = 60; if (warm > last_t / 2) warm = last_t / 2
      for (i = 1; i <= n && t[i] < warm; i++) {}
      first = i
      if (first >= n) { printf "soak: %s: FAIL: nothing after the warm-up of %d s\n", leg, warm; exit 1 }
      base = rss[first]; peak = base; low = base
      for (i = first; i <= n; i++) { if (rss[i] > peak) peak = rss[i]; if (rss[i] < low) low = rss[i] }
      growth = (peak - base) / base * 100; shrink = (base - low) / base * 100
      # Time per agent-frame over the busy windows (at least half the most agents seen: a
      # draining round costs less per agent), first half against last half after warm-up.
      most = 0
      for (i = first; i <= n; i++) if (live[i] > most) most = live[i]
      m = 0
      for (i = first; i <= n; i++) if (live[i] > 0 && 2 * live[i] >= most) { m++; w[m] = us[i] }
      h = int(m / 2)
      fail = 0
      printf "soak: %s: %.1f simulated minutes (%d frames)%s\n", leg, last_t / 60, last_t * 60, (note == "" ? "" : " - " note)
      printf "soak: %s: memory after warm-up (%.0f s): first %.1f MiB, last %.1f MiB, peak %.1f MiB: %+.2f%%",
             leg, t[first], base / 1024, rss[n] / 1024, peak / 1024, growth
      if (growth > 5 || shrink > 5) { print " FAIL (more than 5%)"; fail = 1 } else print " ok"
      printf "soak: %s: NaN or infinite values: %d", leg, bad
      if (bad > 0) { print " FAIL"; fail = 1 } else print " ok"
      printf "soak: %s: tracks above live agents on %d lines", leg, extra + 0
      if (extra > 0) { print " FAIL"; fail = 1 } else print " ok"
      if (h >= 1) {
        a = median(w, 1, h); b = median(w, m - h + 1, m)
        d = (b - a) / a * 100
        printf "soak: %s: CPU time per agent-frame: median %.3f us (first half) -> %.3f us (last half): %+.1f%%",
               leg, a, b, d
        if (d > drift_max || d < -drift_max) { printf " FAIL (more than %s%%)\n", drift_max; fail = 1 } else print " ok"
      }
      exit fail
    }
    function median(v, lo, hi,    k, j, x, s, i2) {
      k = 0
      for (j = lo; j <= hi; j++) s[++k] = v[j]
      for (j = 2; j <= k; j++) { x = s[j]; for (i2 = j - 1; i2 >= 1 && s[i2] > x; i2--) s[i2 + 1] = s[i2]; s[i2 + 1] = x }
      return (k % 2) ? s[(k + 1) / 2] : (s[k / 2] + s[k / 2 + 1]) / 2
    }' "$csv" || status=1
done

# The plot: memory and time per frame against simulated time, one colour per leg.
png="$out/soak.png"
if command -v gnuplot >/dev/null; then
  plot_mem="" plot_ms="" plot_us=""
  for entry in "${legs[@]}"; do
    leg=${entry%%:*}
    sel="(strcol(1) eq \"$leg\" ? \$3 / 60 : NaN)"
    plot_mem+="${plot_mem:+, }'$csv' using $sel:(\$11 / 1024) with lines lw 2 title '$leg'"
    plot_ms+="${plot_ms:+, }'$csv' using $sel:7 with lines title '$leg: wall ms per frame'"
    plot_ms+=", '$csv' using $sel:13 with lines title '$leg: CPU ms per frame'"
    plot_us+="${plot_us:+, }'$csv' using $sel:10 with lines title '$leg: wall us per agent-frame'"
    plot_us+=", '$csv' using $sel:14 with lines lw 2 title '$leg: CPU us per agent-frame'"
  done
  gnuplot <<EOF
set terminal pngcairo size 1200,900 noenhanced font ",11"
set output '$png'
set datafile separator ','
set key autotitle columnhead
set multiplot layout 3,1 title "gaitkeeper soak: $(basename "$scenario" .json) at $agents agents, rounds with --loop, and a looped replay"
set grid
set ylabel 'resident memory [MiB]'
set key bottom right
set yrange [0:*]
plot $plot_mem
set ylabel 'pipeline ms per frame'
set key top right
plot $plot_ms
set ylabel 'pipeline us per agent-frame'
set xlabel 'simulated time [min]'
plot $plot_us
unset multiplot
EOF
  echo "soak: samples in $csv, plot in $png"
else
  echo "soak: samples in $csv; no plot: gnuplot not found (scripts/setup.sh installs it)"
fi
if ((status == 0)); then echo "soak: PASS"; else echo "soak: FAIL"; fi
exit "$status"
