#!/usr/bin/env bash
# The whole test suite: installs what is missing, builds Release and runs every test, builds the
# libFuzzer harnesses (clang, build-fuzz/) and runs each for 10 s (scripts/fuzz.sh --smoke), then
# builds again with AddressSanitizer + UBSan and runs the suite once more.
# Shared data: $GAITKEEPER_DATA (default ../shared/data). GK_SKIP_SANITIZE=1 skips the sanitizer
# pass, GK_SKIP_FUZZ=1 the fuzz smoke run.
set -euo pipefail
cd "$(dirname "$0")/.."
export GAITKEEPER_DATA="${GAITKEEPER_DATA:-$(cd .. && pwd)/shared/data}"
jobs=$(nproc)

bash scripts/setup.sh --no-build

echo "== Release build and tests"
cmake --preset release >/dev/null
cmake --build --preset release -j"$jobs"
ctest --preset release -j"$jobs"

if [[ "${GK_SKIP_FUZZ:-0}" != "1" ]]; then
  echo "== Fuzz smoke run (libFuzzer, 10 s per target)"
  bash scripts/fuzz.sh --smoke
fi

if [[ "${GK_SKIP_SANITIZE:-0}" != "1" ]]; then
  echo "== AddressSanitizer + UBSan build and tests"
  cmake --preset asan >/dev/null
  cmake --build --preset asan -j"$jobs"
  ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    ctest --preset asan -j"$jobs"
fi
