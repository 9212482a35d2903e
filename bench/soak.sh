#!/usr/bin/env bash
# Soak test: runs `gaitkeeper bench` on a crowd whose agents keep walking (the plaza: random goals,
# round and round) at 1,000 agents for MINUTES of wall time, sampling the process's resident
# memory (VmRSS of /proc/PID/status) every few seconds, and reports whether it stays flat after
# the warm-up: the last sample within 5% of the first sample after warm-up. Exits 1 when RSS
# grows more than that (or passes --max-rss-mib, where the run stops early to spare the machine),
# 2 on a usage or run error.
# Usage: bench/soak.sh [--minutes N] [--interval S] [--agents N] [--scenario NAME] [--out FILE.csv]
#                      [--max-rss-mib M] [-- BENCH OPTIONS...]
# (defaults: 10 minutes, 5 s, 1000 agents, plaza, 4096 MiB; samples in build/soak_rss.csv; options
# after -- go to gaitkeeper bench, e.g. -- --threads 1 --sim detour)
set -euo pipefail
cd "$(dirname "$0")/.."

minutes=10
interval=5
agents=1000
scenario=plaza
csv=build/soak_rss.csv
max_rss_mib=4096
while (($#)); do
  case "$1" in
    --minutes) minutes=$2; shift 2 ;;
    --interval) interval=$2; shift 2 ;;
    --agents) agents=$2; shift 2 ;;
    --scenario) scenario=$2; shift 2 ;;
    --out) csv=$2; shift 2 ;;
    --max-rss-mib) max_rss_mib=$2; shift 2 ;;
    --) shift; break ;;
    -h | --help) sed -n '2,10p' "$0"; exit 0 ;;
    *) echo "soak: unknown option $1 (see --help)" >&2; exit 2 ;;
  esac
done
if ! [[ "$minutes" =~ ^[0-9]+([.][0-9]+)?$ && "$interval" =~ ^[0-9]+$ && "$interval" -gt 0 &&
  "$max_rss_mib" =~ ^[0-9]+$ ]]; then
  echo "soak: --minutes takes a number of minutes, --interval and --max-rss-mib whole numbers" >&2
  exit 2
fi
bin=./build/app/gaitkeeper
if [[ ! -x "$bin" ]]; then
  echo "soak: $bin not found: build it first (scripts/setup.sh)" >&2
  exit 2
fi
duration_s=$(awk -v m="$minutes" 'BEGIN { printf "%d", m * 60 }')
# Warm-up: the first fifth of the run, at least one interval (scratch, pools, TBB's threads).
warmup_s=$(awk -v d="$duration_s" -v i="$interval" 'BEGIN { w = d / 5; printf "%d", (w < i ? i : w) }')

log=$(mktemp)
# The most frames bench accepts: the run ends when the wall time is up, not by itself.
"$bin" bench --scenario "$scenario" --agents "$agents" --frames 10000000 "$@" >"$log" 2>&1 &
pid=$!
cleanup() {
  if kill -0 "$pid" 2>/dev/null; then kill "$pid" 2>/dev/null || true; fi
  wait "$pid" 2>/dev/null || true
  rm -f "$log"
}
trap cleanup EXIT

mkdir -p "$(dirname "$csv")"
echo "elapsed_s,rss_kib" >"$csv"
echo "soak: gaitkeeper bench --scenario $scenario --agents $agents $*, pid $pid, ${duration_s} s" \
  "(warm-up ${warmup_s} s), RSS every ${interval} s -> $csv"
start=$(date +%s)
capped=0
while :; do
  now=$(($(date +%s) - start))
  if ! rss=$(awk '/^VmRSS:/ { print $2 }' "/proc/$pid/status" 2>/dev/null) || [[ -z "$rss" ]]; then
    echo "soak: bench ended after ${now} s before the soak did:" >&2
    tail -5 "$log" >&2
    exit 2
  fi
  echo "$now,$rss" >>"$csv"
  printf '   %5d s  %8.1f MiB\n' "$now" "$(awk -v k="$rss" 'BEGIN { print k / 1024 }')"
  ((now >= duration_s)) && break
  if ((rss > max_rss_mib * 1024)); then
    echo "soak: RSS passed --max-rss-mib $max_rss_mib after ${now} s: stopping early"
    capped=1
    break
  fi
  sleep "$interval"
done

# First sample at or after the warm-up, the last sample, the peak after warm-up.
awk -F, -v w="$warmup_s" -v agents="$agents" -v capped="$capped" '
  NR == 1 { next }
  $1 >= w && base == "" { base = $2; base_t = $1 }
  $1 >= w && $2 > peak { peak = $2 }
  { last = $2; last_t = $1 }
  END {
    if (base == "" || last_t <= base_t) {
      if (capped) { printf "soak: NOT FLAT: %.1f MiB after %d s, too soon to compare\n", last / 1024, last_t; exit 1 }
      print "soak: too short to compare (no sample after warm-up)"
      exit 2
    }
    growth = (last - base) / base * 100
    rate = (last - base) / 1024 / ((last_t - base_t) / 60)
    printf "soak: RSS after warm-up %.1f MiB at %d s, last %.1f MiB at %d s, peak %.1f MiB\n",
           base / 1024, base_t, last / 1024, last_t, peak / 1024
    printf "soak: growth %+.1f%% (%.2f MiB per minute, %.1f KiB per agent per minute)\n",
           growth, rate, rate * 1024 / agents
    if (capped || growth > 5 || growth < -5) {
      print "soak: NOT FLAT: RSS changed by more than 5% after warm-up"
      print "soak: note: bench'"'"'s MetricsRecorder keeps every per-frame sample, so growth is"
      print "soak: expected until it bounds them; compare the rate above with the next run"
      exit 1
    }
    print "soak: FLAT: RSS within 5% after warm-up"
  }' "$csv"
