#!/usr/bin/env bash
# Sets up a fresh Debian 12 machine (scripts/setup.sh), builds, and starts Gaitkeeper on its built-in
# data (procedural clips and mannequin, a scenario from data/scenarios). Until the interactive demo
# window lands, this shows the command-line modes on the same built-in data.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
gk=./build/app/gaitkeeper
echo
echo "== gaitkeeper analyze-clip builtin   (the procedural locomotion set)"
"$gk" analyze-clip builtin
echo
echo "== gaitkeeper bench --scenario corridor --agents 200 --frames 600"
"$gk" bench --scenario corridor --agents 200 --frames 600
echo
echo "More: $gk --help"
