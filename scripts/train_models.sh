#!/usr/bin/env bash
# Reproduces the shipped models (models/*.safetensors): demonstrations labelled by the offline Proj-CEM
# expert on generated worlds that share no seed with the benchmark suites, then the three variants of
# shared/spec/policy.md trained end to end on them. The shipped models/cvae.safetensors was made this way:
# the datasets on a 16-core CPU (about 6 minutes), the training on one thread of the 2-core dev machine
# (1200 steps, K = 20, 35 minutes). The model file's metadata records the exact command and the data.
#
# Usage: scripts/train_models.sh [DEVICE] [VARIANT...]   DEVICE: cpu (default) or cuda; VARIANT: cvae bc fixed-q
# Environment: JOBS (labelling threads, default: all cores), STEPS (training steps per variant),
#              DATA (folder for the datasets, default build-data).
set -euo pipefail
cd "$(dirname "$0")/.."
device=${1:-cpu}
shift || true
[ $# -gt 0 ] && variants=("$@") || variants=(cvae bc fixed-q)
jobs=${JOBS:-$(nproc)}
steps=${STEPS:-1200}
data=${DATA:-build-data}
export OPENBLAS_NUM_THREADS=1
mkdir -p "$data" models

# 1. Demonstrations: 2 x 16 episodes of 20 s; online Proj-CEM drives, the expert (2000 samples, 4 CEM
#    iterations, K = 50) labels every second cycle. About 6 minutes on 16 cores.
half=$(( jobs > 1 ? jobs / 2 : 1 ))
for part in a:5000 b:6000; do
  name=${part%%:*}; seed=${part##*:}
  [ -f "$data/demo-$name.safetensors" ] && continue
  build/occtrack dataset generate --out "$data/demo-$name.safetensors" --episodes 16 --seed "$seed" \
    --duration 20 --label-every 2 --driver projcem --jobs "$half" &
done
wait

# 2. The variants on the same data, side by side (one thread each).
for variant in "${variants[@]}"; do
  build/occtrack train --data "$data/demo-a.safetensors" --data "$data/demo-b.safetensors" --variant "$variant" \
    --steps "$steps" --iterations 20 --threads 1 --device "$device" --seed 1 --out "models/$variant.safetensors" \
    --checkpoint "$data/$variant.checkpoint" > "$data/train-$variant.log" 2>&1 &
done
wait
tail -n 3 "$data"/train-*.log
