#!/usr/bin/env bash
# Reproduces the tables of docs/results.md: every suite with every planner (without the safety layer, as
# measured), two episodes at a time (one per
# core of the development machine; each planner itself runs on one thread). Results go to out/results/ as
# JSON and out/figures/ as SVG; the tables are printed. Expect about half an hour on 2 cores (Proj-CEM takes
# most of it; a learned planner runs a suite in about a minute).
# Usage: scripts/run_benchmarks.sh [planner ...]   (default: follower projcem cvae bc cvae-fixed-q)
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -gt 0 ] && planners=("$@") || planners=(follower projcem cvae bc cvae-fixed-q)
mkdir -p out/results out/figures
for suite in static-1ms static-2ms dynamic-1.5ms; do
  for planner in "${planners[@]}"; do
    echo "== $suite / $planner" >&2
    build/occtrack bench suite "$suite" --planner "$planner" --jobs 2 --no-shield \
      --json "out/results/$suite.$planner.json" --svg-dir "out/figures/$suite"
  done
done
