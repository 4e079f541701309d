#!/usr/bin/env bash
# Chooses a model in closed loop (issue 12; docs/learning.md, "Choosing the model"): every model given drives
# a validation suite shaped like the six v2 suites but on episode seeds none of them uses (3000-3599, outside
# the benchmark's 1000-1999, and away from the demonstrations' 5000-7999 and 20000+), 45 s episodes. One line
# per model: time hidden, collisions and share in band, summed over the suite, and the one to keep (no
# collision, least time hidden; ties: the later file on the command line).
#
# Usage: scripts/validate_models.sh MODEL.safetensors [MODEL...]
# Environment (defaults in brackets):
#   OCCTRACK     the occtrack binary [build/occtrack]
#   PLANNER      the learned planner the models are for: cvae, bc or cvae-fixed-q [cvae]
#   VALIDATION   folder of the validation scenarios, made when missing [build-data/validation]
#   LATENCY      command latency in ms, fixed so that the comparison does not depend on the machine's load [3]
#   JOBS         episodes at the same time [all cores]
set -euo pipefail
cd "$(dirname "$0")/.."
occtrack=${OCCTRACK:-build/occtrack}
planner=${PLANNER:-cvae}
validation=${VALIDATION:-build-data/validation}
jobs=${JOBS:-$(nproc)}
[ $# -gt 0 ] || { sed -n '2,15p' "$0" >&2; exit 2; }
suites=(sixwall-1ms sixwall-2ms sixwall-dynamic-1.5ms random-2ms clutter-2ms clutter-dynamic-2ms)

# The validation scenarios: suite s (in the order above) from episode seed base 3000 + 100 s, two episodes per
# world (one per world of clutter-2ms's three).
for (( i = 0; i < ${#suites[@]}; i++ )); do
  suite=${suites[$i]}
  [ -d "$validation/$suite" ] && continue
  episodes=2
  [ "$suite" = clutter-2ms ] && episodes=1
  "$occtrack" scenario generate --suite "$suite" --out "$validation" --seed $(( 3000 + 100 * i )) \
    --episodes "$episodes" --duration 45 >&2
done

best="" best_hidden=""
printf '%-50s %10s %10s %8s  %s\n' model "hidden (s)" collisions "in band" "hidden per suite (s), in the order above"
for model in "$@"; do
  [ -f "$model" ] || { echo "validate_models.sh: no model file $model" >&2; exit 2; }
  results=$(mktemp -d)
  for suite in "${suites[@]}"; do
    "$occtrack" bench suite "$validation/$suite" --planner "$planner" --model "$model" --jobs "$jobs" \
      --latency "${LATENCY:-3}" --tau 0.25 --lidar-noise 0.01 --beams 360 --target-noise 0.05,0.1 --shield \
      --json "$results/$suite.json" > /dev/null 2>&1
  done
  read -r hidden collisions band per_suite < <(python3 - "$results" "${suites[@]}" <<'EOF'
import json, pathlib, sys
hidden = collisions = band = duration = 0.0
per_suite = []
for name in sys.argv[2:]:
    s = json.loads((pathlib.Path(sys.argv[1]) / (name + ".json")).read_text())["summary"]
    per_suite.append(f"{s['occlusion_time_s']:.1f}")
    hidden += s["occlusion_time_s"]
    collisions += s["collisions"]
    band += s["tracking_distance"]["in_band_share"] * s["duration_s"]
    duration += s["duration_s"]
print(f"{hidden:.1f} {int(collisions)} {100 * band / duration:.0f}% {'/'.join(per_suite)}")
EOF
)
  rm -rf "$results"
  printf '%-50s %10s %10s %8s  %s\n' "$model" "$hidden" "$collisions" "$band" "$per_suite"
  if [ "$collisions" = 0 ] && { [ -z "$best" ] || python3 -c "import sys; sys.exit(not $hidden <= $best_hidden)"; }; then
    best=$model best_hidden=$hidden
  fi
done
[ -n "$best" ] || { echo "validate_models.sh: every model collided" >&2; exit 1; }
echo "best: $best ($best_hidden s hidden, no collision)"
