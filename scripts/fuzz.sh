#!/usr/bin/env bash
# Builds the libFuzzer harnesses of fuzz/ (the `fuzz` preset: clang, ASan + UBSan, build-fuzz/)
# and runs every target, one after the other, for SECONDS each (default 60). Seed corpora are made
# here, at run time, in build-fuzz/corpus/<target>/ from the shared real data ($GAITKEEPER_DATA,
# default ../shared/data), the fixtures in tests/data and data/scenarios; the corpora keep what
# the fuzzers add between runs. Crashes, leaks, timeouts and out-of-memory inputs are written to
# build-fuzz/findings/<target>/ and make the script exit with 1.
# Usage: scripts/fuzz.sh [SECONDS | --smoke] [TARGET...]    (--smoke: 10 s per target, for CI)
# GK_FUZZ_ARGS adds libFuzzer flags to every run (e.g. GK_FUZZ_ARGS="-seed=1 -jobs=1").
set -euo pipefail
cd "$(dirname "$0")/.."
data="${GAITKEEPER_DATA:-$(cd .. && pwd)/shared/data}"
export LC_ALL=C  # byte lengths (${#json}) and byte-wise tools
jobs=$(nproc)

seconds=60
if [[ $# -gt 0 && "$1" == "--smoke" ]]; then
  seconds=10
  shift
elif [[ $# -gt 0 && "$1" =~ ^[0-9]+$ ]]; then
  seconds=$1
  shift
fi
all_targets=(fuzz_bvh fuzz_gltf fuzz_role_manifest fuzz_scenario fuzz_trajectory fuzz_params_json
  fuzz_params_set)
targets=("$@")
if ((${#targets[@]} == 0)); then targets=("${all_targets[@]}"); fi

echo "== fuzz: building build-fuzz/ (clang, libFuzzer, ASan + UBSan)"
cmake --preset fuzz >/dev/null
cmake --build --preset fuzz -j"$jobs"

out=build-fuzz
if [[ ! -d "$data" ]]; then
  echo "fuzz: no shared data at $data: seeding from the repository's fixtures only"
fi

# seed TARGET FILE...: copies the files that exist into the target's corpus.
seed() {
  local dir="$out/corpus/$1"
  shift
  mkdir -p "$dir"
  for f in "$@"; do
    if [[ -f "$f" ]]; then
      cp -f "$f" "$dir/seed_$(basename "$f")"
      chmod u+w "$dir/seed_$(basename "$f")"  # the shared data is read-only
    fi
  done
}
# seed_text TARGET NAME TEXT: one generated seed.
seed_text() {
  mkdir -p "$out/corpus/$1"
  printf '%s' "$3" >"$out/corpus/$1/seed_$2"
}

shopt -s nullglob
seed fuzz_bvh "$data"/clips/bvh/*.bvh "$data"/clips/bvh/more/*.bvh tests/data/good/*.bvh \
  tests/data/bad/*.bvh
seed fuzz_gltf "$data"/clips/gltf/*.glb tests/data/good/*.gltf tests/data/bad/*.gltf
seed fuzz_scenario data/scenarios/*.json tests/data/bad/scenarios/*.json
seed fuzz_trajectory "$data"/trajectories/*/*.txt "$data"/trajectories/*/original/obsmat.txt \
  tests/data/bad/trajectories/*.txt tests/data/good/trajectories/*
# The .gltf fixtures again as small .glb files (a JSON chunk only; their buffers are data: URIs),
# so that the binary path has seeds other than the 3 MB mannequin.
le32() { printf '\\x%02x\\x%02x\\x%02x\\x%02x' $(($1 & 255)) $(($1 >> 8 & 255)) \
  $(($1 >> 16 & 255)) $(($1 >> 24 & 255)); }
for f in tests/data/good/*.gltf tests/data/bad/*.gltf; do
  json=$(tr -d '\n' <"$f")
  while ((${#json} % 4)); do json+=" "; done
  printf "glTF$(le32 2)$(le32 $((20 + ${#json})))$(le32 ${#json})JSON%s" "$json" \
    >"$out/corpus/fuzz_gltf/seed_$(basename "$f" .gltf).glb"
done
shopt -u nullglob

# Parameter names from the table in mediator/params.cc; values inside and outside their limits.
mapfile -t params < <(grep -o '^    {"[a-z_]*"' mediator/params.cc | tr -d ' {"')
set_lines="mode=apm"$'\n'"seed=7"$'\n'
json='{"mode": "rate", "seed": 3'
for p in "${params[@]}"; do
  set_lines+="$p=0.5"$'\n'"$p=on"$'\n'
  json+=", \"$p\": 0.5"
done
seed_text fuzz_params_set all.txt "$set_lines"
seed_text fuzz_params_set bad.txt $'torsion_limit_deg=1e400\nfoot_locking=maybe\n=1\nnope=2\n'
seed_text fuzz_params_json all.json "$json}"
seed_text fuzz_params_json bad.json '{"torsion_limit_deg": 400, "feedback": "yes", "x": null}'
# Roles of the built-in humanoid (the skeleton fuzz_role_manifest applies them to).
seed_text fuzz_role_manifest legs.json '{"roles": {"left_knee": "LeftLeg", "right_knee": "RightLeg",
 "left_ankle": "LeftFoot", "right_toe": "RightToeBase", "hips": "Hips", "chest": null}}'
seed_text fuzz_role_manifest bad.json '{"roles": {"left_knee": "NoSuchJoint", "elbow": "LeftArm"}}'

# Per target: the dictionary and the largest input (the mannequin .glb is 3 MB).
declare -A dict=([fuzz_bvh]=bvh [fuzz_gltf]=gltf [fuzz_role_manifest]=json [fuzz_scenario]=json
  [fuzz_params_json]=json)
declare -A max_len=([fuzz_bvh]=524288 [fuzz_gltf]=4194304 [fuzz_trajectory]=262144)

failed=()
summary=()
for t in "${targets[@]}"; do
  if [[ ! -x "$out/fuzz/$t" ]]; then
    echo "fuzz: unknown target $t (known: ${all_targets[*]})" >&2
    exit 2
  fi
  mkdir -p "$out/findings/$t" "$out/logs"
  log="$out/logs/$t.log"
  args=(-max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1
    -artifact_prefix="$out/findings/$t/" -max_len="${max_len[$t]:-16384}")
  if [[ -n "${dict[$t]:-}" ]]; then args+=(-dict="fuzz/dict/${dict[$t]}.dict"); fi
  # shellcheck disable=SC2206  # GK_FUZZ_ARGS: more libFuzzer flags, split on spaces (last wins)
  args+=(${GK_FUZZ_ARGS:-})
  echo "== fuzz: $t for ${seconds} s"
  touch "$log.start"
  rc=0
  ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    "$out/fuzz/$t" "${args[@]}" "$out/corpus/$t" >"$log" 2>&1 || rc=$?
  execs=$(grep -o 'stat::number_of_executed_units: [0-9]*' "$log" | tail -1 | grep -o '[0-9]*$' ||
    true)
  cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | grep -o '[0-9]*$' || true)
  corpus=$(find "$out/corpus/$t" -type f | wc -l)
  line="$t: ${execs:-?} executions in ${seconds} s, coverage ${cov:-?}, corpus $corpus"
  if ((rc != 0)); then
    line+=", FAILED (exit $rc): $(find "$out/findings/$t" -type f -newer "$log.start" | tr '\n' ' ')"
    failed+=("$t")
    grep -m1 -E 'ERROR: (AddressSanitizer|libFuzzer|LeakSanitizer)|runtime error|SUMMARY' "$log" ||
      true
    echo "   log: $log"
  else
    line+=", no findings"
  fi
  echo "   $line"
  summary+=("$line")
done

echo "== fuzz summary"
printf '   %s\n' "${summary[@]}"
if ((${#failed[@]})); then
  echo "fuzz: ${#failed[@]} target(s) failed: ${failed[*]} (inputs in $out/findings/)"
  exit 1
fi
