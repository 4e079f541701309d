#!/usr/bin/env bash
# Demonstrations like the v2 suites, with DAgger rounds (issue 12; docs/learning.md, "DAgger"):
#   round 0   the offline expert drives and labels every cycle;
#   round r   the cvae model trained on rounds 0 .. r-1 drives (through the safety layer) and the expert labels
#             every cycle of the states the policy itself reaches;
#   last      the final models trained on every round (scripts/train_models.sh), with snapshots.
# Every episode: the paper's worlds and occtrack's (sixwall, sixwall-sliding, random, forest, boxes, mixed,
# clutter-dynamic, dynamic) in turn, tele-operated targets at top speeds 1, 1.5, 2 and 2.5 m/s, the v2 sensing
# (360 beams, range noise 0.01 m, target noise 0.05 m and 0.1 m/s), robot lag 0.25 s and a 20 ms latency,
# seeds from 20000 (none is a benchmark seed). A file that exists is kept, so an interrupted run continues.
#
# Usage: scripts/dagger.sh [DEVICE]     DEVICE: cpu (default), cuda or cuda:I
# Environment (defaults in brackets):
#   OCCTRACK      the occtrack binary, built with LibTorch [build/occtrack]
#   DATA          folder for the rounds' datasets, models and logs [build-data/dagger]
#   MODELS        folder the final models are written to [$DATA/final]
#   ROUNDS        DAgger rounds after round 0 [3]
#   EPISODES      episodes per round [32]; DURATION0, DURATION: their simulated seconds [40, 30]
#   JOBS          labelling threads [all cores]
#   ROUND_STEPS   training steps of each round's cvae [1200]
#   DRIVER_TRACKING_WEIGHT   the driving cvae's ranking weight on the tracking distance [1: as the shipped
#                 models' rounds were driven, before the planner's default became 5]
#   DRIVER_MOVING_REACH      the driving cvae's moving reach, s [0: as the shipped models' rounds were driven,
#                 before the cvae's default behind the layer became 1]
#   VARIANTS      the final models, side by side: any of cvae bc fixed-q [cvae]
#   STEPS, BC_STEPS, BATCH, MAX_MINUTES, THREADS, SNAPSHOT_EVERY   the final training (scripts/train_models.sh)
#                 [2000, 8000, 256, none, all cores, 250]
set -euo pipefail
cd "$(dirname "$0")/.."
device=${1:-cpu}
occtrack=${OCCTRACK:-build/occtrack}
data=${DATA:-build-data/dagger}
models=${MODELS:-$data/final}
rounds=${ROUNDS:-3}
episodes=${EPISODES:-32}
jobs=${JOBS:-$(nproc)}
round_steps=${ROUND_STEPS:-1200}
export OPENBLAS_NUM_THREADS=1
mkdir -p "$data" "$models"
[ -x "$occtrack" ] || { echo "dagger.sh: no occtrack binary at $occtrack (build with LibTorch first)" >&2; exit 2; }

v2=(--target teleop --worlds sixwall,sixwall-sliding,random,forest,boxes,mixed,clutter-dynamic,dynamic
    --speeds 1,1.5,2,2.5 --latency 20 --tau 0.25 --beams 360 --lidar-noise 0.01 --target-noise 0.05,0.1
    --label-every 1 --jobs "$jobs")

generate() {  # OUT ARGS...: one round's dataset, unless it exists
  local out=$1
  shift
  [ -f "$out" ] && return 0
  "$occtrack" dataset generate --out "$out.partial" "${v2[@]}" "$@" 2>&1 | tee "${out%.safetensors}.log"
  mv "$out.partial" "$out"
}

train_round() {  # R: the cvae that drives round R + 1, trained on rounds 0 .. R
  local r=$1 files=()
  [ -f "$data/cvae-r$r.safetensors" ] && return 0
  for (( i = 0; i <= r; i++ )); do files+=(--data "$data/demo-r$i.safetensors"); done
  "$occtrack" train "${files[@]}" --variant cvae --device "$device" --threads "${THREADS:-$jobs}" --seed 1 \
    --frame target --steps "$round_steps" --batch "${BATCH:-256}" --iterations 20 --lr 1e-3 --lr-final 1e-4 \
    --out "$data/cvae-r$r.safetensors" --progress-seconds 60 > "$data/train-cvae-r$r.log" 2>&1
  tail -n 2 "$data/train-cvae-r$r.log"
}

start=$(date +%s)
generate "$data/demo-r0.safetensors" --seed 20000 --episodes "$episodes" --duration "${DURATION0:-40}" --driver expert
for (( r = 1; r <= rounds; r++ )); do
  train_round $(( r - 1 ))
  generate "$data/demo-r$r.safetensors" --seed $(( 20000 + 1000 * r )) --episodes "$episodes" \
    --duration "${DURATION:-30}" --driver cvae --model "$data/cvae-r$(( r - 1 )).safetensors" \
    --tracking-weight "${DRIVER_TRACKING_WEIGHT:-1}" --moving-reach "${DRIVER_MOVING_REACH:-0}"
done
echo "dagger.sh: data done after $(( ($(date +%s) - start) / 60 )) min" >&2

# The final models on every round's rows (train_models.sh trains on $DATA/demo-*.safetensors), with snapshots
# for choosing one in closed loop: scripts/validate_models.sh $MODELS/cvae*.safetensors. VARIANTS run side by
# side, THREADS torch threads each.
OCCTRACK="$occtrack" DATA="$data" MODELS="$models" CHUNKS=0 STEPS="${STEPS:-2000}" BC_STEPS="${BC_STEPS:-8000}" \
  BATCH="${BATCH:-256}" MAX_MINUTES="${MAX_MINUTES:-100000}" THREADS="${THREADS:-$jobs}" FRAME=target \
  SNAPSHOT_EVERY="${SNAPSHOT_EVERY:-250}" scripts/train_models.sh "$device" ${VARIANTS:-cvae}
echo "dagger.sh: done after $(( ($(date +%s) - start) / 60 )) min; models in $models" >&2
