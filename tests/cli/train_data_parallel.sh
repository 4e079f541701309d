#!/usr/bin/env bash
# Data-parallel training (docs/scaling.md) against one process, on one machine over loopback:
#   1. a tiny model trained 20 steps by one process, and by two processes meeting at a rendezvous file, then at
#      127.0.0.1:PORT: every step's loss terms, the validation losses every 5 steps and the final model agree
#      to float rounding; only rank 0 writes;
#   2. with mpirun (when given): the same, rank and size taken from the launcher;
#   3. --world-size without --rank or --rendezvous is refused at once; two processes given different settings
#      refuse, naming the difference, without a hang.
# usage: train_data_parallel.sh OCCTRACK WORKDIR [MPIEXEC]
set -euo pipefail
occtrack=$1 work=$2 mpiexec=${3:-}
here=$(cd "$(dirname "$0")" && pwd)
compare=("$(command -v python3)" "$here/compare_models.py")
rm -rf "$work" && mkdir -p "$work" && cd "$work"

"$occtrack" dataset generate --out demo.safetensors --episodes 3 --duration 3 --expert-samples 64 \
  --expert-iterations 1 --jobs 2 > /dev/null 2>&1
train=("$occtrack" train --data demo.safetensors --batch 32 --iterations 4 --hidden 16 --layers 2 --features 8
       --pointnet-hidden 8 --pointnet-widths 8,8 --validation-share 0.3 --validation-every 5 --steps 20
       --progress-seconds 100 --threads 1 --dist-timeout 60)

# Tolerances: float32 rounding differs between one sum over 32 rows and two over 16; after 20 Adam steps the
# loss terms agree to about 2e-5 (relative) and the weights to about 1e-4 of their magnitude. The biases of
# layers that batch norm follows get only rounding noise as gradient (batch norm removes any shift), which Adam
# turns into steps of up to the learning rate in either run alike: hence 5e-3 of max(1, magnitude) for them.
check() {  # check NAME: compares NAME.csv and NAME.safetensors with one process's
  "${compare[@]}" --csv --tolerance 1e-4 one.csv "$1.csv"
  "${compare[@]}" --tolerance 5e-3 one.safetensors "$1.safetensors"
}

"${train[@]}" --out one.safetensors --loss-log one.csv > one.log 2>&1

echo "== two processes, rendezvous file"
"${train[@]}" --out file.safetensors --loss-log file.csv --world-size 2 --rank 1 --rendezvous "$work/rendezvous" \
  > file1.log 2>&1 &
"${train[@]}" --out file.safetensors --loss-log file.csv --world-size 2 --rank 0 --rendezvous "$work/rendezvous" \
  > file0.log 2>&1
wait $!
grep -q "2 processes, each 16 of every 32 rows" file0.log
[ ! -s file1.log ] || { echo "rank 1 printed:"; cat file1.log; exit 1; }
check file

echo "== two processes, rendezvous 127.0.0.1:PORT"
port=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
"${train[@]}" --out tcp.safetensors --loss-log tcp.csv --world-size 2 --rank 1 --rendezvous "127.0.0.1:$port" \
  > tcp1.log 2>&1 &
"${train[@]}" --out tcp.safetensors --loss-log tcp.csv --world-size 2 --rank 0 --rendezvous "127.0.0.1:$port" \
  > tcp0.log 2>&1
wait $!
check tcp

if [ -n "$mpiexec" ]; then
  echo "== mpirun -n 2 (rank and size from the launcher)"
  OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 "$mpiexec" -n 2 --oversubscribe \
    "${train[@]}" --out mpi.safetensors --loss-log mpi.csv --rendezvous "$work/rendezvous-mpi" > mpi.log 2>&1
  grep -q "2 processes" mpi.log
  check mpi
fi

echo "== incomplete options refused before any waiting"
if "${train[@]}" --out x.safetensors --world-size 2 --rendezvous "$work/unused" > norank.log 2>&1; then exit 1; fi
grep -q -- "--rank" norank.log
if "${train[@]}" --out x.safetensors --world-size 2 --rank 0 > nowhere.log 2>&1; then exit 1; fi
grep -q "rendezvous" nowhere.log

echo "== different settings refused"
set +e
"${train[@]}" --out bad.safetensors --world-size 2 --rank 1 --rendezvous "$work/rendezvous-bad" --lr 2e-3 \
  > bad1.log 2>&1 &
"${train[@]}" --out bad.safetensors --world-size 2 --rank 0 --rendezvous "$work/rendezvous-bad" > bad0.log 2>&1
status0=$?
wait $!
status1=$?
set -e
cat bad0.log bad1.log
[ "$status0" -ne 0 ] && [ "$status1" -ne 0 ] && grep -q "differs between the processes" bad0.log && [ ! -e bad.safetensors ]
echo "data-parallel training matches one process"
