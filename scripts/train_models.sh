#!/usr/bin/env bash
# Reproduces the shipped models (models/*.safetensors): demonstrations labelled by the offline Proj-CEM
# expert on generated worlds that share no seed with the benchmark suites, then the three variants of
# shared/spec/policy.md trained end to end on them, side by side. The model files' metadata records the exact
# training command, the datasets and their row counts, the steps, the time and the hardware.
#
# Usage: scripts/train_models.sh [DEVICE] [VARIANT...]   DEVICE: cpu (default), cuda or cuda:I;
#                                                        VARIANT: cvae bc fixed-q (default: all three)
# Environment (defaults in brackets):
#   OCCTRACK        the occtrack binary, built with LibTorch [build/occtrack]
#   DATA            folder for datasets, checkpoints and logs [build-data]
#   MODELS          folder the model files are written to [models]
#   CHUNKS          dataset files of 16 episodes each [8]; one that exists is kept, not made again
#   DATA_MINUTES    start no new chunk after this many minutes (0: no limit) [0]
#   DURATION        simulated seconds per episode [30]
#   EXPERT_SAMPLES, EXPERT_ITERATIONS   the expert's CEM budget [the offline expert's: 120, 8]
#   JOBS            labelling threads [all cores]
#   STEPS, BATCH, ITERATIONS, LR, LR_FINAL   training [6000, 512, 20, 1e-3, 1e-4]
#   BC_STEPS        steps of bc, which has no projection and is far cheaper per step [4 x STEPS]
#   MAX_MINUTES     stop each training after this many minutes and write the model (0: no limit) [0]
#   THREADS         torch CPU threads per training [1]
#   FRAME           what the networks see: robot or target (docs/learning.md, "Target frame") [target]
#   SNAPSHOT_EVERY  also write each model every this many steps, for scripts/validate_models.sh [0: none]
# Every dataset file in DATA named demo-*.safetensors is trained on, older ones included.
#
# The shipped models were made on the 2-core dev machine, no GPU, from the 6400 rows of demo-a and demo-b
# (2 x 16 episodes of 20 s, seeds 5000 and 6000, the full expert: 2000 samples x 4 iterations):
#   OCCTRACK=build/occtrack CHUNKS=0 STEPS=4000 BC_STEPS=4000 BATCH=256 MAX_MINUTES=50 FRAME=robot scripts/train_models.sh cpu
# with the two demo files made first (README, "Training a model"). docs/results.md gives the time and losses.
set -euo pipefail
cd "$(dirname "$0")/.."
device=${1:-cpu}
shift || true
[ $# -gt 0 ] && variants=("$@") || variants=(cvae bc fixed-q)
occtrack=${OCCTRACK:-build/occtrack}
data=${DATA:-build-data}
chunks=${CHUNKS:-8}
data_minutes=${DATA_MINUTES:-0}
jobs=${JOBS:-$(nproc)}
steps=${STEPS:-6000}
export OPENBLAS_NUM_THREADS=1
models=${MODELS:-models}
mkdir -p "$data" "$models"
[ -x "$occtrack" ] || { echo "train_models.sh: no occtrack binary at $occtrack (build with LibTorch first)" >&2; exit 2; }

# 1. Demonstrations: chunks of 16 episodes in turn over forest, boxes, mixed and dynamic worlds and target
#    speeds 1, 1.5 and 2 m/s; online Proj-CEM drives, the expert labels every second cycle. Seeds 7000 + 16 i.
start=$(date +%s)
for (( i = 0; i < chunks; i++ )); do
  out="$data/demo-c$i.safetensors"
  [ -f "$out" ] && continue
  if [ "$data_minutes" != 0 ] && [ $(( $(date +%s) - start )) -ge $(( data_minutes * 60 )) ]; then
    echo "train_models.sh: DATA_MINUTES=$data_minutes reached, $i of $chunks chunks made" >&2
    break
  fi
  "$occtrack" dataset generate --out "$out.partial" --episodes 16 --seed $(( 7000 + 16 * i )) \
    --duration "${DURATION:-30}" --label-every 2 --driver projcem --jobs "$jobs" \
    ${EXPERT_SAMPLES:+--expert-samples "$EXPERT_SAMPLES"} ${EXPERT_ITERATIONS:+--expert-iterations "$EXPERT_ITERATIONS"}
  mv "$out.partial" "$out"
done
files=()
for f in "$data"/demo-*.safetensors; do files+=(--data "$f"); done
[ ${#files[@]} -gt 0 ] || { echo "train_models.sh: no datasets in $data" >&2; exit 2; }

# 2. The variants on the same data, side by side.
for variant in "${variants[@]}"; do
  variant_steps=$steps
  [ "$variant" = bc ] && variant_steps=${BC_STEPS:-$(( 4 * steps ))}
  "$occtrack" train "${files[@]}" --variant "$variant" --device "$device" --threads "${THREADS:-1}" --seed 1 \
    --frame "${FRAME:-target}" --steps "$variant_steps" --batch "${BATCH:-512}" --iterations "${ITERATIONS:-20}" --lr "${LR:-1e-3}" \
    --lr-final "${LR_FINAL:-1e-4}" --max-minutes "${MAX_MINUTES:-100000}" --out "$models/$variant.safetensors" \
    --checkpoint "$data/$variant.checkpoint" --snapshot-every "${SNAPSHOT_EVERY:-0}" --progress-seconds 30 \
    > "$data/train-$variant.log" 2>&1 &
done
wait
tail -n 3 "$data"/train-*.log
